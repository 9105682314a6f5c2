"""A server that can face the internet: no request holds it, security headers, no inline code.

The timing tests run ``tillpath serve`` (app.testing.running_server) on each database and
measure from outside, as an attacker would: the pathological request must be answered within
2 s, and ``/api/health`` must answer within 1 s all the while.
"""

from __future__ import annotations

import json
import re
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2
import pytest
from shapely import Polygon
from starlette.testclient import TestClient

from app.budget import INLINE_MAX_HOLES, INLINE_MAX_VERTICES, area_ha
from app.db import get_engine
from app.testing import ServerUrl, running_server
from tests.conftest import FIELDS_DIR, field_from_local
from tests.databases import DATABASES, scratch_pg_database

ROOT = Path(__file__).resolve().parents[2]
ANSWER_WITHIN_S = 2.0
HEALTH_WITHIN_S = 1.0
#: The served app's planning budget: a quarter of ANSWER_WITHIN_S, so that a loaded machine
#: (a load average of 17 once took the answer past 2 s with a 1 s budget) still answers in time.
PLANNING_BUDGET_S = 0.5
BUDGET = {"TILLPATH_PLANNING_BUDGET_S": str(PLANNING_BUDGET_S)}


@pytest.fixture(scope="module", params=DATABASES)
def served(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ServerUrl]:
    """``tillpath serve`` with one worker on a database of each kind."""
    workdir = tmp_path_factory.mktemp("hardening")
    if request.param == "sqlite":
        with running_server(
            f"sqlite:///{workdir / 't.db'}",
            log=workdir / "serve.log",
            serve_args=["--no-access-log"],
            env=BUDGET,
        ) as url:
            yield url
        get_engine.cache_clear()
        return
    with scratch_pg_database("tillpath_hardening") as db_url:
        with running_server(
            db_url, log=workdir / "serve.log", serve_args=["--no-access-log"], env=BUDGET
        ) as url:
            yield url
        get_engine.cache_clear()


def comb_field(teeth: int = 499) -> dict[str, Any]:
    """A comb: a 10 m bar with ``teeth`` 2 m × 50 m teeth, 2 m apart (4·teeth + 2 vertices)."""
    width = teeth * 4.0
    points = [(0.0, 0.0), (width, 0.0)]
    x = width
    for _ in range(teeth):
        points += [(x, 60.0), (x - 2.0, 60.0), (x - 2.0, 10.0), (x - 4.0, 10.0)]
        x -= 4.0
    polygon = field_from_local(points)
    return {"type": "Polygon", "coordinates": [[list(c) for c in polygon.exterior.coords]]}


def while_health_is_polled(
    base: ServerUrl, request: Any
) -> tuple[httpx2.Response, float, list[float]]:
    """Run ``request()`` in a thread, polling health; return its answer, its time, health's."""
    answer: dict[str, Any] = {}

    def run() -> None:
        start = time.perf_counter()
        answer["response"] = request()
        answer["seconds"] = time.perf_counter() - start

    worker = threading.Thread(target=run)
    worker.start()
    health: list[float] = []
    with httpx2.Client(base_url=base, timeout=10) as client:
        time.sleep(0.05)  # let the request reach the server first
        while worker.is_alive() or not health:
            start = time.perf_counter()
            assert client.get("/api/health").status_code == 200
            health.append(time.perf_counter() - start)
            time.sleep(0.05)
    worker.join()
    return answer["response"], answer["seconds"], health


def test_eight_byte_timestamp_is_answered_at_once(served: ServerUrl):
    with httpx2.Client(base_url=served, headers=served.headers, timeout=30) as client:
        field = {"type": "Polygon", "coordinates": comb_field(3)["coordinates"]}
        plan = client.post("/api/plans", json={"field": field, "interval_m": 2})
        assert plan.status_code == 201, plan.text
        run = client.post(f"/api/plans/{plan.json()['id']}/runs", json={}).json()

        def post() -> httpx2.Response:
            body = b'[{"t": "1e999990", "lat": 0, "lon": 0}]'
            return client.post(
                f"/api/runs/{run['id']}/fixes",
                content=body,
                headers={"Content-Type": "application/json"},
            )

        response, seconds, health = while_health_is_polled(served, post)
    assert response.status_code == 422
    assert response.json()["detail"] == "[0].t: must lie between 1980 and 2100"
    assert seconds < ANSWER_WITHIN_S, seconds
    assert max(health) < HEALTH_WITHIN_S, health


def test_comb_shaped_field_is_answered_within_the_budget(served: ServerUrl):
    comb = comb_field()
    assert len(comb["coordinates"][0]) - 1 > INLINE_MAX_VERTICES  # goes to the budgeted path

    def post() -> httpx2.Response:
        return httpx2.post(
            f"{served}/api/plans/preview",
            json={"field": comb, "interval_m": 1},
            headers=served.headers,
            timeout=30,
        )

    response, seconds, health = while_health_is_polled(served, post)
    assert seconds < ANSWER_WITHIN_S, seconds
    assert max(health) < HEALTH_WITHIN_S, health
    if response.status_code == 422:  # planned within the budget is fine too (a faster planner)
        assert f"limit of {PLANNING_BUDGET_S:g} s per request" in response.json()["detail"]
        assert "1,998 vertices" in response.json()["detail"]
    else:
        assert response.status_code == 200, response.text


def test_security_headers_on_pages_and_api(served: ServerUrl):
    for path in ("/", "/api/health", "/docs", "/static/js/map.js"):
        headers = httpx2.get(served + path).headers
        csp = headers["content-security-policy"]
        assert "frame-ancestors 'none'" in csp and "script-src 'self'" in csp
        assert "style-src 'self'" in csp
        assert "unsafe-inline" not in csp and "unsafe-eval" not in csp
        assert headers["x-content-type-options"] == "nosniff"
        assert headers["referrer-policy"] == "same-origin"
        assert headers["x-frame-options"] == "DENY"


def test_page_urls_do_not_come_from_the_host_header(served: ServerUrl):
    page = httpx2.get(served + "/", headers={"Host": "evil.example"}).text
    assert "evil.example" not in page
    docs = httpx2.get(served + "/docs", headers={"Host": "evil.example"}).text
    assert "evil.example" not in docs


INLINE_PATTERNS = {
    "inline script": re.compile(r"<script(?![^>]*\bsrc=)[^>]*>", re.I),
    "style element": re.compile(r"<style\b", re.I),
    "style attribute": re.compile(r"\sstyle\s*=", re.I),
    "event handler attribute": re.compile(r"\son[a-z]+\s*=", re.I),
    "javascript: URL": re.compile(r"javascript:", re.I),
}


@pytest.mark.parametrize("path", sorted((ROOT / "templates").glob("*.html")), ids=lambda p: p.name)
def test_templates_need_no_unsafe_inline(path: Path):
    text = path.read_text()
    found = {
        what: m.group(0)
        for what, m in ((w, p.search(text)) for w, p in INLINE_PATTERNS.items())
        if m
    }
    assert found == {}, f"{path.name}: the CSP would block {found}"


def test_scripts_set_no_style_attributes_or_inline_handlers():
    for path in sorted((ROOT / "static" / "js").glob("*.js")):
        text = path.read_text()
        assert 'setAttribute("style"' not in text, path.name
        assert not re.search(r"\.on[a-z]+\s*=\s*[\"']", text), path.name


def test_openapi_documents_the_security_schemes(client: TestClient):
    spec = client.get("/openapi.json").json()
    schemes = spec["components"]["securitySchemes"]
    assert schemes["bearerToken"] == {
        "type": "http",
        "scheme": "bearer",
        "description": schemes["bearerToken"]["description"],
    }
    assert schemes["sessionCookie"]["in"] == "cookie"
    assert schemes["sessionCookie"]["name"] == "tillpath_session"
    assert schemes["csrfToken"]["in"] == "header"
    plans = spec["paths"]["/api/plans"]["get"]
    assert {"bearerToken": []} in plans["security"]
    assert "security" not in spec["paths"]["/api/health"]["get"]


def test_large_spiral_is_answered_within_the_budget(served: ServerUrl):
    """A spiral's time grows with the field's area: a 130 ha real field of 76 vertices
    (9 s to plan as a spiral) is planned with the deadline, not in the request's thread."""
    collection = json.loads((FIELDS_DIR / "south_africa_2017.geojson").read_text())
    [field] = [
        f["geometry"]
        for f in collection["features"]
        if f["properties"].get("id") == "south_africa_2017-52"
    ]
    vertices = sum(len(ring) - 1 for ring in field["coordinates"])
    holes = len(field["coordinates"]) - 1
    assert vertices <= INLINE_MAX_VERTICES and holes <= INLINE_MAX_HOLES  # small by its size

    def post() -> httpx2.Response:
        return httpx2.post(
            f"{served}/api/plans/preview",
            json={"field": field, "interval_m": 4, "pattern": "spiral"},
            headers=served.headers,
            timeout=30,
        )

    response, seconds, health = while_health_is_polled(served, post)
    assert seconds < ANSWER_WITHIN_S, seconds
    assert max(health) < HEALTH_WITHIN_S, health
    assert response.status_code == 422, response.text
    detail = response.json()["detail"]
    assert re.search(r"this field of 1[23]\d\.\d ha as a spiral", detail), detail
    assert "another pattern" in detail
    assert f"limit of {PLANNING_BUDGET_S:g} s per request" in detail


def test_a_spirals_area_takes_off_its_holes_however_they_wind():
    """pyproj sums signed ring areas: a hole wound as its exterior must still count as a hole."""
    outer = [(0.0, 0.0), (0.0036, 0.0), (0.0036, 0.0036), (0.0, 0.0036)]
    hole = [(0.0003, 0.0003), (0.0030, 0.0003), (0.0030, 0.0030), (0.0003, 0.0030)]
    opposite = area_ha(Polygon(outer, [hole[::-1]]))
    same = area_ha(Polygon(outer, [hole]))
    assert same == pytest.approx(opposite, rel=1e-9)
    assert same == pytest.approx(area_ha(Polygon(outer)) - area_ha(Polygon(hole)), rel=1e-9)
