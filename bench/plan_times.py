"""Time the 223 real fields at 4 m per vehicle, in process, as ``bench.bench_fields`` plans them.

``python -m bench.plan_times [VEHICLE ...]`` (default ``hand_tractor small_tractor``): the
planner's kernels warmed up, 20 fields planned once untimed, then all 223 fields planned twice
per vehicle with the garbage collector off; prints both totals [s] and the failures. A quick
figure to compare two trees back to back on one machine (run each tree in turn, alternating);
``make bench`` gives the §11 rows.
"""

from __future__ import annotations

import gc
import sys

from bench.bench_fields import DATASETS, load, plan_all
from planner.warm_up import warm_up


def main() -> None:
    vehicles = sys.argv[1:] or ["hand_tractor", "small_tractor"]
    fields = [f for name in DATASETS for f in load(name)]
    warm_up()
    plan_all(fields[:20], 0, vehicles[0])
    for vehicle in vehicles:
        totals, failed = [], 0
        for _ in range(2):
            gc.disable()
            try:
                total, _, _, failures = plan_all(fields, 0, vehicle)
            finally:
                gc.enable()
            totals.append(total)
            failed = len(failures)
        print(
            f"{vehicle}: {len(fields)} fields, {totals[0]:.2f} s and {totals[1]:.2f} s, "
            f"{failed} failed",
            flush=True,
        )


if __name__ == "__main__":
    main()
