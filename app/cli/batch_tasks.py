"""What a Dask worker runs for ``tillpath plan-batch``: plan a handful of fields, never fail.

Each field is planned by the pure planner; a field that cannot be planned (not a polygon, self-
intersecting, no interval) becomes a row with the planner's message, so one bad field never
ends the batch.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from app.cli.batch_read import FieldRecord

if TYPE_CHECKING:
    from planner.types import Waypoint


@dataclass(frozen=True, slots=True)
class FieldResult:
    """One row of ``plan-batch``'s output: a field's figures, or why it has none."""

    index: int
    ident: str
    name: str | None
    field_wkb: bytes | None
    path_wkb: bytes | None
    area_m2: float | None
    line_count: int | None
    path_length_m: float | None
    coverage_ratio: float | None
    estimated_time_s: float | None
    planning_ms: float
    error: str | None


def _failed(record: FieldRecord, error: str, started: float) -> FieldResult:
    return FieldResult(
        index=record.index,
        ident=record.ident,
        name=record.name,
        field_wkb=record.wkb,
        path_wkb=None,
        area_m2=None,
        line_count=None,
        path_length_m=None,
        coverage_ratio=None,
        estimated_time_s=None,
        planning_ms=(time.perf_counter() - started) * 1000,
        error=error,
    )


def plan_record(record: FieldRecord, options: dict[str, Any]) -> FieldResult:
    """Plan one field with ``options`` (``interval_m``, ``angle_deg``, ``objective`` …).

    The flag's ``interval_m`` wins over the field's own property, as in ``tillpath plan``.
    """
    from planner import PlannerError, parse_field_geojson, plan_coverage

    started = time.perf_counter()
    if record.wkb is None:
        return _failed(record, "geometry: the feature has no geometry", started)
    options = dict(options)
    interval = options.pop("interval_m", None) or record.interval_m
    if interval is None:
        return _failed(
            record, "interval_m: give --interval (the field has no interval_m property)", started
        )
    try:
        geometry = shapely.from_wkb(record.wkb)
        spec = parse_field_geojson(json.loads(shapely.to_geojson(geometry)))
        plan = plan_coverage(spec.field_lonlat, interval_m=interval, **options)
    except PlannerError as exc:
        return _failed(record, str(exc), started)
    except Exception as exc:  # a planner bug must not end a batch of a million fields
        return _failed(record, f"internal error: {type(exc).__name__}: {exc}", started)
    path = _path_lonlat(plan.waypoints)
    stats = plan.stats
    return FieldResult(
        index=record.index,
        ident=record.ident,
        name=record.name,
        field_wkb=shapely.to_wkb(spec.field_lonlat),
        path_wkb=None if path is None else shapely.to_wkb(path),
        area_m2=stats.area_m2,
        line_count=stats.line_count,
        path_length_m=stats.path_length_m,
        coverage_ratio=stats.coverage_ratio,
        estimated_time_s=stats.estimated_time_s,
        planning_ms=(time.perf_counter() - started) * 1000,
        error=None,
    )


def _path_lonlat(waypoints: Sequence[Waypoint]) -> shapely.LineString | None:
    """Return the route as one line string, or None under two points.

    From the waypoints' columns when they have them: a batch of real fields has some 500,000
    waypoints, and making a :class:`Waypoint` and a tuple of each took a fifth of the planning.
    """
    from planner.types import Waypoints  # the planner loads on the worker, not the command

    if isinstance(waypoints, Waypoints):
        lon, lat, _, _ = waypoints.columns()
        points = np.column_stack((np.asarray(lon, dtype=float), np.asarray(lat, dtype=float)))
    else:
        points = np.array([(w.lon, w.lat) for w in waypoints], dtype=float).reshape(-1, 2)
    return shapely.LineString(points) if len(points) >= 2 else None


def plan_records(records: list[FieldRecord], options: dict[str, Any]) -> list[FieldResult]:
    """Plan each of ``records`` (one Dask task)."""
    return [plan_record(record, options) for record in records]
