"""Check a planning request before any geometry is built.

Each check raises a :class:`~planner.errors.PlannerError` subclass whose message names the
input and the problem, e.g. ``field: polygon is self-intersecting near (115.29813, -8.62641)``.
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np
import shapely
from shapely import Polygon

from planner.errors import InvalidFieldError, InvalidParameterError
from planner.projection import UTM_LAT_RANGE_DEG, WGS84, LocalFrame, geodesic_area_m2
from planner.types import OBJECTIVES, PATTERNS, Objective, Pattern

INTERVAL_RANGE_M = (0.2, 50.0)
IMPLEMENT_WIDTH_RANGE_M = (0.1, 50.0)
SPEED_RANGE_MPS = (0.05, 10.0)
HEADLAND_PASSES_MAX = 5
MIN_AREA_M2 = 1.0
MAX_AREA_M2 = 2000.0 * 10_000.0
MAX_POINT_DISTANCE_M = 5_000.0
#: A 2,000 ha square is 4.5 km across; a "field" longer than this is a typing slip (a latitude
#: of 4 for -8.6): planned, its few lines run hundreds of km and its answer is hundreds of MB.
MAX_SPAN_M = 25_000.0
#: Real field boundaries have a few hundred vertices (310 at most in shared/fields); a limit
#: keeps a pasted GPS log or a mistaken file from costing seconds and gigabytes.
MAX_VERTICES = 2_000

_WHERE = re.compile(r"\[\s*(-?[\d.eE+-]+)\s+(-?[\d.eE+-]+)\s*\]")


def validate_field(field_lonlat: Any) -> tuple[Polygon, float]:
    """Return ``field_lonlat`` if it is a plannable WGS84 polygon.

    Parameters
    ----------
    field_lonlat : Polygon
        Field boundary in WGS84 ``(lon, lat)``; holes are obstacles.

    Returns
    -------
    field : Polygon
        The same polygon, normalised (exterior counter-clockwise, holes clockwise).
    area_m2 : float
        Its geodesic area [m²], holes subtracted.

    Raises
    ------
    InvalidFieldError
        If it is not a polygon, has fewer than 3 distinct vertices, non-finite or
        out-of-range coordinates, is self-intersecting or otherwise invalid, spans more than
        25 km (its bounding box's diagonal), or its area is not more than 1 m² and at most
        2,000 ha.
    """
    if not isinstance(field_lonlat, Polygon):
        kind = getattr(field_lonlat, "geom_type", type(field_lonlat).__name__)
        raise InvalidFieldError("field", f"must be a Polygon, not {kind}")
    if field_lonlat.is_empty:
        raise InvalidFieldError("field", "polygon is empty")
    coords = shapely.get_coordinates(field_lonlat)
    if len(coords) > MAX_VERTICES:
        raise InvalidFieldError(
            "field",
            f"boundary has {len(coords):,} vertices; simplify it to at most {MAX_VERTICES:,}",
        )
    if not np.isfinite(coords).all():
        raise InvalidFieldError("field", "a coordinate is not a finite number")
    lon, lat = coords[:, 0], coords[:, 1]
    if (np.abs(lon) > 180.0).any() or (np.abs(lat) > 90.0).any():
        bad = int(np.argmax((np.abs(lon) > 180.0) | (np.abs(lat) > 90.0)))
        raise InvalidFieldError(
            "field",
            f"({lon[bad]}, {lat[bad]}) is not a [longitude, latitude] in degrees "
            "(longitude must be within ±180 and latitude within ±90; GeoJSON puts longitude first)",
        )
    if lat.min() < UTM_LAT_RANGE_DEG[0] or lat.max() > UTM_LAT_RANGE_DEG[1]:
        raise InvalidFieldError(
            "field", "latitude is outside the 80°S to 84°N range that tillpath plans in"
        )
    reason = shapely.is_valid_reason(field_lonlat)
    if reason != "Valid Geometry":
        # A valid polygon has three distinct vertices and an area, so count only here.
        if len(set(field_lonlat.exterior.coords)) < 3:
            raise InvalidFieldError("field", "polygon needs at least 3 distinct vertices")
        if field_lonlat.convex_hull.geom_type != "Polygon":  # a bow tie has area 0 too
            raise InvalidFieldError("field", "polygon has no area: its vertices lie on one line")
        raise InvalidFieldError("field", _describe_invalid(reason))
    area_m2 = geodesic_area_m2(field_lonlat)
    if area_m2 <= MIN_AREA_M2:
        raise InvalidFieldError(
            "field", f"area is {area_m2:.3g} m², too small to plan (it must be more than 1 m²)"
        )
    if area_m2 > MAX_AREA_M2:
        raise InvalidFieldError(
            "field",
            f"area is {area_m2 / 10_000:,.0f} ha; tillpath plans fields up to 2,000 ha at once",
        )
    span_m = _span_m(field_lonlat)
    if span_m > MAX_SPAN_M:
        raise InvalidFieldError(
            "field",
            f"spans {span_m / 1000:,.0f} km corner to corner; tillpath plans fields up to "
            f"{MAX_SPAN_M / 1000:g} km across (is a coordinate mistyped?)",
        )
    # A canonical vertex order (normalize) and orientation keep plans deterministic (R7).
    return shapely.orient_polygons(shapely.normalize(field_lonlat)), area_m2


def _span_m(field_lonlat: Polygon) -> float:
    """Geodesic length of the diagonal of the field's longitude-latitude box [m].

    At least the field's longest extent, and cheap for any number of vertices.
    """
    lon_min, lat_min, lon_max, lat_max = field_lonlat.bounds
    return float(WGS84.inv(lon_min, lat_min, lon_max, lat_max)[2])


def _describe_invalid(reason: str) -> str:
    match = _WHERE.search(reason)
    where = f" near ({float(match[1]):.6f}, {float(match[2]):.6f})" if match else ""
    if "Self-intersection" in reason:
        return f"polygon is self-intersecting{where}"
    if "Hole lies outside shell" in reason:
        return f"a hole lies outside the field boundary{where}"
    if "Nested holes" in reason:
        return f"a hole lies inside another hole{where}"
    if "Interior is disconnected" in reason:
        return f"the holes cut the field into separate pieces{where}"
    if "Too few points" in reason:
        return f"a ring has too few distinct points{where}"
    return f"polygon is not valid: {reason}"


def validate_interval(interval_m: Any) -> float:
    """Return ``interval_m`` [m] if it is a number within 0.2–50 m."""
    value = _number("interval_m", interval_m)
    low, high = INTERVAL_RANGE_M
    if not (low <= value <= high):
        raise InvalidParameterError(
            "interval_m", f"must be between {low:g} and {high:g} m, got {value:g}"
        )
    return value


def validate_implement_width(implement_width_m: Any, interval_m: float) -> float:
    """Return the implement's working width [m]: ``interval_m`` if None, else 0.1–50 m."""
    if implement_width_m is None:
        return float(interval_m)
    value = _number("implement_width_m", implement_width_m)
    low, high = IMPLEMENT_WIDTH_RANGE_M
    if not (low <= value <= high):
        raise InvalidParameterError(
            "implement_width_m", f"must be between {low:g} and {high:g} m, got {value:g}"
        )
    return value


def validate_pattern(pattern: Any) -> Pattern:
    """Return ``pattern`` if it is one of :data:`~planner.types.PATTERNS`."""
    for known in PATTERNS:
        if pattern == known:
            return known
    raise InvalidParameterError("pattern", f"must be one of {', '.join(PATTERNS)}, got {pattern!r}")


def validate_angle(angle_deg: Any) -> float | None:
    """Return ``angle_deg`` if it is None or a heading in [0, 180) degrees."""
    if angle_deg is None:
        return None
    value = _number("angle_deg", angle_deg)
    if not (0.0 <= value < 180.0):
        raise InvalidParameterError(
            "angle_deg", f"must be at least 0 and less than 180 degrees, got {value:g}"
        )
    return value


def validate_objective(objective: Any) -> Objective:
    """Return ``objective`` if it is one of :data:`~planner.types.OBJECTIVES`."""
    for known in OBJECTIVES:
        if objective == known:
            return known
    raise InvalidParameterError(
        "objective", f"must be one of {', '.join(OBJECTIVES)}, got {objective!r}"
    )


def validate_headland_passes(headland_passes: Any) -> int:
    """Return ``headland_passes`` if it is a whole number from 0 to 5."""
    if isinstance(headland_passes, bool) or not isinstance(headland_passes, (int, np.integer)):
        raise InvalidParameterError(
            "headland_passes", f"must be a whole number from 0 to 5, got {headland_passes!r}"
        )
    if not (0 <= headland_passes <= HEADLAND_PASSES_MAX):
        raise InvalidParameterError(
            "headland_passes", f"must be from 0 to 5, got {headland_passes}"
        )
    return int(headland_passes)


def validate_speed(speed_mps: Any) -> float:
    """Return ``speed_mps`` [m/s] if it is within 0.05–10 m/s."""
    value = _number("speed_mps", speed_mps)
    low, high = SPEED_RANGE_MPS
    if not (low <= value <= high):
        raise InvalidParameterError(
            "speed_mps", f"must be between {low:g} and {high:g} m/s, got {value:g}"
        )
    return value


def validate_points(
    start_lonlat: Any, finish_lonlat: Any, *, frame: LocalFrame, field_local: Polygon
) -> tuple[tuple[float, float] | None, tuple[float, float] | None]:
    """Return the local ``(x, y)`` [m] of the start and the finish point, each None if not given.

    Both are projected in one call (pyproj's fixed cost per call is most of a point's); the
    errors come in the order of checking each point in turn: the start's form, then its
    distance, then the finish's form and distance.

    Raises
    ------
    InvalidParameterError
        If a point is malformed, not finite, or more than 5 km from the field.
    """
    start = _lonlat("start", start_lonlat)
    finish_error: InvalidParameterError | None = None
    try:
        finish = _lonlat("finish", finish_lonlat)
    except InvalidParameterError as malformed:
        finish, finish_error = None, malformed  # raised after the start's distance
    given = [p for p in (start, finish) if p is not None]
    projected: list[tuple[tuple[float, float], float]] = []
    if given:
        x, y = frame.to_local_xy([p[0] for p in given], [p[1] for p in given])
        # Both distances in one call too; a point that does not project is infinitely far.
        finite = np.isfinite(x + y)
        distance_m = np.full(len(given), np.inf)
        if finite.any():
            at = shapely.points(np.stack([x[finite], y[finite]], axis=1))
            distance_m[finite] = shapely.distance(field_local, at)
        xy = zip(x.tolist(), y.tolist(), strict=True)
        projected = list(zip(xy, distance_m.tolist(), strict=True))
    start_xy = None if start is None else _near("start", start, *projected[0])
    if finish_error is not None:
        raise finish_error
    finish_xy = None if finish is None else _near("finish", finish, *projected[-1])
    return start_xy, finish_xy


def _lonlat(input_name: str, point_lonlat: Any) -> tuple[float, float] | None:
    """Return a start or finish point's ``(lon, lat)`` [deg] if well formed, None if not given."""
    if point_lonlat is None:
        return None
    if not isinstance(point_lonlat, (tuple, list)) or len(point_lonlat) != 2:
        raise InvalidParameterError(input_name, "must be a [lon, lat] pair")
    lon = _number(input_name, point_lonlat[0])
    lat = _number(input_name, point_lonlat[1])
    if abs(lon) > 180.0 or abs(lat) > 90.0:
        raise InvalidParameterError(
            input_name, f"({lon}, {lat}) is not a [longitude, latitude] in degrees"
        )
    return lon, lat


def _near(
    input_name: str, lonlat: tuple[float, float], xy: tuple[float, float], distance_m: float
) -> tuple[float, float]:
    """Return ``xy`` if the point, ``distance_m`` from the field, is within 5 km of it."""
    if not distance_m <= MAX_POINT_DISTANCE_M:
        lon, lat = lonlat
        raise InvalidParameterError(
            input_name,
            f"({lon:.6f}, {lat:.6f}) is {distance_m / 1000:,.1f} km from the field; "
            "it must be within 5 km",
        )
    return xy


def _number(input_name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidParameterError(input_name, f"must be a number, got {value!r}")
    result = float(value)
    if not math.isfinite(result):
        raise InvalidParameterError(input_name, f"must be a finite number, got {value!r}")
    return result
