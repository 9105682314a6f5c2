"""Planner budgets (product.md §11): the paper field ≤ 2 ms, a 100 ha convex field ≤ 25 ms
(both with the default vehicle, the hand tractor), and ≤ 50 ms with ``small_tractor``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import shapely
from shapely import Polygon

from bench.common import summary_ms, time_calls, verdict
from planner import local_frame, parse_field_geojson, plan_coverage
from planner.export import plan_to_geojson

ROOT = Path(__file__).resolve().parent.parent
PAPER = ROOT.parent / "shared" / "fields" / "paper_ketewel.geojson"


def hundred_hectare_field() -> Polygon:
    """A convex, octagon-like 100 ha field in Brandenburg, edges at odd angles."""
    corners = [(0, 0), (820, -60), (1130, 260), (1180, 720), (900, 1080), (300, 1150), (-60, 800)]
    polygon = Polygon(corners)
    polygon = shapely.affinity.scale(polygon, *(2 * [math.sqrt(1_000_000 / polygon.area)]))
    return local_frame(13.4, 52.5).to_lonlat(polygon)


def run() -> str:
    spec = parse_field_geojson(json.loads(PAPER.read_text()))

    def paper() -> None:
        plan = plan_coverage(
            spec.field_lonlat,
            interval_m=4.0,
            start_lonlat=spec.start_lonlat,
            finish_lonlat=spec.finish_lonlat,
        )
        json.dumps(plan_to_geojson(plan))

    big = hundred_hectare_field()
    big_plan = plan_coverage(big, interval_m=1.0)
    paper_ms = summary_ms(time_calls(paper, repeat=500))
    big_ms = summary_ms(time_calls(lambda: plan_coverage(big, interval_m=1.0), repeat=60))
    small_plan = plan_coverage(big, interval_m=1.0, vehicle="small_tractor")
    small_ms = summary_ms(
        time_calls(lambda: plan_coverage(big, interval_m=1.0, vehicle="small_tractor"), repeat=40)
    )
    rows = [
        (
            "Paper field (4 m, start + finish, hand tractor), projection and GeoJSON included",
            paper_ms,
            2.0,
            "4 lines",
        ),
        (
            "100 ha convex field at 1 m, heading searched "
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
        "`python -m bench.run planner`; in process, median of repeated calls after warm-up.",
        "",
        "| case | result | median ms | p10–p90 ms | budget | verdict |",
        "| --- | --- | ---: | ---: | ---: | --- |",
    ]
    for name, (median, p10, p90), budget, result in rows:
        lines.append(
            f"| {name} | {result} | {median:.2f} | {p10:.2f}–{p90:.2f} | ≤ {budget:g} ms "
            f"| {verdict(median, budget)} |"
        )
    lines.append("")
    return "\n".join(lines)
