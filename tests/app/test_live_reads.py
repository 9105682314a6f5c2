"""``GET /api/runs/{id}?since=…``: a live run's poll answers only what is new, with cached figures.

Under a real uvicorn server on committed sessions (SQLite file; PostgreSQL when configured).
"""

from __future__ import annotations

import time
from typing import Any

import httpx2
import pytest

from app import live
from app.testing import ServerUrl
from tests.app.test_live_server import PAPER, database_url, server_url  # noqa: F401

T0 = 1_795_305_600.0  # 2026-11-22T00:00:00Z [s]


def fixes(start: int, stop: int) -> list[dict[str, Any]]:
    """Fixes at 10 Hz creeping north-east across the paper field."""
    return [
        {"t": T0 + i / 10, "lat": -8.6265 + i * 1e-7, "lon": 115.298 + i * 1e-7}
        for i in range(start, stop)
    ]


def test_a_poll_answers_the_new_fixes_and_the_figures_catch_up(
    server_url: ServerUrl,  # noqa: F811
    monkeypatch: pytest.MonkeyPatch,
):
    monkeypatch.setattr(live, "REFRESH_INTERVAL_S", 0.0)
    with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=30) as client:
        plan = client.post("/api/plans", json={"field": PAPER, "interval_m": 4}).json()
        run = client.post(f"/api/plans/{plan['id']}/runs").json()
        url = f"/api/runs/{run['id']}"
        assert client.post(f"{url}/fixes", json=fixes(0, 300)).json()["stored"] == 300

        full = client.get(url).json()
        assert full["fix_count"] == full["metrics_fix_count"] == 300
        assert len(full["track"]["geometry"]["coordinates"]) == 300

        assert client.post(f"{url}/fixes", json=fixes(300, 500)).json()["stored"] == 200
        poll = client.get(url, params={"since": full["last_fix"]["t"]}).json()
        assert poll["fix_count"] == 500
        coords = poll["track"]["geometry"]["coordinates"]
        assert len(coords) == 200
        assert coords[0] == pytest.approx([115.298 + 300e-7, -8.6265 + 300e-7])
        assert poll["track"]["properties"]["time_s"][0] == pytest.approx(30.0)
        assert poll["started_at"] == full["started_at"]
        assert poll["last_fix"]["lat"] == pytest.approx(-8.6265 + 499e-7)
        # The figures are the last ones computed; a recomputation has started meanwhile.
        assert poll["metrics_fix_count"] == 300
        assert poll["metrics"] == full["metrics"]
        # Missed ground and the receiver note come from the same cache: not recomputed per poll.
        assert full["missed"]["features"], "the creeping run leaves most of the field missed"
        assert poll["missed"] == full["missed"]
        assert poll["receiver"] == full["receiver"]

        deadline = time.monotonic() + 20
        while True:
            again = client.get(url, params={"since": poll["last_fix"]["t"]}).json()
            if again["metrics_fix_count"] == 500:
                break
            assert time.monotonic() < deadline, again["metrics_fix_count"]
            time.sleep(0.1)
        assert again["track"] is None  # nothing newer than the last fix
        assert again["metrics"]["fix_count"] == 500
        latest = client.get(url).json()
        assert again["metrics"] == latest["metrics"]
        assert again["missed"] == latest["missed"] and again["missed"] != full["missed"]


def test_a_poll_with_a_bad_since_is_a_422(server_url: ServerUrl):  # noqa: F811
    with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=30) as client:
        plan = client.post("/api/plans", json={"field": PAPER, "interval_m": 4}).json()
        run = client.post(f"/api/plans/{plan['id']}/runs").json()
        response = client.get(f"/api/runs/{run['id']}", params={"since": "yesterday"})
        assert response.status_code == 422
        assert response.json()["detail"].startswith("since: ")
        empty = client.get(f"/api/runs/{run['id']}", params={"since": "2026-01-01T00:00:00Z"})
        assert empty.status_code == 200
        assert empty.json()["fix_count"] == 0 and empty.json()["track"] is None
