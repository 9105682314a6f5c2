"""Track files as loggers write them, made from a real simulated run (for the runs tests).

A simulation of the paper's field gives a true track at 10 Hz; these helpers write it as a GPX
file (through navigation's own exporter), a CSV file and a u-blox style NMEA 0183 log
(``$GNRMC`` and ``$GNGGA`` per epoch, among ``$GNGSA``/``$GPGSV``/``$GNTXT`` chatter).
"""

from __future__ import annotations

import datetime as dt
import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from navigation import SimulationConfig, SimulationLog, simulate
from navigation.export import simulation_to_gpx
from planner import parse_field_geojson, plan_coverage
from planner.types import CoveragePlan
from tests.app.conftest import PAPER_FIELD

#: When the simulated run starts (UTC), just before midnight: the NMEA log crosses a day.
RUN_START = dt.datetime(2026, 11, 21, 23, 58, 30, tzinfo=dt.UTC)


@dataclass(frozen=True)
class SimulatedRun:
    """A simulated run: its plan, its log, and the true track as arrays."""

    plan: CoveragePlan
    log: SimulationLog
    time_s: np.ndarray
    lon: np.ndarray
    lat: np.ndarray


@functools.cache
def paper_plan() -> CoveragePlan:
    """The paper field at 4 m, as ``POST /api/plans`` plans it."""
    import json

    spec = parse_field_geojson(json.loads(PAPER_FIELD.read_text()))
    return plan_coverage(
        spec.field_lonlat,
        interval_m=4,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
    )


@functools.cache
def simulated_run(seed: int = 5) -> SimulatedRun:
    """Simulate the paper plan (m8n, waypoint mode); return the true track at 10 Hz."""
    plan = paper_plan()
    log = simulate(plan, SimulationConfig(gps="m8n"), np.random.default_rng(seed))
    lon, lat = log.lonlat("true")
    return SimulatedRun(plan, log, np.asarray(log.time_s), np.asarray(lon), np.asarray(lat))


def gpx_file(run: SimulatedRun) -> bytes:
    """The run as GPX: plan route, and true, estimated and GPS tracks at 10 Hz."""
    return simulation_to_gpx(run.log, step_s=0, start=RUN_START).encode()


def csv_file(run: SimulatedRun, *, epoch: bool = False) -> bytes:
    """The true track as ``time,lat,lon,heading_deg,speed_mps`` (ISO times, or epoch seconds)."""
    lines = ["time,lat,lon,heading_deg,speed_mps"]
    heading = np.degrees(np.asarray(run.log.true_heading_rad)) % 360
    for t, lon, lat, h in zip(run.time_s, run.lon, run.lat, heading, strict=True):
        when = RUN_START + dt.timedelta(seconds=round(float(t), 3))
        stamp = f"{when.timestamp():.3f}" if epoch else when.isoformat().replace("+00:00", "Z")
        lines.append(f"{stamp},{lat:.9f},{lon:.9f},{h:.1f},0.56")
    return ("\n".join(lines) + "\n").encode()


def nmea_checksum(body: str) -> str:
    """The two hex digits after ``*``: XOR of the characters between ``$`` and ``*``."""
    value = 0
    for char in body:
        value ^= ord(char)
    return f"{value:02X}"


def sentence(body: str) -> str:
    """``$<body>*<checksum>``."""
    return f"${body}*{nmea_checksum(body)}"


def _dm(value: float, degree_digits: int) -> tuple[str, str]:
    hemi = ("N", "S") if degree_digits == 2 else ("E", "W")
    sign = hemi[0] if value >= 0 else hemi[1]
    value = abs(value)
    degrees = int(value)
    minutes = (value - degrees) * 60
    return f"{degrees:0{degree_digits}d}{minutes:08.5f}", sign


def nmea_lines(
    times: Sequence[dt.datetime],
    lon: Sequence[float],
    lat: Sequence[float],
    *,
    quality: Sequence[int] | None = None,
) -> list[str]:
    """u-blox style NMEA: per epoch RMC then GGA, with GSA/GSV/TXT sentences in between."""
    lines = [sentence("GNTXT,01,01,02,u-blox AG - www.u-blox.com")]
    for i, (when, x, y) in enumerate(zip(times, lon, lat, strict=True)):
        q = 1 if quality is None else quality[i]
        hhmmss = when.strftime("%H%M%S") + f".{when.microsecond // 10000:02d}"
        ddmmyy = when.strftime("%d%m%y")
        la, ns = _dm(float(y), 2)
        lo, ew = _dm(float(x), 3)
        status = "A" if q > 0 else "V"
        lines.append(sentence(f"GNRMC,{hhmmss},{status},{la},{ns},{lo},{ew},1.089,,{ddmmyy},,,A"))
        if i % 5 == 0:
            lines.append(sentence("GNGSA,A,3,10,32,14,18,11,,,,,,,,1.54,0.86,1.28"))
            lines.append(sentence("GPGSV,3,1,10,08,20,041,,10,70,316,33,11,24,172,29,14,48,245,34"))
        if q > 0:
            lines.append(
                sentence(f"GNGGA,{hhmmss},{la},{ns},{lo},{ew},{q},09,0.86,35.2,M,18.1,M,,")
            )
        else:
            lines.append(sentence(f"GNGGA,{hhmmss},,,,,0,00,99.99,,,,,,"))
    return lines


def nmea_file(run: SimulatedRun) -> bytes:
    """The true track as a u-blox NMEA log (10 Hz, CRLF line ends as the receiver sends)."""
    times = [RUN_START + dt.timedelta(seconds=round(float(t), 2)) for t in run.time_s]
    return ("\r\n".join(nmea_lines(times, run.lon, run.lat)) + "\r\n").encode()
