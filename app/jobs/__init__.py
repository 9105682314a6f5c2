"""Background jobs (product.md §13): a table, an engine (Dask), and one way to submit.

A route inserts a row and submits; a worker runs pure ``planner``/``navigation`` code and
writes progress and the result back; the web process never waits. To add a kind of job (a
bulk field import, say), write ``run_import(context) -> Finish`` in a module of its own, add
``"field_import": "app.fields_import:run_import"`` to :data:`app.jobs.runner.JOB_KINDS`, and in
the route::

    job = submit_job(session, jobs, access, "field_import", {"upload": ...})
    response.headers["Location"] = f"/api/jobs/{job.id}"   # 202, JobRead as the body
"""

from __future__ import annotations

from app.jobs.service import (
    JobsDep,
    JobsUnavailableError,
    get_jobs,
    jobs_lifespan,
    read_job,
    submit_job,
)

__all__ = [
    "JobsDep",
    "JobsUnavailableError",
    "get_jobs",
    "jobs_lifespan",
    "read_job",
    "submit_job",
]
