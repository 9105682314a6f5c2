"""Thin adapters: request schema -> planner -> ORM row, and stored rows -> downloads.

No geometry is computed here: the planner parses, validates and plans; this module only moves
values between the planner's types, the schemas and the table. Planner errors pass through
untouched (``app.errors`` maps them to HTTP).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
import math
import re
import unicodedata
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, TypeVar

import numpy as np
from shapely import Polygon
from sqlalchemy import func, select
from sqlalchemy.orm import Session

import planner
from app import auth, budget
from app.auth import Access, owned, read_owned
from app.db import Base
from app.models import PLAN_NAME_MAX_LENGTH, Plan, Simulation, utc_now
from app.schemas import (
    ExportFormat,
    PlanCreate,
    PlanList,
    PlanSummary,
    SimulationCreate,
    SimulationList,
    SimulationSummary,
)
from app.track_fixes import check_text
from navigation import GuidanceParams, SimulationConfig, simulate
from navigation.export import simulation_to_geojson
from planner.export import (
    plan_from_geojson,
    plan_to_csv,
    plan_to_geojson,
    plan_to_gpkg,
    plan_to_gpx,
    plan_to_kml,
    plan_to_qgc_plan,
    plan_to_qgc_wpl,
    plan_to_waypoints_json,
)
from planner.export.gpx import GpxTrack
from planner.types import CoveragePlan, PlanStats, Waypoint

#: Ids outside this range cannot exist (``plans.id`` is a 32-bit integer): 404 at once.
MAX_ID: Final = auth.MAX_ID
RowT = TypeVar("RowT", bound=Base)
#: Planning budget of a large field in one request [s] (``Settings.planning_budget_s``).
DEFAULT_PLANNING_BUDGET_S: Final = 1.5

#: Media type and file extension of each download.
EXPORT_TYPES: Final[dict[str, tuple[str, str]]] = {
    "gpx": ("application/gpx+xml", "gpx"),
    "geojson": ("application/geo+json", "geojson"),
    "csv": ("text/csv; charset=utf-8", "csv"),
    "json": ("application/json", "json"),
    "kml": ("application/vnd.google-earth.kml+xml", "kml"),
    "waypoints": ("text/plain; charset=utf-8", "waypoints"),
    "plan": ("application/json", "plan"),
    "gpkg": ("application/geopackage+sqlite3", "gpkg"),
}


@dataclass(frozen=True, slots=True)
class ExportFile:
    """A download: its text (or bytes, for a GeoPackage), media type and file name."""

    content: str | bytes
    media_type: str
    filename: str


def plan_field(body: PlanCreate, *, budget_s: float = DEFAULT_PLANNING_BUDGET_S) -> Plan:
    """Plan the request's field and return an unsaved :class:`Plan` row.

    Start and finish are the request's if given, else the field FeatureCollection's points
    with role ``start``/``finish``; the name likewise falls back on the field's name.

    Parameters
    ----------
    body : PlanCreate
        The validated request.
    budget_s : float
        Longest a large field may take to plan [s] (:mod:`app.budget`).

    Returns
    -------
    Plan
        Transient: ``id`` and ``created_at`` stay None until it is added and flushed.

    Raises
    ------
    PlannerError
        If the field or a parameter cannot be planned (the message names which).
    """
    spec = planner.parse_field_geojson(body.field)
    start = _position(body.start, "start") or spec.start_lonlat
    finish = _position(body.finish, "finish") or spec.finish_lonlat
    coverage = budget.plan_coverage(
        spec.field_lonlat,
        budget_s=budget_s,
        interval_m=body.interval_m,
        start_lonlat=start,
        finish_lonlat=finish,
        angle_deg=body.angle_deg,
        objective=body.objective,
        headland_passes=body.headland_passes,
        speed_mps=body.speed_mps,
        implement_width_m=body.implement_width_m,
        vehicle=_vehicle_spec(body),
        pattern=body.pattern,
    )
    name = (body.name or "").strip() or (spec.name or "").strip() or None
    if name is not None:
        name = name[:PLAN_NAME_MAX_LENGTH]
        try:
            check_text(name)
        except ValueError as exc:  # the field file's name: PostgreSQL cannot store a NUL
            raise planner.InvalidParameterError("name", str(exc)) from None
    request: dict[str, Any] = {
        "name": name,
        "field": polygon_to_geojson(spec.field_lonlat),
        "interval_m": body.interval_m,
        "start": list(start) if start else None,
        "finish": list(finish) if finish else None,
        "angle_deg": body.angle_deg,
        "objective": body.objective,
        "headland_passes": body.headland_passes,
        "speed_mps": body.speed_mps,
        "implement_width_m": body.implement_width_m,
        "vehicle": _vehicle_spec(body),
        "pattern": body.pattern,
    }
    return Plan(
        name=name,
        request=request,
        stats=coverage.stats.as_dict(),
        waypoints=[_waypoint_dict(w) for w in coverage.waypoints],
        geojson=plan_to_geojson(coverage, name=name),
    )


def read_stored(
    session: Session, model: type[RowT], ident: int, access: Access, *, kind: str
) -> RowT:
    """Return the stored ``model`` row with id ``ident`` of the request's organisation.

    Ids outside the 32-bit range are not looked up (PostgreSQL would fail on them).

    Raises
    ------
    NotFoundError
        ``<kind> <ident> not found``, if there is no such row in the organisation.
    """
    return read_owned(session, model, ident, access, kind=kind)


def read_plan(session: Session, plan_id: int, access: Access) -> Plan:
    """Return stored plan ``plan_id`` of the request's organisation.

    Raises
    ------
    NotFoundError
        If there is no such plan (or it is another organisation's).
    """
    return read_stored(session, Plan, plan_id, access, kind="plan")


def list_plans(
    session: Session,
    access: Access,
    *,
    limit: int,
    offset: int,
    field_id: int | None = None,
    q: str | None = None,
) -> PlanList:
    """Return a page of the organisation's plans, newest first, without their geometry.

    ``q`` keeps the plans whose name contains it (any case); ``total`` counts those.
    """
    query = owned(Plan, access)
    if field_id is not None:
        query = query.where(Plan.field_id == field_id)
    if q and q.strip():
        pattern = (
            "%" + q.strip().replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_") + "%"
        )
        query = query.where(Plan.name.ilike(pattern, escape="\\"))
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.execute(
        query.with_only_columns(Plan.id, Plan.name, Plan.created_at, Plan.stats, Plan.field_id)
        .order_by(Plan.created_at.desc(), Plan.id.desc())
        .limit(limit)
        .offset(offset)
    ).all()
    return PlanList(items=[PlanSummary.model_validate(row) for row in rows], total=total)


def export_plan(plan: Plan, fmt: ExportFormat) -> ExportFile:
    """Write stored ``plan`` as a download in format ``fmt``.

    GeoJSON is the stored collection itself; the other formats come from the planner's
    writers, fed with the stored plan (no re-planning). The missions (``waypoints``,
    ``plan``) set the speed the plan was made for.
    """
    media_type, extension = EXPORT_TYPES[fmt]
    filename = f"{export_basename(plan)}.{extension}"
    content: str | bytes
    if fmt == "geojson":
        content = _json_text(plan.geojson)
    else:
        coverage = coverage_plan_from_row(plan)
        title = plan.name or f"plan {plan.id}"
        speed_mps = float((plan.request or {}).get("speed_mps") or planner.DEFAULT_SPEED_MPS)
        if fmt == "gpx":
            content = plan_to_gpx(coverage, name=title)
        elif fmt == "csv":
            content = plan_to_csv(coverage)
        elif fmt == "kml":
            content = plan_to_kml(coverage, name=title)
        elif fmt == "waypoints":
            content = plan_to_qgc_wpl(coverage, speed_mps=speed_mps)
        elif fmt == "plan":
            content = _json_text(plan_to_qgc_plan(coverage, speed_mps=speed_mps))
        elif fmt == "gpkg":
            content = plan_to_gpkg(coverage, name=title)
        else:
            content = _json_text(plan_to_waypoints_json(coverage))
    return ExportFile(content=content, media_type=media_type, filename=filename)


def export_basename(plan: Plan) -> str:
    """Return a safe file name stem from the plan's name, else ``plan-<id>``.

    Examples
    --------
    >>> export_basename(Plan(id=7, name="Sawah Ketewel – blok 3"))
    'sawah-ketewel-blok-3'
    >>> export_basename(Plan(id=7, name="../"))
    'plan-7'
    """
    ascii_name = unicodedata.normalize("NFKD", plan.name or "").encode("ascii", "ignore").decode()
    slug = re.sub(r"[^a-z0-9]+", "-", ascii_name.lower()).strip("-")[:60].strip("-")
    return slug or f"plan-{plan.id}"


def coverage_plan_from_row(plan: Plan) -> CoveragePlan:
    """Rebuild the planner's :class:`CoveragePlan` from a stored row, for the writers.

    The stored GeoJSON holds the whole plan (``planner.export.plan_from_geojson`` reads it
    back); the figures come from the row, which also keeps ``planning_ms``.
    """
    stats_fields = {f.name for f in dataclasses.fields(PlanStats)}
    stats = PlanStats(**{k: v for k, v in plan.stats.items() if k in stats_fields})
    restored = plan_from_geojson(plan.geojson)
    vehicle = restored.vehicle
    if vehicle is None and isinstance(stats.vehicle, dict):
        vehicle = planner.resolve_vehicle(None)
        vehicle = dataclasses.replace(vehicle, **stats.vehicle)
    return dataclasses.replace(restored, stats=stats, vehicle=vehicle)


def polygon_to_geojson(polygon: Polygon) -> dict[str, Any]:
    """Return ``polygon`` as a GeoJSON Polygon geometry, coordinates at full precision."""
    rings = [polygon.exterior, *polygon.interiors]
    return {
        "type": "Polygon",
        "coordinates": [[[x, y] for x, y, *_ in ring.coords] for ring in rings],
    }


def simulate_plan(
    plan: Plan,
    body: SimulationCreate,
    *,
    date: dt.date | None = None,
    on_waypoint: Callable[[int, int], None] | None = None,
) -> Simulation:
    """Drive stored ``plan`` with the simulated tractor; return an unsaved :class:`Simulation`.

    Parameters
    ----------
    plan : Plan
        A stored plan (its ``id`` is set).
    body : SimulationCreate
        Seed, GPS preset and guidance mode.
    date : date, optional
        Date of the run, for the magnetic declination; default today (UTC). It is stored in
        the configuration, so the run can be repeated exactly.
    on_waypoint : callable, optional
        Progress hook, passed to :func:`navigation.simulate`.

    Returns
    -------
    Simulation

    Raises
    ------
    NavigationError
        If the plan cannot be driven (the message names why).
    """
    date = date or utc_now().date()
    config = SimulationConfig(gps=body.gps, guidance=GuidanceParams(mode=body.guidance), date=date)
    log = simulate(
        coverage_plan_from_row(plan),
        config,
        np.random.default_rng(body.seed),
        on_waypoint=on_waypoint,
    )
    return Simulation(
        plan_id=plan.id,
        organisation_id=plan.organisation_id,
        config={
            "seed": body.seed,
            "gps": body.gps,
            "guidance": body.guidance,
            "date": date.isoformat(),
            "vehicle": log.config.vehicle.preset if log.config.vehicle else None,
        },
        metrics=json_ready(log.metrics.as_dict()),
        tracks=json_ready(simulation_to_geojson(log)),
    )


def read_simulation(session: Session, simulation_id: int, access: Access) -> Simulation:
    """Return stored simulation ``simulation_id`` of the request's organisation.

    Raises
    ------
    NotFoundError
        If there is no such simulation (or it is another organisation's).
    """
    return read_stored(session, Simulation, simulation_id, access, kind="simulation")


def list_simulations(session: Session, plan: Plan, access: Access) -> SimulationList:
    """Return the stored simulations of ``plan``, newest first, without their tracks."""
    rows = session.scalars(
        owned(Simulation, access)
        .where(Simulation.plan_id == plan.id)
        .order_by(Simulation.created_at.desc(), Simulation.id.desc())
    ).all()
    items = [SimulationSummary.model_validate(row) for row in rows]
    return SimulationList(items=items, total=len(items))


def export_simulation_gpx(session: Session, simulation: Simulation, access: Access) -> ExportFile:
    """Write a stored simulation as GPX: the plan as ``<rte>``, its three tracks as ``<trk>``.

    The tracks are the stored ones (one vertex per second), timed from midnight UTC of the
    simulation's date, as :func:`navigation.export.simulation_to_gpx` does.
    """
    return export_simulation(session, simulation, access, "gpx")


def export_simulation(
    session: Session, simulation: Simulation, access: Access, fmt: str
) -> ExportFile:
    """Write a stored simulation as ``gpx`` or ``kml`` (its tracks as ``gx:Track``)."""
    plan = read_plan(session, simulation.plan_id, access)
    start = dt.datetime.combine(
        dt.date.fromisoformat(simulation.config["date"]), dt.time(0, 0), tzinfo=dt.UTC
    )
    tracks = []
    for feature in simulation.tracks.get("features", []):
        props = feature.get("properties") or {}
        coords = feature["geometry"]["coordinates"]
        times = props.get("time_s") or []
        if len(times) < len(coords):  # a one-point track is written as two equal vertices
            coords = coords[: len(times)]
        tracks.append(
            GpxTrack(
                name=str(props.get("source", "track")),
                lon=[c[0] for c in coords],
                lat=[c[1] for c in coords],
                time=[start + dt.timedelta(seconds=float(t)) for t in times],
            )
        )
    title = f"{plan.name or f'plan {plan.id}'}: simulation {simulation.id}"
    writer = plan_to_kml if fmt == "kml" else plan_to_gpx
    content = writer(coverage_plan_from_row(plan), name=title, tracks=tracks)
    filename = f"{export_basename(plan)}-simulation-{simulation.id}.{fmt}"
    return ExportFile(content=content, media_type=EXPORT_TYPES[fmt][0], filename=filename)


def json_ready(value: Any) -> Any:
    """Return ``value`` with tuples as lists and non-finite floats as None (JSON columns).

    Examples
    --------
    >>> json_ready({"a": (1.0, float("nan")), "b": [float("inf")]})
    {'a': [1.0, None], 'b': [None]}
    """
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    return value


def _vehicle_spec(body: PlanCreate) -> str | dict[str, Any]:
    """Return the request's vehicle as the planner takes it: a preset name or overrides."""
    if isinstance(body.vehicle, str):
        return body.vehicle
    return body.vehicle.overrides()


def _position(value: tuple[float, float] | None, name: str) -> tuple[float, float] | None:
    return None if value is None else planner.parse_position(value, input_name=name)


def _waypoint_dict(waypoint: Waypoint) -> dict[str, Any]:
    return {
        "seq": waypoint.seq,
        "lon": waypoint.lon,
        "lat": waypoint.lat,
        "role": waypoint.role,
        "line": waypoint.line,
    }


def _json_text(obj: Any) -> str:
    return json.dumps(obj, ensure_ascii=False, allow_nan=False) + "\n"
