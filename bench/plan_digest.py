"""A digest of every plan of the real fields, to show a change leaves plans as they were.

``python -m bench.plan_digest > FILE`` plans the 223 real fields of :mod:`bench.bench_fields`
at 4 m with ``hand_tractor``, ``small_tractor`` and ``rover``; and every fourth field at 2.5 m
with ``paper_g1000`` and ``small_tractor``, at 4 m with one headland pass (``hand_tractor``,
and ``small_tractor`` from a start at the field's first vertex) and at 4 m from that start
with ``small_tractor`` (949 plans, about a minute); and prints one line per plan: the case
and field, then a SHA-256 of its segments (kind and every coordinate's bits) and its
coverage, length and heading (or the error it raised). Run it in
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

#: (vehicle, interval [m], every how many fields, headland passes, start at the first vertex).
CASES = (
    ("hand_tractor", 4.0, 1, 0, False),
    ("small_tractor", 4.0, 1, 0, False),
    ("rover", 4.0, 1, 0, False),
    ("paper_g1000", 2.5, 4, 0, False),
    ("small_tractor", 2.5, 4, 0, False),
    ("hand_tractor", 4.0, 4, 1, False),
    ("small_tractor", 4.0, 4, 1, True),
    ("small_tractor", 4.0, 4, 0, True),
)


def digest(field: Polygon, vehicle: str, interval_m: float, passes: int, start: bool) -> str:
    """SHA-256 of one plan's segments and figures, or the error it raised."""
    start_lonlat = tuple(field.exterior.coords[0]) if start else None
    try:
        plan = plan_coverage(
            field,
            interval_m=interval_m,
            vehicle=vehicle,
            headland_passes=passes,
            start_lonlat=start_lonlat,
        )
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
    for vehicle, interval_m, every, passes, start in CASES:
        for field_id, field in fields[::every]:
            figures = digest(field, vehicle, interval_m, passes, start)
            print(f"{vehicle} {interval_m:g} passes={passes} start={start} {field_id} {figures}")


if __name__ == "__main__":
    main()
