"""What a Dask worker runs for a job: claim it, run its kind, report progress, finish once.

:func:`run_job` is the only function the engine submits. It runs in a worker process (never the
web process), opens the job's database itself, and calls the kind's function (a module path in
:data:`JOB_KINDS`, imported on the worker), which runs pure ``planner``/``navigation`` code and
returns a :data:`~app.jobs.store.Finish` that stores its product. Bad input the kind finds
(a plan that cannot be driven, a deleted plan) fails the job with the input's message; an
unexpected error fails it with the exception named, never silently.
"""

from __future__ import annotations

import importlib
import logging
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Final

from sqlalchemy import Engine
from sqlalchemy.orm import Session

from app.auth import Access
from app.db import get_engine
from app.errors import STATUS_CODES
from app.jobs import store

logger = logging.getLogger(__name__)

#: Job kind -> ``module:function`` run on the worker, as ``function(context) -> Finish``.
#: A new kind (a bulk field import) is a function and a line here.
JOB_KINDS: Final[dict[str, str]] = {
    "simulation": "app.jobs.simulations:run_simulation",
    "monte_carlo": "app.jobs.simulations:run_monte_carlo",
}
#: Progress is written at most this often [s] (and always at the end).
REPORT_EVERY_S: Final = 0.5


@dataclass
class JobContext:
    """What a kind's function gets: the job's parameters, its database and a progress hook.

    Attributes
    ----------
    job_id : int
    organisation_id : int
        The organisation the job belongs to.
    params : dict
        The job's ``params`` as stored.
    engine : Engine
        The job's database.
    token : str
        This attempt's lease token.
    """

    job_id: int
    organisation_id: int
    params: dict[str, Any]
    engine: Engine
    token: str
    _last_report: float = field(default=0.0, repr=False)

    def report(self, progress: float, *, force: bool = False) -> None:
        """Record ``progress`` (0–1), at most every :data:`REPORT_EVERY_S` unless ``force``.

        Raises
        ------
        JobStoppedError
            If the job was cancelled or taken over: the kind's function must let it through.
        """
        now = time.monotonic()
        if not force and now - self._last_report < REPORT_EVERY_S:
            return
        self._last_report = now
        store.report_progress(self.engine, self.job_id, self.token, progress)

    @property
    def access(self) -> Access:
        """The access of whoever asked for the job, in the job's organisation only."""
        who = self.params["requested_by"]
        return Access(
            organisation_id=self.organisation_id,
            role=str(who["role"]),
            user_id=int(who["user_id"]),
            via=who["via"],
        )

    @contextmanager
    def session(self) -> Iterator[Session]:
        """Open a short session on the job's database, for reading the job's inputs."""
        with Session(self.engine, expire_on_commit=False) as session:
            yield session


KindFunction = Callable[[JobContext], store.Finish]


def kind_function(kind: str) -> KindFunction:
    """Import and return the function that runs jobs of ``kind``.

    Raises
    ------
    KeyError
        If ``kind`` is not in :data:`JOB_KINDS`.
    """
    module_name, _, name = JOB_KINDS[kind].partition(":")
    function: KindFunction = getattr(importlib.import_module(module_name), name)
    return function


def warm_up() -> None:
    """Import every kind's module, so that a worker's first job does not wait for imports."""
    for kind in JOB_KINDS:
        kind_function(kind)


def _is_bad_input(exc: Exception) -> bool:
    """Tell whether ``exc`` is one the error table maps to a 4xx (its message names the input)."""
    return any(cls in STATUS_CODES and STATUS_CODES[cls] < 500 for cls in type(exc).__mro__)


def run_job(database_url: str, job_id: int, owner: str) -> str:
    """Run job ``job_id`` once, if it is still queued; return what became of the attempt.

    Parameters
    ----------
    database_url : str
        The jobs' database (the worker opens it itself).
    job_id : int
        The job.
    owner : str
        The submitting engine's id, kept in the lease.

    Returns
    -------
    str
        ``done``, ``failed``, ``stopped`` (cancelled or taken over while running) or
        ``skipped`` (not queued when the attempt began: done, cancelled or running elsewhere).
    """
    engine = get_engine(database_url)
    token = uuid.uuid4().hex
    job = store.claim(engine, job_id, owner=owner, token=token)
    if job is None:
        return "skipped"
    context = JobContext(
        job_id=job_id,
        organisation_id=job.organisation_id,
        params=job.params,
        engine=engine,
        token=token,
    )
    try:
        finish = kind_function(job.kind)(context)
        store.complete(engine, job_id, token, finish)
    except store.JobStoppedError:
        return "stopped"
    except Exception as exc:
        if _is_bad_input(exc):
            message = str(exc)
        else:
            logger.exception("job %s (%s) failed", job_id, job.kind)
            message = f"job: internal error ({type(exc).__name__}: {exc})"
        store.fail(engine, job_id, token, message)
        return "failed"
    return "done"
