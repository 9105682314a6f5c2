"""How far the heading search is from a 1° brute force on the 223 real fields (R5, issue 9 item 5).

``python -m bench.heading_brute_force_real [VEHICLE] [--workers N] [--limit K]`` plans every
real field of :mod:`bench.bench_fields` at its 4 m interval once with the heading searched and
180 times at a fixed heading, every 1° (``angle_deg``, as a user would), and measures per field
the rule's measure (:mod:`bench.heading_rule`, as the test holds it and
:mod:`bench.heading_brute_force_non_convex` counts it on star fields): the *coverage
shortfall* beyond R5's 0.2 pp slack (target: 0) and the *length excess* over the shortest
fixed heading that keeps the rule (target: ≤ 1 %).

It prints the fields that miss either target, then the counts. VEHICLE defaults to
``hand_tractor``. The fields are shared among ``--workers`` processes (default 2): with the
hand tractor, 114 s wall and 223 s of CPU on a 2-core AMD EPYC (the planner of fc04eca).
``--limit K`` takes the first K fields. Not part of ``make bench``.

``--fixed-cache DIR`` keeps the fixed-heading figures in ``DIR/VEHICLE/FIELD.npy`` and reads
them back on the next run: then only the searched plans are planned (3.4 s wall on the same
machine, against the 114 s that filled the cache). Only right while the fixed-heading plans
are unchanged (:mod:`bench.heading_brute_force_non_convex`): empty ``DIR`` after any other
change.
"""

from __future__ import annotations

import argparse
import multiprocessing
import time
from pathlib import Path

from bench.bench_fields import DATASETS, INTERVAL_M, load
from bench.heading_rule import LOSS_PCT, Outcome, compare
from planner.errors import PlannerError


def _field_outcome(
    job: tuple[str, object, str, Path | None],
) -> tuple[str, Outcome | None, float]:
    field_id, field, vehicle, cache_dir = job
    cache = None if cache_dir is None else cache_dir / vehicle / f"{field_id}.npy"
    started = time.process_time()
    try:
        outcome = compare(field, INTERVAL_M, vehicle, cache)  # type: ignore[arg-type]
    except PlannerError:  # the field is refused at 4 m (the bench_fields row counts those)
        outcome = None
    return field_id, outcome, time.process_time() - started


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.heading_brute_force_real")
    parser.add_argument("vehicle", nargs="?", default="hand_tractor")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--limit", type=int, default=None, help="only the first LIMIT fields")
    parser.add_argument(
        "--fixed-cache", type=Path, default=None, help="keep the fixed-heading figures here"
    )
    args = parser.parse_args()
    vehicle, workers = args.vehicle, args.workers
    fields = [(fid, field) for name in DATASETS for fid, field in load(name)][: args.limit]
    jobs = [(fid, field, vehicle, args.fixed_cache) for fid, field in fields]
    with multiprocessing.get_context("fork").Pool(workers) as pool:
        results = pool.map(_field_outcome, jobs, chunksize=1)
    planned = [(fid, o) for fid, o, _ in results if o is not None]
    for fid, o in planned:
        if not o.keeps_rule:
            print(f"{fid}: {o.describe()}")
    refused = [fid for fid, o, _ in results if o is None]
    if refused:
        print(f"refused at {INTERVAL_M:g} m, left out: {', '.join(refused)}")
    short = [o.shortfall_pp for _, o in planned]
    excess = [o.excess_pct for _, o in planned]
    print(
        f"{vehicle}, {len(planned)} fields at {INTERVAL_M:g} m: coverage more than 0.2 pp below "
        f"the best fixed heading's on {sum(s > 0.0 for s in short)} (worst "
        f"{max(short):.3f} pp beyond the slack); length within {LOSS_PCT:g} % of the brute "
        f"force on {sum(e <= LOSS_PCT for e in excess)} (worst {max(excess):+.2f} %); "
        f"{sum(t for _, _, t in results):.0f} s CPU"
    )


if __name__ == "__main__":
    main()
