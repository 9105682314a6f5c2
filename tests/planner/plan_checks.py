"""Checks of a plan's requirements (R1–R4), shared by the planner's property tests.

Everything is measured independently of the planner's internals: from the plan's exported
waypoints and segments, re-projected into the field's frame, with shapely.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely import LineString

from planner.projection import field_frame
from planner.types import CoveragePlan

TOLERANCE_M = 0.01  # R1: 1 cm
SPACING_TOLERANCE_M = 1e-3


def local_segments(plan: CoveragePlan, kind: str) -> list[LineString]:
    frame = field_frame(plan.field_lonlat)
    return [frame.to_local(LineString(s.lonlat)) for s in plan.segments if s.kind == kind]


def assert_inside(plan: CoveragePlan) -> None:
    """R1: lines, turns and headland passes lie inside the field, outside every hole."""
    field_local = field_frame(plan.field_lonlat).to_local(plan.field_lonlat)
    grown = field_local.buffer(TOLERANCE_M)
    for kind in ("line", "turn", "headland"):
        for segment in local_segments(plan, kind):
            assert grown.covers(segment), f"{kind} leaves the field by {segment.difference(grown)}"


def line_offsets(plan: CoveragePlan) -> tuple[np.ndarray, float, float]:
    """Lines' positions across the heading, and the field's extent across it [m]."""
    frame = field_frame(plan.field_lonlat)
    theta = np.radians(plan.stats.angle_deg)
    lines = local_segments(plan, "line")
    coords = np.array([np.asarray(line.coords) for line in lines])  # (n, 2, 2)
    across = coords[..., 0] * np.cos(theta) - coords[..., 1] * np.sin(theta)
    # Both ends of a line sit at the same offset: the line runs along the heading.
    assert np.allclose(across[:, 0], across[:, 1], atol=SPACING_TOLERANCE_M)
    field_xy = shapely.get_coordinates(frame.to_local(plan.field_lonlat))
    field_across = field_xy[:, 0] * np.cos(theta) - field_xy[:, 1] * np.sin(theta)
    return np.sort(across[:, 0]), float(field_across.min()), float(field_across.max())


def assert_spacing_and_edges(plan: CoveragePlan) -> None:
    """R2 (interval apart, only an end gap may be smaller) and R3 (outer lines d/2 inside)."""
    d = plan.interval_m
    offsets, low, high = line_offsets(plan)
    if high - low <= d:
        assert len(offsets) == 1
        assert abs(offsets[0] - (low + high) / 2) < SPACING_TOLERANCE_M
        return
    assert abs(offsets[0] - (low + d / 2)) < SPACING_TOLERANCE_M
    assert abs(offsets[-1] - (high - d / 2)) < SPACING_TOLERANCE_M
    gaps = np.diff(offsets)
    assert (gaps <= d + SPACING_TOLERANCE_M).all(), "lines farther apart than the interval"
    off = np.nonzero(np.abs(gaps - d) > SPACING_TOLERANCE_M)[0]
    assert len(off) <= 1, f"more than one gap differs from the interval: {gaps}"
    assert all(i in (0, len(gaps) - 1) for i in off), "a short gap in the middle"


def reference_coverage(plan: CoveragePlan) -> float:
    """R4 with shapely: field ∩ union of footprints (flat caps), over the field's area."""
    field_local = field_frame(plan.field_lonlat).to_local(plan.field_lonlat)
    half = plan.interval_m / 2
    pieces = [line.buffer(half, cap_style="flat") for line in local_segments(plan, "line")]
    pieces += [
        ring.buffer(half, cap_style="flat", join_style="mitre")
        for ring in local_segments(plan, "headland")
    ]
    covered = shapely.intersection(field_local, shapely.union_all(pieces))
    return float(covered.area / field_local.area)


def assert_figures_add_up(plan: CoveragePlan) -> None:
    s = plan.stats
    assert s.line_count == len(local_segments(plan, "line"))
    assert s.waypoint_count == len(plan.waypoints)
    assert [w.seq for w in plan.waypoints] == list(range(len(plan.waypoints)))
    total = s.working_length_m + s.turn_length_m + s.transit_length_m
    assert abs(total - s.path_length_m) < 0.01
    assert s.estimated_time_s >= s.path_length_m / 10.0
    assert 0.0 < s.coverage_ratio <= 1.0
