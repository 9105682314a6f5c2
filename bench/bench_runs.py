"""Field runs: store a 6-hour 10 Hz run (216,000 fixes), then load and score it (issue 6).

Budgets: storing the uploaded log (product.md §11: ≤ 2 s on SQLite and on PostgreSQL) with the
bulk path of :mod:`app.ingest` (the fixes as columns; a new run and its fixes in one
transaction: ``COPY`` on PostgreSQL, ``executemany`` on SQLite), and loading a run's fixes and
scoring them against the plan (``app.runs.load_track`` + ``app.runs.score_run``, i.e.
``navigation.score_track``) in under 2 s. A retried upload of the same fixes into the existing
run (``COPY`` into a temporary table, ``INSERT … ON CONFLICT DO NOTHING``: nothing new) and the
whole ``GET /api/runs/{id}`` body (``run_view``: load, score, thinned track and stretches) are
shown beside them.

The track drives a 1.2 ha plan at 1 m (about 12 km of path) in exactly 6 hours at 10 Hz, with
a slowly wandering 0.5 m error as a tractor on RTK-less GPS shows. PostgreSQL is measured on a
database made for the run on the server named by ``TILLPATH_BENCH_DATABASE_URL`` or
``TILLPATH_TEST_DATABASE_URL``, and dropped afterwards; without either it is left out.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from sqlalchemy.orm import Session

from app import accounts, ingest, runs
from app.db import make_engine, upgrade_database, write
from app.models import Plan, Run
from app.schemas import PlanCreate
from app.services import plan_field
from app.testing import scratch_pg_database
from app.track_fixes import TrackFix
from planner import local_frame

FIXES = 216_000  # 6 h at 10 Hz
RATE_HZ = 10.0
BUDGET_S = 2.0
REPEAT = 5
PG_ENVS = ("TILLPATH_BENCH_DATABASE_URL", "TILLPATH_TEST_DATABASE_URL")


def field_geojson() -> dict[str, Any]:
    """A 150 m × 80 m field near the paper's, as a GeoJSON Polygon."""
    frame = local_frame(115.298, -8.6265)
    box = shapely.box(0.0, 0.0, 150.0, 80.0)
    lon, lat = frame.to_lonlat_xy(*np.asarray(box.exterior.coords).T)
    return {
        "type": "Polygon",
        "coordinates": [[[float(a), float(b)] for a, b in zip(lon, lat, strict=True)]],
    }


def six_hour_track(plan: Plan) -> list[TrackFix]:
    """Drive the plan's waypoints at constant speed for 6 h at 10 Hz, with a wandering error."""
    lon = np.array([w["lon"] for w in plan.waypoints])
    lat = np.array([w["lat"] for w in plan.waypoints])
    frame = local_frame(float(lon.mean()), float(lat.mean()))
    x, y = frame.to_local_xy(lon, lat)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    along = np.linspace(0.0, s[-1], FIXES)
    rng = np.random.default_rng(6)
    # First-order Gauss–Markov error, 0.5 m sigma, 30 s time constant, per axis.
    phi = np.exp(-1.0 / (RATE_HZ * 30.0))
    noise = rng.normal(0.0, 0.5 * np.sqrt(1 - phi**2), (FIXES, 2))
    err = np.zeros_like(noise)
    for i in range(1, FIXES):
        err[i] = phi * err[i - 1] + noise[i]
    tx = np.interp(along, s, x) + err[:, 0]
    ty = np.interp(along, s, y) + err[:, 1]
    tlon, tlat = frame.to_lonlat_xy(tx, ty)
    t0 = 1_795_305_600_000_000  # 2026-11-22T00:00:00Z [µs]
    return [
        TrackFix(t=t0 + i * 100_000, lat=float(b), lon=float(a))
        for i, (a, b) in enumerate(zip(tlon, tlat, strict=True))
    ]


def measure(url: str) -> dict[str, Any]:
    """Insert the run, then time load + score (median of REPEAT) on the database at ``url``."""
    upgrade_database(url)
    engine = make_engine(url)
    try:
        with Session(engine, expire_on_commit=False) as session:
            plan = plan_field(PlanCreate(name="bench", field=field_geojson(), interval_m=1.0))
            plan.organisation_id = accounts.get_or_create_organisation(session, "bench").id
            session.add(plan)
            session.commit()
            fixes = six_hour_track(plan)
            started = time.perf_counter()
            columns = ingest.collect(fixes)
            collect_s = time.perf_counter() - started
            started = time.perf_counter()
            run = runs.create_run_from_columns(
                session, plan, columns, source="csv", report={}, name="6 h"
            )
            insert_s = time.perf_counter() - started
            assert runs.count_fixes(session, run.id) == FIXES
            started = time.perf_counter()
            again = write(session, lambda s: ingest.store_fixes(s, run.id, columns))
            again_s = time.perf_counter() - started
            assert again == 0, again

        load, score, total, view = [], [], [], []
        metrics = None
        for _ in range(REPEAT):
            with Session(engine, expire_on_commit=False) as session:
                plan_row = session.get(Plan, plan.id)
                assert plan_row is not None
                started = time.perf_counter()
                track = runs.load_track(session, run.id)
                loaded = time.perf_counter()
                metrics = runs.score_run(plan_row, track, threshold_m=1.0)
                done = time.perf_counter()
                load.append(loaded - started)
                score.append(done - loaded)
                total.append(done - started)
                assert len(track.t) == FIXES
            with Session(engine, expire_on_commit=False) as session:
                run_row = session.get(Run, run.id)
                assert run_row is not None
                started = time.perf_counter()
                runs.run_view(session, run_row)
                view.append(time.perf_counter() - started)
        assert metrics is not None
        return {
            "collect_s": collect_s,
            "again_s": again_s,
            "insert_s": insert_s,
            "load_s": statistics.median(load),
            "score_s": statistics.median(score),
            "total_s": statistics.median(total),
            "total_max_s": max(total),
            "view_s": statistics.median(view),
            "path_km": plan.stats["path_length_m"] / 1000,
            "xte_rms": metrics.cross_track_rms_m,
            "coverage": metrics.coverage_ratio,
            "stretches": len(metrics.stretches),
        }
    finally:
        engine.dispose()


def _pg_url() -> str | None:
    for name in PG_ENVS:
        if os.environ.get(name):
            return os.environ[name]
    return None


def run() -> str:
    """Measure on SQLite (a temporary file) and PostgreSQL (if configured); return Markdown."""
    results: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        results["SQLite (file, WAL)"] = measure(f"sqlite:///{Path(tmp) / 'bench.db'}")
    base = _pg_url()
    if base:
        with scratch_pg_database(base, prefix="tillpath_bench") as url:
            results["PostgreSQL"] = measure(url)

    lines = [
        "## Field runs: store, load and score a 6-hour 10 Hz run",
        "",
        f"{FIXES:,} fixes (6 h at 10 Hz) along a 1.2 ha plan at 1 m; median of {REPEAT}. "
        f"Budgets: store ≤ {BUDGET_S:.0f} s (bulk path, once), load + score < "
        f"{BUDGET_S:.0f} s. Measured on the shared 2-core machine while other work ran on it.",
        "",
        "| database | fixes to columns | **store (new run)** | verdict | same fixes again | "
        "load | score | load + score | verdict | whole `GET /api/runs/{id}` |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for label, r in results.items():
        store_verdict = "met" if r["insert_s"] <= BUDGET_S else "**missed**"
        verdict = "met" if r["total_max_s"] < BUDGET_S else "**missed**"
        lines.append(
            f"| {label} | {r['collect_s']:.2f} s | **{r['insert_s']:.2f} s** | {store_verdict} | "
            f"{r['again_s']:.2f} s | {r['load_s']:.2f} s | {r['score_s']:.2f} s | "
            f"{r['total_s']:.2f} s (max {r['total_max_s']:.2f} s) | {verdict} | "
            f"{r['view_s']:.2f} s |"
        )
    if not base:
        lines.append(
            "| PostgreSQL | not measured: set TILLPATH_BENCH_DATABASE_URL | | | | | | | | |"
        )
    any_result = next(iter(results.values()))
    lines += [
        "",
        f"Path {any_result['path_km']:.1f} km; the run's cross-track RMS "
        f"{any_result['xte_rms']:.2f} m, coverage {any_result['coverage'] * 100:.1f} %, "
        f"{any_result['stretches']} stretches over 1 m.",
        "",
    ]
    return "\n".join(lines)
