"""How far the convex heading search is from a 0.1° brute force (issue 9 item 5).

``python -m bench.heading_brute_force [FIELDS]`` plans each of a fixed set of random convex
fields (:func:`bench.shapes.random_convex_jobs`) once with the heading searched
and 1,800 times at a fixed heading, every 0.1°. Coverage first (R5): only the fixed headings
within 0.2 pp of the best fixed coverage count; the best of them by path length is the brute
force. The excess is the searched plan's ``path_length_m`` over that best, in per cent; the
target is ≤ 0.05 % on every field. Not part of ``make bench`` (minutes of CPU).
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from bench.shapes import fixed_heading_figures, random_convex_jobs
from planner import plan_coverage
from planner.angles import COVERAGE_SLACK
from planner.errors import PlannerError

#: The 0.1° grid of fixed headings [deg].
GRID_DEG = np.round(np.arange(0.0, 180.0, 0.1), 1)


def excess_pct(job: tuple, vehicle: str = "hand_tractor") -> tuple[float, float] | None:
    """Searched plan's excess length over the 0.1° brute force [%], and its coverage shortfall
    [pp] against the best fixed coverage; None if the field is too small for the vehicle."""
    field, interval, start, finish = job
    kwargs = {
        "interval_m": interval,
        "start_lonlat": start,
        "finish_lonlat": finish,
        "vehicle": vehicle,
    }
    try:
        searched = plan_coverage(field, **kwargs).stats
    except PlannerError:
        return None
    _, lengths, cover = fixed_heading_figures(field, GRID_DEG.tolist(), **kwargs)
    eligible = cover >= cover.max() - COVERAGE_SLACK - 1e-9
    best = float(lengths[eligible].min())
    shortfall_pp = max(float(cover.max()) - searched.coverage_ratio - COVERAGE_SLACK, 0.0) * 100
    return (searched.path_length_m / best - 1.0) * 100.0, shortfall_pp


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    started = time.process_time()
    excesses, shortfalls = [], []
    for k, job in enumerate(random_convex_jobs(count)):
        result = excess_pct(job)
        if result is None:
            print(f"field {k}: too small for the vehicle", flush=True)
            continue
        excess, shortfall = result
        excesses.append(excess)
        shortfalls.append(shortfall)
        print(
            f"field {k}: {job[1]:.2f} m interval, excess {excess:+.4f} %, "
            f"coverage beyond R5 {shortfall:.4f} pp",
            flush=True,
        )
    print(
        f"{len(excesses)} fields: median excess {statistics.median(excesses):+.4f} %, "
        f"worst {max(excesses):+.4f} %, fields over 0.05 %: "
        f"{sum(e > 0.05 for e in excesses)}; worst coverage beyond R5 {max(shortfalls):.4f} pp; "
        f"{time.process_time() - started:.0f} s CPU"
    )


if __name__ == "__main__":
    main()
