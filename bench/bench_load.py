"""A server that stays up (issue 15): mixed load, upload memory, live reads, on a real server.

- **Mixed load**: :func:`app.testing_load.mixed_load` (previews, plans, reads, live fixes,
  polls, uploads, simulations, deletes racing reads) from ``THREADS`` threads for ``LOAD_S``
  seconds against ``tillpath serve`` with one and two workers, on a SQLite file and on
  PostgreSQL: requests, answers ≥ 500, p50/p99 latency, and every acknowledged write read back.
- **Upload memory**: a 60 MiB CSV log (about 1.3 million fixes) and a 60 MiB GPX track uploaded
  to a one-worker server on SQLite; the server's peak resident memory (``VmHWM``) above its
  idle size (``VmRSS``).
- **Live reads**: a live run fed 216,000 fixes (6 h at 10 Hz) in batches of 10,000; then the
  page's poll, ``GET /api/runs/{id}?since=<last fix>``, median of ``POLLS``; and one full read.
- **Upload of a 6-hour log**: the same 216,000 fixes as a CSV file, end to end over HTTP (read
  as a stream, stored with the bulk path, scored in the answer).

PostgreSQL runs on a database made for the benchmark on the server named by
``TILLPATH_BENCH_DATABASE_URL`` or ``TILLPATH_TEST_DATABASE_URL`` (dropped afterwards).
"""

from __future__ import annotations

import datetime as dt
import json
import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx2
from sqlalchemy import create_engine, text

from app.testing import ServerProcess, scratch_pg_database
from app.testing_load import mixed_load, verify

ROOT = Path(__file__).resolve().parent.parent
PAPER = ROOT.parent / "shared" / "fields" / "paper_ketewel.geojson"
LOAD_S = float(os.environ.get("TILLPATH_BENCH_LOAD_S", "30"))
THREADS = 8
UPLOAD_MIB = 60
LIVE_FIXES = 216_000
POLLS = 20
PG_ENVS = ("TILLPATH_BENCH_DATABASE_URL", "TILLPATH_TEST_DATABASE_URL")
T0_S = 1_795_305_600.0


def _pg_url() -> str | None:
    for name in PG_ENVS:
        if os.environ.get(name):
            return os.environ[name]
    return None


def _memory_mib(pid: int, key: str) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(key):
            return int(line.split()[1]) / 1024
    raise KeyError(key)


def _paper() -> dict[str, Any]:
    geometry: dict[str, Any] = json.loads(PAPER.read_text())["features"][0]["geometry"]
    return geometry


def _csv_file(path: Path, *, rows: int | None = None, mib: float | None = None) -> int:
    """Write a 10 Hz CSV log (``rows`` fixes, or ``mib`` MiB of them); return the fix count."""
    written = 0
    with path.open("w") as out:
        out.write("time,lat,lon,heading_deg,speed_mps\n")
        while True:
            if rows is not None and written >= rows:
                break
            if mib is not None and out.tell() >= mib * 2**20:
                break
            i = written
            out.write(
                f"{T0_S + i / 10:.1f},{-8.62645 + (i % 1000) * 2e-8:.8f},"
                f"{115.29805 + (i % 777) * 2e-8:.8f},{i % 360}.0,0.5\n"
            )
            written += 1
    return written


def _gpx_file(path: Path, *, mib: float) -> int:
    """Write a 10 Hz GPX 1.1 track of ``mib`` MiB (the CSV log's fixes); return the count."""
    start = dt.datetime.fromtimestamp(T0_S, tz=dt.UTC)
    written = 0
    with path.open("w") as out:
        out.write(
            '<?xml version="1.0" encoding="UTF-8"?>\n<gpx version="1.1" creator="bench" '
            'xmlns="http://www.topografix.com/GPX/1/1"><trk><name>bench</name><trkseg>\n'
        )
        while out.tell() < mib * 2**20:
            i = written
            when = (start + dt.timedelta(milliseconds=100 * i)).isoformat(timespec="milliseconds")
            out.write(
                f'<trkpt lat="{-8.62645 + (i % 1000) * 2e-8:.8f}" '
                f'lon="{115.29805 + (i % 777) * 2e-8:.8f}"><time>{when[:-6]}Z</time>'
                f"<course>{i % 360}.0</course><speed>0.5</speed></trkpt>\n"
            )
            written += 1
        out.write("</trkseg></trk></gpx>\n")
    return written


def _load_average() -> float:
    """The machine's 1-minute load average (``uptime``)."""
    return os.getloadavg()[0]


def _load_row(label: str, url: str, workers: int, log: Path) -> str:
    server = ServerProcess(url, log=log, serve_args=("--workers", str(workers), "--no-access-log"))
    base = server.start()
    try:
        result = mixed_load(
            lambda: base, _paper(), duration_s=LOAD_S, threads=THREADS, headers=base.headers
        )
        missing = verify(base, result, headers=base.headers)
    finally:
        server.stop()
    return (
        f"| {label} | {workers} | {result.requests:,} | {result.requests / LOAD_S:.0f} | "
        f"{result.errors_5xx} | {result.percentile_ms(0.5):.0f} ms | "
        f"{result.percentile_ms(0.99):.0f} ms | {len(missing)} |"
    )


def _upload_memory(tmp: Path, fmt: str = "csv") -> str:
    big = tmp / f"big.{fmt}"
    fixes = (_gpx_file if fmt == "gpx" else _csv_file)(big, mib=UPLOAD_MIB)
    server = ServerProcess(
        f"sqlite:///{tmp / 'memory.db'}",
        log=tmp / "memory.log",
        serve_args=("--no-access-log",),
        env={"TILLPATH_MAX_UPLOAD_BYTES": str((UPLOAD_MIB + 8) * 2**20)},
    )
    base = server.start()
    try:
        with httpx2.Client(base_url=base, headers=base.headers, timeout=900) as client:
            plan = client.post("/api/plans", json={"field": _paper(), "interval_m": 4}).json()
            idle = _memory_mib(server.pid, "VmRSS")
            started = time.perf_counter()
            with big.open("rb") as body:
                response = client.post(
                    f"/api/plans/{plan['id']}/runs", files={"file": (big.name, body)}
                )
            elapsed = time.perf_counter() - started
            peak = _memory_mib(server.pid, "VmHWM")
        assert response.status_code == 201, response.text[:300]
        assert response.json()["fix_count"] == fixes
    finally:
        server.stop()
    return (
        f"| {big.stat().st_size / 2**20:.0f} MiB {fmt.upper()}, {fixes:,} fixes | {idle:.0f} MiB | "
        f"{peak:.0f} MiB | **{peak - idle:.0f} MiB** | {elapsed:.1f} s |"
    )


def _live_rows(label: str, url: str, tmp: Path) -> str:
    server = ServerProcess(url, log=tmp / "live.log", serve_args=("--no-access-log",))
    base = server.start()
    try:
        with httpx2.Client(base_url=base, headers=base.headers, timeout=600) as client:
            plan = client.post("/api/plans", json={"field": _paper(), "interval_m": 4}).json()
            run = client.post(f"/api/plans/{plan['id']}/runs", json={}).json()
            url_run = f"/api/runs/{run['id']}"
            for start in range(0, LIVE_FIXES, 10_000):
                batch = [
                    {"t": T0_S + i / 10, "lat": -8.62645 + (i % 1000) * 2e-8, "lon": 115.29805}
                    for i in range(start, min(start + 10_000, LIVE_FIXES))
                ]
                assert client.post(f"{url_run}/fixes", json=batch).status_code == 200
            started = time.perf_counter()
            full = client.get(url_run).json()
            full_s = time.perf_counter() - started
            assert full["fix_count"] == LIVE_FIXES
            since = full["last_fix"]["t"]
            polls = []
            for _ in range(POLLS):
                started = time.perf_counter()
                poll = client.get(url_run, params={"since": since})
                polls.append(time.perf_counter() - started)
                assert poll.status_code == 200 and poll.json()["fix_count"] == LIVE_FIXES
            count_s = _count_seconds(url, run["id"])

            csv = tmp / "six_hours.csv"
            _csv_file(csv, rows=LIVE_FIXES)
            started = time.perf_counter()
            with csv.open("rb") as body:
                upload = client.post(
                    f"/api/plans/{plan['id']}/runs", files={"file": ("six_hours.csv", body)}
                )
            upload_s = time.perf_counter() - started
            assert upload.status_code == 201 and upload.json()["fix_count"] == LIVE_FIXES
    finally:
        server.stop()
    return (
        f"| {label} | **{statistics.median(polls) * 1000:.0f} ms** (max "
        f"{max(polls) * 1000:.0f} ms) | {count_s * 1000:.0f} ms | {full_s:.2f} s | "
        f"{upload_s:.1f} s |"
    )


def _count_seconds(url: str, run_id: int) -> float:
    """Median time of the ``count(*)`` of a run's fixes that each poll made before issue 15."""
    engine = create_engine(url)
    try:
        times = []
        with engine.connect() as conn:
            for _ in range(5):
                started = time.perf_counter()
                conn.execute(
                    text("SELECT count(*) FROM fixes WHERE run_id = :r"), {"r": run_id}
                ).scalar_one()
                times.append(time.perf_counter() - started)
        return statistics.median(times)
    finally:
        engine.dispose()


def run() -> str:
    """Measure on SQLite and (if configured) PostgreSQL; return the Markdown section."""
    pg = _pg_url()
    load_rows, live_rows = [], []
    loads = [_load_average()]
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        for workers in (1, 2):
            load_rows.append(
                _load_row(
                    "SQLite (file, WAL)",
                    f"sqlite:///{tmp / f'load{workers}.db'}",
                    workers,
                    tmp / "load.log",
                )
            )
            if pg:
                with scratch_pg_database(pg, prefix="tillpath_bench") as url:
                    load_rows.append(_load_row("PostgreSQL", url, workers, tmp / "load.log"))
        loads.append(_load_average())
        memory_rows = [_upload_memory(tmp, fmt) for fmt in ("csv", "gpx")]
        loads.append(_load_average())
        live_rows.append(_live_rows("SQLite (file, WAL)", f"sqlite:///{tmp / 'live.db'}", tmp))
        if pg:
            with scratch_pg_database(pg, prefix="tillpath_bench") as url:
                live_rows.append(_live_rows("PostgreSQL", url, tmp))
    loads.append(_load_average())
    quiet = max(loads) <= 2
    machine = (
        f"1-minute load average (`uptime`) {min(loads):.1f}–{max(loads):.1f} during the runs"
        + (
            " (the 2-core machine was quiet)."
            if quiet
            else ": other work ran on the 2-core machine, so latencies are upper bounds."
        )
    )
    missing_pg = (
        [] if pg else ["| PostgreSQL | not measured: set TILLPATH_BENCH_DATABASE_URL | | | |"]
    )
    return "\n".join(
        [
            "## A server that stays up: mixed load, upload memory, live reads",
            "",
            f"`tillpath serve` on loopback; {THREADS} client threads of the mixed load "
            f"(`app/testing_load.py`) for {LOAD_S:.0f} s each; the paper field. {machine} "
            f"Command: `TILLPATH_BENCH_LOAD_S={LOAD_S:.0f} python -m bench.run bench_load`.",
            "",
            "| database | workers | requests | per s | answers ≥ 500 | p50 | p99 | "
            "acknowledged writes missing |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
            *load_rows,
            *(["| PostgreSQL | not measured: set TILLPATH_BENCH_DATABASE_URL | | | | | | |"]
              if not pg else []),
            "",
            "Upload memory (one worker, SQLite; budget: under 300 MiB above idle). The server "
            "process's peak resident memory (`VmHWM`) over its size before the upload (`VmRSS`); "
            "the upload is parsed, stored and scored (the answer embeds the metrics, the track "
            "thinned to 20,000 points and the stretches drawn as finely):",
            "",
            "| upload | idle RSS | peak RSS | peak above idle | time |",
            "| --- | --- | --- | --- | --- |",
            *memory_rows,
            "",
            f"Live run of {LIVE_FIXES:,} fixes (6 h at 10 Hz): the page's poll "
            f"(`?since=<last fix>`, median of {POLLS}; budget well under 100 ms; the fix count "
            "is read from the run's row), the `count(*)` of the run's fixes each poll made "
            "before (for comparison, straight on the database), a full read (scored), and the "
            "same log uploaded as a CSV file end to end:",
            "",
            "| database | poll | `count(*)` (no longer in a poll) | full read | "
            "upload 216,000-fix CSV |",
            "| --- | --- | --- | --- | --- |",
            *live_rows,
            *missing_pg,
            "",
        ]
    )  # fmt: skip
