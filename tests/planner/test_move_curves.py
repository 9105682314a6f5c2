"""Moves between cells that a vehicle with a turning radius drives (planner.move_curves)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import event, given, settings
from hypothesis import strategies as st
from shapely import Polygon, box

from planner import PRESETS, plan_coverage
from planner.move_curves import (
    _END_POINTS,
    _SCREEN_STRIDE,
    PULL_STEPS_R,
    DrivenMoves,
    _pull_pairs,
    _screened_inside,
    drivable_moves,
    pull_pairs_m,
)
from planner.routing import FieldRouter
from planner.turns import TurnEnds, vehicle_turns
from tests.conftest import FIELDS_DIR, field_from_local
from tests.planner.field_files import shared_feature
from tests.planner.plan_checks import (
    assert_body_inside,
    assert_every_turn_within_the_radius,
    line_to_line_turns,
    turn_curvatures,
)

SMALL = PRESETS["small_tractor"]
RADIUS_M = SMALL.min_turn_radius_m
#: The curvature the tests allow: 1 / radius, and the waypoints' rounding (plan_checks).
KAPPA_MAX = 1.0 / RADIUS_M * 1.02 + 0.02
UP, DOWN = math.pi / 2.0, -math.pi / 2.0


def one_move(
    area: Polygon,
    here: tuple[float, float, float],
    there: tuple[float, float, float],
    *,
    room_m: float = 15.0,
) -> tuple[DrivenMoves, FieldRouter, TurnEnds]:
    """Plan one move from pose ``here`` to pose ``there`` (x, y, yaw) inside ``area``."""
    router = FieldRouter(area)
    ends = TurnEnds(*(np.array([value]) for value in (*here, *there)))
    moves = drivable_moves(
        ends,
        back_room_m=np.array([room_m]),
        on_room_m=np.array([room_m]),
        router=router,
        vehicle=SMALL,
    )
    return moves, router, ends


def assert_drivable(moves: DrivenMoves, router: FieldRouter, ends: TurnEnds, k: int = 0) -> None:
    """The move's curve starts and ends on its pulled poses, stays inside and within the radius."""
    curve = moves.curves[k]
    assert curve is not None
    back, on = moves.pulled_back_m[k], moves.pushed_on_m[k]
    start = (ends.x0[k] - back * math.cos(ends.yaw0[k]), ends.y0[k] - back * math.sin(ends.yaw0[k]))
    end = (ends.x1[k] + on * math.cos(ends.yaw1[k]), ends.y1[k] + on * math.sin(ends.yaw1[k]))
    np.testing.assert_allclose(curve[0], start, atol=1e-6)
    np.testing.assert_allclose(curve[-1], end, atol=1e-6)
    assert router.inside_path(curve)
    # The line it leaves and the line it joins, half a metre of each, drive on smoothly.
    seam = np.vstack(
        [
            curve[:1] - 0.5 * np.array([math.cos(ends.yaw0[k]), math.sin(ends.yaw0[k])]),
            curve,
            curve[-1:] + 0.5 * np.array([math.cos(ends.yaw1[k]), math.sin(ends.yaw1[k])]),
        ]
    )
    assert (turn_curvatures(seam) <= KAPPA_MAX).all()
    assert (np.hypot(*np.diff(curve, axis=0).T) <= 0.5 + 1e-6).all()


def test_pull_pairs_are_cheapest_first() -> None:
    pairs = pull_pairs_m(RADIUS_M)
    totals = pairs.sum(axis=1)
    assert (np.diff(totals) >= 0.0).all()
    assert tuple(pairs[0]) == (0.0, 0.0)
    assert len({tuple(p) for p in pairs.tolist()}) == len(pairs)
    # Each pair's steps name its two pulls; the kept pairs are not the caller's to change.
    pairs_m, step_ids = _pull_pairs(RADIUS_M)
    assert np.array_equal(pairs_m, np.asarray(PULL_STEPS_R)[step_ids] * RADIUS_M)
    assert not pairs_m.flags.writeable and not step_ids.flags.writeable
    expected = pairs.copy()
    pairs[:] = -1.0
    assert np.array_equal(pull_pairs_m(RADIUS_M), expected)


def _end_points(points: np.ndarray) -> np.ndarray:
    """A curve's first and last :data:`_END_POINTS` points (all of a shorter curve's)."""
    return np.vstack([points[:_END_POINTS], points[-_END_POINTS:]])


def test_the_point_screen_passes_every_curve_inside_and_tests_its_strided_points() -> None:
    """A curve that stays inside always passes; one that passes has every point screened inside.

    The screen's points are each curve's first and last few and one in a stride; the test
    names them afresh, rank by rank, for turns of every length into and out of an L.
    """
    router = FieldRouter(Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)]))
    rng = np.random.default_rng(7)
    count = 400
    xy = rng.uniform(2.0, 58.0, (count, 4))
    yaw = rng.uniform(-math.pi, math.pi, (count, 2))
    turns = vehicle_turns(
        TurnEnds(xy[:, 0], xy[:, 1], yaw[:, 0], xy[:, 2], xy[:, 3], yaw[:, 1]), SMALL
    )
    screened = _screened_inside(turns, router)
    exact = router.inside_paths([turns.curve(k) for k in range(count)])
    assert (screened | ~exact).all()
    for k in range(count):
        points = turns.curve(k)
        strided = points[np.arange(len(points)) % _SCREEN_STRIDE == 0]
        named = np.vstack([_end_points(points), strided])
        assert screened[k] == router.holds_points(named).all()
    # Every stage at work on these turns: curves inside; curves turned away at their ends;
    # curves whose ends pass but a strided point does not; curves that pass the screen and
    # fail the exact test.
    assert exact.any()
    ends_pass = np.array(
        [router.holds_points(_end_points(turns.curve(k))).all() for k in range(count)]
    )
    assert (~ends_pass).any() and (ends_pass & ~screened).any() and (screened & ~exact).any()


def test_a_u_turn_at_the_edge_pulls_both_lines_back_just_enough() -> None:
    """Lines 20 m apart end at the area's edge: no forward curve leaves or joins them there."""
    area = box(0.0, 0.0, 60.0, 40.0)
    moves, router, ends = one_move(area, (10.0, 39.99, UP), (30.0, 39.99, DOWN))
    assert_drivable(moves, router, ends)
    total = moves.pulled_back_m[0] + moves.pushed_on_m[0]
    assert total > 0.0
    # No cheaper pair of pulls gives a turn that stays inside (the route is straight: no
    # chain, so the least total is the turn's own).
    pairs = pull_pairs_m(RADIUS_M)
    cheaper = pairs[pairs.sum(axis=1) < total - 1e-9]
    tried = TurnEnds(
        np.full(len(cheaper), 10.0),
        39.99 - cheaper[:, 0],
        np.full(len(cheaper), UP),
        np.full(len(cheaper), 30.0),
        39.99 - cheaper[:, 1],
        np.full(len(cheaper), DOWN),
    )
    turns = vehicle_turns(tried, SMALL)
    assert not router.inside_paths([turns.curve(t) for t in range(len(turns))]).any()


def test_a_push_on_alone_is_refined_below_its_coarse_step() -> None:
    """Only the line joined needs shortening: its push-on is refined like a pull-back."""
    area = box(0.0, 0.0, 60.0, 40.0)
    moves, router, ends = one_move(area, (10.0, 20.0, UP), (30.0, 39.0, DOWN))
    assert_drivable(moves, router, ends)
    assert moves.pulled_back_m[0] == 0.0
    steps_m = np.unique(pull_pairs_m(RADIUS_M))
    assert 0.0 < moves.pushed_on_m[0] and moves.pushed_on_m[0] not in steps_m


def test_no_room_on_the_lines_gives_no_curve() -> None:
    area = box(0.0, 0.0, 60.0, 40.0)
    moves, _, _ = one_move(area, (10.0, 39.99, UP), (30.0, 39.99, DOWN), room_m=0.0)
    assert moves.curves == [None]
    assert moves.pulled_back_m[0] == 0.0 and moves.pushed_on_m[0] == 0.0


def test_a_move_round_an_inner_corner_is_a_chain_off_the_corner() -> None:
    """An L: from the end of a line in one arm to a line in the other, round the inner corner."""
    area = Polygon([(0, 0), (80, 0), (80, 30), (30, 30), (30, 80), (0, 80)])
    moves, router, ends = one_move(area, (70.0, 29.99, UP), (10.0, 79.99, DOWN))
    assert_drivable(moves, router, ends)
    # Not the vehicle's own turn between the ends it found: that cuts the corner.
    back, on = moves.pulled_back_m[0], moves.pushed_on_m[0]
    own = TurnEnds(
        np.array([70.0]), np.array([29.99 - back]), np.array([UP]),
        np.array([10.0]), np.array([79.99 + on * math.sin(DOWN)]), np.array([DOWN]),
    )  # fmt: skip
    assert not router.inside_path(vehicle_turns(own, SMALL).curve(0))


@settings(max_examples=40, deadline=None)
@given(
    width=st.floats(30.0, 120.0),
    height=st.floats(30.0, 120.0),
    a=st.floats(0.05, 0.95),
    b=st.floats(0.05, 0.95),
    up_first=st.booleans(),
    up_second=st.booleans(),
)
def test_every_curve_found_is_drivable_inside(
    width: float, height: float, a: float, b: float, up_first: bool, up_second: bool
) -> None:
    """Lines across a rectangle, ending and starting at its edges: any curve found is right."""
    area = box(0.0, 0.0, width, height)
    edge = 0.01
    here = (a * width, height - edge if up_first else edge, UP if up_first else DOWN)
    there = (b * width, edge if up_second else height - edge, UP if up_second else DOWN)
    moves, router, ends = one_move(area, here, there, room_m=(height - 1.0) / 2.0)
    event(f"curve found: {moves.curves[0] is not None}")
    if moves.curves[0] is not None:
        assert_drivable(moves, router, ends)
        assert moves.pulled_back_m[0] <= (height - 1.0) / 2.0 + 1e-9
        assert moves.pushed_on_m[0] <= (height - 1.0) / 2.0 + 1e-9


COMB = [(0, 0), (150, 0), (150, 90), (110, 90), (110, 35), (90, 35), (90, 90), (50, 90)]
COMB += [(50, 35), (30, 35), (30, 90), (0, 90)]


@pytest.mark.parametrize("heading_deg", [0.0, 90.0, 33.0])
def test_a_comb_field_is_driven_within_the_radius_between_cells_too(heading_deg: float) -> None:
    """A comb: cells in each tooth and the back; every turn, moves between cells too."""
    field = field_from_local(COMB, [], at=(110.4, -7.8))
    plan = plan_coverage(field, interval_m=4.0, vehicle="small_tractor", angle_deg=heading_deg)
    assert_body_inside(plan)
    turns = line_to_line_turns(plan)
    assert any(not same_cell for _, same_cell in turns)  # moves between cells are checked
    assert_every_turn_within_the_radius(plan)


#: Real fields whose plans had moves between cells with corners, each leaving or joining
#: a cell of one short line, before such lines were dropped (``bench.move_corners``).
SLIVERED = ["germany_2018_2019-53", "germany_2018_2019-49", "germany_2018_2019-6"]


@pytest.mark.parametrize("feature_id", SLIVERED)
def test_a_line_too_short_for_a_curve_is_dropped_not_cornered(feature_id: str) -> None:
    """Every move between cells is a curve within the radius, and the body stays inside."""
    feature = shared_feature(FIELDS_DIR / "germany_2018_2019.geojson", feature_id)
    field = shapely.geometry.shape(feature["geometry"])
    plan = plan_coverage(field, interval_m=4.0, vehicle="small_tractor")
    assert_body_inside(plan)
    assert_every_turn_within_the_radius(plan)
