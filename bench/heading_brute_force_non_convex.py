"""How far the non-convex heading search is from a 1° brute force (R5, issue 9 item 5).

``python -m bench.heading_brute_force_non_convex [FIELDS] [--cases] [--fixed-cache DIR]``
plans each of a seeded draw of star fields with holes (:func:`star_jobs`: the fields of
``tests/planner/test_heading_rule_non_convex.py``, drawn the way its cases are: 5–16
vertices, 1–3 holes asked for, 50–500 m, intervals a tenth to a fortieth of the size) once
with the heading searched and 180 times at a fixed heading, every 1° (``angle_deg``, as a
user would). ``--cases`` measures that test file's own cases instead.

Per field it prints the rule's measure (:mod:`bench.heading_rule`, the one the test holds):
the *coverage shortfall* beyond R5's 0.2 pp slack (target: 0 on every field) and the
*length excess* over the shortest fixed heading that keeps the rule (target: ≤ 1 %).
Then the counts.
The default hand tractor. Not part of ``make bench`` (43 s of CPU for the 25 fields,
filling the cache, on a 2-core AMD EPYC with the planner of fc04eca).

``--fixed-cache DIR`` keeps each field's 180 fixed-heading figures (heading, coverage,
length) in ``DIR`` and reads them back on the next run, so that only the searched plan is
planned again: a change to the search is then measured in seconds. The cache is only right
while the change leaves every fixed-heading plan as it was (a change to how headings are
ranked or fitted, not to how a heading is planned): empty ``DIR`` after any other change.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from bench.heading_rule import LOSS_PCT, Outcome, compare
from bench.shapes import NON_CONVEX_CASES, field_from_local, star_field

#: The test file's cases: (vertices, seed, size [m], holes asked for, interval [m]).
TEST_CASES = list(NON_CONVEX_CASES.values())


def star_jobs(count: int, *, seed: int = 5) -> list[tuple[int, int, float, int, float]]:
    """A seeded draw of ``count`` star-field cases: (vertices, seed, size, holes, interval)."""
    rng = np.random.default_rng(seed)
    jobs = []
    for _ in range(count):
        n = int(rng.integers(5, 17))
        field_seed = int(rng.integers(0, 2**32))
        size_m = float(10 ** rng.uniform(math.log10(50.0), math.log10(500.0)))
        holes = int(rng.integers(1, 4))
        interval_m = round(size_m / float(rng.uniform(10.0, 40.0)), 2)
        jobs.append((n, field_seed, size_m, holes, interval_m))
    return jobs


def measure(
    n: int, seed: int, size_m: float, holes: int, interval_m: float, cache: Path | None = None
) -> Outcome:
    """Plan one star-field case searched and at every 1° fixed heading (:func:`compare`)."""
    local = star_field(n, seed, size_m, holes)
    field = field_from_local(list(local.exterior.coords), [list(h.coords) for h in local.interiors])
    return compare(field, interval_m, cache=cache)


def main() -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.heading_brute_force_non_convex")
    parser.add_argument("fields", nargs="?", type=int, default=25, help="star fields drawn")
    parser.add_argument("--cases", action="store_true", help="the test file's cases instead")
    parser.add_argument(
        "--fixed-cache", type=Path, default=None, help="keep the fixed-heading figures here"
    )
    args = parser.parse_args()
    cache_dir = args.fixed_cache
    jobs = TEST_CASES if args.cases else star_jobs(args.fields)
    started = time.process_time()
    outcomes = []
    for k, job in enumerate(jobs):
        n, seed, size_m, holes, interval_m = job
        name = f"star-{n}-{seed}-{size_m:.6f}-{holes}-{interval_m:g}.npy"
        o = measure(*job, cache=None if cache_dir is None else cache_dir / name)
        outcomes.append(o)
        print(
            f"field {k:2d} ({n}, {seed}, {size_m:.1f} m, {holes} holes, {interval_m} m): "
            f"{o.describe()}",
            flush=True,
        )
    short = [o.shortfall_pp for o in outcomes]
    print(
        f"{len(outcomes)} fields: coverage more than 0.2 pp below the best fixed heading's on "
        f"{sum(s > 0.0 for s in short)} (worst {max(short):.3f} pp beyond the slack); length "
        f"within {LOSS_PCT:g} % of the brute force on "
        f"{sum(o.excess_pct <= LOSS_PCT for o in outcomes)} (worst "
        f"{max(o.excess_pct for o in outcomes):+.2f} %); "
        f"{time.process_time() - started:.0f} s CPU"
    )


if __name__ == "__main__":
    main()
