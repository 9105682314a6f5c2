"""All 223 real fields at 4 m (product.md §11: ≤ 5 s total, none fails), per dataset."""

from __future__ import annotations

import gc
import json
import statistics
import time
from pathlib import Path

import shapely
from shapely import Polygon

from bench.common import verdict
from planner import plan_coverage

ROOT = Path(__file__).resolve().parent.parent
FIELDS = ROOT.parent / "shared" / "fields"
DATASETS = ("rwanda_2021", "south_africa_2017", "germany_2018_2019", "netherlands_f2c")
INTERVAL_M = 4.0
BUDGET_S = 5.0


def load(name: str) -> list[tuple[str, Polygon]]:
    collection = json.loads((FIELDS / f"{name}.geojson").read_text(encoding="utf-8"))
    return [
        (f["properties"]["id"], shapely.geometry.shape(f["geometry"]))
        for f in collection["features"]
    ]


def plan_all(
    fields: list[tuple[str, Polygon]], passes: int
) -> tuple[float, list[float], list[float], list[str]]:
    """Total seconds, coverage ratios, path length per hectare, failures."""
    coverage, per_ha, failures = [], [], []
    total = 0.0
    for field_id, field in fields:
        started = time.perf_counter()
        try:
            plan = plan_coverage(field, interval_m=INTERVAL_M, headland_passes=passes)
        except ValueError as error:
            failures.append(f"{field_id}: {error}")
            continue
        finally:
            total += time.perf_counter() - started
        coverage.append(plan.stats.coverage_ratio)
        per_ha.append(plan.stats.path_length_m / (plan.stats.area_m2 / 10_000.0))
    return total, coverage, per_ha, failures


def run() -> str:
    datasets = {name: load(name) for name in DATASETS}
    everything = [f for fields in datasets.values() for f in fields]
    plan_all(everything[:20], 0)  # warm-up: imports, projection caches
    cpu_started = time.process_time()
    plan_all(everything, 0)
    cpu_s = time.process_time() - cpu_started
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        rows, all_failures, total_s, total_hl_s = [], [], 0.0, 0.0
        for name, fields in datasets.items():
            seconds, coverage, per_ha, failures = plan_all(fields, 0)
            seconds_hl, coverage_hl, _, failures_hl = plan_all(fields, 1)
            total_s += seconds
            total_hl_s += seconds_hl
            all_failures += failures + [f"{f} (one headland pass)" for f in failures_hl]
            median = lambda xs: statistics.median(xs) if xs else float("nan")  # noqa: E731
            rows.append(
                f"| {name} | {len(fields)} | {median(coverage):.4f} | {median(coverage_hl):.4f} "
                f"| {min(coverage_hl, default=float('nan')):.4f} | {median(per_ha):,.0f} "
                f"| {seconds * 1000:,.0f} | {seconds_hl * 1000:,.0f} |"
            )
    finally:
        if gc_was_enabled:
            gc.enable()
    count = len(everything)
    lines = [
        "## All real fields (product.md §11, issue 5)",
        "",
        f"`python -m bench.run fields`; every field of `../shared/fields` ({count}, "
        f"paper field excluded) planned once at {INTERVAL_M:g} m, heading searched, no start or "
        "finish, in process (projection included); then again with one headland pass. "
        "Coverage is the plan's reported `coverage_ratio` (R4).",
        "",
        "| dataset | fields | median coverage, no headland | median coverage, 1 headland "
        "pass | lowest, 1 pass | median path m/ha | time ms | time ms, 1 pass |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
        *rows,
        "",
        f"All {count} fields at {INTERVAL_M:g} m: {total_s:.2f} s total (budget ≤ {BUDGET_S:g} s: "
        f"{verdict(total_s, BUDGET_S)}); CPU time of the same run, repeated: {cpu_s:.2f} s "
        "(wall and CPU differ when other processes share the machine); "
        f"with one headland pass {total_hl_s:.2f} s. "
        f"Failures: {len(all_failures) or 'none'}.",
        "",
        *[f"- {failure}" for failure in all_failures],
    ]
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(run())
