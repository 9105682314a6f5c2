"""The clear answers of a server under load or given values it cannot store: 422, 404, 503.

Each runs on SQLite and PostgreSQL (a NUL character was a 500 on PostgreSQL only).
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import pytest
from fastapi import FastAPI
from starlette.testclient import TestClient

from app.capacity import get_heavy_work
from app.dependencies import request_settings
from app.settings import Settings


def a_plan(client: TestClient, body: dict[str, Any]) -> dict[str, Any]:
    response = client.post("/api/plans", json=body)
    assert response.status_code == 201, response.text
    result: dict[str, Any] = response.json()
    return result


@pytest.mark.parametrize("name", ["a\x00b", "line\nbreak", "\x7f"])
def test_control_characters_in_a_plan_name_are_a_422(
    client: TestClient, paper_body: dict[str, Any], name: str
):
    response = client.post("/api/plans", json={**paper_body, "name": name})
    assert response.status_code == 422, response.text
    assert response.json()["detail"] == "name: must not contain control characters such as NUL"
    assert client.get("/api/plans").json()["total"] == 0


def test_a_nul_in_the_field_name_is_a_422(client: TestClient, paper_body: dict[str, Any]):
    field = copy.deepcopy(paper_body["field"])  # the fixture's GeoJSON is shared
    field["features"][0]["properties"] = {"name": "sawah\x00"}
    response = client.post("/api/plans", json={"field": field, "interval_m": 4})
    assert response.status_code == 422, response.text
    assert response.json()["detail"].startswith("name: ")


def test_a_nul_in_a_run_name_is_a_422(client: TestClient, paper_body: dict[str, Any]):
    plan = a_plan(client, paper_body)
    response = client.post(f"/api/plans/{plan['id']}/runs", data={"name": "r\x00"})
    assert response.status_code == 422, response.text
    assert "name: must not contain" in response.json()["detail"]


@pytest.mark.parametrize(
    ("fix", "detail"),
    [
        ({"t": "1e999999999"}, "[0].t: must lie between 1980 and 2100"),
        ({"t": 1e300}, "[0].t: must lie between 1980 and 2100"),
        ({"t": "9" * 65}, "[0].t: is 65 characters long; a time has at most 64"),
        ({"t": "x" * 65}, "[0].t: is 65 characters long; a time has at most 64"),
        ({"heading_deg": 361}, "[0].heading_deg: must be at most 360.0"),
        ({"heading_deg": -1e9}, "[0].heading_deg: must be at least -360.0"),
        ({"speed_mps": -0.1}, "[0].speed_mps: must be at least 0.0"),
        ({"speed_mps": 1e6}, "[0].speed_mps: must be at most 100.0"),
    ],
)
def test_out_of_range_fix_values_are_a_422_naming_the_value(
    client: TestClient, paper_body: dict[str, Any], fix: dict[str, Any], detail: str
):
    plan = a_plan(client, paper_body)
    run = client.post(f"/api/plans/{plan['id']}/runs").json()
    body = [{"t": "2026-11-22T00:00:00Z", "lat": -8.6265, "lon": 115.298, **fix}]
    response = client.post(f"/api/runs/{run['id']}/fixes", json=body)
    assert response.status_code == 422, response.text
    assert detail in response.json()["detail"]
    assert client.get(f"/api/runs/{run['id']}").json()["fix_count"] == 0


def test_an_uploaded_fix_with_an_impossible_speed_refuses_the_file(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = a_plan(client, paper_body)
    data = b"time,lat,lon,speed\n2026-11-22T00:00:00Z,-8.6265,115.298,400\n"
    response = client.post(f"/api/plans/{plan['id']}/runs", files={"file": ("x.csv", data)})
    assert response.status_code == 422
    assert response.json()["detail"] == (
        "file: line 2: speed_mps must be between 0 and 100, got 400.0"
    )


def test_a_saturated_server_answers_503_with_retry_after(
    app: FastAPI, client_as: Callable[[str | None], TestClient], paper_body: dict[str, Any]
):
    settings = Settings(database_url="sqlite://", heavy_work_slots=1, heavy_work_queue=0)
    app.dependency_overrides[request_settings] = lambda: settings
    heavy = get_heavy_work(settings)
    with client_as("owner") as client:
        a_plan(client, paper_body)
        assert heavy.try_slot()  # another request computes
        try:
            for method, url, kwargs in [
                ("POST", "/api/plans/preview", {"json": paper_body}),
                ("POST", "/api/plans", {"json": paper_body}),
                # (a simulation is a Dask job now: it takes no heavy-work slot here)
            ]:
                response = client.request(method, url, **kwargs)
                assert response.status_code == 503, response.text
                assert response.headers["retry-after"] == "2"
                assert "busy" in response.json()["detail"]
            assert client.get("/api/health").status_code == 200  # light requests still pass
            assert client.get("/api/plans").json()["total"] == 1
        finally:
            heavy.release()
        assert client.post("/api/plans/preview", json=paper_body).status_code == 200
