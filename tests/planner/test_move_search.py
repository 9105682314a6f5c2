"""The last resort for a move between cells: the vehicle's arcs searched (planner.move_search)."""

from __future__ import annotations

import math

import numpy as np
import shapely
from hypothesis import event, given, settings
from hypothesis import strategies as st
from shapely import Polygon, box

from planner import PRESETS, plan_coverage
from planner.move_search import SearchedMove, search_move
from planner.routing import FieldRouter
from planner.turns import STEP_M, TurnEnds
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import shared_feature
from tests.planner.plan_checks import assert_body_inside, assert_every_turn_within_the_radius

SMALL = PRESETS["small_tractor"]
RADIUS_M = SMALL.min_turn_radius_m
UP, DOWN, EAST = math.pi / 2.0, -math.pi / 2.0, 0.0


def _exact_curvatures(points: np.ndarray) -> np.ndarray:
    """Curvature [1/m] of the circle through every three consecutive points (unrounded)."""
    a, b, c = points[:-2], points[1:-1], points[2:]
    ab, bc, ca = (np.hypot(*(q - p).T) for p, q in ((a, b), (b, c), (c, a)))
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    ok = (ab > 1e-6) & (bc > 1e-6)
    return np.asarray(2.0 * cross[ok] / (ab * bc * ca)[ok])


def assert_searched_drivable(
    found: SearchedMove, router: FieldRouter, ends: TurnEnds, pulls: np.ndarray, pushes: np.ndarray
) -> None:
    """From a pulled-back end to a pushed-on start, inside, steps ≤ 0.5 m, within the radius."""
    assert found.pulled_back_m in pulls.tolist()
    assert found.pushed_on_m in pushes.tolist()
    back, on = found.pulled_back_m, found.pushed_on_m
    yaw0, yaw1 = float(ends.yaw0[0]), float(ends.yaw1[0])
    start = (ends.x0[0] - back * math.cos(yaw0), ends.y0[0] - back * math.sin(yaw0))
    end = (ends.x1[0] + on * math.cos(yaw1), ends.y1[0] + on * math.sin(yaw1))
    points = found.points
    np.testing.assert_allclose(points[0], start, atol=1e-6)
    np.testing.assert_allclose(points[-1], end, atol=1e-6)
    assert router.inside_path(points)
    assert (np.hypot(*np.diff(points, axis=0).T) <= STEP_M + 1e-9).all()
    # The line before and after, half a metre of each, drive on smoothly too.
    seam = np.vstack(
        [
            points[:1] - 0.5 * np.array([math.cos(yaw0), math.sin(yaw0)]),
            points,
            points[-1:] + 0.5 * np.array([math.cos(yaw1), math.sin(yaw1)]),
        ]
    )
    assert (_exact_curvatures(seam) <= 1.0 / RADIUS_M * (1.0 + 1e-6)).all()


def test_a_move_that_must_turn_round_in_a_room_at_the_corridors_end_is_found() -> None:
    """Up a corridor too narrow to turn in, round in the room at its end, and back down."""
    # Both arms 5 m wide: less than the small tractor's 6 m turning circle.
    corridor = box(0.0, 0.0, 58.0, 5.0).union(box(53.0, 0.0, 58.0, 20.0))
    area = corridor.union(box(44.0, 20.0, 69.0, 40.0))
    router = FieldRouter(area)
    # Leave a line heading east along the bottom; join one heading down the corridor.
    ends = TurnEnds(*(np.array([v]) for v in (10.0, 2.5, EAST, 55.5, 12.0, DOWN)))
    pulls, pushes = np.array([0.0, 1.5, 3.0]), np.array([0.0, 1.5])

    found = search_move(ends, pulls, pushes, router=router, vehicle=SMALL)

    assert found is not None
    assert_searched_drivable(found, router, ends, pulls, pushes)
    assert found.points[:, 1].max() > 20.0  # it went round in the room


def test_a_goal_just_ahead_in_a_narrow_strip_is_reached_by_a_straight() -> None:
    """A strip narrower than a turn, the goal a few metres on: the last piece is a straight
    (a U-turn's loop, all the vehicle's turns between lines would try there, has no room)."""
    router = FieldRouter(box(0.0, 0.0, 40.0, 4.0))
    for ahead_m in (4.0, 5.0, 9.0):
        ends = TurnEnds(*(np.array([v]) for v in (10.0, 2.0, EAST, 10.0 + ahead_m, 2.0, EAST)))
        none = np.zeros(1)

        found = search_move(ends, none, none, router=router, vehicle=SMALL)

        assert found is not None
        assert_searched_drivable(found, router, ends, none, none)


def test_a_move_with_no_room_to_turn_is_not_found() -> None:
    """A dead-end corridor narrower than a turn: no forward path turns round in it."""
    router = FieldRouter(box(0.0, 0.0, 40.0, 4.0))
    ends = TurnEnds(*(np.array([v]) for v in (20.0, 2.0, EAST, 10.0, 2.0, math.pi)))

    assert search_move(ends, np.array([0.0]), np.array([0.0]), router=router, vehicle=SMALL) is None


@settings(max_examples=40, deadline=None)
@given(
    hole_x=st.floats(15.0, 45.0),
    hole_y=st.floats(10.0, 30.0),
    hole_m=st.floats(2.0, 12.0),
    start=st.tuples(st.floats(3.0, 57.0), st.floats(3.0, 37.0), st.floats(-math.pi, math.pi)),
    goal=st.tuples(st.floats(3.0, 57.0), st.floats(3.0, 37.0), st.floats(-math.pi, math.pi)),
)
def test_any_move_found_is_drivable_and_inside(
    hole_x: float,
    hole_y: float,
    hole_m: float,
    start: tuple[float, float, float],
    goal: tuple[float, float, float],
) -> None:
    area = box(0.0, 0.0, 60.0, 40.0).difference(
        shapely.Point(hole_x, hole_y).buffer(hole_m / 2.0, quad_segs=4)
    )
    assert isinstance(area, Polygon)
    router = FieldRouter(area)
    ends = TurnEnds(*(np.array([v]) for v in (*start, *goal)))
    pulls, pushes = np.array([0.0, 1.5]), np.array([0.0, 3.0])

    found = search_move(ends, pulls, pushes, router=router, vehicle=SMALL, most_expansions=300)

    event("found" if found is not None else "not found")
    if found is not None:
        assert_searched_drivable(found, router, ends, pulls, pushes)


def test_the_move_no_curve_or_drop_served_is_searched_on_a_real_field() -> None:
    """south_africa_2017-25: a move into a narrow strip kept its corners before the search
    (``bench.move_corners``); now every turn and seam is within the small tractor's radius."""
    feature = shared_feature(FIELDS_DIR / "south_africa_2017.geojson", "south_africa_2017-25")
    field = shapely.geometry.shape(feature["geometry"])
    plan = plan_coverage(field, interval_m=4.0, vehicle="small_tractor")
    assert_body_inside(plan)
    assert_every_turn_within_the_radius(plan)
