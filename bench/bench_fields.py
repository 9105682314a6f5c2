"""All 223 real fields at 4 m (product.md §11: ≤ 5 s total, none fails), per dataset; and
with ``small_tractor`` (≤ 5 s, none fails, 0 m of path outside)."""

from __future__ import annotations

import gc
import json
import statistics
import time
from pathlib import Path

import shapely
from shapely import LineString, Polygon

from bench.common import verdict
from planner import plan_coverage
from planner.projection import field_frame

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
    fields: list[tuple[str, Polygon]], passes: int, vehicle: str = "hand_tractor"
) -> tuple[float, list[float], list[float], list[str]]:
    """Total seconds, coverage ratios, path length per hectare, failures."""
    coverage, per_ha, failures = [], [], []
    total = 0.0
    for field_id, field in fields:
        started = time.perf_counter()
        try:
            plan = plan_coverage(
                field, interval_m=INTERVAL_M, headland_passes=passes, vehicle=vehicle
            )
        except ValueError as error:
            failures.append(f"{field_id}: {error}")
            continue
        finally:
            total += time.perf_counter() - started
        coverage.append(plan.stats.coverage_ratio)
        per_ha.append(plan.stats.path_length_m / (plan.stats.area_m2 / 10_000.0))
    return total, coverage, per_ha, failures


def outside_m(field: Polygon, vehicle: str) -> float:
    """Plan once; return the metres of path whose body (half the width) leaves the field.

    The turns' curvature is held by ``tests/planner/test_vehicles_in_plans.py`` on the same
    fields (``assert_turns_drivable``), not measured here.
    """
    plan = plan_coverage(field, interval_m=INTERVAL_M, vehicle=vehicle)
    frame = field_frame(plan.field_lonlat)
    field_local = frame.to_local(plan.field_lonlat)
    assert plan.vehicle is not None
    machine = field_local.buffer(-plan.vehicle.width_m / 2 + 0.01)
    outside = 0.0
    for segment in plan.segments:
        if segment.kind == "transit" or len(segment.lonlat) < 2:
            continue
        path = frame.to_local(LineString(segment.lonlat))
        outside += path.difference(machine).length
    return outside


#: Timed passes over all the fields per §11 row: the best is held to the budget, every pass
#: is reported. On a shared VM one pass can run 20 % slower than the next (the same tree,
#: minutes apart); the planner's work is the same in each.
PASSES = 3


def timed_passes(
    fields: list[tuple[str, Polygon]], vehicle: str
) -> tuple[list[float], list[float], list[float], list[str]]:
    """Plan ``fields`` :data:`PASSES` times, the garbage collector off while timed.

    Returns each pass's wall and CPU seconds, and the last pass's coverage ratios and
    failures.
    """
    walls, cpus = [], []
    coverage: list[float] = []
    failures: list[str] = []
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        for _ in range(PASSES):
            cpu_started = time.process_time()
            seconds, coverage, _, failures = plan_all(fields, 0, vehicle)
            cpus.append(time.process_time() - cpu_started)
            walls.append(seconds)
    finally:
        if gc_was_enabled:
            gc.enable()
    return walls, cpus, coverage, failures


def passes_text(walls: list[float], cpus: list[float]) -> str:
    """Every pass's wall (CPU) seconds, in the order run."""
    return ", ".join(f"{w:.2f} s ({c:.2f} s CPU)" for w, c in zip(walls, cpus, strict=True))


def run_vehicle(datasets: dict[str, list[tuple[str, Polygon]]], vehicle: str) -> list[str]:
    """§11: all fields at 4 m with ``vehicle``: time, failures, metres of path outside."""
    everything = [f for fields in datasets.values() for f in fields]
    plan_all(everything[:20], 0, vehicle)
    walls, cpus, coverage, failures = timed_passes(everything, vehicle)
    seconds, cpu_s = min(walls), cpus[walls.index(min(walls))]
    outside = sum(outside_m(field, vehicle) for _, field in everything)
    ok = seconds <= BUDGET_S and not failures and outside < 0.01
    return [
        f"### All {len(everything)} fields at {INTERVAL_M:g} m with `{vehicle}` (§11)",
        "",
        "`python -m bench.run fields`: each field planned once, heading searched, turns the "
        "vehicle drives, its body kept inside; then each plan checked with shapely: the "
        "path's length outside the field eroded by half the vehicle's width. Time: the best "
        f"of {PASSES} passes over all the fields ({passes_text(walls, cpus)}).",
        "",
        "| vehicle | fields | time s | CPU s | failures | path outside m | median coverage | "
        "budget | verdict |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- |",
        f"| {vehicle} | {len(everything)} | {seconds:.2f} | {cpu_s:.2f} | {len(failures)} | "
        f"{outside:.3f} | {statistics.median(coverage):.4f} | ≤ {BUDGET_S:g} s, none fails, "
        f"0 m outside | {'met' if ok else 'NOT met'} |",
        "",
        *[f"- {failure}" for failure in failures],
    ]


def run() -> str:
    datasets = {name: load(name) for name in DATASETS}
    everything = [f for fields in datasets.values() for f in fields]
    plan_all(everything[:20], 0)  # warm-up: imports, projection caches
    walls, cpus, _, _ = timed_passes(everything, "hand_tractor")
    total_s = min(walls)
    gc_was_enabled = gc.isenabled()
    gc.disable()
    try:
        rows, all_failures, total_hl_s = [], [], 0.0
        for name, fields in datasets.items():
            seconds, coverage, per_ha, failures = plan_all(fields, 0)
            seconds_hl, coverage_hl, _, failures_hl = plan_all(fields, 1)
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
        f"All {count} fields at {INTERVAL_M:g} m: {total_s:.2f} s total, the best of {PASSES} "
        f"passes over all of them ({passes_text(walls, cpus)}; budget ≤ {BUDGET_S:g} s: "
        f"{verdict(total_s, BUDGET_S)}); with one headland pass {total_hl_s:.2f} s (the "
        f"datasets' times above, one pass). Failures: {len(all_failures) or 'none'}.",
        "",
        *[f"- {failure}" for failure in all_failures],
    ]
    lines += ["", *run_vehicle(datasets, "small_tractor")]
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(run())
