"""Read a tractor's recorded track: GPX, CSV or an NMEA 0183 log (product.md §8).

Pure: the uploaded bytes in, a :class:`ParsedTrack` out (fixes sorted by time, one per
timestamp), or a :class:`TrackFormatError` naming the problem. No database, no HTTP. gpsbabel
unicsv, RTKLIB .pos, u-blox UBX and KML tracks are read by :mod:`app.track_formats`.

Formats
-------
- **GPX 1.0/1.1**: the first ``<trk>`` that has timed points (all its segments); points without
  a time are dropped and counted. The XML is checked with defusedxml first: a DTD, entity
  declarations (the "billion laughs" bomb) or external references are refused before gpxpy
  parses anything.
- **CSV**: a header naming ``time``, ``lat``, ``lon`` and optionally ``heading_deg`` and
  ``speed_mps`` (``heading`` and ``speed`` are accepted too), in any order. Times are ISO 8601
  (``2026-11-22T03:14:15.2Z``; without an offset, UTC) or Unix epoch seconds. A row that cannot
  be read refuses the whole file, naming its line.
- **NMEA 0183** as a u-blox receiver logs it (``$GNGGA``/``$GPGGA``, ``$GNRMC``/``$GPRMC`` among
  GSV, GSA, VTG, TXT …): every sentence must carry a correct checksum; a sentence that does not,
  or cannot be parsed, is skipped and counted. Fixes with GGA quality 0 or RMC status ``V``
  (no fix) are dropped and counted. GGA has no date: the date comes from the last RMC before it
  (for fixes before the first RMC, counted back from that one), and a time of day that falls
  back by more than 12 h means midnight passed.

Timestamps are integers, microseconds since the Unix epoch (UTC): equal times written
differently (``…T00:00:01.500Z`` and ``1767225601.5``) become the same fix.
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from typing import Any, Final

import gpxpy
import gpxpy.gpx
import pynmea2

from planner.errors import UnreadableFileError
from planner.io.safety import check_xml

#: The formats :func:`parse_track` reads.
TRACK_FORMATS: Final = ("gpx", "csv", "nmea")

#: Earliest and latest times accepted: the GPS epoch (1980-01-06) to 2100 [µs since 1970].
MIN_TIME_US: Final = 315_964_800 * 1_000_000
MAX_TIME_US: Final = 4_102_444_800 * 1_000_000

_EPOCH: Final = dt.datetime(1970, 1, 1, tzinfo=dt.UTC)
_MICROSECOND: Final = dt.timedelta(microseconds=1)
#: m/s per knot (NMEA speeds are in knots).
MPS_PER_KNOT: Final = 1852.0 / 3600.0
_NMEA_LINE = re.compile(r"^\$[A-Z]{2}[A-Z0-9]{3},")

_CSV_COLUMNS: Final[dict[str, str]] = {
    "time": "time",
    "timestamp": "time",
    "t": "time",
    "lat": "lat",
    "latitude": "lat",
    "lon": "lon",
    "lng": "lon",
    "longitude": "lon",
    "heading_deg": "heading_deg",
    "heading": "heading_deg",
    "course": "heading_deg",
    "speed_mps": "speed_mps",
    "speed": "speed_mps",
}


#: Fix qualities a track may carry (NMEA GGA 4 = rtk_fixed, 5 = rtk_float, 2 = dgps, 1 = single,
#: 6 = dead_reckoning; RTKLIB Q 1/2/4/5 and u-blox carrier solutions map to the same names).
FIX_QUALITIES = ("rtk_fixed", "rtk_float", "dgps", "single", "dead_reckoning")
#: GGA fix quality -> FIX_QUALITIES (3 PPS and 7/8 manual/simulated carry no quality).
_GGA_QUALITIES: Final = {
    1: "single",
    2: "dgps",
    4: "rtk_fixed",
    5: "rtk_float",
    6: "dead_reckoning",
}
#: GPX 1.1 ``<fix>`` values (none, 2d, 3d, dgps, pps) mapped where they say something.
GPX_FIXES: Final[dict[str, str]] = {"2d": "single", "3d": "single", "dgps": "dgps"}


class TrackFormatError(ValueError):
    """A track file (or a posted fix) that cannot be read; the message names what and where.

    Parameters
    ----------
    input_name : str
        The input at fault (``file``, ``fixes[3].t`` …).
    problem : str
        What is wrong with it.
    """

    def __init__(self, input_name: str, problem: str) -> None:
        super().__init__(f"{input_name}: {problem}")
        self.input_name = input_name
        self.problem = problem


@dataclass(frozen=True, slots=True)
class TrackFix:
    """One position with its time.

    Attributes
    ----------
    t : int
        Time [µs since 1970-01-01T00:00:00Z].
    lat, lon : float
        WGS84 [deg].
    heading_deg : float or None
        Course or heading, clockwise from true north [deg].
    speed_mps : float or None
        Speed over ground [m/s].
    quality : str or None
        Fix quality where the format says it: one of :data:`FIX_QUALITIES` (``rtk_fixed``,
        ``rtk_float``, ``dgps``, ``single``, ``dead_reckoning``), else None.
    hdop : float or None
        Horizontal dilution of precision, where the format has it.
    satellites : int or None
        Satellites used in the fix, where the format has it.
    """

    t: int
    lat: float
    lon: float
    heading_deg: float | None = None
    speed_mps: float | None = None
    quality: str | None = None
    hdop: float | None = None
    satellites: int | None = None


@dataclass(frozen=True, slots=True)
class ParsedTrack:
    """A track file's fixes, sorted by time with one fix per timestamp.

    Attributes
    ----------
    format : str
        ``gpx``, ``csv`` or ``nmea``.
    fixes : list of TrackFix
    report : dict
        What was kept and dropped: ``fixes``, ``duplicate_times`` and, per format,
        ``untimed_points`` (GPX), ``bad_sentences``, ``no_fix`` (NMEA).
    """

    format: str
    fixes: list[TrackFix]
    report: dict[str, Any] = field(default_factory=dict)


# --- times and positions -------------------------------------------------------------------


def datetime_to_us(value: dt.datetime) -> int:
    """Return ``value`` as µs since the Unix epoch; a naive datetime is taken as UTC.

    Examples
    --------
    >>> datetime_to_us(dt.datetime(2026, 1, 1, 0, 0, 1, 500000, tzinfo=dt.UTC))
    1767225601500000
    """
    if value.tzinfo is None:
        value = value.replace(tzinfo=dt.UTC)
    return (value - _EPOCH) // _MICROSECOND


def us_to_datetime(t: int) -> dt.datetime:
    """Return µs since the Unix epoch as an aware UTC datetime."""
    return _EPOCH + dt.timedelta(microseconds=t)


#: Longest text read as a time [characters] (ISO 8601 with nanoseconds and an offset is 35).
MAX_TIME_TEXT_LENGTH = 64
#: Epoch seconds of 1980–2100 have 10 digits before the point: ``Decimal.adjusted()`` ≤ 9.
MAX_EPOCH_DIGITS = 9


def parse_time(value: object, *, input_name: str) -> int:
    """Read a time: ISO 8601 text or Unix epoch seconds (number or numeric text).

    Parameters
    ----------
    value : str, int or float
        ``2026-11-22T03:14:15.2Z``, ``2026-11-22 03:14:15`` (UTC), ``1795318455.2`` …
    input_name : str
        Named in the error.

    Returns
    -------
    int
        µs since the Unix epoch.

    Raises
    ------
    TrackFormatError
        If it is neither, or lies outside 1980–2100.

    Examples
    --------
    >>> parse_time("2026-01-01T00:00:01.5Z", input_name="t")
    1767225601500000
    >>> parse_time(1767225601.5, input_name="t")
    1767225601500000
    """
    if isinstance(value, bool) or value is None:
        raise TrackFormatError(input_name, "must be an ISO 8601 time or Unix epoch seconds")
    if isinstance(value, (int, float)):
        if not math.isfinite(value):
            raise TrackFormatError(input_name, "must be a finite number of seconds")
        t = _epoch_us(Decimal(repr(value)), input_name)
    elif isinstance(value, str):
        text = value.strip()
        if len(text) > MAX_TIME_TEXT_LENGTH:
            raise TrackFormatError(
                input_name,
                f"is {len(text)} characters long; a time has at most {MAX_TIME_TEXT_LENGTH}",
            )
        number: Decimal | None
        try:
            number = Decimal(text)
        except InvalidOperation:
            number = None
        if number is None:
            try:
                t = datetime_to_us(dt.datetime.fromisoformat(text))
            except ValueError:
                raise TrackFormatError(
                    input_name,
                    f"{text[:40]!r} is neither an ISO 8601 time nor Unix epoch seconds",
                ) from None
        else:
            t = _epoch_us(number, input_name)
    else:
        raise TrackFormatError(input_name, "must be an ISO 8601 time or Unix epoch seconds")
    if not MIN_TIME_US <= t <= MAX_TIME_US:
        raise TrackFormatError(input_name, "must lie between 1980 and 2100")
    return t


def _epoch_us(seconds: Decimal, input_name: str) -> int:
    """Return epoch ``seconds`` in µs, refusing what lies far outside 1980–2100 at once.

    The exponent is looked at before the number becomes an integer, which costs time in
    proportion to its digits (``1e999990`` has a million of them).
    """
    if not seconds.is_finite():
        raise TrackFormatError(input_name, "must be a finite number of seconds")
    if seconds and seconds.adjusted() > MAX_EPOCH_DIGITS:
        raise TrackFormatError(input_name, "must lie between 1980 and 2100")
    return int(round(seconds * 1_000_000))


def check_position(lat: float, lon: float, *, input_name: str) -> None:
    """Raise :class:`TrackFormatError` unless ``lat``/``lon`` are finite WGS84 degrees."""
    if not (math.isfinite(lat) and -90.0 <= lat <= 90.0):
        raise TrackFormatError(input_name, f"lat must be between -90 and 90, got {lat}")
    if not (math.isfinite(lon) and -180.0 <= lon <= 180.0):
        raise TrackFormatError(input_name, f"lon must be between -180 and 180, got {lon}")


def _optional_float(value: float | str | None, *, input_name: str) -> float | None:
    if value is None or value == "":
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise TrackFormatError(input_name, f"{str(value)[:40]!r} is not a number") from None
    if not math.isfinite(number):
        raise TrackFormatError(input_name, "must be a finite number")
    return number


def sort_fixes(fixes: Iterable[TrackFix]) -> tuple[list[TrackFix], int]:
    """Sort by time, keeping the first fix of each timestamp; return them and how many fell.

    Examples
    --------
    >>> fixes, dropped = sort_fixes([TrackFix(2, 0, 0), TrackFix(1, 0, 0), TrackFix(2, 1, 1)])
    >>> [(f.t, f.lat) for f in fixes], dropped
    ([(1, 0), (2, 0)], 1)
    """
    ordered = sorted(fixes, key=lambda f: f.t)  # stable: the first of equal times stays first
    kept: list[TrackFix] = []
    for fix in ordered:
        if not kept or fix.t != kept[-1].t:
            kept.append(fix)
    return kept, len(ordered) - len(kept)


# --- detection -------------------------------------------------------------------------------


def detect_format(text: str) -> str | None:
    """Tell ``gpx``, ``nmea`` or ``csv`` from the file's first lines; None if none fits.

    Examples
    --------
    >>> detect_format('<?xml version="1.0"?><gpx/>'), detect_format("time,lat,lon")
    ('gpx', 'csv')
    >>> detect_format("$GNGGA,1,2*00"), detect_format("hello")
    ('nmea', None)
    """
    head = text.lstrip("\ufeff \t\r\n")
    if head.startswith("<"):
        return "gpx"
    lines = [line.strip() for line in head.splitlines()[:50] if line.strip()]
    if any(_NMEA_LINE.match(line) for line in lines):
        return "nmea"
    if lines:
        names = {name.strip().lower() for name in lines[0].split(",")}
        mapped = {_CSV_COLUMNS.get(name) for name in names}
        if {"lat", "lon"} <= mapped or ("," in lines[0] and "time" in mapped):
            return "csv"
    return None


def parse_track(data: bytes) -> ParsedTrack:
    """Read a GPX, CSV or NMEA track file (the format is detected from its content).

    Parameters
    ----------
    data : bytes
        The file as uploaded.

    Returns
    -------
    ParsedTrack
        At least one fix.

    Raises
    ------
    TrackFormatError
        For an unknown format, a malformed file, XML with a DTD or entities, or a file with no
        usable fix.
    """
    from app.track_formats import EXTRA_TRACK_FORMATS, detect_extra_format, read_extra_format

    text = data.decode("utf-8", errors="replace")
    fmt = detect_extra_format(data) or detect_format(text)
    if fmt in EXTRA_TRACK_FORMATS:
        fixes, report = read_extra_format(fmt, data)
    elif fmt == "gpx":
        fixes, report = _read_gpx(data)
    elif fmt == "nmea":
        fixes, report = _read_nmea(text)
    elif fmt == "csv":
        fixes, report = _read_csv(text)
    else:
        raise TrackFormatError(
            "file",
            "is not a track file tillpath can read: expected GPX, KML, CSV with a "
            "time,lat,lon header, gpsbabel unicsv, RTKLIB .pos, u-blox UBX or an NMEA 0183 log",
        )
    fixes, duplicates = sort_fixes(fixes)
    if not fixes:
        details = ", ".join(f"{k.replace('_', ' ')}: {v}" for k, v in report.items() if v)
        raise TrackFormatError(
            "file", f"has no usable fix ({fmt.upper()}{'; ' + details if details else ''})"
        )
    return ParsedTrack(
        format=fmt,
        fixes=fixes,
        report={"format": fmt, "fixes": len(fixes), "duplicate_times": duplicates, **report},
    )


# --- GPX ---------------------------------------------------------------------------------------


def _read_gpx(data: bytes) -> tuple[list[TrackFix], dict[str, Any]]:
    try:
        check_xml(data, filename="file", kind="GPX")  # the one XML safety check (planner.io)
    except UnreadableFileError as exc:
        raise TrackFormatError("file", exc.problem) from None
    try:
        gpx = gpxpy.parse(data.decode("utf-8", errors="replace"))
    except (gpxpy.gpx.GPXException, ValueError) as exc:
        raise TrackFormatError("file", f"is not a valid GPX file ({exc})") from None

    untimed = 0
    for index, track in enumerate(gpx.tracks):
        fixes: list[TrackFix] = []
        untimed = 0
        for segment in track.segments:
            for point in segment.points:
                if point.time is None:
                    untimed += 1
                    continue
                lat, lon = float(point.latitude), float(point.longitude)
                check_position(lat, lon, input_name=f"file: track {index + 1}")
                fixes.append(
                    TrackFix(
                        t=_checked_time(datetime_to_us(point.time), "file: GPX point time"),
                        lat=lat,
                        lon=lon,
                        heading_deg=_finite_or_none(point.course),
                        speed_mps=_finite_or_none(point.speed),
                        quality=GPX_FIXES.get(str(point.type_of_gpx_fix or "").lower()),
                        hdop=_finite_or_none(_float_or_none(point.horizontal_dilution)),
                        satellites=_int_or_none(point.satellites),
                    )
                )
        if fixes:
            return fixes, {
                "track": track.name or f"track {index + 1}",
                "tracks_ignored": len(gpx.tracks) - 1,
                "untimed_points": untimed,
            }
    return [], {"tracks": len(gpx.tracks), "untimed_points": untimed}


def _float_or_none(value: object) -> float | None:
    try:
        return None if value in (None, "") else float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None


def _int_or_none(value: object) -> int | None:
    number = _float_or_none(value)
    return int(number) if number is not None and number >= 0 else None


def _finite_or_none(value: float | None) -> float | None:
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _checked_time(t: int, input_name: str) -> int:
    if not MIN_TIME_US <= t <= MAX_TIME_US:
        raise TrackFormatError(input_name, "must lie between 1980 and 2100")
    return t


# --- CSV ---------------------------------------------------------------------------------------


def _read_csv(text: str) -> tuple[list[TrackFix], dict[str, Any]]:
    reader = csv.reader(io.StringIO(text.lstrip("\ufeff")))
    try:
        header = next(reader)
    except StopIteration:
        raise TrackFormatError("file", "the CSV file is empty") from None
    except csv.Error as exc:
        raise TrackFormatError("file", f"line 1: {exc}") from None
    columns: dict[str, int] = {}
    for i, name in enumerate(header):
        key = _CSV_COLUMNS.get(name.strip().lower())
        if key is not None and key not in columns:
            columns[key] = i
    missing = [name for name in ("time", "lat", "lon") if name not in columns]
    if missing:
        raise TrackFormatError(
            "file",
            f"the CSV header must name time, lat and lon (optional: heading_deg, speed_mps); "
            f"missing: {', '.join(missing)}",
        )
    width = max(columns.values()) + 1
    fixes: list[TrackFix] = []
    try:
        for row in reader:
            line = reader.line_num
            if not row or all(not cell.strip() for cell in row):
                continue
            where = f"file: line {line}"
            if len(row) < width:
                raise TrackFormatError(
                    where, f"has {len(row)} fields, the header needs at least {width}"
                )
            lat = _optional_float(row[columns["lat"]], input_name=f"{where}: lat")
            lon = _optional_float(row[columns["lon"]], input_name=f"{where}: lon")
            if lat is None or lon is None:
                raise TrackFormatError(where, "lat and lon are required")
            check_position(lat, lon, input_name=where)
            heading = speed = None
            if "heading_deg" in columns and columns["heading_deg"] < len(row):
                heading = _optional_float(
                    row[columns["heading_deg"]], input_name=f"{where}: heading_deg"
                )
            if "speed_mps" in columns and columns["speed_mps"] < len(row):
                speed = _optional_float(row[columns["speed_mps"]], input_name=f"{where}: speed_mps")
            fixes.append(
                TrackFix(
                    t=parse_time(row[columns["time"]], input_name=f"{where}: time"),
                    lat=lat,
                    lon=lon,
                    heading_deg=heading,
                    speed_mps=speed,
                )
            )
    except csv.Error as exc:
        raise TrackFormatError(f"file: line {reader.line_num}", str(exc)) from None
    return fixes, {}


# --- NMEA 0183 -------------------------------------------------------------------------------


@dataclass(slots=True)
class _Epoch:
    """What the GGA and RMC sentences of one time of day said."""

    seconds: float  # time of day [s]
    date: dt.date | None = None
    lat: float | None = None
    lon: float | None = None
    heading_deg: float | None = None
    speed_mps: float | None = None
    no_fix: bool = False
    quality: str | None = None
    hdop: float | None = None
    satellites: int | None = None


def _time_of_day_s(value: dt.time) -> float:
    return value.hour * 3600 + value.minute * 60 + value.second + value.microsecond * 1e-6


def _nmea_position(msg: Any) -> tuple[float, float] | None:
    if not (msg.lat and msg.lon and msg.lat_dir and msg.lon_dir):
        return None
    return float(msg.latitude), float(msg.longitude)


def _read_nmea(text: str) -> tuple[list[TrackFix], dict[str, Any]]:
    bad = 0
    no_fix = 0
    sentences: list[tuple[str, Any]] = []
    for raw in text.splitlines():
        line = raw.strip()
        if not line:
            continue
        start = line.find("$")
        if start < 0 or not _NMEA_LINE.match(line[start:]):
            bad += 1
            continue
        try:
            msg = pynmea2.parse(line[start:], check=True)
        except (pynmea2.ParseError, ValueError, AttributeError, TypeError, IndexError):
            bad += 1
            continue
        kind = line[start + 3 : start + 6]
        if kind in ("GGA", "RMC"):
            sentences.append((kind, msg))

    # One epoch per time of day, in log order; consecutive sentences with the same time merge.
    epochs: list[_Epoch] = []
    for kind, msg in sentences:
        try:
            stamp = msg.timestamp
            position = _nmea_position(msg)
            if kind == "GGA":
                quality = int(msg.gps_qual or 0)
                hdop = _finite_or_none(float(msg.horizontal_dil)) if msg.horizontal_dil else None
                sats = int(msg.num_sats) if msg.num_sats else None
            else:
                status = msg.status
                date = msg.datestamp
        except (ValueError, TypeError, AttributeError, IndexError):
            bad += 1
            continue
        if not isinstance(stamp, dt.time):
            bad += 1
            continue
        seconds = _time_of_day_s(stamp)
        if not epochs or abs(epochs[-1].seconds - seconds) > 1e-6:
            epochs.append(_Epoch(seconds=seconds))
        epoch = epochs[-1]
        if kind == "GGA":
            if quality == 0 or position is None:
                epoch.no_fix = True
            elif epoch.lat is None:
                epoch.lat, epoch.lon = position
            epoch.quality, epoch.hdop, epoch.satellites = _GGA_QUALITIES.get(quality), hdop, sats
        else:
            if isinstance(date, dt.date):
                epoch.date = date
            if status != "A" or position is None:
                epoch.no_fix = True
                continue
            if epoch.lat is None:
                epoch.lat, epoch.lon = position
            epoch.heading_deg = _finite_or_none(msg.true_course)
            knots = _finite_or_none(msg.spd_over_grnd)
            epoch.speed_mps = None if knots is None else knots * MPS_PER_KNOT

    dates = [e.date for e in epochs if e.date is not None]
    report = {"bad_sentences": bad, "no_fix": 0, "sentences": len(sentences)}
    if not dates:
        if any(e.lat is not None for e in epochs):
            raise TrackFormatError(
                "file",
                "the NMEA log has no RMC sentence with a date, so its GGA fixes cannot be "
                "placed in time; log RMC too (u-blox receivers do by default)",
            )
        report["no_fix"] = sum(1 for e in epochs if e.no_fix)
        return [], report

    # Each epoch's day: the date of the last RMC, moved on by a day where the time of day falls
    # back by more than 12 h (midnight passed); before the first RMC, counted back from it.
    first = next(i for i, e in enumerate(epochs) if e.date is not None)
    days: list[dt.date] = [dates[0]] * len(epochs)
    for i in range(first - 1, -1, -1):
        later = epochs[i + 1].seconds
        days[i] = days[i + 1] - dt.timedelta(days=1 if epochs[i].seconds > later + 43_200 else 0)
    for i in range(first + 1, len(epochs)):
        epoch = epochs[i]
        if epoch.date is not None:
            days[i] = epoch.date
        else:
            passed = epoch.seconds < epochs[i - 1].seconds - 43_200
            days[i] = days[i - 1] + dt.timedelta(days=1 if passed else 0)

    fixes: list[TrackFix] = []
    for epoch, day in zip(epochs, days, strict=True):
        if epoch.no_fix or epoch.lat is None or epoch.lon is None:
            no_fix += 1
            continue
        check_position(epoch.lat, epoch.lon, input_name="file: NMEA position")
        midnight = datetime_to_us(dt.datetime.combine(day, dt.time(0, 0), tzinfo=dt.UTC))
        fixes.append(
            TrackFix(
                t=_checked_time(midnight + round(epoch.seconds * 1e6), "file: NMEA time"),
                lat=epoch.lat,
                lon=epoch.lon,
                heading_deg=epoch.heading_deg,
                speed_mps=epoch.speed_mps,
                quality=epoch.quality,
                hdop=epoch.hdop,
                satellites=epoch.satellites,
            )
        )
    report["no_fix"] = no_fix
    return fixes, report
