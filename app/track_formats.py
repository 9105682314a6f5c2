"""More track formats (product.md §4, §8): gpsbabel ``unicsv``, RTKLIB ``.pos``, u-blox UBX, KML.

Pure like :mod:`app.tracks`: bytes in, fixes out, or a :class:`TrackFormatError` naming the
problem. :func:`app.tracks.parse_track` asks :func:`detect_extra_format` first and hands the
file here when it is one of these; everything else goes on to its GPX/CSV/NMEA readers.

Formats
-------
- **unicsv** (``gpsbabel -o unicsv``): a CSV header with ``Latitude``, ``Longitude``, ``Date``
  and ``Time`` columns (UTC; ``YYYY/MM/DD`` or ``YYYY-MM-DD`` and ``HH:MM:SS[.fff]``), and
  optionally ``Speed`` [m/s], ``Course``, ``FIX`` (``none``, ``2d``, ``3d``, ``dgps``, ``pps``),
  ``HDOP`` and ``Satellites``/``Sat``. Rows with ``FIX`` ``none`` are dropped and counted.
- **RTKLIB .pos** (RTKPOST, RTKNAVI, rtkrcv): ``%`` header lines, then one solution per line:
  time as ``YYYY/MM/DD HH:MM:SS.sss`` or GPS week and seconds, in GPST (converted to UTC with
  the leap seconds of the day) or UTC, latitude and longitude in degrees (or d m s), height,
  ``Q`` (1 fixed, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP) and ``ns`` satellites. ECEF
  (x/y/z) solutions are refused with a clear message.
- **u-blox UBX** (with pyubx2), NMEA mixed in or not: ``NAV-PVT`` epochs with a valid date and
  time and ``gnssFixOk``; the carrier solution gives RTK fixed/float, ``NAV-DOP`` of the same
  epoch the HDOP; NMEA sentences beside them are counted and ignored (NAV-PVT is finer). A log
  of NMEA sentences with UBX frames but no ``NAV-PVT`` is an NMEA log (:mod:`app.tracks`).
- **KML** (Google Earth, tillpath's own exports; with fastkml after the XML safety check):
  the first ``gx:Track`` (``<when>`` with ``<gx:coord>``) or ``gx:MultiTrack``; else a
  LineString whose Placemark has a ``TimeSpan``, its times spread along it at constant speed.
"""

from __future__ import annotations

import bisect
import csv
import datetime as dt
import io
import math
import re
from typing import Any, Final

from app.track_fixes import TrackFix, TrackFormatError, check_position, datetime_to_us
from planner.errors import UnreadableFileError
from planner.io.safety import check_xml

#: The formats this module reads (names stored as a run's ``source``).
EXTRA_TRACK_FORMATS: Final = ("unicsv", "pos", "ubx", "kml")

#: GPS - UTC [s] from each date on (IERS Bulletin C; GPS time has no leap seconds).
_GPS_LEAP_SECONDS: Final = (
    (dt.date(1999, 1, 1), 13),
    (dt.date(2006, 1, 1), 14),
    (dt.date(2009, 1, 1), 15),
    (dt.date(2012, 7, 1), 16),
    (dt.date(2015, 7, 1), 17),
    (dt.date(2017, 1, 1), 18),
)
_GPS_EPOCH: Final = dt.datetime(1980, 1, 6, tzinfo=dt.UTC)
_UBX_SYNC: Final = b"\xb5\x62"
#: Sync, class NAV (0x01), id PVT (0x07) and its 92-byte payload length (little-endian).
_UBX_NAV_PVT: Final = b"\xb5\x62\x01\x07\x5c\x00"
_NMEA_SENTENCE = re.compile(r"\$[A-Z]{2}[A-Z0-9]{3},")
_POS_TIME = re.compile(r"^\d{4}/\d{1,2}/\d{1,2}\s+\d{1,2}:\d{2}:\d{2}(\.\d+)?\s")
_POS_WEEK = re.compile(r"^\d{3,4}\s+\d+(\.\d+)?\s")

#: unicsv header names (lower case) -> ours.
_UNICSV_COLUMNS: Final[dict[str, str]] = {
    "latitude": "lat",
    "lat": "lat",
    "longitude": "lon",
    "lon": "lon",
    "long": "lon",
    "date": "date",
    "utc_d": "date",
    "utc date": "date",
    "time": "time",
    "utc_t": "time",
    "utc time": "time",
    "speed": "speed_mps",
    "course": "heading_deg",
    "heading": "heading_deg",
    "fix": "fix",
    "hdop": "hdop",
    "satellites": "satellites",
    "sat": "satellites",
    "sats": "satellites",
}
#: gpsbabel's fix types -> FIX_QUALITIES (``none`` means no fix).
_UNICSV_FIX: Final[dict[str, str | None]] = {
    "none": None,
    "2d": "single",
    "3d": "single",
    "dgps": "dgps",
    "pps": "single",
}
#: RTKLIB Q -> FIX_QUALITIES (3 SBAS and 6 PPP are corrected, decimetre to metre: ``dgps``).
_POS_QUALITY: Final[dict[int, str]] = {
    1: "rtk_fixed",
    2: "rtk_float",
    3: "dgps",
    4: "dgps",
    5: "single",
    6: "dgps",
}


def detect_extra_format(data: bytes) -> str | None:
    r"""Tell ``unicsv``, ``pos``, ``ubx`` or ``kml`` from a file's first bytes; else None.

    Examples
    --------
    >>> detect_extra_format(b"No,Latitude,Longitude,Date,Time\n")
    'unicsv'
    >>> detect_extra_format(b"% program   : RTKPOST ver.2.4.3\n")
    'pos'
    >>> detect_extra_format(b"time,lat,lon\n") is None
    True
    """
    head = data[:8192]
    if _UBX_NAV_PVT in data[:65536]:
        return "ubx"
    text = head.decode("utf-8", errors="replace").lstrip("\ufeff \t\r\n")
    if _UBX_SYNC in head and not _NMEA_SENTENCE.search(text):
        return "ubx"  # UBX without NAV-PVT: the reader says what to enable
    # An NMEA log with UBX frames among its sentences (and no NAV-PVT) is read as NMEA.
    if text.startswith("<"):
        return "kml" if re.search(r"<(\w+:)?kml[\s>]", text[:2048]) else None
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    if not lines:
        return None
    if lines[0].startswith("%"):
        return "pos"
    if _POS_TIME.match(lines[0]) or _POS_WEEK.match(lines[0]):
        return "pos"
    names = {_UNICSV_COLUMNS.get(n.strip().strip('"').lower()) for n in lines[0].split(",")}
    if {"lat", "lon", "date", "time"} <= names:
        return "unicsv"
    return None


def read_extra_format(fmt: str, data: bytes) -> tuple[list[TrackFix], dict[str, Any]]:
    """Read a file of format ``fmt`` (from :func:`detect_extra_format`).

    Returns
    -------
    fixes : list of TrackFix
        In file order (:func:`app.tracks.parse_track` sorts them).
    report : dict
        What was dropped, per format.

    Raises
    ------
    TrackFormatError
        For a malformed file, naming the line or the problem.
    """
    if fmt == "unicsv":
        return _read_unicsv(data)
    if fmt == "pos":
        return _read_pos(data)
    if fmt == "ubx":
        return _read_ubx(data)
    if fmt == "kml":
        return _read_kml(data)
    raise TrackFormatError("file", f"unknown track format {fmt!r}")


# --- unicsv ----------------------------------------------------------------------------------


def _read_unicsv(data: bytes) -> tuple[list[TrackFix], dict[str, Any]]:
    reader = csv.reader(io.StringIO(data.decode("utf-8", errors="replace").lstrip("\ufeff")))
    header = next(reader)
    columns: dict[str, int] = {}
    for i, name in enumerate(header):
        key = _UNICSV_COLUMNS.get(name.strip().lower())
        if key is not None and key not in columns:
            columns[key] = i
    fixes: list[TrackFix] = []
    no_fix = 0

    def cell(row: list[str], key: str) -> str:
        i = columns.get(key)
        return row[i].strip() if i is not None and i < len(row) else ""

    try:
        for row in reader:
            if not row or all(not c.strip() for c in row):
                continue
            where = f"file: line {reader.line_num}"
            fix_type = cell(row, "fix").lower()
            if fix_type and fix_type not in _UNICSV_FIX:
                raise TrackFormatError(where, f"unknown FIX {fix_type!r}")
            quality = _UNICSV_FIX.get(fix_type) if fix_type else None
            if fix_type == "none":
                no_fix += 1
                continue
            lat = _number(cell(row, "lat"), f"{where}: Latitude")
            lon = _number(cell(row, "lon"), f"{where}: Longitude")
            if lat is None or lon is None:
                raise TrackFormatError(where, "Latitude and Longitude are required")
            check_position(lat, lon, input_name=where)
            satellites = _number(cell(row, "satellites"), f"{where}: Satellites")
            fixes.append(
                TrackFix(
                    t=_unicsv_time(cell(row, "date"), cell(row, "time"), where),
                    lat=lat,
                    lon=lon,
                    heading_deg=_number(cell(row, "heading_deg"), f"{where}: Course"),
                    speed_mps=_number(cell(row, "speed_mps"), f"{where}: Speed"),
                    quality=quality,
                    hdop=_number(cell(row, "hdop"), f"{where}: HDOP"),
                    satellites=None if satellites is None else int(satellites),
                )
            )
    except csv.Error as exc:
        raise TrackFormatError(f"file: line {reader.line_num}", str(exc)) from None
    return fixes, {"no_fix": no_fix}


def _unicsv_time(date_text: str, time_text: str, where: str) -> int:
    try:
        day = dt.date.fromisoformat(date_text.replace("/", "-"))
        clock = dt.time.fromisoformat(time_text)
    except ValueError:
        raise TrackFormatError(
            where, f"Date {date_text!r} and Time {time_text!r} are not YYYY/MM/DD and HH:MM:SS"
        ) from None
    return datetime_to_us(dt.datetime.combine(day, clock, tzinfo=dt.UTC))


def _number(text: str, input_name: str) -> float | None:
    if text == "":
        return None
    try:
        value = float(text)
    except ValueError:
        raise TrackFormatError(input_name, f"{text[:40]!r} is not a number") from None
    if not math.isfinite(value):
        raise TrackFormatError(input_name, "must be a finite number")
    return value


# --- RTKLIB .pos -----------------------------------------------------------------------------


def gps_to_utc(gps_time: dt.datetime) -> dt.datetime:
    """Return a GPS-time instant (a naive or UTC-labelled datetime) as UTC.

    Examples
    --------
    >>> gps_to_utc(dt.datetime(2026, 11, 22, 3, 14, 33, tzinfo=dt.UTC)).time()
    datetime.time(3, 14, 15)
    """
    day = gps_time.date()
    dates = [d for d, _ in _GPS_LEAP_SECONDS]
    index = bisect.bisect_right(dates, day) - 1
    leap = _GPS_LEAP_SECONDS[index][1] if index >= 0 else 0
    return gps_time.replace(tzinfo=dt.UTC) - dt.timedelta(seconds=leap)


def _read_pos(data: bytes) -> tuple[list[TrackFix], dict[str, Any]]:
    text = data.decode("utf-8", errors="replace")
    time_system = "GPST"
    fixes: list[TrackFix] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        where = f"file: line {number}"
        if line.startswith("%"):
            header = line.lstrip("% ").split()
            if header and header[0] in ("GPST", "UTC", "JST"):
                time_system = header[0]
                if any("ecef" in h for h in header):
                    raise TrackFormatError(
                        "file",
                        "RTKLIB solutions in ECEF x/y/z are not read; output latitude/longitude "
                        "(RTKPOST: Solution Format Lat/Lon/Height)",
                    )
            continue
        parts = line.split()
        if _POS_TIME.match(line + " "):
            stamp = dt.datetime.strptime(
                f"{parts[0]} {parts[1]}".split(".")[0], "%Y/%m/%d %H:%M:%S"
            )
            fraction = float("0." + parts[1].split(".")[1]) if "." in parts[1] else 0.0
            stamp = stamp + dt.timedelta(seconds=fraction)
        elif _POS_WEEK.match(line + " "):
            stamp = (
                _GPS_EPOCH + dt.timedelta(weeks=int(parts[0]), seconds=float(parts[1]))
            ).replace(tzinfo=None)
        else:
            raise TrackFormatError(
                where, "is not an RTKLIB solution line (time lat lon height Q ns …)"
            )
        rest = parts[2:]
        try:
            if len(rest) >= 9 and _is_dms(rest):  # d m s d m s height Q ns
                lat = _dms(rest[0:3])
                lon = _dms(rest[3:6])
                q, ns = int(rest[7]), int(rest[8])
            else:
                lat, lon = float(rest[0]), float(rest[1])
                q, ns = int(rest[3]), int(rest[4])
        except (IndexError, ValueError):
            raise TrackFormatError(where, "needs latitude, longitude, height, Q and ns") from None
        check_position(lat, lon, input_name=where)
        if time_system == "GPST":
            utc = gps_to_utc(stamp)
        elif time_system == "JST":
            utc = stamp.replace(tzinfo=dt.UTC) - dt.timedelta(hours=9)
        else:
            utc = stamp.replace(tzinfo=dt.UTC)
        fixes.append(
            TrackFix(
                t=datetime_to_us(utc),
                lat=lat,
                lon=lon,
                quality=_POS_QUALITY.get(q),
                satellites=ns,
            )
        )
    return fixes, {"time_system": time_system}


def _is_dms(fields: list[str]) -> bool:
    try:
        degrees_lat, minutes_lat = float(fields[0]), float(fields[1])
    except ValueError:
        return False
    return (
        degrees_lat == int(degrees_lat)
        and 0 <= minutes_lat < 60
        and minutes_lat == int(minutes_lat)
    )


def _dms(fields: list[str]) -> float:
    degrees, minutes, seconds = (float(f) for f in fields)
    sign = -1.0 if fields[0].strip().startswith("-") else 1.0
    return sign * (abs(degrees) + minutes / 60.0 + seconds / 3600.0)


# --- u-blox UBX ------------------------------------------------------------------------------


def _read_ubx(data: bytes) -> tuple[list[TrackFix], dict[str, Any]]:
    from pyubx2 import ERR_IGNORE, NMEA_PROTOCOL, UBX_PROTOCOL, UBXReader

    reader = UBXReader(
        io.BytesIO(data), protfilter=NMEA_PROTOCOL | UBX_PROTOCOL, quitonerror=ERR_IGNORE
    )
    epochs: list[Any] = []
    hdop_by_itow: dict[int, float] = {}
    nmea_lines: list[str] = []
    try:
        for raw, message in reader:
            if message is None:
                continue
            identity = getattr(message, "identity", "")
            if identity == "NAV-PVT":
                epochs.append(message)
            elif identity == "NAV-DOP":
                hdop_by_itow[int(message.iTOW)] = float(message.hDOP)
            elif raw[:1] == b"$":
                nmea_lines.append(raw.decode("ascii", errors="replace").strip())
    except Exception as exc:  # pyubx2 raises its own error types for a truncated stream
        raise TrackFormatError("file", f"the UBX log cannot be read ({exc})") from None

    if not epochs:
        raise TrackFormatError(
            "file",
            "the UBX log has no NAV-PVT message with a position and time; enable UBX-NAV-PVT "
            "output on the receiver (u-center: UBX-CFG-MSG, or CFG-MSGOUT-UBX_NAV_PVT)",
        )

    fixes: list[TrackFix] = []
    no_fix = no_time = 0
    for pvt in epochs:
        if not (pvt.validDate and pvt.validTime):
            no_time += 1
            continue
        if not pvt.gnssFixOk or pvt.fixType in (0, 5):
            no_fix += 1
            continue
        stamp = dt.datetime(pvt.year, pvt.month, pvt.day, pvt.hour, pvt.min, tzinfo=dt.UTC)
        stamp += dt.timedelta(seconds=int(pvt.second), microseconds=int(pvt.nano) / 1000)
        lat, lon = float(pvt.lat), float(pvt.lon)
        check_position(lat, lon, input_name="file: UBX NAV-PVT position")
        fixes.append(
            TrackFix(
                t=datetime_to_us(stamp),
                lat=lat,
                lon=lon,
                heading_deg=float(pvt.headMot),
                speed_mps=float(pvt.gSpeed) / 1000.0,
                quality=_ubx_quality(pvt),
                hdop=hdop_by_itow.get(int(pvt.iTOW)),
                satellites=int(pvt.numSV),
            )
        )
    report = {
        "ubx_nav_pvt": len(epochs),
        "no_fix": no_fix,
        "no_time": no_time,
        "nmea_sentences_ignored": len(nmea_lines),
    }
    return fixes, report


def _ubx_quality(pvt: Any) -> str:
    if pvt.fixType == 1:
        return "dead_reckoning"
    if pvt.carrSoln == 2:
        return "rtk_fixed"
    if pvt.carrSoln == 1:
        return "rtk_float"
    if pvt.diffSoln:
        return "dgps"
    return "single"


# --- KML -------------------------------------------------------------------------------------


def _read_kml(data: bytes) -> tuple[list[TrackFix], dict[str, Any]]:
    try:
        check_xml(data, filename="file", kind="KML")
    except UnreadableFileError as exc:
        raise TrackFormatError("file", exc.problem) from None
    from fastkml import kml

    try:
        # Bytes, not str: lxml refuses a str that declares its encoding.
        document = kml.KML.from_string(data)  # type: ignore[arg-type]
    except Exception as exc:  # fastkml raises lxml/ElementTree and its own errors
        raise TrackFormatError("file", f"is not a KML document fastkml can read ({exc})") from None
    placemarks = list(_placemarks(document))
    for placemark in placemarks:
        geometry = getattr(placemark, "kml_geometry", None)
        tracks = _tracks_of(geometry)
        if tracks:
            fixes = [
                TrackFix(
                    t=datetime_to_us(item.when.dt),
                    lat=float(item.coord.y),
                    lon=float(item.coord.x),
                )
                for track in tracks
                for item in track.track_items
                if item.when is not None and item.coord is not None
            ]
            for fix in fixes:
                check_position(fix.lat, fix.lon, input_name="file: gx:coord")
            return fixes, {"track": placemark.name or "gx:Track", "kind": "gx:Track"}
    for placemark in placemarks:
        geometry = getattr(placemark, "kml_geometry", None)
        if geometry is None or type(geometry).__name__ != "LineString":
            continue
        span = getattr(placemark, "times", None)
        begin = getattr(getattr(span, "begin", None), "dt", None)
        end = getattr(getattr(span, "end", None), "dt", None)
        if not isinstance(begin, dt.datetime) or not isinstance(end, dt.datetime):
            raise TrackFormatError(
                "file",
                "the KML LineString has no times (no TimeSpan); tillpath needs a timed track: "
                "a gx:Track, or a LineString in a Placemark with a TimeSpan",
            )
        return _spread_in_time(list(geometry.geometry.coords), begin, end), {
            "track": placemark.name or "LineString",
            "kind": "LineString",
            "times_interpolated": True,
        }
    raise TrackFormatError("file", "the KML holds no track (no gx:Track and no LineString)")


def _placemarks(container: Any) -> Any:
    for feature in getattr(container, "features", None) or []:
        if type(feature).__name__ == "Placemark":
            yield feature
        else:
            yield from _placemarks(feature)


def _tracks_of(geometry: Any) -> list[Any]:
    kind = type(geometry).__name__
    if kind == "Track":
        return [geometry]
    if kind == "MultiTrack":
        return list(getattr(geometry, "tracks", []) or [])
    return []


def _spread_in_time(
    coords: list[tuple[float, ...]], begin: dt.datetime, end: dt.datetime
) -> list[TrackFix]:
    """Time an untimed line from ``begin`` to ``end`` in proportion to distance."""
    from pyproj import Geod

    lons = [c[0] for c in coords]
    lats = [c[1] for c in coords]
    steps = Geod(ellps="WGS84").inv(lons[:-1], lats[:-1], lons[1:], lats[1:])[2]
    cumulative = [0.0]
    for step in steps:
        cumulative.append(cumulative[-1] + float(step))
    total = cumulative[-1] or 1.0
    t0, t1 = datetime_to_us(begin), datetime_to_us(end)
    fixes = []
    for lon, lat, distance in zip(lons, lats, cumulative, strict=True):
        check_position(lat, lon, input_name="file: LineString coordinate")
        fixes.append(TrackFix(t=t0 + round((t1 - t0) * distance / total), lat=lat, lon=lon))
    return fixes


__all__ = ["EXTRA_TRACK_FORMATS", "detect_extra_format", "gps_to_utc", "read_extra_format"]
