"""KML 2.2 for Google Earth, written with simplekml (product.md §4).

A plan is a Document with one Folder per kind: the field (holes as inner boundaries), the
tillage lines, headland passes, turns, start and finish legs, the whole path, and a Point per
waypoint, each kind with its own shared style. A recorded or simulated track is a ``gx:Track``
(``<when>`` and ``<gx:coord>`` pairs) when it has times, else a LineString.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence
from typing import Any, Final

import simplekml

from planner.export.gpx import GpxTrack
from planner.types import CoveragePlan

#: Line colour (KML ``aabbggrr``) and width [px] per kind of segment.
_LINE_STYLES: Final[dict[str, tuple[str, float]]] = {
    "line": ("ff00d7ff", 3.0),  # gold
    "headland": ("ffffff00", 3.0),  # cyan
    "turn": ("ff0080ff", 2.0),  # orange
    "transit": ("ffb0b0b0", 2.0),  # grey
    "path": ("c0ffffff", 1.0),  # white, translucent
}
_FOLDERS: Final = (
    ("line", "Tillage lines"),
    ("headland", "Headland passes"),
    ("turn", "Turns"),
    ("transit", "Start and finish legs"),
)
#: Track colours, cycled over the tracks of a file.
_TRACK_COLOURS: Final = ("ff0000ff", "ffff0000", "ff00ff00", "ffff00ff")
_ICON: Final = "http://maps.google.com/mapfiles/kml/shapes/placemark_circle.png"
_ROLE_COLOURS: Final[dict[str, str]] = {"start": "ff00ff00", "finish": "ff0000ff"}


def plan_to_kml(plan: CoveragePlan, *, name: str, tracks: Sequence[GpxTrack] = ()) -> str:
    """Return KML 2.2 text with the plan as styled placemarks, and any ``tracks``.

    Parameters
    ----------
    plan : CoveragePlan
    name : str
        The Document's name.
    tracks : sequence of GpxTrack
        Recorded or simulated tracks, written after the plan.

    Returns
    -------
    str
        A KML 2.2 document (``gx:`` extension namespace for tracks).
    """
    kml = simplekml.Kml(name=name)
    field_style = simplekml.Style()
    field_style.linestyle.color = "ff00ff00"
    field_style.linestyle.width = 2
    field_style.polystyle.color = "4000ff00"
    field_folder = kml.newfolder(name="Field")
    polygon = field_folder.newpolygon(
        name=name,
        outerboundaryis=list(plan.field_lonlat.exterior.coords),
        innerboundaryis=[list(ring.coords) for ring in plan.field_lonlat.interiors],
    )
    polygon.style = field_style
    polygon.description = _describe(plan)

    styles = {kind: _line_style(colour, width) for kind, (colour, width) in _LINE_STYLES.items()}
    folders = {kind: kml.newfolder(name=title) for kind, title in _FOLDERS}
    for segment in plan.segments:
        kind = str(segment.kind)
        if kind not in folders:  # a kind added after this writer (a spiral's rounds …)
            folders[kind] = kml.newfolder(name=kind)
            styles.setdefault(kind, _line_style("ff00d7ff", 3.0))
        label = kind if segment.index is None else f"{kind} {segment.index}"
        line = folders[kind].newlinestring(name=label, coords=list(segment.lonlat))
        line.style = styles[kind]
    if len(plan.waypoints) >= 2:
        path = kml.newfolder(name="Path").newlinestring(
            name="path", coords=[(w.lon, w.lat) for w in plan.waypoints]
        )
        path.style = styles["path"]

    waypoint_folder = kml.newfolder(name="Waypoints")
    point_styles: dict[str, Any] = {}
    for w in plan.waypoints:
        style = point_styles.get(w.role)
        if style is None:
            style = simplekml.Style()
            style.iconstyle.icon.href = _ICON
            style.iconstyle.color = _ROLE_COLOURS.get(w.role, "ffffffff")
            style.iconstyle.scale = 0.6
            style.labelstyle.scale = 0.6
            point_styles[w.role] = style
        point = waypoint_folder.newpoint(name=f"WP{w.seq:03d}", coords=[(w.lon, w.lat)])
        point.description = w.role if w.line is None else f"{w.role}, line {w.line}"
        point.style = style
    _add_tracks(kml, tracks)
    return str(kml.kml())


def tracks_to_kml(*, name: str, tracks: Sequence[GpxTrack]) -> str:
    """Return KML 2.2 text with ``tracks`` alone (``gx:Track`` when timed, else LineString)."""
    kml = simplekml.Kml(name=name)
    _add_tracks(kml, tracks)
    return str(kml.kml())


def _add_tracks(kml: Any, tracks: Sequence[GpxTrack]) -> None:
    if not tracks:
        return
    folder = kml.newfolder(name="Tracks")
    for i, track in enumerate(tracks):
        style = _line_style(_TRACK_COLOURS[i % len(_TRACK_COLOURS)], 2.0)
        coords = [(float(lon), float(lat)) for lon, lat in zip(track.lon, track.lat, strict=True)]
        if track.time is not None and len(track.time) == len(coords) and coords:
            placemark = folder.newgxtrack(name=track.name)
            placemark.newwhen([_iso(t) for t in track.time])
            placemark.newgxcoord([(lon, lat, 0.0) for lon, lat in coords])
        else:
            placemark = folder.newlinestring(name=track.name, coords=coords)
        placemark.style = style


def _line_style(colour: str, width: float) -> Any:
    style = simplekml.Style()
    style.linestyle.color = colour
    style.linestyle.width = width
    return style


def _iso(time: dt.datetime) -> str:
    return time.astimezone(dt.UTC).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def _describe(plan: CoveragePlan) -> str:
    s = plan.stats
    return (
        f"{s.line_count} lines at {plan.interval_m:g} m, {s.waypoint_count} waypoints, "
        f"area {s.area_m2:,.1f} m², path {s.path_length_m:,.1f} m, "
        f"coverage {s.coverage_ratio:.1%}, about {s.estimated_time_s / 60:.1f} min"
    )
