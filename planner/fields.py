"""Read a field boundary, start, finish and interval out of a GeoJSON object.

Pure: takes the parsed JSON (``dict``), never a file. Accepts a Polygon, a Feature of one, a
one-polygon MultiPolygon, or a FeatureCollection holding one field polygon plus optional Points
whose ``role`` property is ``start`` or ``finish`` (the layout of ``shared/fields/*.geojson``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from shapely import Polygon

from planner.errors import InvalidFieldError, InvalidParameterError


@dataclass(frozen=True, slots=True)
class FieldSpec:
    """What a GeoJSON field file says about the job.

    Attributes
    ----------
    field_lonlat : Polygon
        The boundary, holes included, WGS84 ``(lon, lat)``; not yet validated.
    start_lonlat, finish_lonlat : tuple of float or None
        Points with role ``start`` / ``finish``, if the file has them.
    interval_m : float or None
        The field's ``interval_m`` property, if present.
    name : str or None
        The field's ``name`` or ``id`` property, or the collection's ``name``.
    """

    field_lonlat: Polygon
    start_lonlat: tuple[float, float] | None = None
    finish_lonlat: tuple[float, float] | None = None
    interval_m: float | None = None
    name: str | None = None


def parse_position(value: Any, *, input_name: str) -> tuple[float, float]:
    """Return ``value`` as a finite ``(lon, lat)`` pair.

    Raises
    ------
    InvalidParameterError
        If ``value`` is not two finite numbers with a valid latitude.

    Examples
    --------
    >>> parse_position([115.29, -8.62], input_name="start")
    (115.29, -8.62)
    """
    if (
        not isinstance(value, (list, tuple))
        or len(value) < 2
        or not all(_is_number(v) for v in value[:2])
    ):
        raise InvalidParameterError(input_name, "must be a [lon, lat] pair of numbers")
    lon, lat = float(value[0]), float(value[1])
    if not (math.isfinite(lon) and math.isfinite(lat)):
        raise InvalidParameterError(input_name, "coordinates must be finite numbers")
    if not (-180.0 <= lon <= 180.0 and -90.0 <= lat <= 90.0):
        raise InvalidParameterError(
            input_name, f"({lon}, {lat}) is not a longitude/latitude in degrees"
        )
    return lon, lat


def parse_field_geojson(obj: Any) -> FieldSpec:
    """Extract the field polygon and the job's points from a GeoJSON object.

    Parameters
    ----------
    obj : dict
        Parsed GeoJSON: Polygon, MultiPolygon of one polygon, Feature, or FeatureCollection.

    Returns
    -------
    FieldSpec

    Raises
    ------
    InvalidFieldError
        If no single polygon can be found, or its coordinates are malformed.
    """
    if not isinstance(obj, Mapping):
        raise InvalidFieldError("field", "must be a GeoJSON object")
    kind = obj.get("type")
    if kind == "FeatureCollection":
        return _from_collection(obj)
    if kind == "Feature":
        props = _properties(obj)
        return FieldSpec(
            field_lonlat=_polygon_from_geometry(obj.get("geometry")),
            interval_m=_interval_property(props),
            name=_name_property(props),
        )
    return FieldSpec(field_lonlat=_polygon_from_geometry(obj))


def _from_collection(obj: Mapping[str, Any]) -> FieldSpec:
    features = obj.get("features")
    if not isinstance(features, list):
        raise InvalidFieldError("field", "FeatureCollection has no 'features' list")
    polygons: list[tuple[Polygon, Mapping[str, Any]]] = []
    points: dict[str, tuple[float, float]] = {}
    for feature in features:
        if not isinstance(feature, Mapping):
            raise InvalidFieldError("field", "every feature must be a GeoJSON Feature object")
        geometry = feature.get("geometry") or {}
        props = _properties(feature)
        gtype = geometry.get("type") if isinstance(geometry, Mapping) else None
        if gtype in ("Polygon", "MultiPolygon"):
            polygons.append((_polygon_from_geometry(geometry), props))
        elif gtype == "Point" and props.get("role") in ("start", "finish"):
            role = str(props["role"])
            points[role] = parse_position(geometry.get("coordinates"), input_name=role)
    if not polygons:
        raise InvalidFieldError("field", "the FeatureCollection holds no Polygon")
    if len(polygons) > 1:
        raise InvalidFieldError(
            "field",
            f"the FeatureCollection holds {len(polygons)} polygons; give one field at a time",
        )
    polygon, props = polygons[0]
    name = _name_property(props) or (str(obj["name"]) if obj.get("name") else None)
    return FieldSpec(
        field_lonlat=polygon,
        start_lonlat=points.get("start"),
        finish_lonlat=points.get("finish"),
        interval_m=_interval_property(props),
        name=name,
    )


def _polygon_from_geometry(geometry: Any) -> Polygon:
    if not isinstance(geometry, Mapping):
        raise InvalidFieldError("field", "must be a GeoJSON Polygon geometry")
    gtype = geometry.get("type")
    coords = geometry.get("coordinates")
    if gtype == "MultiPolygon":
        if not isinstance(coords, list) or len(coords) != 1:
            raise InvalidFieldError("field", "a MultiPolygon must hold exactly one polygon")
        coords = coords[0]
    elif gtype != "Polygon":
        raise InvalidFieldError("field", f"must be a Polygon, not {gtype!r}")
    if not isinstance(coords, list) or not coords:
        raise InvalidFieldError("field", "polygon has no coordinates")
    rings = [_ring(ring, i) for i, ring in enumerate(coords)]
    return Polygon(rings[0], rings[1:])


def _ring(ring: Any, index: int) -> list[tuple[float, float]]:
    where = "exterior ring" if index == 0 else f"hole {index}"
    if not isinstance(ring, list):
        raise InvalidFieldError("field", f"{where} must be a list of [lon, lat] positions")
    points: list[tuple[float, float]] = []
    for position in ring:
        if (
            not isinstance(position, (list, tuple))
            or len(position) < 2
            or not all(_is_number(v) for v in position[:2])
        ):
            raise InvalidFieldError("field", f"{where} has a position that is not [lon, lat]")
        lon, lat = float(position[0]), float(position[1])
        if not (math.isfinite(lon) and math.isfinite(lat)):
            raise InvalidFieldError("field", f"{where} has a coordinate that is not finite")
        points.append((lon, lat))
    if len(points) < 4:
        raise InvalidFieldError(
            "field", f"{where} needs at least 3 distinct vertices and a closing point"
        )
    return points


def _properties(feature: Mapping[str, Any]) -> Mapping[str, Any]:
    props = feature.get("properties")
    if props is None:
        return {}
    if not isinstance(props, Mapping):
        raise InvalidFieldError("field", "a Feature's properties must be a JSON object or null")
    return props


def _interval_property(props: Mapping[str, Any]) -> float | None:
    value: Any = props.get("interval_m")
    return float(value) if _is_number(value) else None


def _name_property(props: Mapping[str, Any]) -> str | None:
    for key in ("name", "id"):
        if props.get(key) not in (None, ""):
            return str(props[key])
    return None


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)
