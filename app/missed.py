"""Missed ground: the field a run's footprint did not cover, and a follow-up plan over it (§8).

:func:`missed_ground_geojson` turns a run's track into the polygons of the field it left
untilled (:func:`navigation.coverage.missed_ground`, with the implement width), for the API
answer and the map. :func:`plan_follow_up` plans a path over just those gaps: each gap is
planned like any field (same interval, objective and speed as the run's plan), the gaps
visited nearest first from the plan's start, and the pieces joined into one plan of the
original field whose cells are the gaps. It is stored as a plan like any other (exports,
simulations, runs), its request saying what it follows up.
"""

from __future__ import annotations

import dataclasses
import inspect
from typing import Any

import numpy as np
import shapely
from shapely import Polygon

import planner
from app import budget
from app.errors import ConflictError
from app.models import PLAN_NAME_MAX_LENGTH, Plan
from app.services import _waypoint_dict, coverage_plan_from_row, polygon_to_geojson
from navigation.coverage import implement_width_m, missed_ground
from navigation.metrics import to_local_xy
from planner.export import plan_to_geojson
from planner.projection import LocalFrame, field_frame
from planner.types import CoveragePlan, PathSegment, PlanStats, Waypoint


def _gaps(plan: Plan, lon: Any, lat: Any) -> tuple[CoveragePlan, LocalFrame, list[Polygon]]:
    coverage = coverage_plan_from_row(plan)
    frame = field_frame(coverage.field_lonlat)
    x, y = to_local_xy(frame, np.asarray(lon, dtype=float), np.asarray(lat, dtype=float))
    gaps = missed_ground(frame, coverage, x, y)
    return coverage, frame, gaps


def missed_ground_geojson(plan: Plan, track: Any) -> dict[str, Any]:
    """Return the field area a run's footprint missed, as a GeoJSON FeatureCollection.

    Parameters
    ----------
    plan : Plan
        The run's plan.
    track : RunTrack
        The run's fixes (``lon``, ``lat`` arrays).

    Returns
    -------
    dict
        One Polygon Feature per gap (``kind: missed``, ``index``, ``area_m2``), largest first;
        the collection's properties give ``area_m2`` in all, ``field_share`` and
        ``implement_width_m``.
    """
    coverage, frame, gaps = _gaps(plan, track.lon, track.lat)
    field_area = float(frame.to_local(coverage.field_lonlat).area)
    total = float(sum(g.area for g in gaps))
    features = [
        {
            "type": "Feature",
            "properties": {"kind": "missed", "index": i, "area_m2": round(g.area, 2)},
            "geometry": polygon_to_geojson(frame.to_lonlat(g)),
        }
        for i, g in enumerate(gaps)
    ]
    return {
        "type": "FeatureCollection",
        "properties": {
            "area_m2": round(total, 2),
            "field_share": total / field_area if field_area > 0 else 0.0,
            "implement_width_m": implement_width_m(coverage),
        },
        "features": features,
    }


def _plan_kwargs(request: dict[str, Any]) -> dict[str, Any]:
    """Pick the run's planning options that :func:`planner.plan_coverage` takes."""
    accepted = inspect.signature(planner.plan_coverage).parameters
    names = ("interval_m", "objective", "speed_mps", "vehicle", "implement_width_m", "pattern")
    return {k: request[k] for k in names if k in request and k in accepted}


def plan_follow_up(plan: Plan, track: Any, *, run_id: int, budget_s: float) -> Plan:
    """Plan a path over the gaps a run left; return an unsaved :class:`Plan` row.

    Each gap is planned within ``budget_s`` (:mod:`app.budget`, as any large field); a gap
    the planner refuses or cannot plan in time is left out and listed in
    ``request.follow_up.skipped_gaps`` with the reason.

    Raises
    ------
    ConflictError
        If the run left no gap worth going back for, or no gap can be planned.
    """
    coverage, frame, gaps = _gaps(plan, track.lon, track.lat)
    if not gaps:
        raise ConflictError(
            f"run {run_id}: its footprint covered the field; there is no missed ground to plan"
        )
    request = dict(plan.request)
    kwargs = _plan_kwargs(request)
    start = request.get("start")
    finish = request.get("finish")
    # Nearest gap first, from the gate (or the first gap, the largest, without one).
    remaining = list(gaps)
    ordered: list[Polygon] = []
    here = shapely.Point(frame.to_local_xy(*start)) if start else remaining[0].centroid
    while remaining:
        nearest = min(remaining, key=lambda g: g.distance(here))
        remaining.remove(nearest)
        ordered.append(nearest)
        here = nearest.centroid
    pieces: list[tuple[Polygon, CoveragePlan]] = []
    skipped: list[dict[str, Any]] = []
    position = tuple(start) if start else None
    for i, gap in enumerate(ordered):
        gap_lonlat = frame.to_lonlat(gap)
        try:
            part = budget.plan_coverage(
                gap_lonlat,
                budget_s=budget_s,
                start_lonlat=position,
                finish_lonlat=tuple(finish) if finish and i == len(ordered) - 1 else None,
                **kwargs,
            )
        except planner.PlannerError as exc:
            skipped.append({"area_m2": round(gap.area, 2), "reason": str(exc)})
            continue
        pieces.append((gap_lonlat, part))
        last = part.waypoints[-1]
        position = (last.lon, last.lat)
    if not pieces:
        raise ConflictError(
            f"run {run_id}: none of its {len(gaps)} gaps can be planned "
            f"({skipped[0]['reason'] if skipped else 'no gap'})"
        )
    joined = _join(coverage, pieces)
    name = f"{plan.name or f'plan {plan.id}'}: follow-up of run {run_id}"[:PLAN_NAME_MAX_LENGTH]
    request.update(
        {
            "name": name,
            "follow_up": {
                "plan_id": plan.id,
                "run_id": run_id,
                "gaps": [polygon_to_geojson(g) for g, _ in pieces],
                "skipped_gaps": skipped,
            },
        }
    )
    return Plan(
        organisation_id=plan.organisation_id,
        field_id=plan.field_id,
        name=name,
        request=request,
        stats=joined.stats.as_dict(),
        waypoints=[_waypoint_dict(w) for w in joined.waypoints],
        geojson=plan_to_geojson(joined, name=name),
    )


def _join(original: CoveragePlan, pieces: list[tuple[Polygon, CoveragePlan]]) -> CoveragePlan:
    """One plan of the original field from the gap plans, in order, lines numbered on."""
    waypoints: list[Waypoint] = []
    segments: list[PathSegment] = []
    line_offset = 0
    for k, (_, part) in enumerate(pieces):
        lines = [w.line for w in part.waypoints if w.line is not None]
        for j, w in enumerate(part.waypoints):
            if k > 0 and j == 0 and w.role == "start":
                continue  # where the previous gap's path ended
            role = w.role
            if k < len(pieces) - 1 and role == "finish":
                role = "turn"
            if k > 0 and role == "start":
                role = "turn"
            waypoints.append(
                dataclasses.replace(
                    w,
                    seq=len(waypoints),
                    role=role,
                    line=None if w.line is None else w.line + line_offset,
                )
            )
        for seg in part.segments:
            index = (
                seg.index + line_offset
                if seg.kind == "line" and seg.index is not None
                else seg.index
            )
            segments.append(dataclasses.replace(seg, index=index))
        line_offset += (max(lines) + 1) if lines else 0
    parts = [p for _, p in pieces]
    area = sum(p.stats.area_m2 for p in parts)
    stats = PlanStats(
        area_m2=area,
        line_count=sum(p.stats.line_count for p in parts),
        waypoint_count=len(waypoints),
        working_length_m=sum(p.stats.working_length_m for p in parts),
        turn_length_m=sum(p.stats.turn_length_m for p in parts),
        transit_length_m=sum(p.stats.transit_length_m for p in parts),
        path_length_m=sum(p.stats.path_length_m for p in parts),
        coverage_ratio=sum(p.stats.coverage_ratio * p.stats.area_m2 for p in parts) / area
        if area > 0
        else 0.0,
        angle_deg=parts[0].stats.angle_deg,
        estimated_time_s=sum(p.stats.estimated_time_s for p in parts),
        planning_ms=sum(p.stats.planning_ms for p in parts),
    )
    extra = {
        k: getattr(parts[0], k)
        for k in ("vehicle", "implement_width_m", "pattern")
        if hasattr(parts[0], k) and k in {f.name for f in dataclasses.fields(parts[0])}
    }
    return dataclasses.replace(
        original,
        waypoints=tuple(waypoints),
        segments=tuple(segments),
        stats=stats,
        cells_lonlat=tuple(g for g, _ in pieces),
        **extra,
    )


__all__ = ["missed_ground_geojson", "plan_follow_up"]
