"""The jobs API (product.md §5, §13) on a real Dask cluster, on every database kind."""

from __future__ import annotations

import datetime as dt
import time
import uuid
from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app import accounts
from app.auth import Access
from app.auth_models import Organisation
from app.jobs import store
from app.jobs.simulations import simulation_params
from app.models import Job, Simulation
from app.schemas import SimulationCreate
from tests.app.conftest import JobsCaller, add_user, wait_for_job


def create_plan(client: TestClient, body: dict[str, Any]) -> dict[str, Any]:
    response = client.post("/api/plans", json=body)
    assert response.status_code == 201, response.text
    plan: dict[str, Any] = response.json()
    return plan


def start_job(client: TestClient, plan_id: int, **body: Any) -> str:
    response = client.post(f"/api/plans/{plan_id}/simulations", json=body)
    assert response.status_code == 202, response.text
    job = response.json()
    assert job["status"] == "queued" and job["progress"] == 0
    location: str = response.headers["location"]
    assert location == f"/api/jobs/{job['id']}"
    return location


def simulations_of(session: Session, plan_id: int) -> int:
    session.rollback()  # a fresh snapshot: see what the workers committed since
    count = session.scalar(
        select(func.count()).select_from(Simulation).where(Simulation.plan_id == plan_id)
    )
    return int(count or 0)


def test_monte_carlo_job_reports_progress_and_summarises_the_runs(
    jobs_client: TestClient, jobs_session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(jobs_client, paper_body)
    location = start_job(jobs_client, plan["id"], runs=11, seed=5, gps="rtk")
    seen: list[float] = []
    while (job := jobs_client.get(location).json())["status"] in ("queued", "running"):
        seen.append(job["progress"])
        time.sleep(0.05)
    assert job["status"] == "done", job
    assert job["progress"] == 1
    assert any(0 < p < 1 for p in seen), seen
    assert seen == sorted(seen)
    result = job["result"]
    assert result["runs"] == 11 and result["seeds"] == [5, 15]
    assert 5 <= result["shown_seed"] <= 15
    summary = result["summary"]
    assert summary["completed_share"] == 1
    rms = summary["cross_track_rms_m"]
    assert rms["n"] == 11 and rms["min"] <= rms["median"] <= rms["max"]
    # The stored run is the median one (odd count): its RMS is the summary's median.
    simulation = jobs_client.get(job["result_url"]).json()
    assert simulation["config"]["seed"] == result["shown_seed"]
    assert abs(simulation["metrics"]["cross_track_rms_m"] - rms["median"]) < 1e-3
    assert simulations_of(jobs_session, plan["id"]) == 1
    assert job["attempts"] == 1 and job["finished_at"] >= job["started_at"]


def test_cancel_stops_the_work_and_stores_nothing(
    jobs_client: TestClient, jobs_session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(jobs_client, paper_body)
    location = start_job(jobs_client, plan["id"], runs=500)
    running = wait_for_job(jobs_client, location, until=("running",))
    assert running["status"] == "running"
    cancelled = jobs_client.delete(location)
    assert cancelled.status_code == 200, cancelled.text
    assert cancelled.json()["status"] == "cancelled"
    # The worker stops at its next progress report: the job's row no longer moves.
    time.sleep(1.5)
    first = jobs_client.get(location).json()
    time.sleep(1.0)
    later = jobs_client.get(location).json()
    assert later["status"] == "cancelled"
    assert later["updated_at"] == first["updated_at"]
    assert later["progress"] < 0.5
    assert simulations_of(jobs_session, plan["id"]) == 0
    # The worker is free again: a new job runs to the end at once.
    after = wait_for_job(jobs_client, start_job(jobs_client, plan["id"]), timeout_s=30)
    assert after["status"] == "done"
    again = jobs_client.delete(location)
    assert again.status_code == 409
    assert again.json() == {"detail": f"job {later['id']}: already cancelled, nothing to cancel"}


def test_a_job_whose_plan_is_gone_fails_with_a_clear_message(
    jobs_client: TestClient, jobs_session: Session, jobs_caller: JobsCaller
):
    # A job asked for a plan that was deleted before a worker took the job.
    params = simulation_params(987_654, SimulationCreate(), dt.date(2026, 12, 1))
    access = Access(
        organisation_id=jobs_caller.organisation_id,
        role="owner",
        user_id=jobs_caller.user_id,
        via="token",
    )
    job = store.create_job(jobs_session, access, "simulation", params)
    engine = jobs_client.app.state.jobs  # type: ignore[attr-defined]
    engine.submit(job.id)
    failed = wait_for_job(jobs_client, f"/api/jobs/{job.id}")
    assert failed["status"] == "failed"
    assert failed["error"] == "plan 987654 not found"
    assert failed["result"] is None and failed["result_url"] is None


def test_unknown_job_is_404(jobs_client: TestClient):
    for method in ("GET", "DELETE"):
        response = jobs_client.request(method, "/api/jobs/987654")
        assert response.status_code == 404
        assert response.json() == {"detail": "job 987654 not found"}


def test_without_a_shared_database_jobs_answer_503(client: TestClient, paper_body):
    plan = create_plan(client, paper_body)
    response = client.post(f"/api/plans/{plan['id']}/simulations", json={})
    assert response.status_code == 503
    assert response.json()["detail"].startswith("jobs: this server runs no job engine")


def test_jobs_table_keeps_what_was_asked(
    jobs_client: TestClient,
    jobs_session: Session,
    jobs_caller: JobsCaller,
    paper_body: dict[str, Any],
):
    plan = create_plan(jobs_client, paper_body)
    location = start_job(jobs_client, plan["id"], seed=9, guidance="line")
    job_id = int(location.rsplit("/", 1)[1])
    wait_for_job(jobs_client, location)
    row = jobs_session.get(Job, job_id)
    assert row is not None
    assert row.kind == "simulation"
    assert row.params["plan_id"] == plan["id"]
    assert row.params["request"] == {"seed": 9, "gps": "m8n", "guidance": "line", "runs": 1}
    assert row.params["requested_by"]["role"] == "owner"
    assert row.organisation_id == jobs_caller.organisation_id
    assert row.lease_token is None


def test_another_organisation_sees_no_job(
    jobs_client: TestClient, jobs_session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(jobs_client, paper_body)
    location = start_job(jobs_client, plan["id"])
    wait_for_job(jobs_client, location)
    org = Organisation(name=f"jobs-other-{uuid.uuid4().hex[:8]}")
    jobs_session.add(org)
    jobs_session.flush()
    stranger = add_user(jobs_session, f"stranger-{uuid.uuid4().hex[:8]}", {org.id: "owner"})
    token = accounts.create_token(jobs_session, stranger, name="other").token
    headers = {"Authorization": f"Bearer {token}"}
    job_id = location.rsplit("/", 1)[1]
    for method in ("GET", "DELETE"):
        response = jobs_client.request(method, location, headers=headers)
        assert response.status_code == 404
        assert response.json() == {"detail": f"job {job_id} not found"}
    response = jobs_client.get(location, headers={"Authorization": "Bearer nope"})
    assert response.status_code == 401
