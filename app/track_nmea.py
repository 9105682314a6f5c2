"""Read an NMEA 0183 log (GGA and RMC sentences), line by line: see :mod:`app.tracks`."""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Final

import pynmea2

from app.track_fixes import (
    MAX_HEADING_DEG,
    MAX_SPEED_MPS,
    TrackFix,
    TrackFormatError,
    check_position,
    checked_time,
    datetime_to_us,
    finite_or_none,
)

#: m/s per knot (NMEA speeds are in knots).
MPS_PER_KNOT: Final = 1852.0 / 3600.0
#: A line that starts like an NMEA sentence (``$GNGGA,``): how a log is told apart.
NMEA_LINE = re.compile(r"^\$[A-Z]{2}[A-Z0-9]{3},")
#: GGA fix quality -> FIX_QUALITIES (3 PPS and 7/8 manual/simulated carry no quality).
_GGA_QUALITIES: Final = {
    1: "single",
    2: "dgps",
    4: "rtk_fixed",
    5: "rtk_float",
    6: "dead_reckoning",
}
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
        if start < 0 or not NMEA_LINE.match(line[start:]):
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
                hdop = finite_or_none(float(msg.horizontal_dil)) if msg.horizontal_dil else None
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
            heading = finite_or_none(msg.true_course)
            knots = finite_or_none(msg.spd_over_grnd)
            speed = None if knots is None else knots * MPS_PER_KNOT
            # A value out of range is dropped (as an unreadable sentence would be).
            epoch.heading_deg = (
                heading if heading is None or abs(heading) <= MAX_HEADING_DEG else None
            )
            epoch.speed_mps = speed if speed is None or 0 <= speed <= MAX_SPEED_MPS else None
    if epoch is not None:
        yield epoch


def read_nmea(lines: Iterable[str], report: dict[str, Any]) -> Iterator[TrackFix]:
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
        t=checked_time(midnight + round(epoch.seconds * 1e6), "file: NMEA time"),
        lat=epoch.lat,
        lon=epoch.lon,
        heading_deg=epoch.heading_deg,
        speed_mps=epoch.speed_mps,
        quality=epoch.quality,
        hdop=epoch.hdop,
        satellites=epoch.satellites,
    )
