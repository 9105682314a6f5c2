"""The plans API of product.md §5, on every database of the ``engine`` fixture."""

from __future__ import annotations

import copy
import csv
import datetime as dt
import io
import json
from pathlib import Path
from typing import Any

import gpxpy
from lxml import etree
from sqlalchemy import func, select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app.models import Plan

GPX_XSD = Path(__file__).resolve().parents[3] / "shared" / "schemas" / "gpx-1.1.xsd"

STATS_KEYS = {
    "area_m2",
    "line_count",
    "waypoint_count",
    "working_length_m",
    "turn_length_m",
    "transit_length_m",
    "path_length_m",
    "coverage_ratio",
    "angle_deg",
    "estimated_time_s",
    "planning_ms",
}


def create(client: TestClient, body: dict[str, Any]) -> dict[str, Any]:
    response = client.post("/api/plans", json=body)
    assert response.status_code == 201, response.text
    plan: dict[str, Any] = response.json()
    return plan


def test_preview_plan_returns_plan_without_id(client: TestClient, paper_body: dict[str, Any]):
    response = client.post("/api/plans/preview", json=paper_body)
    assert response.status_code == 200, response.text
    plan = response.json()
    assert plan["id"] is None and plan["created_at"] is None
    assert plan["name"] == "Sawah Ketewel"
    assert set(plan["stats"]) >= STATS_KEYS
    # Coverage first (R5): the line count follows the heading the search keeps, 4 or 5 here.
    starts = [w for w in plan["waypoints"] if w["role"] == "line_start"]
    assert plan["stats"]["line_count"] == len(starts) in (4, 5)
    assert plan["stats"]["waypoint_count"] == len(plan["waypoints"])
    assert [w["seq"] for w in plan["waypoints"]] == list(range(len(plan["waypoints"])))
    assert set(plan["waypoints"][0]) == {"seq", "lon", "lat", "role", "line"}
    assert plan["geojson"]["type"] == "FeatureCollection"
    # The normalised request: defaults filled in, start/finish taken from the collection.
    request = plan["request"]
    assert request["field"]["type"] == "Polygon"
    assert request["objective"] == "shortest_path"
    assert request["headland_passes"] == 0
    assert request["speed_mps"] == 0.56
    assert request["start"] == [115.29797264, -8.62652248]
    assert request["finish"] == [115.29816889, -8.62652064]


def test_preview_plan_stores_nothing(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    assert client.post("/api/plans/preview", json=paper_body).status_code == 200
    assert session.scalar(select(func.count()).select_from(Plan)) == 0


def test_preview_of_normalised_request_gives_same_plan(
    client: TestClient, paper_body: dict[str, Any]
):
    first = client.post("/api/plans/preview", json=paper_body).json()
    again = client.post("/api/plans/preview", json=first["request"]).json()
    assert again["waypoints"] == first["waypoints"]
    assert again["request"] == first["request"]


def test_preview_uses_request_start_over_collection_start(
    client: TestClient, paper_body: dict[str, Any]
):
    body = {**paper_body, "start": [115.29790, -8.62655], "finish": None}
    plan = client.post("/api/plans/preview", json=body).json()
    assert plan["request"]["start"] == [115.29790, -8.62655]
    assert plan["waypoints"][0]["role"] == "start"
    assert (plan["waypoints"][0]["lon"], plan["waypoints"][0]["lat"]) == (115.29790, -8.62655)


def test_preview_accepts_bare_polygon_and_feature(
    client: TestClient, paper_geojson: dict[str, Any]
):
    feature = paper_geojson["features"][0]
    for field in (feature, feature["geometry"]):
        response = client.post("/api/plans/preview", json={"field": field, "interval_m": 4})
        assert response.status_code == 200, response.text
        assert response.json()["stats"]["line_count"] >= 4
        assert response.json()["request"]["start"] is None


def test_preview_options_reach_the_planner(client: TestClient, paper_body: dict[str, Any]):
    body = {**paper_body, "angle_deg": 90, "objective": "fewest_lines", "speed_mps": 1.0}
    plan = client.post("/api/plans/preview", json=body).json()
    assert abs(plan["stats"]["angle_deg"] - 90) < 1e-6
    assert plan["request"]["objective"] == "fewest_lines"
    slow = client.post("/api/plans/preview", json={**body, "speed_mps": 0.5}).json()
    assert slow["stats"]["estimated_time_s"] > plan["stats"]["estimated_time_s"]


def test_create_plan_returns_201_with_location(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    response = client.post("/api/plans", json=paper_body)
    assert response.status_code == 201, response.text
    plan = response.json()
    assert isinstance(plan["id"], int)
    assert response.headers["location"] == f"/api/plans/{plan['id']}"
    created = dt.datetime.fromisoformat(plan["created_at"])
    assert created.utcoffset() == dt.timedelta(0)
    assert abs(dt.datetime.now(dt.UTC) - created) < dt.timedelta(minutes=1)
    assert session.scalar(select(func.count()).select_from(Plan)) == 1


def test_read_plan_returns_what_was_created(client: TestClient, paper_body: dict[str, Any]):
    created = create(client, paper_body)
    response = client.get(f"/api/plans/{created['id']}")
    assert response.status_code == 200
    assert response.json() == created


def test_read_plan_unknown_id_returns_404(client: TestClient):
    for plan_id in (42, 0, -1, 10**12):
        response = client.get(f"/api/plans/{plan_id}")
        assert response.status_code == 404
        assert response.json() == {"detail": f"plan {plan_id} not found"}


def test_list_plans_newest_first_with_total(client: TestClient, paper_body: dict[str, Any]):
    ids = [create(client, {**paper_body, "name": f"field {i}"})["id"] for i in range(5)]
    response = client.get("/api/plans")
    assert response.status_code == 200
    listing = response.json()
    assert listing["total"] == 5
    assert [item["id"] for item in listing["items"]] == ids[::-1]
    assert set(listing["items"][0]) == {"id", "name", "created_at", "field_id", "stats"}
    assert listing["items"][0]["name"] == "field 4"

    page = client.get("/api/plans", params={"limit": 2, "offset": 1}).json()
    assert page["total"] == 5
    assert [item["id"] for item in page["items"]] == ids[::-1][1:3]
    beyond = client.get("/api/plans", params={"offset": 10}).json()
    assert beyond == {"items": [], "total": 5}


def test_list_plans_empty(client: TestClient):
    assert client.get("/api/plans").json() == {"items": [], "total": 0}


def test_list_plans_bad_paging_returns_422(client: TestClient):
    cases = {
        "limit=0": "limit",
        "limit=1000": "limit",
        "limit=ten": "limit",
        "offset=-1": "offset",
    }
    for query, name in cases.items():
        response = client.get(f"/api/plans?{query}")
        assert response.status_code == 422, query
        assert response.json()["detail"].startswith(f"{name}: "), response.json()


def test_delete_plan_returns_204_and_removes_it(client: TestClient, paper_body: dict[str, Any]):
    keep = create(client, paper_body)
    gone = create(client, paper_body)
    response = client.delete(f"/api/plans/{gone['id']}")
    assert response.status_code == 204
    assert response.content == b""
    assert client.get(f"/api/plans/{gone['id']}").status_code == 404
    assert [p["id"] for p in client.get("/api/plans").json()["items"]] == [keep["id"]]
    again = client.delete(f"/api/plans/{gone['id']}")
    assert again.status_code == 404
    assert again.json() == {"detail": f"plan {gone['id']} not found"}


def test_plan_name_falls_back_on_field_name(client: TestClient, paper_geojson: dict[str, Any]):
    plan = create(client, {"field": paper_geojson, "interval_m": 4})
    assert plan["name"] == "paper_ketewel"


# --- exports ----------------------------------------------------------------------------------


def test_export_gpx_validates_and_parses(client: TestClient, paper_body: dict[str, Any]):
    plan = create(client, paper_body)
    response = client.get(f"/api/plans/{plan['id']}/export/gpx")
    assert response.status_code == 200
    assert response.headers["content-type"].startswith("application/gpx+xml")
    assert response.headers["content-disposition"] == 'attachment; filename="sawah-ketewel.gpx"'

    schema = etree.XMLSchema(etree.parse(str(GPX_XSD)))
    document = etree.fromstring(response.content)
    assert schema.validate(document), schema.error_log

    gpx = gpxpy.parse(response.text)
    assert len(gpx.routes) == 1
    route = gpx.routes[0]
    assert route.name == "Sawah Ketewel"
    assert len(route.points) == len(plan["waypoints"])
    assert route.points[0].name == "WP000"
    for point, waypoint in zip(route.points, plan["waypoints"], strict=True):
        assert abs(point.longitude - waypoint["lon"]) < 1e-7
        assert abs(point.latitude - waypoint["lat"]) < 1e-7


def test_export_csv_parses(client: TestClient, paper_body: dict[str, Any]):
    plan = create(client, paper_body)
    response = client.get(f"/api/plans/{plan['id']}/export/csv")
    assert response.status_code == 200
    assert response.headers["content-type"].startswith("text/csv")
    assert response.headers["content-disposition"] == 'attachment; filename="sawah-ketewel.csv"'
    rows = list(csv.DictReader(io.StringIO(response.text)))
    assert list(rows[0]) == ["seq", "lat", "lon", "role", "line"]
    assert len(rows) == plan["stats"]["waypoint_count"]
    for row, waypoint in zip(rows, plan["waypoints"], strict=True):
        assert int(row["seq"]) == waypoint["seq"]
        assert row["role"] == waypoint["role"]
        assert abs(float(row["lat"]) - waypoint["lat"]) < 1e-7
        assert abs(float(row["lon"]) - waypoint["lon"]) < 1e-7


def test_export_geojson_is_the_stored_collection(client: TestClient, paper_body: dict[str, Any]):
    plan = create(client, paper_body)
    response = client.get(f"/api/plans/{plan['id']}/export/geojson")
    assert response.status_code == 200
    assert response.headers["content-type"].startswith("application/geo+json")
    assert response.headers["content-disposition"].endswith('filename="sawah-ketewel.geojson"')
    collection = json.loads(response.text)
    assert collection == plan["geojson"]
    kinds = {f["properties"].get("kind") for f in collection["features"]}
    assert {"field", "line", "path", "waypoint"} <= kinds


def test_export_waypoints_json(client: TestClient, paper_body: dict[str, Any]):
    plan = create(client, paper_body)
    response = client.get(f"/api/plans/{plan['id']}/export/json")
    assert response.status_code == 200
    assert response.headers["content-type"].startswith("application/json")
    assert response.headers["content-disposition"].endswith('filename="sawah-ketewel.json"')
    waypoints = response.json()["waypoints"]
    assert [(w["seq"], w["lat"], w["lon"], w["role"], w["line"]) for w in waypoints] == [
        (w["seq"], w["lat"], w["lon"], w["role"], w["line"]) for w in plan["waypoints"]
    ]


def test_export_file_name_without_usable_name_uses_id(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create(client, {**paper_body, "name": "../../etc/passwd"})
    response = client.get(f"/api/plans/{plan['id']}/export/csv")
    assert response.headers["content-disposition"] == 'attachment; filename="etc-passwd.csv"'
    plan = create(client, {**paper_body, "name": "☀☀"})
    response = client.get(f"/api/plans/{plan['id']}/export/gpx")
    assert response.headers["content-disposition"] == (
        f'attachment; filename="plan-{plan["id"]}.gpx"'
    )


def test_export_unknown_format_returns_422(client: TestClient, paper_body: dict[str, Any]):
    plan = create(client, paper_body)
    response = client.get(f"/api/plans/{plan['id']}/export/kmz")
    assert response.status_code == 422
    assert response.json()["detail"].startswith("format: must be 'gpx'")


def test_export_unknown_plan_returns_404(client: TestClient):
    response = client.get("/api/plans/42/export/gpx")
    assert response.status_code == 404
    assert response.json() == {"detail": "plan 42 not found"}


def test_stored_plan_survives_a_round_trip_unchanged(
    client: TestClient, paper_body: dict[str, Any]
):
    preview = client.post("/api/plans/preview", json=paper_body).json()
    stored = create(client, copy.deepcopy(paper_body))
    read = client.get(f"/api/plans/{stored['id']}").json()
    for key in ("request", "waypoints", "geojson"):
        assert read[key] == preview[key]
    stats = {k: v for k, v in read["stats"].items() if k != "planning_ms"}
    assert stats == {k: v for k, v in preview["stats"].items() if k != "planning_ms"}


def test_openapi_documents_every_plans_route(client: TestClient):
    schema = client.get("/openapi.json").json()
    paths = schema["paths"]
    assert set(paths["/api/plans"]) == {"get", "post"}
    assert set(paths["/api/plans/preview"]) == {"post"}
    assert set(paths["/api/plans/{plan_id}"]) == {"get", "delete"}
    assert set(paths["/api/plans/{plan_id}/export/{format}"]) == {"get"}
    assert set(paths["/api/health"]) == {"get"}
    assert "422" in paths["/api/plans"]["post"]["responses"]
    assert client.get("/docs").status_code == 200


def test_preview_spiral_returns_rounds(client: TestClient, paper_body: dict[str, Any]):
    response = client.post("/api/plans/preview", json={**paper_body, "pattern": "spiral"})
    assert response.status_code == 200, response.text
    plan = response.json()
    kinds = [f["properties"]["kind"] for f in plan["geojson"]["features"]]
    assert "round" in kinds and plan["request"]["pattern"] == "spiral"


def test_preview_unknown_pattern_returns_422(client: TestClient, paper_body: dict[str, Any]):
    response = client.post("/api/plans/preview", json={**paper_body, "pattern": "zigzag"})
    assert response.status_code == 422
