"""Read a tractor's recorded track: GPX, CSV or an NMEA 0183 log (product.md §8).

Pure: the uploaded bytes in, a :class:`ParsedTrack` out (fixes sorted by time, one per
timestamp), or a :class:`TrackFormatError` naming the problem. No database, no HTTP. gpsbabel
unicsv, RTKLIB .pos, u-blox UBX and KML tracks are read by :mod:`app.track_formats`.

Formats
-------
- **GPX 1.0/1.1**: the first ``<trk>`` that has timed points (all its segments); points without
  a time are dropped and counted. The XML is read incrementally by defusedxml's ``iterparse``
  (expat), one point at a time: a DTD, entity declarations (the "billion laughs" bomb) or
  external references are refused as soon as they appear.
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

Every reader streams (:func:`read_track`): memory holds a line or a point, never the file.

Timestamps are integers, microseconds since the Unix epoch (UTC): equal times written
differently (``…T00:00:01.500Z`` and ``1767225601.5``) become the same fix.
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import math
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from typing import Any, BinaryIO, Final

import defusedxml.ElementTree
import pynmea2
from defusedxml import DefusedXmlException

#: The formats :func:`parse_track` reads.
TRACK_FORMATS: Final = ("gpx", "csv", "nmea")

#: Earliest and latest times accepted: the GPS epoch (1980-01-06) to 2100 [µs since 1970].
MIN_TIME_US: Final = 315_964_800 * 1_000_000
MAX_TIME_US: Final = 4_102_444_800 * 1_000_000

#: Bounds of a fix's heading [deg] and speed [m/s] (360 km/h: no tractor, nor a GPS glitch
#: worth storing, goes faster).
MAX_HEADING_DEG: Final = 360.0
MAX_SPEED_MPS: Final = 100.0

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
#: The same, under the name the schemas and the readers use.
MAX_TIME_TEXT: Final = MAX_TIME_TEXT_LENGTH
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


def check_text(value: str, *, input_name: str | None = None) -> str:
    """Refuse text with a NUL or another control character (tab excepted); return it.

    Raises
    ------
    ValueError
        ``must not contain control characters such as NUL``; a :class:`TrackFormatError`
        naming ``input_name`` if given.

    Examples
    --------
    >>> check_text("Sawah 3")
    'Sawah 3'
    """
    if any(ord(c) < 32 and c != "\t" or ord(c) == 127 for c in value):
        problem = "must not contain control characters such as NUL"
        if input_name is not None:
            raise TrackFormatError(input_name, problem)
        raise ValueError(problem)
    return value


def check_motion(heading_deg: float | None, speed_mps: float | None, *, input_name: str) -> None:
    """Raise :class:`TrackFormatError` unless heading and speed (where given) are in range.

    Heading within ±:data:`MAX_HEADING_DEG`, speed within 0–:data:`MAX_SPEED_MPS`.
    """
    if heading_deg is not None and not abs(heading_deg) <= MAX_HEADING_DEG:
        raise TrackFormatError(
            input_name, f"heading_deg must be between -360 and 360, got {heading_deg}"
        )
    if speed_mps is not None and not 0.0 <= speed_mps <= MAX_SPEED_MPS:
        raise TrackFormatError(input_name, f"speed_mps must be between 0 and 100, got {speed_mps}")


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
    stream = read_track(io.BytesIO(data))
    fixes, duplicates = sort_fixes(stream.fixes)
    return stream.parsed(fixes, duplicates)


@dataclass(slots=True)
class TrackStream:
    """A track file being read: its format, its fixes as they are read, and the report.

    Attributes
    ----------
    format : str
        ``gpx``, ``csv`` or ``nmea``.
    fixes : iterator of TrackFix
        In file order; consuming it may raise :class:`TrackFormatError`.
    report : dict
        Filled in while ``fixes`` is consumed (see :class:`ParsedTrack`).
    """

    format: str
    fixes: Iterator[TrackFix]
    report: dict[str, Any]

    def parsed(self, fixes: list[TrackFix], duplicates: int) -> ParsedTrack:
        """Wrap the sorted, de-duplicated ``fixes`` as a :class:`ParsedTrack`."""
        check_not_empty(self.format, len(fixes), self.report)
        return ParsedTrack(
            format=self.format, fixes=fixes, report=self.summary(len(fixes), duplicates)
        )

    def summary(self, count: int, duplicates: int) -> dict[str, Any]:
        """Return the import report: ``count`` fixes kept, ``duplicates`` dropped."""
        return {"format": self.format, "fixes": count, "duplicate_times": duplicates, **self.report}


#: Bytes read ahead to tell the format.
_HEAD_BYTES: Final = 64 * 1024


def read_track(stream: BinaryIO) -> TrackStream:
    """Start reading a track file from a seekable binary stream, one line or element at a time.

    Memory stays bounded whatever the file's size: CSV and NMEA are read line by line, GPX
    with an incremental XML parser (defusedxml, no DTD or entities) that drops each point once
    read. Nothing is sorted here (see :func:`sort_fixes`).

    Parameters
    ----------
    stream : binary file
        Positioned at the start; must be seekable (the head is read twice).

    Returns
    -------
    TrackStream

    Raises
    ------
    TrackFormatError
        If the format is none of GPX, CSV and NMEA (the fixes raise it for a malformed file).
    """
    from app.track_formats import EXTRA_TRACK_FORMATS, detect_extra_format, read_extra_format

    head_bytes = stream.read(_HEAD_BYTES)
    stream.seek(0)
    fmt = detect_extra_format(head_bytes) or detect_format(
        head_bytes.decode("utf-8", errors="replace")
    )
    report: dict[str, Any] = {}
    if fmt in EXTRA_TRACK_FORMATS:  # read whole (within the upload limit), as before
        fixes, extra_report = read_extra_format(fmt, stream.read())
        return TrackStream(fmt, iter(fixes), extra_report)
    if fmt == "gpx":
        return TrackStream(fmt, _read_gpx(stream, report), report)
    if fmt in ("nmea", "csv"):
        text = io.TextIOWrapper(stream, encoding="utf-8-sig", errors="replace", newline="")
        reader = _read_nmea if fmt == "nmea" else _read_csv
        return TrackStream(fmt, reader(text, report), report)
    raise TrackFormatError(
        "file",
        "is not a track file tillpath can read: expected GPX, KML, CSV with a "
        "time,lat,lon header, gpsbabel unicsv, RTKLIB .pos, u-blox UBX or an NMEA 0183 log",
    )


def check_not_empty(fmt: str, count: int, report: dict[str, Any]) -> None:
    """Raise ``file: has no usable fix (…)`` if a file of format ``fmt`` gave no fix."""
    if count:
        return
    details = ", ".join(f"{k.replace('_', ' ')}: {v}" for k, v in report.items() if v)
    raise TrackFormatError(
        "file", f"has no usable fix ({fmt.upper()}{'; ' + details if details else ''})"
    )


# --- GPX ---------------------------------------------------------------------------------------


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _read_gpx(stream: BinaryIO, report: dict[str, Any]) -> Iterator[TrackFix]:
    """Yield the timed points of the first ``<trk>`` that has any, reading incrementally.

    Each ``<trkpt>``, ``<rtept>`` and ``<wpt>`` is removed from the tree once read, so memory
    holds one point at a time. The rest of the file is still parsed (to count the tracks and
    to refuse a file that is not well-formed).
    """
    try:
        events = defusedxml.ElementTree.iterparse(
            stream,
            events=("start", "end"),
            forbid_dtd=True,
            forbid_entities=True,
            forbid_external=True,
        )
        stack: list[Any] = []
        tracks = 0
        chosen = False  # a track with timed points has been read
        untimed = 0
        track_name: str | None = None
        yielded = 0
        for event, elem in events:
            name = _local(elem.tag)
            if event == "start":
                if not stack and name != "gpx":
                    raise TrackFormatError(
                        "file", f"is not a valid GPX file (its root element is <{name}>)"
                    )
                stack.append(elem)
                if name == "trk":
                    tracks += 1
                    if not chosen:
                        untimed, track_name, yielded = 0, None, 0
                continue
            stack.pop()
            parent = _local(stack[-1].tag) if stack else ""
            if name == "name" and parent == "trk" and not chosen and tracks:
                track_name = (elem.text or "").strip() or None
            elif name == "trkpt" and not chosen:
                fix = _gpx_point(elem, tracks)
                if fix is None:
                    untimed += 1
                else:
                    yielded += 1
                    yield fix
            elif name == "trk" and yielded and not chosen:
                chosen = True
                report.update(
                    track=track_name or f"track {tracks}", tracks_ignored=0, untimed_points=untimed
                )
            if name in ("trkpt", "rtept", "wpt") and stack:
                stack[-1].remove(elem)
    except DefusedXmlException:
        raise TrackFormatError(
            "file", "GPX with a DTD, entity declarations or external references is refused"
        ) from None
    except TrackFormatError:
        raise
    except Exception as exc:  # ParseError: not well-formed (truncated, …)
        raise TrackFormatError("file", f"is not well-formed XML ({exc})") from None
    if chosen:
        report["tracks_ignored"] = tracks - 1
    else:
        report.update(tracks=tracks, untimed_points=untimed)


def _gpx_point(elem: Any, track: int) -> TrackFix | None:
    where = f"file: track {track}"
    lat = _optional_float(elem.get("lat"), input_name=f"{where}: lat")
    lon = _optional_float(elem.get("lon"), input_name=f"{where}: lon")
    if lat is None or lon is None:
        raise TrackFormatError(where, "a <trkpt> needs lat and lon")
    check_position(lat, lon, input_name=where)
    values: dict[str, str] = {}
    for child in elem:
        values.setdefault(_local(child.tag), (child.text or "").strip())
    if not values.get("time"):
        return None
    try:
        when = dt.datetime.fromisoformat(values["time"][:MAX_TIME_TEXT])
    except ValueError:
        raise TrackFormatError(
            f"{where}: time", f"{values['time'][:40]!r} is not an ISO 8601 time"
        ) from None
    heading = _finite_or_none(_optional_float(values.get("course"), input_name=f"{where}: course"))
    speed = _finite_or_none(_optional_float(values.get("speed"), input_name=f"{where}: speed"))
    check_motion(heading, speed, input_name=where)
    hdop = _optional_float(values.get("hdop"), input_name=f"{where}: hdop")
    sat = _optional_float(values.get("sat"), input_name=f"{where}: sat")
    return TrackFix(
        t=_checked_time(datetime_to_us(when), "file: GPX point time"),
        lat=lat,
        lon=lon,
        heading_deg=heading,
        speed_mps=speed,
        quality=GPX_FIXES.get(values.get("fix", "").lower()),
        hdop=hdop if hdop is not None and 0 <= hdop <= 1000 else None,
        satellites=int(sat) if sat is not None and 0 <= sat <= 1000 else None,
    )


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


def _read_csv(lines: Iterable[str], report: dict[str, Any]) -> Iterator[TrackFix]:
    reader = csv.reader(lines)
    try:
        header = next(reader)
    except StopIteration:
        raise TrackFormatError("file", "the CSV file is empty") from None
    except csv.Error as exc:
        raise TrackFormatError("file", f"line 1: {exc}") from None
    columns: dict[str, int] = {}
    for i, name in enumerate(header):
        key = _CSV_COLUMNS.get(name.strip().lstrip("\ufeff").lower())
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
            check_motion(heading, speed, input_name=where)
            yield TrackFix(
                t=parse_time(row[columns["time"]], input_name=f"{where}: time"),
                lat=lat,
                lon=lon,
                heading_deg=heading,
                speed_mps=speed,
            )
    except csv.Error as exc:
        raise TrackFormatError(f"file: line {reader.line_num}", str(exc)) from None


# --- NMEA 0183 -------------------------------------------------------------------------------

#: Epochs held while waiting for the first RMC date (about 3 h at 10 Hz); then the log is
#: refused, so that a log without dates cannot hold the whole file in memory.
_MAX_UNDATED_EPOCHS: Final = 100_000


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


def _nmea_sentences(lines: Iterable[str], report: dict[str, Any]) -> Iterator[tuple[str, Any]]:
    """Yield ``(kind, message)`` of the GGA and RMC sentences; count the unreadable ones."""
    for raw in lines:
        line = raw.strip()
        if not line:
            continue
        start = line.find("$")
        if start < 0 or not _NMEA_LINE.match(line[start:]):
            report["bad_sentences"] += 1
            continue
        try:
            msg = pynmea2.parse(line[start:], check=True)
        except (pynmea2.ParseError, ValueError, AttributeError, TypeError, IndexError):
            report["bad_sentences"] += 1
            continue
        kind = line[start + 3 : start + 6]
        if kind in ("GGA", "RMC"):
            report["sentences"] += 1
            yield kind, msg


def _nmea_epochs(lines: Iterable[str], report: dict[str, Any]) -> Iterator[_Epoch]:
    """Yield one epoch per time of day, in log order, once its sentences are all read."""
    epoch: _Epoch | None = None
    for kind, msg in _nmea_sentences(lines, report):
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
            report["bad_sentences"] += 1
            continue
        if not isinstance(stamp, dt.time):
            report["bad_sentences"] += 1
            continue
        seconds = _time_of_day_s(stamp)
        if epoch is None or abs(epoch.seconds - seconds) > 1e-6:
            if epoch is not None:
                yield epoch
            epoch = _Epoch(seconds=seconds)
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
            heading = _finite_or_none(msg.true_course)
            knots = _finite_or_none(msg.spd_over_grnd)
            speed = None if knots is None else knots * MPS_PER_KNOT
            # A value out of range is dropped (as an unreadable sentence would be).
            epoch.heading_deg = (
                heading if heading is None or abs(heading) <= MAX_HEADING_DEG else None
            )
            epoch.speed_mps = speed if speed is None or 0 <= speed <= MAX_SPEED_MPS else None
    if epoch is not None:
        yield epoch


def _read_nmea(lines: Iterable[str], report: dict[str, Any]) -> Iterator[TrackFix]:
    """Yield the NMEA log's fixes, dating each epoch as it streams by.

    Each epoch's day is the date of the last RMC, moved on by a day where the time of day
    falls back by more than 12 h (midnight passed); the epochs before the first RMC are held
    and counted back from it.
    """
    report.update(bad_sentences=0, no_fix=0, sentences=0)
    undated: list[_Epoch] = []
    previous: tuple[_Epoch, dt.date] | None = None
    for epoch in _nmea_epochs(lines, report):
        if previous is None:
            if epoch.date is None:
                undated.append(epoch)
                if len(undated) > _MAX_UNDATED_EPOCHS:
                    _refuse_undated(undated, report)
                continue
            # The first dated epoch: count the held ones back from it.
            days = [epoch.date]
            later = epoch
            for held in reversed(undated):
                back = 1 if held.seconds > later.seconds + 43_200 else 0
                days.append(days[-1] - dt.timedelta(days=back))
                later = held
            for held, day in zip(undated, reversed(days[1:]), strict=True):
                yield from _nmea_fix(held, day, report)
            undated = []
            day = epoch.date
        else:
            before, before_day = previous
            if epoch.date is not None:
                day = epoch.date
            else:
                passed = epoch.seconds < before.seconds - 43_200
                day = before_day + dt.timedelta(days=1 if passed else 0)
        yield from _nmea_fix(epoch, day, report)
        previous = (epoch, day)
    if previous is None:
        _refuse_undated(undated, report)


def _refuse_undated(undated: list[_Epoch], report: dict[str, Any]) -> None:
    if any(e.lat is not None for e in undated):
        raise TrackFormatError(
            "file",
            "the NMEA log has no RMC sentence with a date, so its GGA fixes cannot be "
            "placed in time; log RMC too (u-blox receivers do by default)",
        )
    report["no_fix"] = sum(1 for e in undated if e.no_fix)


def _nmea_fix(epoch: _Epoch, day: dt.date, report: dict[str, Any]) -> Iterator[TrackFix]:
    if epoch.no_fix or epoch.lat is None or epoch.lon is None:
        report["no_fix"] += 1
        return
    check_position(epoch.lat, epoch.lon, input_name="file: NMEA position")
    midnight = datetime_to_us(dt.datetime.combine(day, dt.time(0, 0), tzinfo=dt.UTC))
    yield TrackFix(
        t=_checked_time(midnight + round(epoch.seconds * 1e6), "file: NMEA time"),
        lat=epoch.lat,
        lon=epoch.lon,
        heading_deg=epoch.heading_deg,
        speed_mps=epoch.speed_mps,
        quality=epoch.quality,
        hdop=epoch.hdop,
        satellites=epoch.satellites,
    )
