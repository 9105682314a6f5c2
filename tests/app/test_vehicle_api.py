"""The vehicle, implement width and pattern through the API (product.md §3, §3a, §5)."""

from __future__ import annotations

from typing import Any

from starlette.testclient import TestClient


def test_preview_takes_a_vehicle_object_implement_width_and_pattern(
    client: TestClient, paper_body: dict[str, Any]
) -> None:
    body = {
        **paper_body,
        "vehicle": {"preset": "small_tractor", "min_turn_radius_m": 2.5},
        "implement_width_m": 4.5,
        "pattern": "snake",
    }
    response = client.post("/api/plans/preview", json=body)
    assert response.status_code == 200, response.text
    plan = response.json()
    assert plan["stats"]["vehicle"]["preset"] == "small_tractor"
    assert plan["stats"]["vehicle"]["min_turn_radius_m"] == 2.5
    assert plan["stats"]["implement_width_m"] == 4.5
    assert plan["stats"]["overlap_m"] == 0.5
    # The request is kept as asked, so the same plan can be made again from it.
    assert plan["request"]["vehicle"] == {"preset": "small_tractor", "min_turn_radius_m": 2.5}
    assert plan["request"]["pattern"] == "snake"
    again = client.post("/api/plans/preview", json=plan["request"]).json()
    assert again["waypoints"] == plan["waypoints"]


def test_stored_plan_keeps_its_vehicle(client: TestClient, paper_body: dict[str, Any]) -> None:
    created = client.post("/api/plans", json={**paper_body, "vehicle": "rover"})
    assert created.status_code == 201, created.text
    stored = client.get(created.headers["Location"]).json()
    assert stored["request"]["vehicle"] == "rover"
    assert stored["stats"]["vehicle"]["can_reverse"] is True


def test_default_vehicle_is_the_hand_tractor(
    client: TestClient, paper_body: dict[str, Any]
) -> None:
    plan = client.post("/api/plans/preview", json=paper_body).json()
    assert plan["request"]["vehicle"] == "hand_tractor"
    assert plan["stats"]["vehicle"]["width_m"] == 0.85


def test_bad_vehicles_get_422_naming_the_input(
    client: TestClient, paper_body: dict[str, Any]
) -> None:
    cases = [
        ("tank", "vehicle: unknown preset 'tank'"),
        ({"preset": "hand_tractor", "width_m": -1}, "vehicle.width_m: must be between"),
        ({"preset": "hand_tractor", "wheels": 3}, "vehicle.wheels: is not a vehicle field"),
    ]
    for vehicle, message in cases:
        response = client.post("/api/plans/preview", json={**paper_body, "vehicle": vehicle})
        assert response.status_code == 422, response.text
        assert response.json()["detail"].startswith(message), response.json()
    response = client.post("/api/plans/preview", json={**paper_body, "implement_width_m": 0})
    assert response.status_code == 422
    assert response.json()["detail"].startswith("implement_width_m: must be between 0.1 and 50")


def test_vehicle_presets_are_listed(client: TestClient) -> None:
    response = client.get("/api/vehicles")
    assert response.status_code == 200
    presets = {v["preset"]: v for v in response.json()["items"]}
    assert set(presets) == {"hand_tractor", "paper_g1000", "small_tractor", "rover"}
    assert presets["paper_g1000"]["track_m"] == 1.8  # the paper's Table 3
