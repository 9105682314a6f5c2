"""Write a simulated run's tracks as GeoJSON and GPX (pure: run in, text or dict out).

Three tracks: ``true`` (where the tractor went), ``estimated`` (where the filter thought it
was) and ``gps`` (the raw fixes). The 10 Hz log is thinned to one point every ``step_s``
seconds (1 s by default, as loggers record), always keeping the last point.
"""

from __future__ import annotations

import datetime as dt
from typing import Any

import numpy as np
import numpy.typing as npt

from navigation.simulator import SimulationLog
from planner.export.gpx import GpxTrack, plan_to_gpx

TRACKS = ("true", "estimated", "gps")


def _thin(time_s: npt.NDArray[np.float64], step_s: float) -> npt.NDArray[np.int64]:
    if step_s <= 0 or len(time_s) == 0:
        return np.arange(len(time_s))
    slot = np.floor(time_s / step_s + 1e-9)
    keep = np.flatnonzero(np.diff(slot, prepend=-1.0) > 0)
    if keep[-1] != len(time_s) - 1:
        keep = np.append(keep, len(time_s) - 1)
    return keep


def track_arrays(
    log: SimulationLog, which: str, *, step_s: float = 1.0
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Return ``(time_s, lon, lat)`` of the ``true``, ``estimated`` or ``gps`` track, thinned."""
    lon, lat = log.lonlat(which)
    time_s = log.gps_time_s if which == "gps" else log.time_s
    keep = _thin(time_s, step_s)
    return time_s[keep], np.asarray(lon)[keep], np.asarray(lat)[keep]


def _round(values: npt.NDArray[np.float64], digits: int) -> list[float]:
    return [round(float(v), digits) for v in values]


def simulation_to_geojson(log: SimulationLog, *, step_s: float = 1.0) -> dict[str, Any]:
    """Return a GeoJSON FeatureCollection: a LineString per track, metrics in its properties.

    Each track feature has ``kind: track``, ``source`` (``true``, ``estimated``, ``gps``) and
    ``time_s``, the time of each vertex [s]. Coordinates are rounded to 1e-8° (about 1 mm).
    """
    features = []
    for which in TRACKS:
        time_s, lon, lat = track_arrays(log, which, step_s=step_s)
        coords = [list(p) for p in zip(_round(lon, 8), _round(lat, 8), strict=True)]
        if len(coords) == 1:
            coords.append(coords[0])
        features.append(
            {
                "type": "Feature",
                "properties": {"kind": "track", "source": which, "time_s": _round(time_s, 3)},
                "geometry": {"type": "LineString", "coordinates": coords},
            }
        )
    gps = log.config.gps
    return {
        "type": "FeatureCollection",
        "properties": {
            "kind": "simulation",
            "gps": getattr(gps, "name", str(gps)),
            "guidance": log.config.guidance.mode,
            "declination_deg": round(log.declination_deg, 3),
            "metrics": log.metrics.as_dict(),
        },
        "features": features,
    }


def simulation_to_gpx(
    log: SimulationLog,
    *,
    name: str = "tillpath simulation",
    step_s: float = 1.0,
    start: dt.datetime | None = None,
) -> str:
    """GPX 1.1 with the plan as a route and the three tracks as ``<trk>`` with times.

    ``start`` (timezone-aware) is the time of the run's first step; by default midnight UTC of
    the configuration's date.
    """
    start = start or dt.datetime.combine(log.config.date, dt.time(0, 0), tzinfo=dt.UTC)
    tracks = []
    for which in TRACKS:
        time_s, lon, lat = track_arrays(log, which, step_s=step_s)
        times = [start + dt.timedelta(seconds=float(t)) for t in time_s]
        tracks.append(GpxTrack(name=which, lon=lon.tolist(), lat=lat.tolist(), time=times))
    return plan_to_gpx(log.plan, name=name, tracks=tracks)
