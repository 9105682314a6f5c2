"""What the page asks of the API beyond plans: search, a plan's simulations, lighter answers."""

from __future__ import annotations

import gzip
import json
from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient

from app.display import DISPLAY_TOLERANCE_M, METRES_PER_DEGREE
from tests.app.conftest import wait_for_job


def create(client: TestClient, body: dict[str, Any], name: str) -> dict[str, Any]:
    answer = client.post("/api/plans", json={**body, "name": name})
    assert answer.status_code == 201, answer.text
    plan: dict[str, Any] = answer.json()
    return plan


def test_plans_are_searched_by_name_and_paged(
    client: TestClient, paper_body: dict[str, Any]
) -> None:
    for name in ["Sawah utara", "sawah UTARA 2", "Sawah selatan", "100%_odd"]:
        create(client, paper_body, name)
    found = client.get("/api/plans", params={"q": "utara"}).json()
    assert found["total"] == 2
    assert {p["name"] for p in found["items"]} == {"Sawah utara", "sawah UTARA 2"}
    page = client.get("/api/plans", params={"q": "sawah", "limit": 2, "offset": 2}).json()
    assert page["total"] == 3 and len(page["items"]) == 1
    # LIKE wildcards typed by a person are letters, not patterns.
    assert client.get("/api/plans", params={"q": "%"}).json()["total"] == 1
    assert client.get("/api/plans", params={"q": "0%_"}).json()["total"] == 1
    assert client.get("/api/plans", params={"q": "_"}).json()["total"] == 1
    assert client.get("/api/plans", params={"q": "x" * 201}).status_code == 422


def simulate(client: TestClient, plan_id: int, **body: Any) -> dict[str, Any]:
    """Run a simulation job to its end; return the stored simulation (issue 14)."""
    started = client.post(f"/api/plans/{plan_id}/simulations", json=body)
    assert started.status_code == 202, started.text
    job = wait_for_job(client, started.headers["location"])
    assert job["status"] == "done", job
    simulation: dict[str, Any] = client.get(job["result_url"]).json()
    return simulation


def test_a_plans_simulations_are_listed_newest_first(
    jobs_client: TestClient, paper_body: dict[str, Any]
) -> None:
    client = jobs_client
    plan = create(client, paper_body, "Listed")
    other = create(client, paper_body, "Other")
    ids = [simulate(client, plan["id"], seed=seed)["id"] for seed in (1, 2)]
    simulate(client, other["id"], seed=3)
    listed = client.get(f"/api/plans/{plan['id']}/simulations").json()
    assert [s["id"] for s in listed["items"]] == ids[::-1]
    assert listed["total"] == 2
    assert "tracks" not in listed["items"][0]
    assert listed["items"][0]["metrics"]["time_s"] > 0
    assert client.get("/api/plans/999999/simulations").status_code == 404


def test_display_tracks_are_the_true_track_thinned_within_tolerance(
    jobs_client: TestClient, paper_body: dict[str, Any]
) -> None:
    import shapely

    client = jobs_client
    plan = create(client, paper_body, "Thin")
    full = simulate(client, plan["id"], seed=5)
    shown = client.get(f"/api/simulations/{full['id']}", params={"tracks": "display"}).json()
    (true,) = [f for f in full["tracks"]["features"] if f["properties"]["source"] == "true"]
    assert [f["properties"]["source"] for f in shown["tracks"]["features"]] == ["true"]
    thin = shown["tracks"]["features"][0]
    coords = thin["geometry"]["coordinates"]
    assert thin["properties"]["stored_vertices"] == len(true["geometry"]["coordinates"])
    assert 2 <= len(coords) < len(true["geometry"]["coordinates"]) / 2
    assert len(thin["properties"]["time_s"]) == len(coords)
    assert coords[0] == true["geometry"]["coordinates"][0]
    assert coords[-1] == true["geometry"]["coordinates"][-1]
    # Every stored vertex lies within the tolerance of the thinned line.
    gap_deg = shapely.LineString(coords).hausdorff_distance(
        shapely.LineString(true["geometry"]["coordinates"])
    )
    assert gap_deg * METRES_PER_DEGREE <= DISPLAY_TOLERANCE_M * 1.01
    assert shown["metrics"] == full["metrics"]
    # The stored simulation and its GPX keep every vertex.
    again = client.get(f"/api/simulations/{full['id']}").json()
    assert again["tracks"] == full["tracks"]
    assert client.get(f"/api/simulations/{full['id']}", params={"tracks": "x"}).status_code == 422


def test_answers_are_gzipped_when_the_client_accepts_it(
    client: TestClient, paper_body: dict[str, Any]
) -> None:
    plan = create(client, paper_body, "Zip")
    answer = client.get(f"/api/plans/{plan['id']}", headers={"Accept-Encoding": "gzip"})
    assert answer.headers["content-encoding"] == "gzip"
    assert answer.json()["id"] == plan["id"]  # the client decoded it
    plain = client.get(f"/api/plans/{plan['id']}", headers={"Accept-Encoding": "identity"})
    assert "content-encoding" not in plain.headers
    raw = json.dumps(plain.json()).encode()
    assert len(gzip.compress(raw)) < len(raw) / 2
    script = client.get("/static/js/map.js", headers={"Accept-Encoding": "gzip"})
    assert script.headers["content-encoding"] == "gzip"


def test_manifest_and_service_worker(client: TestClient) -> None:
    manifest = client.get("/manifest.webmanifest", headers={"Accept-Language": "id"})
    assert manifest.headers["content-type"].startswith("application/manifest+json")
    body = manifest.json()
    assert body["display"] == "standalone" and body["lang"] == "id"
    assert body["description"] == "Jalur bolak-balik untuk traktor tangan"
    worker = client.get("/sw.js")
    assert worker.headers["content-type"].startswith("text/javascript")
    assert worker.headers["cache-control"] == "no-cache"
    text = worker.text
    assert "/*SHELL*/" not in text and "/*VERSION*/" not in text
    shell = json.loads(text.split("const SHELL = ", 1)[1].split(".map(", 1)[0])
    for path in ["", "static/js/map.js", "static/js/i18n.js", "i18n/id.json"]:
        assert path in shell
    # Every module the page imports is cached too (map.js is split by concern).
    js = Path(__file__).parents[2] / "static" / "js"
    modules = sorted(p.name for p in js.glob("*.js") if p.name != "sw.js")  # sw.js: at /sw.js
    assert {"pagestate.js", "fieldedit.js", "draft.js", "planview.js"} <= set(modules)
    for name in modules:
        assert f"static/js/{name}" in shell, name
    for path in shell:
        assert client.get("/" + path).status_code == 200, path
