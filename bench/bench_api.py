"""``POST /api/plans/preview`` under load: the paper field at 4 m, one worker, loopback.

Starts ``tillpath serve --workers 1`` on a free loopback port with a throw-away SQLite
database, checks that the request plans (200), then loads it with ``wrk`` (Debian's package;
installed with apt-get if missing and this runs as root) through a Lua script that sends the
JSON body. Budget (product.md §11): median latency ≤ 10 ms and ≥ 150 requests/s.

Two loads are measured: one connection (latency: each request alone, no queueing) and four
connections (the worker kept busy, requests queueing). The latency budget is judged on the
first, the throughput budget on the better of the two.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

import psutil

from app.testing import ServerUrl, running_server

ROOT = Path(__file__).resolve().parent.parent
PAPER_FIELD = ROOT.parent / "shared" / "fields" / "paper_ketewel.geojson"
BUDGET_MEDIAN_MS = 10.0
BUDGET_RPS = 150.0
WARMUP_S = 2
DURATION_S = 10
#: (label, wrk threads, connections)
LOADS = [("1 connection", 1, 1), ("4 connections", 2, 4)]

LUA = """
wrk.method = "POST"
wrk.body = {body}
wrk.headers["Content-Type"] = "application/json"
wrk.headers["Authorization"] = {authorization}

done = function(summary, latency, requests)
  local e = summary.errors
  io.write(string.format(
    "TILLPATH p50_us=%d p90_us=%d p99_us=%d requests=%d duration_us=%d "
    .. "status_errors=%d socket_errors=%d\\n",
    latency:percentile(50), latency:percentile(90), latency:percentile(99),
    summary.requests, summary.duration, e.status, e.connect + e.read + e.write + e.timeout))
end
"""


def ensure_wrk() -> str | None:
    """Return the path of ``wrk``, installing Debian's package if possible."""
    found = shutil.which("wrk")
    if found or shutil.which("apt-get") is None or os.geteuid() != 0:
        return found
    print("installing wrk with apt-get …", file=sys.stderr, flush=True)
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    install = ["apt-get", "install", "-y", "-qq", "wrk"]

    def quiet(command: list[str]) -> int:
        done = subprocess.run(
            command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        return done.returncode

    if quiet(install) != 0:
        quiet(["apt-get", "update", "-qq"])
        quiet(install)
    return shutil.which("wrk")


def post_once(url: ServerUrl, body: bytes) -> dict[str, object]:
    headers = {"Content-Type": "application/json", **url.headers}
    request = urllib.request.Request(f"{url}/api/plans/preview", data=body, headers=headers)
    with urllib.request.urlopen(request, timeout=10) as response:
        assert response.status == 200, response.status
        plan: dict[str, object] = json.loads(response.read())
        return plan


def settle(url: ServerUrl, *, timeout_s: float = 60.0, idle_cpu_s: float = 0.3) -> float:
    """Wait until the server and its job workers are idle; return the seconds waited.

    ``tillpath serve`` answers ``/api/health`` before the embedded Dask cluster's worker
    processes have started (some 10 s of a core on a loaded 2-core machine): measured then,
    the first load shares the cores with that start-up, not with what the budget is about.
    Idle: the server's process tree used under ``idle_cpu_s`` of CPU in the last second (an
    idle cluster's heartbeats take some 0.1 s a second of it).
    """
    started = time.monotonic()
    if url.pid is None:
        return 0.0
    server = psutil.Process(url.pid)

    def tree_cpu_s() -> float:
        total = 0.0
        for process in [server, *server.children(recursive=True)]:
            try:
                times = process.cpu_times()
            except psutil.Error:
                continue
            total += times.user + times.system
        return total

    while time.monotonic() - started < timeout_s:
        before = tree_cpu_s()
        time.sleep(1.0)
        if tree_cpu_s() - before < idle_cpu_s:
            break
    return time.monotonic() - started


def run_wrk(
    wrk: str, url: str, script: Path, threads: int, connections: int, seconds: int
) -> dict[str, int]:
    result = subprocess.run(
        [
            wrk,
            f"-t{threads}",
            f"-c{connections}",
            f"-d{seconds}s",
            "--timeout",
            "5s",
            "-s",
            str(script),
            f"{url}/api/plans/preview",
        ],
        capture_output=True,
        text=True,
        timeout=seconds + 30,
        check=True,
    )
    match = re.search(r"^TILLPATH (.*)$", result.stdout, re.MULTILINE)
    if match is None:
        raise RuntimeError(f"wrk printed no summary:\n{result.stdout}\n{result.stderr}")
    return {key: int(value) for key, value in (p.split("=") for p in match.group(1).split())}


def run() -> str:
    """Measure and return the Markdown section."""
    title = "## `POST /api/plans/preview` (HTTP, one worker)\n"
    wrk = ensure_wrk()
    if wrk is None:
        return title + "\nNot measured: `wrk` is not installed (`apt-get install wrk`).\n"

    field = json.loads(PAPER_FIELD.read_text())
    body = json.dumps({"name": "paper_ketewel", "field": field, "interval_m": 4}).encode()

    with tempfile.TemporaryDirectory(prefix="tillpath-bench-") as tmp:
        script = Path(tmp) / "preview.lua"
        with running_server(f"sqlite:///{tmp}/bench.db", serve_args=["--workers", "1"]) as url:
            authorization = json.dumps(url.headers["Authorization"])
            script.write_text(
                LUA.format(body=json.dumps(body.decode()), authorization=authorization)
            )
            plan = post_once(url, body)
            stats = plan["stats"]
            assert isinstance(stats, dict) and stats["line_count"] == 4, stats
            settled_s = settle(url)
            run_wrk(wrk, url, script, 1, 1, WARMUP_S)
            results = [
                (label, run_wrk(wrk, url, script, threads, connections, DURATION_S))
                for label, threads, connections in LOADS
            ]

    rows = []
    for label, r in results:
        rps = r["requests"] / (r["duration_us"] / 1e6)
        errors = r["status_errors"] + r["socket_errors"]
        rows.append(
            f"| {label} | {r['p50_us'] / 1000:.2f} | {r['p90_us'] / 1000:.2f} | "
            f"{r['p99_us'] / 1000:.2f} | {rps:.0f} | {r['requests']} | {errors} |"
        )
    median_ms = results[0][1]["p50_us"] / 1000
    best_rps = max(r["requests"] / (r["duration_us"] / 1e6) for _, r in results)
    verdict_latency = "within" if median_ms <= BUDGET_MEDIAN_MS else "OVER"
    verdict_rps = "within" if best_rps >= BUDGET_RPS else "UNDER"
    return "\n".join(
        [
            title,
            "`tillpath serve --workers 1` (uvicorn) on loopback with a SQLite database, loaded by "
            f"`wrk` for {DURATION_S} s per row after a {WARMUP_S} s warm-up, once the server and "
            f"its job workers were idle ({settled_s:.0f} s after `/api/health` answered); body: "
            "the paper field (`paper_ketewel.geojson`, 4 m). Access log on, as served by "
            "default.",
            "",
            "| load | median ms | p90 ms | p99 ms | requests/s | requests | errors |",
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
            *rows,
            "",
            f"Budget: median ≤ {BUDGET_MEDIAN_MS:g} ms (one connection): {median_ms:.2f} ms, "
            f"{verdict_latency} budget; ≥ {BUDGET_RPS:g} requests/s (best of the two loads): "
            f"{best_rps:.0f}, "
            f"{verdict_rps} budget.",
            "",
        ]
    )


if __name__ == "__main__":
    print(run())
