"""GPX 1.1 for a plan and for recorded or simulated tracks, written with gpxpy.

The start and finish are ``<wpt>``; the route is one ``<rte>`` named after the plan whose
``<rtept>`` are the waypoints in order, named ``WP000``, ``WP001`` …, with the waypoint's role
as ``<type>``; each track is a ``<trk>`` with one segment.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence
from dataclasses import dataclass

import gpxpy.gpx

from planner.types import CoveragePlan


@dataclass(frozen=True, slots=True)
class GpxTrack:
    """A track to write as ``<trk>``.

    Attributes
    ----------
    name : str
    lon, lat : sequence of float
        WGS84 degrees.
    time : sequence of datetime, optional
        Timezone-aware UTC times, one per point.
    """

    name: str
    lon: Sequence[float]
    lat: Sequence[float]
    time: Sequence[dt.datetime] | None = None


def plan_to_gpx(plan: CoveragePlan | None, *, name: str, tracks: Sequence[GpxTrack] = ()) -> str:
    """Return GPX 1.1 text with the plan as a route and any ``tracks``.

    Parameters
    ----------
    plan : CoveragePlan or None
        The plan; None writes the tracks alone.
    name : str
        Name of the file's metadata and of the route.
    tracks : sequence of GpxTrack

    Returns
    -------
    str
        A GPX 1.1 document that validates against the GPX 1.1 schema.
    """
    gpx = gpxpy.gpx.GPX()
    gpx.creator = "tillpath"
    gpx.name = name
    if plan is not None:
        for w in plan.waypoints:
            if w.role in ("start", "finish"):
                gpx.waypoints.append(
                    gpxpy.gpx.GPXWaypoint(latitude=w.lat, longitude=w.lon, name=w.role)
                )
        route = gpxpy.gpx.GPXRoute(name=name)
        for w in plan.waypoints:
            point = gpxpy.gpx.GPXRoutePoint(latitude=w.lat, longitude=w.lon, name=f"WP{w.seq:03d}")
            point.type = w.role
            if w.line is not None:
                point.description = f"line {w.line}"
            route.points.append(point)
        gpx.routes.append(route)
    for track in tracks:
        gpx_track = gpxpy.gpx.GPXTrack(name=track.name)
        segment = gpxpy.gpx.GPXTrackSegment()
        times = track.time if track.time is not None else [None] * len(track.lon)
        for lon, lat, time in zip(track.lon, track.lat, times, strict=True):
            segment.points.append(
                gpxpy.gpx.GPXTrackPoint(latitude=float(lat), longitude=float(lon), time=time)
            )
        gpx_track.segments.append(segment)
        gpx.tracks.append(gpx_track)
    return str(gpx.to_xml(version="1.1"))
