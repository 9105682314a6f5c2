"""``/api/plans``: preview, create, list, read, delete and export plans (product.md §5)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Query, Response, status
from fastapi.concurrency import run_in_threadpool
from sqlalchemy.orm import Session

from app import fields, services
from app.auth import Planner, Viewer
from app.capacity import HeavyWorkDep
from app.db import SessionDep, copy_row, delete_row, end_reads, write
from app.dependencies import SettingsDep
from app.models import Plan
from app.routers.downloads import download
from app.schemas import ErrorRead, ExportFormat, PlanCreate, PlanList, PlanRead

router = APIRouter(prefix="/plans", tags=["plans"])

_BAD_INPUT: dict[int | str, dict[str, Any]] = {
    422: {"model": ErrorRead, "description": "The input named in `detail` is wrong"}
}
_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorRead, "description": "No such plan"}
}
_TOO_LARGE: dict[int | str, dict[str, Any]] = {
    413: {"model": ErrorRead, "description": "Body over the configured limit"}
}
_BUSY: dict[int | str, dict[str, Any]] = {
    503: {"model": ErrorRead, "description": "Server busy: retry after `Retry-After` seconds"}
}


@router.post("/preview", response_model=PlanRead, responses={**_BAD_INPUT, **_TOO_LARGE, **_BUSY})
async def preview_plan(
    body: PlanCreate,
    session: SessionDep,
    access: Viewer,
    settings: SettingsDep,
    heavy: HeavyWorkDep,
) -> Plan:
    """Plan a coverage path without storing it (``id`` and ``created_at`` are null)."""

    def plan() -> Plan:
        resolved = fields.resolve_plan_body(session, body, access)
        end_reads(session)  # no connection held while planning
        with heavy.slot("preview"):
            return services.plan_field(resolved, budget_s=settings.planning_budget_s)

    # Async with one worker thread for the work: FastAPI validates a sync route's answer in
    # a thread hop of its own, and this is the busiest route (product.md §11: 150 per second).
    # The answer is a transient row (no lazy loads), validated and encoded on the loop.
    return await run_in_threadpool(plan)


@router.post(
    "",
    response_model=PlanRead,
    status_code=status.HTTP_201_CREATED,
    responses={**_BAD_INPUT, **_TOO_LARGE, **_BUSY},
)
def create_plan(
    body: PlanCreate,
    session: SessionDep,
    access: Planner,
    settings: SettingsDep,
    response: Response,
    heavy: HeavyWorkDep,
) -> Plan:
    """Plan a coverage path and store it; ``Location`` names the new plan.

    With `field_id` the registry's field is planned; a drawn `field` creates a field in the
    registry, or reuses the organisation's field with the same boundary.
    """
    resolved = fields.resolve_plan_body(session, body, access)
    end_reads(session)  # no connection held while planning
    with heavy.slot("plan"):
        planned = services.plan_field(resolved, budget_s=settings.planning_budget_s)

    def store(s: Session) -> Plan:
        plan = copy_row(planned)  # afresh for each try of the write
        fields.attach_field(s, plan, resolved, access)
        return plan

    plan = write(session, store)
    response.headers["Location"] = f"/api/plans/{plan.id}"
    return plan


@router.get("", response_model=PlanList, responses=_BAD_INPUT)
def list_plans(
    session: SessionDep,
    access: Viewer,
    limit: Annotated[int, Query(ge=1, le=200, description="Page size.")] = 50,
    offset: Annotated[int, Query(ge=0, le=1_000_000_000, description="Plans to skip.")] = 0,
    field_id: Annotated[
        int | None, Query(ge=1, le=services.MAX_ID, description="Only the plans of this field.")
    ] = None,
    q: Annotated[
        str | None, Query(max_length=200, description="Only plans whose name contains this.")
    ] = None,
) -> PlanList:
    """List the organisation's plans, newest first, with their figures but no geometry."""
    return services.list_plans(session, access, limit=limit, offset=offset, field_id=field_id, q=q)


@router.get("/{plan_id}", response_model=PlanRead, responses={**_NOT_FOUND, **_BAD_INPUT})
def read_plan(plan_id: int, session: SessionDep, access: Viewer) -> Plan:
    """Return one stored plan with its request, figures, waypoints and GeoJSON."""
    return services.read_plan(session, plan_id, access)


@router.delete(
    "/{plan_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    response_class=Response,
    responses={**_NOT_FOUND, **_BAD_INPUT},
)
def delete_plan(plan_id: int, session: SessionDep, access: Planner) -> None:
    """Delete a stored plan with its simulations and runs."""
    services.read_plan(session, plan_id, access)
    delete_row(session, Plan, plan_id, kind="plan")


@router.get(
    "/{plan_id}/export/{format}",
    response_class=Response,
    responses={
        200: {
            "description": "The plan as a file download",
            "content": {media: {} for media, _ in services.EXPORT_TYPES.values()},
        },
        **_NOT_FOUND,
        **_BAD_INPUT,
    },
)
def export_plan(
    plan_id: int,
    fmt: Annotated[ExportFormat, Path(alias="format", description="File format.")],
    session: SessionDep,
    access: Viewer,
) -> Response:
    """Download a stored plan as GPX, GeoJSON, CSV or waypoints JSON."""
    export = services.export_plan(services.read_plan(session, plan_id, access), fmt)
    return download(export)
