"""The web side of the jobs: submit from a route, read and cancel, and the app's lifespan."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Annotated, Any

from fastapi import Depends, FastAPI, Request
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session

from app.auth import Access
from app.errors import ConflictError, UnavailableError
from app.jobs import store
from app.jobs.engine import JobEngine
from app.models import Job
from app.services import read_stored
from app.settings import Settings

logger = logging.getLogger(__name__)


class JobsUnavailableError(UnavailableError):
    """The server has no job engine (in-memory SQLite cannot be shared with worker processes)."""


def shares_database(url: str) -> bool:
    """Tell whether worker processes can open ``url`` (a file or a server, not in-memory).

    Examples
    --------
    >>> shares_database("sqlite://"), shares_database("sqlite:///data/tillpath.db")
    (False, True)
    """
    parsed = make_url(url)
    if parsed.get_backend_name() != "sqlite":
        return True
    database = parsed.database or ""
    return database not in ("", ":memory:") and "mode=memory" not in database


@asynccontextmanager
async def jobs_lifespan(app: FastAPI, settings: Settings) -> AsyncIterator[None]:
    """Start the job engine with the app and stop it (and its local cluster) with it.

    On in-memory SQLite there is no engine: job routes answer 503 saying why.
    """
    engine: JobEngine | None = None
    if shares_database(settings.database_url):
        engine = JobEngine(
            settings.database_url,
            scheduler_address=settings.dask_scheduler,
            n_workers=settings.dask_workers,
        )
    # The cluster starts in the background (Dask's synchronous API runs its own event loop
    # thread, and worker processes take seconds to start): the server answers meanwhile, and
    # jobs asked for before it is up stay queued until its first sweep submits them.
    starting = None if engine is None else asyncio.create_task(asyncio.to_thread(engine.start))
    app.state.jobs = engine
    try:
        yield
    finally:
        app.state.jobs = None
        if engine is not None and starting is not None:
            try:
                await starting
            except Exception:
                logger.exception("the job engine did not start; queued jobs wait for the next")
            await asyncio.to_thread(engine.stop)


def get_jobs(request: Request) -> JobEngine:
    """Return the app's job engine.

    Raises
    ------
    JobsUnavailableError
        If the app runs without one.
    """
    engine: JobEngine | None = getattr(request.app.state, "jobs", None)
    if engine is None:
        raise JobsUnavailableError(
            "jobs: this server runs no job engine (background jobs need a database file or "
            "server that worker processes can open, not in-memory SQLite)"
        )
    return engine


JobsDep = Annotated[JobEngine, Depends(get_jobs)]


def submit_job(
    session: Session, jobs: JobEngine, access: Access, kind: str, params: dict[str, Any]
) -> Job:
    """Insert a queued job of ``kind`` for the request's organisation; return it at once.

    The job belongs to ``access``'s organisation, and its worker acts with ``access``'s
    user and role (:attr:`app.jobs.runner.JobContext.access`). If the engine cannot take it
    now (the scheduler is away), the job stays queued and the engine's sweep submits it later.
    """
    job = store.create_job(session, access, kind, params)
    try:
        jobs.submit(job.id)  # a no-op while the engine starts: its first sweep submits the job
    except Exception:
        logger.warning("job %s stays queued: the engine refused it for now", job.id, exc_info=True)
    return job


def read_job(session: Session, job_id: int, access: Access) -> Job:
    """Return job ``job_id`` of the request's organisation, as the database has it now.

    Raises
    ------
    NotFoundError
        ``job <id> not found`` (also if it is another organisation's).
    """
    job = read_stored(session, Job, job_id, access, kind="job")
    session.refresh(job)
    return job


def cancel_job(session: Session, jobs: JobEngine | None, job_id: int, access: Access) -> Job:
    """Cancel job ``job_id`` and return it.

    Raises
    ------
    NotFoundError
        If there is no such job.
    ConflictError
        If it has already finished.
    """
    job = read_job(session, job_id, access)
    if not store.cancel(session, job_id):
        raise ConflictError(f"job {job_id}: already {job.status}, nothing to cancel")
    if jobs is not None:
        jobs.cancel(job_id)
    return read_job(session, job_id, access)
