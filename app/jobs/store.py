"""The jobs table's state machine: every write a job's life makes, each one guarded.

A job goes ``queued`` → ``running`` (a worker *claims* it and gets a lease) → ``done`` or
``failed``; ``cancelled`` is reachable from both of the first two. Each write is one
conditional ``UPDATE`` (``WHERE status = …`` and, for a worker, ``AND lease_token = …``), so two
workers, a worker and a cancel, or a worker and a restarted server can race and the database
decides: a job is claimed by one attempt at a time and finished once.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable
from typing import Any, Final, cast

from sqlalchemy import CursorResult, Engine, select, update
from sqlalchemy.orm import Session

from app.auth import Access
from app.db import end_reads
from app.models import Job, utc_now

#: How long a worker's lease lasts unless renewed by a progress report [s]. A running job whose
#: lease has lapsed (its worker died with the machine) is queued again by the engine's sweep.
LEASE_S: Final = 20.0
#: How many times a job is started before a lost worker counts as the job's failure.
MAX_ATTEMPTS: Final = 3
#: Longest error message stored [characters] (the column's width).
ERROR_MAX_LENGTH: Final = 2000


def _rowcount(result: Any) -> int:
    """Return how many rows an ``UPDATE`` changed."""
    return int(cast(CursorResult[Any], result).rowcount)


class JobStoppedError(Exception):
    """The attempt no longer holds the job: it was cancelled, or another attempt took over."""


def create_job(session: Session, access: Access, kind: str, params: dict[str, Any]) -> Job:
    """Insert a queued job of ``access``'s organisation and commit; return it (with its ``id``).

    Who asked (``access``'s user, role and way in) is kept in the job's parameters as
    ``requested_by``: the worker acts with that access, in that organisation only.

    What ``session`` read before (the plan) is committed first: on SQLite a read transaction
    cannot turn into a write once a worker has written since it began (``database is locked``).
    """
    end_reads(session)
    now = utc_now()
    requested_by = {"user_id": access.user_id, "role": access.role, "via": access.via}
    job = Job(
        organisation_id=access.organisation_id,
        kind=kind,
        params={**params, "requested_by": requested_by},
        status="queued",
        progress=0.0,
        attempts=0,
        created_at=now,
        updated_at=now,
    )
    session.add(job)
    session.commit()
    return job


def _lease_end(now: dt.datetime) -> dt.datetime:
    return now + dt.timedelta(seconds=LEASE_S)


def claim(engine: Engine, job_id: int, *, owner: str, token: str) -> Job | None:
    """Take queued job ``job_id`` for one attempt; return it, or None if it is not queued.

    Parameters
    ----------
    engine : Engine
        The jobs' database.
    job_id : int
        The job.
    owner : str
        The engine (server start) whose worker runs the attempt.
    token : str
        This attempt's lease token.
    """
    now = utc_now()
    with Session(engine, expire_on_commit=False) as session, session.begin():
        claimed = _rowcount(
            session.execute(
                update(Job)
                .where(Job.id == job_id, Job.status == "queued")
                .values(
                    status="running",
                    attempts=Job.attempts + 1,
                    lease_owner=owner,
                    lease_token=token,
                    lease_expires_at=_lease_end(now),
                    started_at=now,
                    updated_at=now,
                )
            )
        )
        if claimed != 1:
            return None
        return session.get(Job, job_id)


def report_progress(engine: Engine, job_id: int, token: str, progress: float) -> None:
    """Record ``progress`` (0–1) and renew the lease.

    Raises
    ------
    JobStoppedError
        If the attempt no longer holds the job (cancelled, or run again elsewhere).
    """
    now = utc_now()
    with engine.begin() as conn:
        updated = _rowcount(
            conn.execute(
                update(Job)
                .where(Job.id == job_id, Job.lease_token == token, Job.status == "running")
                .values(
                    progress=min(max(progress, 0.0), 1.0),
                    lease_expires_at=_lease_end(now),
                    updated_at=now,
                )
            )
        )
    if updated != 1:
        raise JobStoppedError(f"job {job_id}: the attempt no longer holds the job")


#: Writes a job's product in the finishing transaction; returns ``(result, result_url)``.
Finish = Callable[[Session], tuple[dict[str, Any], str | None]]


def complete(engine: Engine, job_id: int, token: str, finish: Finish) -> None:
    """Store the job's product and mark it done, in one transaction, if the attempt holds it.

    Raises
    ------
    JobStoppedError
        If the attempt no longer holds the job; nothing ``finish`` wrote is kept.
    """
    with Session(engine) as session, session.begin():
        result, result_url = finish(session)
        session.flush()
        now = utc_now()
        done = _rowcount(
            session.execute(
                update(Job)
                .where(Job.id == job_id, Job.lease_token == token, Job.status == "running")
                .values(
                    status="done",
                    progress=1.0,
                    result=result,
                    result_url=result_url,
                    error=None,
                    lease_token=None,
                    lease_expires_at=None,
                    updated_at=now,
                    finished_at=now,
                )
            )
        )
        if done != 1:
            # Raising inside ``session.begin()`` rolls back what ``finish`` added.
            raise JobStoppedError(f"job {job_id}: the attempt no longer holds the job")


def fail(engine: Engine, job_id: int, token: str, message: str) -> None:
    """Mark the job failed with ``message``, if the attempt still holds it."""
    now = utc_now()
    with engine.begin() as conn:
        conn.execute(
            update(Job)
            .where(Job.id == job_id, Job.lease_token == token, Job.status == "running")
            .values(
                status="failed",
                error=message[:ERROR_MAX_LENGTH],
                lease_token=None,
                lease_expires_at=None,
                updated_at=now,
                finished_at=now,
            )
        )


def cancel(session: Session, job_id: int) -> bool:
    """Cancel a queued or running job; return False if it had already finished.

    A running attempt notices at its next progress report (within a second) and stops; what
    it computed is not stored.
    """
    end_reads(session)
    now = utc_now()
    result = session.execute(
        update(Job)
        .where(Job.id == job_id, Job.status.in_(("queued", "running")))
        .values(
            status="cancelled",
            lease_token=None,
            lease_expires_at=None,
            updated_at=now,
            finished_at=now,
        )
    )
    session.commit()
    return _rowcount(result) == 1


def release(engine: Engine, owner: str) -> int:
    """Queue again the running jobs of engine ``owner`` (its workers are being stopped).

    Their attempts can then neither report nor finish; the next server start runs them.

    Returns
    -------
    int
        How many jobs were released.
    """
    now = utc_now()
    with engine.begin() as conn:
        result = conn.execute(
            update(Job)
            .where(Job.status == "running", Job.lease_owner == owner)
            .values(status="queued", lease_token=None, lease_expires_at=None, updated_at=now)
        )
    return _rowcount(result)


def requeue_lapsed(engine: Engine) -> None:
    """Queue again the running jobs whose lease lapsed (their worker was lost).

    A job lost :data:`MAX_ATTEMPTS` times fails instead, with a message that says so.
    """
    now = utc_now()
    lapsed = (Job.status == "running", Job.lease_expires_at < now)
    with engine.begin() as conn:
        conn.execute(
            update(Job)
            .where(*lapsed, Job.attempts >= MAX_ATTEMPTS)
            .values(
                status="failed",
                error=(
                    f"job: its worker was lost {MAX_ATTEMPTS} times (out of memory, or the "
                    "machine stopped); not tried again"
                ),
                lease_token=None,
                lease_expires_at=None,
                updated_at=now,
                finished_at=now,
            )
        )
        conn.execute(
            update(Job)
            .where(*lapsed)
            .values(status="queued", lease_token=None, lease_expires_at=None, updated_at=now)
        )


def queued_ids(engine: Engine) -> list[int]:
    """Return the ids of the queued jobs, oldest first."""
    with engine.connect() as conn:
        rows = conn.execute(select(Job.id).where(Job.status == "queued").order_by(Job.id))
        return [row[0] for row in rows]
