"""tillpath's planner: back-and-forth coverage paths over a field, in pure geometry.

No I/O, no web, no database: a field polygon and parameters in, a :class:`CoveragePlan` out.
The stages are modules (``projection``, ``validation``, ``lines``, ``ordering``, ``turns``,
``coverage``, ``pipeline``) and ``planner.export`` writes plans as GeoJSON, GPX, CSV and JSON.
"""

from planner.errors import (
    InvalidFieldError,
    InvalidParameterError,
    PlannerError,
    PlanTooLargeError,
)
from planner.fields import FieldSpec, parse_field_geojson, parse_position
from planner.pipeline import plan_coverage
from planner.projection import LocalFrame, field_frame, local_frame
from planner.types import (
    DEFAULT_SPEED_MPS,
    OBJECTIVES,
    PATTERNS,
    CoveragePlan,
    Machine,
    Objective,
    PathSegment,
    PathSegments,
    Pattern,
    PlanStats,
    Vehicle,
    Waypoint,
    Waypoints,
)
from planner.vehicles import PRESETS, resolve_vehicle

__all__ = [
    "DEFAULT_SPEED_MPS",
    "OBJECTIVES",
    "PATTERNS",
    "PRESETS",
    "CoveragePlan",
    "FieldSpec",
    "InvalidFieldError",
    "InvalidParameterError",
    "LocalFrame",
    "Machine",
    "Objective",
    "PathSegment",
    "PathSegments",
    "Pattern",
    "PlanStats",
    "PlanTooLargeError",
    "PlannerError",
    "Vehicle",
    "Waypoint",
    "Waypoints",
    "field_frame",
    "local_frame",
    "parse_field_geojson",
    "parse_position",
    "plan_coverage",
    "resolve_vehicle",
]
