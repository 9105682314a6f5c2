"""GeoJSON (RFC 7946) for a plan, and back.

One FeatureCollection: the field (``kind: field``), its cells (``cell``), one LineString per
tillage line (``line``, ``index``), turns (``turn``), headland passes (``headland``,
``index``), start and finish legs (``transit``), the whole route (``path``) and a Point per
waypoint (``waypoint``, ``seq``, ``role``, ``line``). The plan's figures are the collection's
``properties``, except ``planning_ms``, which is a measurement of the run, not of the plan:
leaving it out keeps the file the same byte for byte for the same request (R7).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import shapely
from shapely import Polygon

from planner.errors import InvalidFieldError
from planner.fields import parse_field_geojson
from planner.types import (
    CoveragePlan,
    PathSegment,
    PathSegments,
    PlanStats,
    Vehicle,
    Waypoint,
    Waypoints,
)

_ROLES = {"start", "line_start", "line_end", "turn", "headland", "finish"}
_SEGMENT_KINDS = ("transit", "line", "turn", "headland", "round")


def plan_to_geojson(plan: CoveragePlan, *, name: str | None = None) -> dict[str, Any]:
    """Return ``plan`` as a GeoJSON FeatureCollection (a ``dict`` ready for ``json.dumps``).

    Parameters
    ----------
    plan : CoveragePlan
    name : str, optional
        Stored in the collection's properties.
    """
    features: list[dict[str, Any]] = [_feature(_polygon(plan.field_lonlat), {"kind": "field"})]
    for index, cell in enumerate(plan.cells_lonlat):
        features.append(_feature(_polygon(cell), {"kind": "cell", "index": index}))
    for kind, segment_index, coordinates in _segments(plan.segments):
        line = {"type": "LineString", "coordinates": coordinates}
        properties: dict[str, Any] = {"kind": kind}
        if kind in ("line", "headland", "round"):
            properties["index"] = segment_index
        features.append(_feature(line, properties))
    seq, lon, lat, roles, lines = _waypoint_columns(plan.waypoints)
    if len(lon) >= 2:
        path = [[x, y] for x, y in zip(lon, lat, strict=True)]
        features.append(_feature({"type": "LineString", "coordinates": path}, {"kind": "path"}))
    features += [  # a list comprehension: a generator resumes once per waypoint
        {
            "type": "Feature",
            "properties": {"kind": "waypoint", "seq": i, "role": role, "line": line},
            "geometry": {"type": "Point", "coordinates": [x, y]},
        }
        for i, x, y, role, line in zip(seq, lon, lat, roles, lines, strict=True)
    ]
    stats = plan.stats.as_dict()
    del stats["planning_ms"]
    properties = {"name": name, "interval_m": plan.interval_m, **stats}
    return {"type": "FeatureCollection", "properties": properties, "features": features}


def plan_from_geojson(obj: Any) -> CoveragePlan:
    """Read a plan written by :func:`plan_to_geojson`.

    Raises
    ------
    InvalidFieldError
        If ``obj`` is not a tillpath plan (no field, or no waypoints).
    """
    if not isinstance(obj, Mapping) or obj.get("type") != "FeatureCollection":
        raise InvalidFieldError("plan", "must be a GeoJSON FeatureCollection written by tillpath")
    by_kind: dict[str, list[Mapping[str, Any]]] = {}
    for feature in obj.get("features") or []:
        kind = (feature.get("properties") or {}).get("kind")
        by_kind.setdefault(str(kind), []).append(feature)
    if len(by_kind.get("field", [])) != 1 or not by_kind.get("waypoint"):
        raise InvalidFieldError("plan", "holds no tillpath plan (a field and waypoints)")
    field_feature = dict(by_kind["field"][0])
    field_feature["properties"] = {}
    field_lonlat = parse_field_geojson(field_feature).field_lonlat
    waypoints = []
    for feature in sorted(by_kind["waypoint"], key=lambda f: int(f["properties"]["seq"])):
        props = feature["properties"]
        lon, lat = feature["geometry"]["coordinates"][:2]
        role = props.get("role")
        if role not in _ROLES:
            raise InvalidFieldError(
                "plan", f"waypoint {props.get('seq')} has unknown role {role!r}"
            )
        line = props.get("line")
        waypoints.append(
            Waypoint(
                int(props["seq"]), float(lon), float(lat), role, None if line is None else int(line)
            )
        )
    segments = []
    for feature in obj["features"]:
        kind = feature["properties"].get("kind")
        if kind in _SEGMENT_KINDS:
            coords = tuple((float(p[0]), float(p[1])) for p in feature["geometry"]["coordinates"])
            segments.append(PathSegment(kind, feature["properties"].get("index"), coords))
    cells = tuple(
        parse_field_geojson({**f, "properties": {}}).field_lonlat for f in by_kind.get("cell", [])
    )
    props = obj.get("properties") or {}
    optional = {"implement_width_m", "overlap_m", "vehicle"}
    figures: dict[str, Any] = {
        k: props.get(k, None if k in optional else 0) for k in PlanStats.__slots__
    }
    stats = PlanStats(**figures)
    vehicle = _vehicle(props.get("vehicle"))
    implement = props.get("implement_width_m")
    return CoveragePlan(
        field_lonlat=field_lonlat,
        waypoints=tuple(waypoints),
        segments=tuple(segments),
        stats=stats,
        interval_m=float(props.get("interval_m", 0.0)),
        cells_lonlat=cells,
        vehicle=vehicle,
        implement_width_m=None if implement is None else float(implement),
    )


def _vehicle(value: Any) -> Vehicle | None:
    """Return the plan's vehicle from its figures, or None if the file has none."""
    if not isinstance(value, Mapping):
        return None
    try:
        return Vehicle(**{f: value[f] for f in Vehicle.__slots__})
    except (KeyError, TypeError):
        return None


def _segments(segments: Sequence[PathSegment]) -> Iterator[tuple[str, int | None, list[Any]]]:
    """Each segment's kind, index and ``[lon, lat]`` lists, from the columns if it has them."""
    if isinstance(segments, PathSegments):  # no PathSegment (tuple of tuples) made per segment
        lon, lat, bounds = segments.columns()
        for kind, index, first, last in bounds:
            stop = last + 1
            coordinates = [[x, y] for x, y in zip(lon[first:stop], lat[first:stop], strict=True)]
            yield kind, index, coordinates
        return
    for segment in segments:
        yield segment.kind, segment.index, [list(p) for p in segment.lonlat]


def _waypoint_columns(
    waypoints: Sequence[Waypoint],
) -> tuple[Sequence[int], list[float], list[float], Sequence[str], list[int | None]]:
    """``(seq, lon, lat, role, line)`` of every waypoint, from the columns if it has them."""
    if isinstance(waypoints, Waypoints):  # no Waypoint made per point
        lon, lat, roles, lines = waypoints.columns()
        return range(len(lon)), lon, lat, roles, lines
    return (
        [w.seq for w in waypoints],
        [w.lon for w in waypoints],
        [w.lat for w in waypoints],
        [w.role for w in waypoints],
        [w.line for w in waypoints],
    )


def _feature(geometry: dict[str, Any], properties: dict[str, Any]) -> dict[str, Any]:
    return {"type": "Feature", "properties": properties, "geometry": geometry}


def _polygon(polygon: Polygon) -> dict[str, Any]:
    rings = [polygon.exterior, *polygon.interiors]
    # The rings' coordinates as lists of [x, y] (or [x, y, z]) floats, as list(c) per point.
    z = polygon.has_z
    return {
        "type": "Polygon",
        "coordinates": [shapely.get_coordinates(r, include_z=z).tolist() for r in rings],
    }
