"""Checks of a plan's requirements (R1–R4), shared by the planner's property tests.

Everything is measured independently of the planner's internals: from the plan's exported
waypoints and segments, re-projected into the field's frame, with shapely.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely import LineString

from bench import move_corners
from bench.shapes import fixed_heading_figures as fixed_heading_figures
from planner.projection import field_frame
from planner.turns import turning_radius_m
from planner.types import CoveragePlan, Vehicle

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


def assert_spacing_and_edges(plan: CoveragePlan, *, exact_edges: bool = True) -> None:
    """R2 (interval apart, only an end gap may be smaller) and R3 (outer lines d/2 inside).

    With ``exact_edges`` False, the outer lines may lie further in: the vehicle's body and
    turns need room, and lines the turns cannot reach at a corner are left out.
    """
    d = plan.interval_m
    offsets, low, high = line_offsets(plan)
    if high - low <= d:
        assert len(offsets) == 1
        if exact_edges:
            assert abs(offsets[0] - (low + high) / 2) < SPACING_TOLERANCE_M
        return
    if exact_edges:
        assert abs(offsets[0] - (low + d / 2)) < SPACING_TOLERANCE_M
        assert abs(offsets[-1] - (high - d / 2)) < SPACING_TOLERANCE_M
    else:
        assert offsets[0] >= low + d / 2 - SPACING_TOLERANCE_M
        assert offsets[-1] <= high - d / 2 + SPACING_TOLERANCE_M
    gaps = np.diff(offsets)
    assert (gaps <= d + SPACING_TOLERANCE_M).all(), "lines farther apart than the interval"
    off = np.nonzero(np.abs(gaps - d) > SPACING_TOLERANCE_M)[0]
    assert len(off) <= 1, f"more than one gap differs from the interval: {gaps}"
    assert all(i in (0, len(gaps) - 1) for i in off), "a short gap in the middle"


def reference_coverage(plan: CoveragePlan) -> float:
    """R4 with shapely: field ∩ union of footprints (flat caps), over the field's area.

    A footprint is as wide as the implement (the interval unless the plan says otherwise).
    """
    field_local = field_frame(plan.field_lonlat).to_local(plan.field_lonlat)
    half = (plan.implement_width_m or plan.interval_m) / 2
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


#: A vehicle small enough that the point-vehicle properties (R3 at d/2, R5 orders) still
#: hold to within its size: a 0.1 m body that pivots about a wheel 0.1 m away.
TINY_VEHICLE = {"preset": "hand_tractor", "width_m": 0.1, "track_m": 0.1}


def plan_vehicle(plan: CoveragePlan) -> Vehicle:
    assert plan.vehicle is not None
    return plan.vehicle


def assert_body_inside(plan: CoveragePlan) -> None:
    """R1 for the machine: the path buffered by half the vehicle's width (round caps) lies
    inside the field and outside every hole, along lines, turns and headland passes."""
    field_local = field_frame(plan.field_lonlat).to_local(plan.field_lonlat)
    grown = field_local.buffer(TOLERANCE_M)
    half = plan_vehicle(plan).width_m / 2.0
    for kind in ("line", "turn", "headland"):
        for segment in local_segments(plan, kind):
            body = segment.buffer(half)
            outside = body.difference(grown).area
            assert outside < 1e-6, f"the body leaves the field along a {kind} by {outside} m²"


def turn_curvatures(curve: np.ndarray) -> np.ndarray:
    """Curvature [1/m] of the circle through every three consecutive points of a polyline."""
    a, b, c = curve[:-2], curve[1:-1], curve[2:]
    ab, bc, ca = (np.hypot(*(q - p).T) for p, q in ((a, b), (b, c), (c, a)))
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    # A cusp (forwards, then backwards: Reeds–Shepp) folds the polyline back on itself.
    onward = np.einsum("ij,ij->i", b - a, c - b) > 0.0
    # Waypoints are rounded to 0.1 mm: steps under 5 cm say nothing about curvature.
    ok = (ab > 0.05) & (bc > 0.05) & (ca > 0.05) & onward
    return np.asarray(2.0 * cross[ok] / (ab * bc * ca)[ok])


def assert_turns_drivable(plan: CoveragePlan) -> None:
    """R1: turns between lines are curves the vehicle drives: points ≤ 0.5 m apart and,
    between two lines of one cell, curvature ≤ 1 / radius (the minimum turning radius, or
    half the track for a vehicle that pivots). Moves between cells are checked for spacing
    only: where no curve is found (:mod:`planner.move_curves`) they are the shortest path
    inside the field, with corners (``python -m bench.move_corners`` counts them)."""
    vehicle = plan_vehicle(plan)
    radius = turning_radius_m(vehicle)
    for turn, same_cell in line_to_line_turns(plan):
        step = np.hypot(*np.diff(turn, axis=0).T)
        assert (step <= 0.5 + 1e-3).all(), f"turn points {step.max():.3f} m apart"
        if same_cell:
            kappa = turn_curvatures(turn)
            # Waypoints are rounded to 1e-9° (0.1 mm): allow for that on short steps.
            assert (kappa <= 1.0 / radius * 1.02 + 0.02).all(), f"curvature {kappa.max():.3f}"


def line_to_line_turns(plan: CoveragePlan) -> list[tuple[np.ndarray, bool]]:
    """The turns from the end of one line to the start of the next, local [m], and whether
    both lines lie in one cell."""
    frame = field_frame(plan.field_lonlat)
    cells = [frame.to_local(c) for c in plan.cells_lonlat]

    def cell_of(segment_index: int) -> int:
        middle = frame.to_local(LineString(plan.segments[segment_index].lonlat)).centroid
        return int(np.argmin([c.distance(middle) for c in cells])) if cells else 0

    turns = []
    kinds = [s.kind for s in plan.segments]
    for k, segment in enumerate(plan.segments):
        if segment.kind != "turn" or not (0 < k < len(kinds) - 1):
            continue
        if kinds[k - 1] == "line" and kinds[k + 1] == "line":
            x, y = frame.to_local_xy(*np.asarray(segment.lonlat).T)
            turns.append((np.stack([x, y], axis=1), cell_of(k - 1) == cell_of(k + 1)))
    return turns


def assert_continuous(plan: CoveragePlan) -> None:
    """Each segment begins where the one before it ends (the same waypoint, to the bit)."""
    for before, after in zip(plan.segments[:-1], plan.segments[1:], strict=True):
        assert before.lonlat[-1] == after.lonlat[0], "the path is not continuous"


def assert_every_turn_within_the_radius(plan: CoveragePlan) -> None:
    """Every turn between two lines, and its seams with them, is within the turning radius.

    Measured as ``bench.move_corners`` counts: each circle through three consecutive points
    at the least curvature the exported points' rounding allows
    (:func:`bench.move_corners.curvatures`), against ``1 / radius`` itself, with half a
    metre of the lines on either side (:func:`bench.move_corners.turn_seams`): each move must
    leave its line and join the next where they end and start, heading on.
    """
    vehicle = plan_vehicle(plan)
    limit = 1.0 / turning_radius_m(vehicle) * (1.0 + 1e-6)
    assert_continuous(plan)
    kinds = [s.kind for s in plan.segments]
    between_lines = [
        k for k in range(1, len(kinds) - 1) if kinds[k - 1 : k + 2] == ["line", "turn", "line"]
    ]
    seams = dict(move_corners.turn_seams(plan))
    assert sorted(seams) == between_lines, "a turn joins a line with no length"
    for k, seam in seams.items():
        kappa = move_corners.curvatures(seam)
        assert (kappa <= limit).all(), f"turn {k}: curvature {kappa.max():.4f} > {limit:.4f}"
