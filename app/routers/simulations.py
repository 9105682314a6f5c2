"""Simulations: drive a stored plan with the simulated tractor (product.md §5, §7, §13)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Request, Response, status

from app import services
from app.auth import Planner, Viewer
from app.db import SessionDep
from app.display import TrackDetail, display_tracks
from app.jobs import get_jobs, submit_job
from app.jobs.schemas import JobRead
from app.jobs.simulations import simulation_params
from app.models import Job, Simulation, utc_now
from app.routers.downloads import download
from app.schemas import (
    ErrorRead,
    SimulationCreate,
    SimulationList,
    SimulationRead,
)

router = APIRouter(tags=["simulations"])

_BAD_INPUT: dict[int | str, dict[str, Any]] = {
    422: {"model": ErrorRead, "description": "The input named in `detail` is wrong"}
}
_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorRead, "description": "No such plan or simulation"}
}
#: ``?tracks=display``: only the true track, thinned for drawing (app/display.py).
TracksQuery = Annotated[
    TrackDetail,
    Query(description="`full` (every second, three tracks) or `display` (true track, thinned)."),
]


def _answer(simulation: Simulation, tracks: TrackDetail) -> Simulation | SimulationRead:
    if tracks == "full":
        return simulation
    answer = SimulationRead.model_validate(simulation)
    return answer.model_copy(update={"tracks": display_tracks(simulation.tracks)})


@router.post(
    "/plans/{plan_id}/simulations",
    response_model=JobRead,
    status_code=status.HTTP_202_ACCEPTED,
    responses={
        **_BAD_INPUT,
        **_NOT_FOUND,
        503: {
            "model": ErrorRead,
            "description": "No job engine, or server busy: retry after `Retry-After` seconds",
        },
    },
)
def create_simulation(
    plan_id: int,
    session: SessionDep,
    access: Planner,
    request: Request,
    response: Response,
    body: SimulationCreate | None = None,
) -> Job:
    """Simulate the tractor driving a stored plan, as a background job (product.md §13).

    Answers 202 at once with the job and `Location: /api/jobs/{id}`; the job's `result_url`
    names the stored simulation when it is done. With `runs` > 1 it is a Monte Carlo batch
    over seeds `seed … seed+runs-1`: the result summarises each metric, and the stored
    simulation is the run of median cross-track RMS. The body is optional (defaults: seed 0,
    `m8n`, `waypoint`, one run).
    """
    plan = services.read_plan(session, plan_id, access)
    jobs = get_jobs(request)  # after the plan: a missing plan is 404 whatever the engine
    body = body or SimulationCreate()
    kind = "monte_carlo" if body.runs > 1 else "simulation"
    params = simulation_params(plan.id, body, utc_now().date())
    job = submit_job(session, jobs, access, kind, params)
    response.headers["Location"] = f"/api/jobs/{job.id}"
    return job


@router.get(
    "/plans/{plan_id}/simulations",
    response_model=SimulationList,
    responses={**_BAD_INPUT, **_NOT_FOUND},
)
def list_simulations(plan_id: int, session: SessionDep, access: Viewer) -> SimulationList:
    """List a stored plan's simulations, newest first, with their metrics but no tracks."""
    return services.list_simulations(session, services.read_plan(session, plan_id, access), access)


@router.get(
    "/simulations/{simulation_id}",
    response_model=SimulationRead,
    responses={**_BAD_INPUT, **_NOT_FOUND},
)
def read_simulation(
    simulation_id: int, session: SessionDep, access: Viewer, tracks: TracksQuery = "full"
) -> Simulation | SimulationRead:
    """Return a stored simulation with its metrics and tracks."""
    return _answer(services.read_simulation(session, simulation_id, access), tracks)


@router.get(
    "/simulations/{simulation_id}/export/gpx",
    response_class=Response,
    responses={
        200: {"description": "GPX 1.1 download", "content": {"application/gpx+xml": {}}},
        **_NOT_FOUND,
        **_BAD_INPUT,
    },
)
def export_simulation_gpx(simulation_id: int, session: SessionDep, access: Viewer) -> Response:
    """Download a simulation as GPX: the plan as a route, true/estimated/GPS tracks as tracks."""
    simulation = services.read_simulation(session, simulation_id, access)
    export = services.export_simulation_gpx(session, simulation, access)
    return download(export)


@router.get(
    "/simulations/{simulation_id}/export/kml",
    response_class=Response,
    responses={
        200: {
            "description": "KML 2.2 download",
            "content": {"application/vnd.google-earth.kml+xml": {}},
        },
        **_NOT_FOUND,
        **_BAD_INPUT,
    },
)
def export_simulation_kml(simulation_id: int, session: SessionDep, access: Viewer) -> Response:
    """Download a simulation as KML: the plan, true/estimated/GPS tracks as ``gx:Track``."""
    simulation = services.read_simulation(session, simulation_id, access)
    export = services.export_simulation(session, simulation, access, "kml")
    return download(export)
