"""``POST /api/plans/preview`` while a 200-run Monte Carlo job runs on the same server.

Starts ``tillpath serve --workers 1`` (its local Dask cluster: one worker process,
``TILLPATH_DASK_WORKERS=1``) with a throw-away SQLite database, measures the preview's latency
with ``wrk`` (one connection) on the idle server, then starts a 200-run Monte Carlo simulation
of a real 2.5 ha Rwandan field as a job and measures again while it runs. Budget (product.md
§11): the median within 1.5 × of the idle server's.
"""

from __future__ import annotations

import json
import os
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any

from app.testing import ServerUrl, running_server
from bench.bench_api import LUA, PAPER_FIELD, ensure_wrk, post_once, run_wrk

ROOT = Path(__file__).resolve().parent.parent
RWANDA = ROOT.parent / "shared" / "fields" / "rwanda_2021.geojson"
BUDGET_RATIO = 1.5
DURATION_S = 8
RUNS = 200


def call(
    base: ServerUrl, path: str, body: Any = None, method: str | None = None
) -> tuple[dict[str, str], Any]:
    data = None if body is None else json.dumps(body).encode()
    headers = {"Content-Type": "application/json", **base.headers}
    request = urllib.request.Request(base + path, data=data, headers=headers, method=method)
    with urllib.request.urlopen(request, timeout=30) as response:
        return dict(response.headers), json.loads(response.read())


def job_field() -> dict[str, Any]:
    """A real field of about 2.5 ha, so that 200 runs last well beyond the measurement."""
    features = json.loads(RWANDA.read_text())["features"]
    feature: dict[str, Any] = min(features, key=lambda f: abs(f["properties"]["area_m2"] - 25_000))
    return feature


def run() -> str:
    """Measure and return the Markdown section."""
    title = "## Preview latency while a Monte Carlo job runs\n"
    wrk = ensure_wrk()
    if wrk is None:
        return title + "\nNot measured: `wrk` is not installed (`apt-get install wrk`).\n"
    field = json.loads(PAPER_FIELD.read_text())
    body = json.dumps({"name": "paper_ketewel", "field": field, "interval_m": 4}).encode()
    os.environ["TILLPATH_DASK_WORKERS"] = "1"
    with tempfile.TemporaryDirectory(prefix="tillpath-bench-") as tmp:
        script = Path(tmp) / "preview.lua"
        with running_server(f"sqlite:///{tmp}/bench.db", serve_args=["--workers", "1"]) as url:
            authorization = json.dumps(url.headers["Authorization"])
            script.write_text(
                LUA.format(body=json.dumps(body.decode()), authorization=authorization)
            )
            post_once(url, body)
            run_wrk(wrk, url, script, 1, 1, 2)
            idle = run_wrk(wrk, url, script, 1, 1, DURATION_S)
            feature = job_field()
            _, plan = call(url, "/api/plans", {"field": feature, "interval_m": 4})
            headers, job = call(url, f"/api/plans/{plan['id']}/simulations", {"runs": RUNS})
            location = headers["location"]
            while call(url, location)[1]["status"] == "queued":
                time.sleep(0.2)
            busy = run_wrk(wrk, url, script, 1, 1, DURATION_S)
            after = call(url, location)[1]
            # Cancel the rest: the figure is taken, the machine is shared.
            call(url, location, method="DELETE")
    ratio = busy["p50_us"] / idle["p50_us"]
    still = after["status"] == "running"
    rows = [
        f"| idle | {idle['p50_us'] / 1000:.2f} | {idle['p90_us'] / 1000:.2f} | "
        f"{idle['p99_us'] / 1000:.2f} | {idle['requests'] / (idle['duration_us'] / 1e6):.0f} |",
        f"| {RUNS}-run Monte Carlo job running | {busy['p50_us'] / 1000:.2f} | "
        f"{busy['p90_us'] / 1000:.2f} | {busy['p99_us'] / 1000:.2f} | "
        f"{busy['requests'] / (busy['duration_us'] / 1e6):.0f} |",
    ]
    verdict = "within" if ratio <= BUDGET_RATIO else "OVER"
    return "\n".join(
        [
            title,
            "`tillpath serve --workers 1` with its local Dask cluster of one worker process "
            "(`TILLPATH_DASK_WORKERS=1`), SQLite, loopback; `wrk`, one connection, "
            f"{DURATION_S} s per row. The job: {RUNS} runs of field "
            f"`{feature['properties']['id']}` of `rwanda_2021.geojson` "
            f"({feature['properties']['area_m2'] / 1e4:.1f} ha, 4 m); it was "
            f"{'still running' if still else after['status']} at the end of the second row "
            f"({after['progress'] * 100:.1f} % done).",
            "",
            "| server | median ms | p90 ms | p99 ms | requests/s |",
            "| --- | ---: | ---: | ---: | ---: |",
            *rows,
            "",
            f"Budget: busy median within {BUDGET_RATIO:g} × of idle: {ratio:.2f} ×, "
            f"{verdict} budget.",
            "",
        ]
    )


if __name__ == "__main__":
    print(run())
