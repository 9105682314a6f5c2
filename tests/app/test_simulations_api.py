"""The simulations API (product.md §5, §7), on every database of the ``engine`` fixture."""

from __future__ import annotations

import math
from typing import Any

import gpxpy
import numpy as np
import pytest
from lxml import etree
from sqlalchemy import func, select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app.models import Simulation
from navigation import score_track
from planner.export import plan_from_geojson
from tests.app.conftest import GPX_XSD, wait_for_job


@pytest.fixture
def client(jobs_client: TestClient) -> TestClient:
    """Simulations are background jobs: their workers need a database they can open."""
    return jobs_client


@pytest.fixture
def session(jobs_session: Session) -> Session:
    return jobs_session


def simulation_count(session: Session, plan_id: int) -> int:
    session.rollback()  # a fresh snapshot: see what the workers committed since
    count = session.scalar(
        select(func.count()).select_from(Simulation).where(Simulation.plan_id == plan_id)
    )
    return int(count or 0)


def create_plan(client: TestClient, body: dict[str, Any]) -> dict[str, Any]:
    response = client.post("/api/plans", json=body)
    assert response.status_code == 201, response.text
    plan: dict[str, Any] = response.json()
    return plan


def simulate(client: TestClient, plan_id: int, **body: Any) -> dict[str, Any]:
    response = client.post(f"/api/plans/{plan_id}/simulations", json=body)
    assert response.status_code == 202, response.text
    assert response.headers["location"] == f"/api/jobs/{response.json()['id']}"
    job = wait_for_job(client, response.headers["location"])
    assert job["status"] == "done", job
    assert job["result_url"] == f"/api/simulations/{job['result']['simulation_id']}"
    stored = client.get(job["result_url"])
    assert stored.status_code == 200
    simulation: dict[str, Any] = stored.json()
    return simulation


def true_track(simulation: dict[str, Any]) -> dict[str, Any]:
    (feature,) = [
        f for f in simulation["tracks"]["features"] if f["properties"]["source"] == "true"
    ]
    return feature


def test_create_simulation_runs_a_job_that_stores_metrics_and_tracks(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    simulation = simulate(client, plan["id"], seed=3, gps="m8n", guidance="waypoint")
    assert simulation["plan_id"] == plan["id"]
    assert simulation["config"]["seed"] == 3
    assert simulation["config"]["gps"] == "m8n"
    assert simulation["config"]["guidance"] == "waypoint"
    metrics = simulation["metrics"]
    assert metrics["completed"] is True
    # The paper field: about 100 m of path at 0.56 m/s.
    assert 120 < metrics["time_s"] < 400
    assert 0 < metrics["waypoint_error_mean_m"] <= metrics["waypoint_error_max_m"] < 10
    assert 0 < metrics["cross_track_rms_m"] < 5
    assert 0.5 < metrics["coverage_ratio"] <= 1
    assert len(metrics["waypoint_errors_m"]) == plan["stats"]["waypoint_count"]
    assert {f["properties"]["source"] for f in simulation["tracks"]["features"]} == {
        "true",
        "estimated",
        "gps",
    }
    assert simulation_count(session, plan["id"]) == 1


def test_simulation_metrics_are_those_of_its_true_track(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    simulation = simulate(client, plan["id"], seed=1)
    track = true_track(simulation)
    lon, lat = np.array(track["geometry"]["coordinates"]).T
    # The stored track is thinned to 1 s; scored again it gives nearly the 10 Hz figures.
    again = score_track(plan_from_geojson(plan["geojson"]), track["properties"]["time_s"], lon, lat)
    metrics = simulation["metrics"]
    assert math.isclose(again.time_s, metrics["time_s"], abs_tol=1.0)
    assert math.isclose(again.coverage_ratio, metrics["coverage_ratio"], abs_tol=0.02)
    assert math.isclose(again.waypoint_error_max_m, metrics["waypoint_error_max_m"], abs_tol=0.3)


def test_same_seed_gives_same_simulation(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    first = simulate(client, plan["id"], seed=7, guidance="line")
    again = simulate(client, plan["id"], seed=7, guidance="line")
    other = simulate(client, plan["id"], seed=8, guidance="line")
    assert first["id"] != again["id"]
    assert first["metrics"] == again["metrics"]
    assert first["tracks"] == again["tracks"]
    assert other["metrics"] != first["metrics"]


def test_rtk_line_mode_follows_the_lines_more_closely_than_m8n(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    rtk = simulate(client, plan["id"], seed=2, gps="rtk", guidance="line")
    m8n = simulate(client, plan["id"], seed=2, gps="m8n", guidance="waypoint")
    assert rtk["metrics"]["cross_track_rms_m"] < m8n["metrics"]["cross_track_rms_m"]


def test_create_simulation_without_body_uses_defaults(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    response = client.post(f"/api/plans/{plan['id']}/simulations")
    assert response.status_code == 202, response.text
    job = wait_for_job(client, response.headers["location"])
    simulation = client.get(job["result_url"]).json()
    assert simulation["config"] | {"date": None} == {
        "seed": 0,
        "gps": "m8n",
        "guidance": "waypoint",
        "date": None,
        "vehicle": "hand_tractor",  # the plan's vehicle (the default, as it names none)
    }


def test_read_simulation_returns_what_was_stored(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    simulation = simulate(client, plan["id"])
    response = client.get(f"/api/simulations/{simulation['id']}")
    assert response.status_code == 200
    assert response.json() == simulation


def test_bad_gps_preset_returns_422_naming_gps(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    response = client.post(f"/api/plans/{plan['id']}/simulations", json={"gps": "garmin"})
    assert response.status_code == 422
    assert response.json()["detail"].startswith("gps: must be")
    assert "m8n" in response.json()["detail"]


def test_bad_guidance_and_seed_return_422_naming_them(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    url = f"/api/plans/{plan['id']}/simulations"
    guidance = client.post(url, json={"guidance": "autopilot"})
    assert guidance.status_code == 422
    assert guidance.json()["detail"].startswith("guidance: must be")
    seed = client.post(url, json={"seed": -1})
    assert seed.status_code == 422
    assert seed.json()["detail"] == "seed: must be at least 0"
    extra = client.post(url, json={"speed": 3})
    assert extra.status_code == 422
    assert extra.json()["detail"] == "speed: is not a known input"
    runs = client.post(url, json={"runs": 501})
    assert runs.status_code == 422
    assert runs.json()["detail"].startswith("runs: must be at most 500")
    assert simulation_count(session, plan["id"]) == 0


def test_simulation_of_unknown_plan_returns_404(client: TestClient):
    response = client.post("/api/plans/999999/simulations", json={})
    assert response.status_code == 404
    assert response.json() == {"detail": "plan 999999 not found"}


def test_read_unknown_simulation_returns_404(client: TestClient):
    for url in ["/api/simulations/424242", "/api/simulations/424242/export/gpx"]:
        response = client.get(url)
        assert response.status_code == 404
        assert response.json() == {"detail": "simulation 424242 not found"}


def test_export_simulation_gpx_has_plan_route_and_three_timed_tracks(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    simulation = simulate(client, plan["id"], seed=4)
    response = client.get(f"/api/simulations/{simulation['id']}/export/gpx")
    assert response.status_code == 200
    assert response.headers["content-type"].startswith("application/gpx+xml")
    assert response.headers["content-disposition"] == (
        f'attachment; filename="sawah-ketewel-simulation-{simulation["id"]}.gpx"'
    )
    schema = etree.XMLSchema(etree.parse(str(GPX_XSD)))
    assert schema.validate(etree.fromstring(response.content)), schema.error_log
    gpx = gpxpy.parse(response.text)
    (route,) = gpx.routes
    assert len(route.points) == plan["stats"]["waypoint_count"]
    assert [t.name for t in gpx.tracks] == ["true", "estimated", "gps"]
    points = gpx.tracks[0].segments[0].points
    assert len(points) == len(true_track(simulation)["geometry"]["coordinates"])
    duration = (points[-1].time - points[0].time).total_seconds()
    assert math.isclose(duration, simulation["metrics"]["time_s"], abs_tol=1.0)


def test_deleting_the_plan_deletes_its_simulations(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    simulation = simulate(client, plan["id"])
    assert client.delete(f"/api/plans/{plan['id']}").status_code == 204
    assert client.get(f"/api/simulations/{simulation['id']}").status_code == 404
    assert simulation_count(session, plan["id"]) == 0
