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
    feature_id : str or None
        The feature's ``id`` (property or GeoJSON Feature ``id``), in a file of many fields;
        a MultiPolygon's parts get ``<id>.1``, ``<id>.2`` ….
    """

    field_lonlat: Polygon
    start_lonlat: tuple[float, float] | None = None
    finish_lonlat: tuple[float, float] | None = None
    interval_m: float | None = None
    name: str | None = None
    feature_id: str | None = None


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


def parse_fields_geojson(obj: Any) -> list[FieldSpec]:
    """Extract every field of a GeoJSON object: each Polygon, and each part of a MultiPolygon.

    Points with ``role`` ``start``/``finish`` apply to every field. A one-field collection's
    field falls back on the collection's ``name``.

    Parameters
    ----------
    obj : dict
        Parsed GeoJSON: a geometry, a Feature or a FeatureCollection.

    Returns
    -------
    list of FieldSpec
        At least one, in file order.

    Raises
    ------
    InvalidFieldError
        If there is no polygon, or a polygon's coordinates are malformed.

    Examples
    --------
    >>> ring = [[0, 0], [0.001, 0], [0.001, 0.001], [0, 0]]
    >>> multi = {"type": "MultiPolygon", "coordinates": [[ring], [ring]]}
    >>> feature = {"type": "Feature", "properties": {"id": "a"}, "geometry": multi}
    >>> [f.feature_id for f in parse_fields_geojson(feature)]
    ['a.1', 'a.2']
    """
    if not isinstance(obj, Mapping):
        raise InvalidFieldError("field", "must be a GeoJSON object")
    kind = obj.get("type")
    if kind == "FeatureCollection":
        features = obj.get("features")
        if not isinstance(features, list):
            raise InvalidFieldError("field", "FeatureCollection has no 'features' list")
    elif kind == "Feature":
        features = [obj]
    else:
        features = [{"type": "Feature", "properties": {}, "geometry": obj}]
    found: list[tuple[Polygon, Mapping[str, Any], str | None]] = []
    points: dict[str, tuple[float, float]] = {}
    for feature in features:
        if not isinstance(feature, Mapping):
            raise InvalidFieldError("field", "every feature must be a GeoJSON Feature object")
        geometry = feature.get("geometry") or {}
        props = _properties(feature)
        gtype = geometry.get("type") if isinstance(geometry, Mapping) else None
        ident = props.get("id", feature.get("id"))
        feature_id = None if ident in (None, "") else str(ident)
        if gtype == "Polygon":
            found.append((_polygon_from_geometry(geometry), props, feature_id))
        elif gtype == "MultiPolygon":
            parts = geometry.get("coordinates")
            if not isinstance(parts, list) or not parts:
                raise InvalidFieldError("field", "a MultiPolygon has no polygons")
            for k, part in enumerate(parts, start=1):
                polygon = _polygon_from_geometry({"type": "Polygon", "coordinates": part})
                if len(parts) == 1:
                    found.append((polygon, props, feature_id))
                else:
                    name = _name_property(props)
                    part_props = {
                        **props,
                        "name": f"{name} ({k} of {len(parts)})" if name else None,
                    }
                    part_id = f"{feature_id}.{k}" if feature_id else None
                    found.append((polygon, {**part_props, "id": part_id}, part_id))
        elif gtype == "Point" and props.get("role") in ("start", "finish"):
            role = str(props["role"])
            points[role] = parse_position(geometry.get("coordinates"), input_name=role)
    if not found:
        raise InvalidFieldError("field", "holds no field boundary (no Polygon feature)")
    collection_name = str(obj["name"]) if kind == "FeatureCollection" and obj.get("name") else None
    return [
        FieldSpec(
            field_lonlat=polygon,
            start_lonlat=points.get("start"),
            finish_lonlat=points.get("finish"),
            interval_m=_interval_property(props),
            name=_name_property(props) or (collection_name if len(found) == 1 else None),
            feature_id=feature_id,
        )
        for polygon, props, feature_id in found
    ]


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
