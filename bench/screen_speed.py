"""The compiled heading screen against ``cover_heading`` in a loop, on the 223 real fields.

``python -m bench.screen_speed [--step DEG] [--repeats N] [--limit K]`` prepares every real
field of :mod:`bench.bench_fields` as :func:`planner.general.plan_general` does without
headland passes (the ``hand_tractor``'s machine area at 4 m, its parts largest first), then
measures the CPU time (``time.process_time``) of :func:`planner.heading_screen.screen_covers`
over the headings ``0, DEG, ..., < 180`` (default 1°) of every field, and of a Python loop of
:func:`planner.cell_plans.cover_heading` over the same. The two runs alternate ``N`` times
(default 3; the best of each is printed) and their figures are checked equal. The kernels are
warmed first (``make install-dev`` has cached them). ``--limit K`` takes the first K fields.
Not part of ``make bench``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import shapely

from bench.bench_fields import DATASETS, INTERVAL_M, load
from planner.cell_plans import cover_heading
from planner.decomposition import SweepRings, sweep_rings
from planner.errors import PlannerError
from planner.fitted_cells import _turn_count
from planner.heading_screen import screen_covers
from planner.line_ends import machine_area
from planner.projection import field_frame
from planner.screen_kernels import warm_up
from planner.vehicles import resolve_vehicle


def prepared_field(
    field_lonlat: shapely.Polygon, interval_m: float = INTERVAL_M, vehicle: str = "hand_tractor"
) -> tuple[list[SweepRings], float]:
    """``plan_general``'s parts of a field (no headland passes) and its ``edge_m`` [m]."""
    local = shapely.orient_polygons(field_frame(field_lonlat).to_local(field_lonlat))
    machine = resolve_vehicle(vehicle)
    parts = list(shapely.get_parts(machine_area(local, machine)))
    parts.sort(key=lambda p: (-p.area, p.bounds))
    edge_m = max((interval_m - machine.width_m) / 2.0, interval_m / 4.0)
    return [sweep_rings(p) for p in parts], edge_m


def _screened(
    fields: list[tuple[list[SweepRings], float]], headings: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    return [screen_covers(parts, headings, INTERVAL_M, edge) for parts, edge in fields]


def _looped(
    fields: list[tuple[list[SweepRings], float]], headings: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    out = []
    for parts, edge in fields:
        covers = [cover_heading(parts, float(h), INTERVAL_M, edge) for h in headings]
        out.append(
            (
                np.array([c.covered_m2 for c in covers]),
                np.array([c.line_count for c in covers]),
                np.array([_turn_count(c) for c in covers]),
            )
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.screen_speed")
    parser.add_argument("--step", type=float, default=1.0, help="heading step [deg]")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--limit", type=int, default=None, help="only the first LIMIT fields")
    args = parser.parse_args()
    headings = np.arange(0.0, 180.0, args.step)
    fields = []
    for name in DATASETS:
        for _, field in load(name):
            try:
                fields.append(prepared_field(field))
            except PlannerError:  # too narrow for the vehicle: plan_general refuses it too
                continue
    fields = fields[: args.limit]
    warm_up()
    best = {"screen": np.inf, "loop": np.inf}
    results = {}
    for _ in range(args.repeats):
        for name, run in (("screen", _screened), ("loop", _looped)):
            started = time.process_time()
            results[name] = run(fields, headings)
            best[name] = min(best[name], time.process_time() - started)
    for fast, slow in zip(results["screen"], results["loop"], strict=True):
        for f, s in zip(fast, slow, strict=True):
            assert np.array_equal(f, s, equal_nan=True), (f, s)
    print(
        f"{len(fields)} fields × {len(headings)} headings: screen_covers {best['screen']:.2f} s, "
        f"cover_heading loop {best['loop']:.2f} s CPU (best of {args.repeats}), "
        f"{best['loop'] / best['screen']:.1f} ×; figures equal"
    )


if __name__ == "__main__":
    main()
