"""Time the spiral on every ninth real field at 4 m, per vehicle, in process.

``python -m bench.spiral_times [VEHICLE ...]`` (default ``small_tractor hand_tractor``): the
planner's kernels warmed up, then fields 1, 10, 19, … of the 223 (25 fields) planned once
each with ``pattern="spiral"``. Prints each plan's time, coverage and path length, and the
totals; ``--json FILE`` also writes them, to compare two trees field by field. A spiral's time
grows with the field's area (its rounds); no §11 budget covers it, and the server plans one
over 10 ha within its per-request budget (:mod:`app.budget`).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from bench.bench_fields import DATASETS, load
from planner import PlannerError, plan_coverage
from planner.warm_up import warm_up


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("vehicles", nargs="*", default=["small_tractor", "hand_tractor"])
    parser.add_argument("--json", type=Path, help="write the figures to this file")
    args = parser.parse_args()
    fields = [f for name in DATASETS for f in load(name)][1::9]
    warm_up()
    figures: dict[str, list[object]] = {}
    times: list[float] = []
    for vehicle in args.vehicles:
        for name, field in fields:
            started = time.perf_counter()
            try:
                plan = plan_coverage(field, interval_m=4.0, vehicle=vehicle, pattern="spiral")
                result: list[object] = [
                    round(plan.stats.coverage_ratio, 6),
                    round(plan.stats.path_length_m, 1),
                ]
            except PlannerError as exc:
                result = [f"refused: {exc}"]
            seconds = time.perf_counter() - started
            times.append(seconds)
            figures[f"{vehicle} {name}"] = [*result, round(seconds, 3)]
            print(f"{vehicle:14} {name:24} {seconds:7.2f} s  {result}", flush=True)
    print(f"{len(times)} plans: {sum(times):.1f} s in all, the slowest {max(times):.2f} s")
    if args.json:
        args.json.write_text(json.dumps(figures, indent=0))


if __name__ == "__main__":
    main()
