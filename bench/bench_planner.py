"""Planner budgets (product.md §11): the paper field ≤ 2 ms, a 100 ha convex field ≤ 25 ms
(both with the default vehicle, the hand tractor), and ≤ 50 ms with ``small_tractor``.

And three pathological fields (issue 9), each ≤ 2 s: a 1,999-vertex wavy boundary, a field
with 50 holes and a 1,998-vertex comb.
"""

from __future__ import annotations

import json
import math
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from pydantic import TypeAdapter
from shapely import Polygon

from bench.common import small_quadrilaterals, summary_ms, time_calls_cpu, verdict
from planner import PlanStats, local_frame, parse_field_geojson, plan_coverage
from planner.export import plan_to_geojson

ROOT = Path(__file__).resolve().parent.parent
PAPER = ROOT.parent / "shared" / "fields" / "paper_ketewel.geojson"
#: Random small fields planned for the CPU per plan of a smallholder's plot.
SMALL_FIELDS = 150
#: The plan's GeoJSON as the API writes it: POST /plans answers a ``PlanRead`` (its
#: ``geojson: dict[str, Any]``) through FastAPI's response model, which serialises with
#: pydantic's JSON serialiser (``dump_json``, pydantic-core), not ``json.dumps``.
GEOJSON_JSON = TypeAdapter(dict[str, Any])


def hundred_hectare_field() -> Polygon:
    """A convex, octagon-like 100 ha field in Brandenburg, edges at odd angles."""
    corners = [(0, 0), (820, -60), (1130, 260), (1180, 720), (900, 1080), (300, 1150), (-60, 800)]
    polygon = Polygon(corners)
    polygon = shapely.affinity.scale(polygon, *(2 * [math.sqrt(1_000_000 / polygon.area)]))
    return local_frame(13.4, 52.5).to_lonlat(polygon)


def wavy_field() -> Polygon:
    """A 7 ha round field whose 1,999-vertex boundary waves 2 m in and out 666 times."""
    t = np.linspace(0.0, 2.0 * math.pi, 1999, endpoint=False)
    r = 150.0 + 2.0 * np.sin(666.0 * t)
    return local_frame(13.4, 52.5).to_lonlat(Polygon(np.stack([r * np.cos(t), r * np.sin(t)], 1)))


def holes_field() -> Polygon:
    """A 60 ha rectangle with 50 round holes (ponds, trees) of 5–15 m radius, 32 vertices each."""
    rng = np.random.default_rng(1)
    holes: list[Polygon] = []
    while len(holes) < 50:
        hole = shapely.Point(rng.uniform([20, 20], [980, 580])).buffer(rng.uniform(5, 15), 8)
        if all(hole.distance(other) > 5 for other in holes):
            holes.append(hole)
    field = Polygon(shapely.box(0, 0, 1000, 600).exterior, [h.exterior for h in holes])
    return local_frame(13.4, 52.5).to_lonlat(field)


def comb_field() -> Polygon:
    """A 14 ha comb: a 20 m back with 499 teeth 60 m long, 3 m wide, 2 m apart (1,998 vertices)."""
    teeth, width, gap = 499, 3.0, 2.0
    boxes = [shapely.box(0, 0, teeth * (width + gap), 20)]
    boxes += [
        shapely.box(i * (width + gap), 0, i * (width + gap) + width, 80) for i in range(teeth)
    ]
    comb: Polygon = shapely.union_all(boxes).simplify(0)
    return local_frame(13.4, 52.5).to_lonlat(comb)


def _plan_once(field: Polygon) -> tuple[float, float, PlanStats]:
    """Wall and CPU seconds of one plan at 4 m, and its figures."""
    wall, cpu = time.perf_counter(), time.process_time()
    plan = plan_coverage(field, interval_m=4.0)
    return time.perf_counter() - wall, time.process_time() - cpu, plan.stats


def _wall_and_cpu(
    function: Callable[[], object], *, repeat: int
) -> tuple[tuple[float, float, float], float]:
    """Median, p10 and p90 of the wall clock [ms], and the median CPU time [ms]."""
    wall, cpu = time_calls_cpu(function, repeat=repeat)
    return summary_ms(wall), statistics.median(cpu) * 1000.0


def run() -> str:
    spec = parse_field_geojson(json.loads(PAPER.read_text()))

    def paper() -> None:
        plan = plan_coverage(
            spec.field_lonlat,
            interval_m=4.0,
            start_lonlat=spec.start_lonlat,
            finish_lonlat=spec.finish_lonlat,
        )
        GEOJSON_JSON.dump_json(plan_to_geojson(plan))

    paper_plan = plan_coverage(
        spec.field_lonlat,
        interval_m=4.0,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
    )
    big = hundred_hectare_field()
    big_plan = plan_coverage(big, interval_m=1.0)
    paper_ms = _wall_and_cpu(paper, repeat=500)
    big_ms = _wall_and_cpu(lambda: plan_coverage(big, interval_m=1.0), repeat=60)
    small_plan = plan_coverage(big, interval_m=1.0, vehicle="small_tractor")
    small_ms = _wall_and_cpu(
        lambda: plan_coverage(big, interval_m=1.0, vehicle="small_tractor"), repeat=40
    )
    rows = [
        (
            "Paper field (4 m, start + finish, hand tractor), projection and GeoJSON included",
            paper_ms,
            2.0,
            f"{paper_plan.stats.line_count} lines",
        ),
        (
            "100 ha convex field at 1 m, heading searched, `hand_tractor` "
            f"({big_plan.stats.area_m2 / 10_000:.1f} ha)",
            big_ms,
            25.0,
            f"{big_plan.stats.line_count} lines",
        ),
        (
            "100 ha convex field at 1 m with `small_tractor` (curved turns inside)",
            small_ms,
            50.0,
            f"{small_plan.stats.line_count} lines",
        ),
    ]
    lines = [
        "## Planner (product.md §11)",
        "",
        "`python -m bench.run planner`; in process, median of repeated calls after warm-up; "
        "wall clock and CPU time (`time.process_time`) of the same calls. The verdict is on "
        "the CPU median: on a shared machine the wall clock also counts other processes.",
        "",
        "| case | result | median ms | p10–p90 ms | CPU median ms | budget | verdict (CPU) |",
        "| --- | --- | ---: | ---: | ---: | ---: | --- |",
    ]
    for name, ((median, p10, p90), cpu_median), budget, result in rows:
        lines.append(
            f"| {name} | {result} | {median:.2f} | {p10:.2f}–{p90:.2f} | {cpu_median:.2f} "
            f"| ≤ {budget:g} ms | {verdict(cpu_median, budget)} |"
        )
    lines += [
        "",
        "Pathological fields (issue 9), 4 m, heading searched, one call each (wall clock and CPU"
        " time: when the machine is shared, CPU time is the figure to compare with the budget).",
        "",
        "| field | result | wall s | CPU s | budget | verdict (CPU) |",
        "| --- | --- | ---: | ---: | ---: | --- |",
    ]
    for name, make in (
        ("1,999-vertex wavy boundary (7 ha)", wavy_field),
        ("50 holes (58 ha)", holes_field),
        ("1,998-vertex comb (14 ha)", comb_field),
    ):
        wall, cpu, stats = _plan_once(make())
        lines.append(
            f"| {name} | {stats.line_count} lines, {stats.coverage_ratio:.3f} covered "
            f"| {wall:.2f} | {cpu:.2f} | ≤ 2 s | {verdict(cpu, 2.0)} |"
        )
    quads = small_quadrilaterals(SMALL_FIELDS)
    for quad in quads[:10]:
        plan_coverage(quad, interval_m=10.0)
    started = time.process_time()
    for quad in quads:
        plan_coverage(quad, interval_m=10.0)
    per_plan_ms = (time.process_time() - started) / len(quads) * 1e3
    lines += [
        "",
        "Small fields (no budget; `plan-batch`'s memory run plans 100,000 of them): "
        f"{SMALL_FIELDS} random quadrilaterals of 0.1–0.6 ha at 10 m, `hand_tractor`, "
        "heading searched: "
        f"{per_plan_ms:.2f} ms CPU per plan.",
        "",
    ]
    return "\n".join(lines)
