"""A live run fed by a flaky logger: concurrent, shuffled, overlapping and repeated batches.

Runs under a real uvicorn server on committed sessions (the fixtures of
``test_live_server``): on a SQLite file and on PostgreSQL when ``TILLPATH_TEST_DATABASE_URL``
is set. Every fix must end up stored exactly once, in time order.
"""

from __future__ import annotations

import datetime as dt
import random
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import gpxpy
import httpx2
from sqlalchemy import text

from app.db import get_engine
from app.testing import ServerUrl
from tests.app.test_live_server import PAPER, database_url, server_url  # noqa: F401
from tests.app.track_files import RUN_START, simulated_run

N_FIXES = 1000
THREADS = 8


def logger_fixes() -> list[dict[str, Any]]:
    """1,000 fixes of the simulated run at 10 Hz, times alternately ISO and epoch seconds."""
    sim = simulated_run()
    fixes = []
    for i in range(N_FIXES):
        when = RUN_START + dt.timedelta(milliseconds=round(float(sim.time_s[i]) * 1000))
        t: str | float = when.isoformat() if i % 2 else when.timestamp()
        fixes.append({"t": t, "lat": float(sim.lat[i]), "lon": float(sim.lon[i])})
    return fixes


def flaky_batches(fixes: list[dict[str, Any]], rng: random.Random) -> list[list[dict[str, Any]]]:
    """Shuffled batches of 20–120 fixes, overlapping windows, and every batch sent twice."""
    shuffled = fixes[:]
    rng.shuffle(shuffled)
    batches = []
    i = 0
    while i < len(shuffled):
        size = rng.randint(20, 120)
        batches.append(shuffled[i : i + size])
        i += size
    for _ in range(10):  # windows in time order that overlap the batches above
        start = rng.randrange(0, len(fixes) - 150)
        batches.append(fixes[start : start + rng.randint(50, 150)])
    batches = batches + [rng.sample(b, len(b)) for b in batches]  # retried, reordered
    rng.shuffle(batches)
    return batches


def test_concurrent_retried_batches_store_each_fix_once_in_time_order(
    server_url: ServerUrl,  # noqa: F811
    database_url: str,  # noqa: F811
):
    with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=60) as client:
        plan = client.post("/api/plans", json={"field": PAPER, "interval_m": 4})
        assert plan.status_code == 201, plan.text
        run = client.post(f"/api/plans/{plan.json()['id']}/runs")
        assert run.status_code == 201, run.text
        run_id = run.json()["id"]

    fixes = logger_fixes()
    batches = flaky_batches(fixes, random.Random(11))
    assert sum(len(b) for b in batches) > 2 * N_FIXES

    def post(worker: int) -> int:
        stored = 0
        with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=60) as client:
            for batch in batches[worker::THREADS]:
                response = client.post(f"/api/runs/{run_id}/fixes", json=batch)
                assert response.status_code == 200, response.text
                assert response.json()["received"] == len(batch)
                stored += response.json()["stored"]
        return stored

    with ThreadPoolExecutor(max_workers=THREADS) as pool:
        stored = sum(pool.map(post, range(THREADS)))

    # Each fix was reported new by exactly one response, and is stored exactly once.
    assert stored == N_FIXES
    with get_engine(database_url).connect() as conn:
        count, distinct = conn.execute(
            text("SELECT count(*), count(DISTINCT t) FROM fixes WHERE run_id = :r"), {"r": run_id}
        ).one()
    assert count == distinct == N_FIXES

    with httpx2.Client(base_url=server_url, headers=server_url.headers, timeout=60) as client:
        view = client.get(f"/api/runs/{run_id}").json()
        assert view["fix_count"] == N_FIXES
        gpx = gpxpy.parse(client.get(f"/api/runs/{run_id}/export/gpx").text)
    points = gpx.tracks[0].segments[0].points
    expected = [
        RUN_START + dt.timedelta(milliseconds=round(float(t) * 1000))
        for t in simulated_run().time_s[:N_FIXES]
    ]
    assert [p.time for p in points] == expected
    assert [(p.latitude, p.longitude) for p in points] == [(f["lat"], f["lon"]) for f in fixes]
