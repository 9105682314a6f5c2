"""A digest of every plan of the real fields, to show a change leaves plans as they were.

``python -m bench.plan_digest > FILE`` plans the 223 real fields of :mod:`bench.bench_fields`
at 4 m with ``hand_tractor``, ``small_tractor`` and ``rover``, and every fourth field at 2.5 m
with ``paper_g1000`` and ``small_tractor`` (781 plans, about 30 s), and prints one line per
plan: the vehicle, interval and field, then a SHA-256 of its segments (kind and every
coordinate's bits) and its coverage, length and heading (or the error it raised). Run it in
two trees and ``diff`` the files: a speed-up meant to change nothing must leave no line
different (``bench.compare_trees`` compares the figures of two trees instead, for a change
meant to move them).
"""

from __future__ import annotations

import hashlib

import numpy as np
from shapely import Polygon

from bench.bench_fields import DATASETS, load
from planner import plan_coverage

#: (vehicle, interval [m], every how many fields).
CASES = (
    ("hand_tractor", 4.0, 1),
    ("small_tractor", 4.0, 1),
    ("rover", 4.0, 1),
    ("paper_g1000", 2.5, 4),
    ("small_tractor", 2.5, 4),
)


def digest(field: Polygon, vehicle: str, interval_m: float) -> str:
    """SHA-256 of one plan's segments and figures, or the error it raised."""
    try:
        plan = plan_coverage(field, interval_m=interval_m, vehicle=vehicle)
    except ValueError as error:
        return f"error {error}"
    h = hashlib.sha256()
    for segment in plan.segments:
        h.update(segment.kind.encode())
        h.update(np.asarray(segment.lonlat, dtype=np.float64).tobytes())
    s = plan.stats
    h.update(repr((s.coverage_ratio, s.path_length_m, s.angle_deg)).encode())
    return h.hexdigest()


def main() -> None:
    fields = [f for name in DATASETS for f in load(name)]
    for vehicle, interval_m, every in CASES:
        for field_id, field in fields[::every]:
            print(f"{vehicle} {interval_m:g} {field_id} {digest(field, vehicle, interval_m)}")


if __name__ == "__main__":
    main()
