"""Background jobs (product.md §5, §13): how far a job has got, and cancelling it."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request

from app.auth import Planner, Viewer
from app.db import SessionDep
from app.jobs.schemas import JobRead
from app.jobs.service import cancel_job, read_job
from app.models import Job
from app.schemas import ErrorRead

router = APIRouter(tags=["jobs"])

_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorRead, "description": "No such job"},
    422: {"model": ErrorRead, "description": "The input named in `detail` is wrong"},
}


@router.get("/jobs/{job_id}", response_model=JobRead, responses=_NOT_FOUND)
def read_job_status(job_id: int, session: SessionDep, access: Viewer) -> Job:
    """Return a job: its status, progress (0–1), and when done its result and `result_url`."""
    return read_job(session, job_id, access)


@router.delete(
    "/jobs/{job_id}",
    response_model=JobRead,
    responses={
        **_NOT_FOUND,
        409: {"model": ErrorRead, "description": "The job has already finished"},
    },
)
def cancel_job_route(job_id: int, session: SessionDep, access: Planner, request: Request) -> Job:
    """Cancel a queued or running job; a running one stops within a second, storing nothing."""
    return cancel_job(session, getattr(request.app.state, "jobs", None), job_id, access)
