"""Simulations: drive a stored plan with the simulated tractor (product.md §5, §7)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Response, status

from app import services
from app.auth import Planner, Viewer
from app.db import SessionDep
from app.display import TrackDetail, display_tracks
from app.models import Simulation
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
    response_model=SimulationRead,
    status_code=status.HTTP_201_CREATED,
    responses={**_BAD_INPUT, **_NOT_FOUND},
)
def create_simulation(
    plan_id: int,
    session: SessionDep,
    access: Planner,
    response: Response,
    body: SimulationCreate | None = None,
    tracks: TracksQuery = "full",
) -> Simulation | SimulationRead:
    """Simulate the tractor driving a stored plan; store and return the run.

    The body is optional (defaults: seed 0, `m8n`, `waypoint`).
    """
    plan = services.read_plan(session, plan_id, access)
    simulation = services.simulate_plan(plan, body or SimulationCreate())
    session.add(simulation)
    session.commit()
    response.headers["Location"] = f"/api/simulations/{simulation.id}"
    return _answer(simulation, tracks)


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
    return Response(
        content=export.content,
        media_type=export.media_type,
        headers={"Content-Disposition": f'attachment; filename="{export.filename}"'},
    )


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
    return Response(
        content=export.content,
        media_type=export.media_type,
        headers={"Content-Disposition": f'attachment; filename="{export.filename}"'},
    )
