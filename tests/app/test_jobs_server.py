"""Jobs on the real server (``tillpath serve``): restarts, and the local cluster's processes."""

from __future__ import annotations

import json
import time
import urllib.request
from pathlib import Path
from typing import Any

import psutil
import pytest
from sqlalchemy import create_engine, func, select
from sqlalchemy.orm import Session

from app.models import Job, Simulation
from app.testing import ServerUrl, running_server

pytestmark = pytest.mark.slow


def call(base: ServerUrl, path: str, body: Any = None) -> tuple[int, Any, Any]:
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(
        base + path, data=data, headers={"Content-Type": "application/json", **base.headers}
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        return response.status, response.headers, json.loads(response.read() or b"null")


def wait_until(base: ServerUrl, location: str, done: Any, timeout_s: float = 90) -> dict[str, Any]:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        job: dict[str, Any] = call(base, location)[2]
        if done(job):
            return job
        time.sleep(0.2)
    raise AssertionError(f"job at {location} did not get there in {timeout_s} s: {job}")


def test_a_running_job_survives_a_restart_and_completes_once(
    tmp_path: Path, paper_body: dict[str, Any], monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.setenv("TILLPATH_DASK_WORKERS", "1")
    url = f"sqlite:///{tmp_path / 'restart.db'}"
    with running_server(url, log=tmp_path / "first.log") as base:
        plan = call(base, "/api/plans", paper_body)[2]
        status, headers, job = call(base, f"/api/plans/{plan['id']}/simulations", {"runs": 60})
        assert status == 202
        location = headers["Location"]
        running = wait_until(base, location, lambda j: j["progress"] > 0.02)
        assert running["status"] == "running"
    # Stopped mid-run: the job is queued again, for the next start.
    engine = create_engine(url)
    with Session(engine) as session:
        row = session.get(Job, job["id"])
        assert row is not None
        assert (row.status, row.attempts, row.lease_token) == ("queued", 1, None)
    with running_server(url, log=tmp_path / "second.log") as base:
        finished = wait_until(base, location, lambda j: j["status"] not in ("queued", "running"))
    assert finished["status"] == "done", finished
    assert finished["attempts"] == 2
    assert finished["result"]["runs"] == 60
    with Session(engine) as session:
        stored = session.scalar(
            select(func.count()).select_from(Simulation).where(Simulation.plan_id == plan["id"])
        )
    assert stored == 1
    engine.dispose()


def command_line(process: psutil.Process) -> str:
    """The process's command line, or "" once it has exited (a zombie has none to read)."""
    try:
        return " ".join(process.cmdline())
    except psutil.Error:
        return ""


def children(process: psutil.Process) -> list[psutil.Process]:
    """The process's children, none once it has exited."""
    try:
        return process.children()
    except psutil.Error:
        return []


def test_the_local_cluster_starts_and_stops_with_the_server(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.setenv("TILLPATH_DASK_WORKERS", "2")
    me = psutil.Process()
    before = {p.pid for p in me.children(recursive=True)}
    with running_server(f"sqlite:///{tmp_path / 'cluster.db'}") as base:
        assert call(base, "/api/health")[0] == 200
        # The cluster starts in the background: the server and, soon, its two worker
        # processes (the nannies live in the server), forked by a forkserver that has
        # loaded the planner (app.preload).
        deadline = time.monotonic() + 60
        while True:
            # Short-lived helpers come and go meanwhile: one that has just exited is a
            # zombie whose command line cannot be read (psutil.ZombieProcess under load).
            started = [p for p in me.children(recursive=True) if p.pid not in before]
            forkservers = [p for p in started if "forkserver" in command_line(p)]
            workers = [c for f in forkservers for c in children(f)]
            if len(workers) >= 2 or time.monotonic() > deadline:
                break
            time.sleep(0.2)
        assert len(workers) >= 2, [command_line(p) for p in started]
    _gone, alive = psutil.wait_procs(started, timeout=15)
    assert alive == [], [command_line(p) for p in alive]
