"""What a recorded track is: its fixes, their times and the checks every reader applies.

Pure, shared by the readers (:mod:`app.track_gpx`, :mod:`app.track_csv`, :mod:`app.track_nmea`,
:mod:`app.track_formats`) and by the API's posted fixes. Timestamps are integers,
microseconds since the Unix epoch (UTC): equal times written differently
(``…T00:00:01.500Z`` and ``1767225601.5``) become the same fix.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from typing import Any, Final

#: Earliest and latest times accepted: the GPS epoch (1980-01-06) to 2100 [µs since 1970].
MIN_TIME_US: Final = 315_964_800 * 1_000_000
MAX_TIME_US: Final = 4_102_444_800 * 1_000_000

#: Bounds of a fix's heading [deg] and speed [m/s] (360 km/h: no tractor, nor a GPS glitch
#: worth storing, goes faster).
MAX_HEADING_DEG: Final = 360.0
MAX_SPEED_MPS: Final = 100.0

_EPOCH: Final = dt.datetime(1970, 1, 1, tzinfo=dt.UTC)
_MICROSECOND: Final = dt.timedelta(microseconds=1)

#: Fix qualities a track may carry (NMEA GGA 4 = rtk_fixed, 5 = rtk_float, 2 = dgps, 1 = single,
#: 6 = dead_reckoning; RTKLIB Q 1/2/4/5 and u-blox carrier solutions map to the same names).
FIX_QUALITIES = ("rtk_fixed", "rtk_float", "dgps", "single", "dead_reckoning")


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


def optional_float(value: float | str | None, *, input_name: str) -> float | None:
    """Read an optional number (None or empty text: None); refuse text or non-finite ones."""
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


def check_not_empty(fmt: str, count: int, report: dict[str, Any]) -> None:
    """Raise ``file: has no usable fix (…)`` if a file of format ``fmt`` gave no fix."""
    if count:
        return
    details = ", ".join(f"{k.replace('_', ' ')}: {v}" for k, v in report.items() if v)
    raise TrackFormatError(
        "file", f"has no usable fix ({fmt.upper()}{'; ' + details if details else ''})"
    )


def finite_or_none(value: float | None) -> float | None:
    """Return ``value`` as a float if it is finite, else None (a reader's missing value)."""
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def checked_time(t: int, input_name: str) -> int:
    """Return ``t`` [µs since 1970] if it lies between the GPS epoch and 2100, else refuse."""
    if not MIN_TIME_US <= t <= MAX_TIME_US:
        raise TrackFormatError(input_name, "must lie between 1980 and 2100")
    return t
