"""The plan's curves as the controller reads them: which legs, how far it looks, where it aims."""

from __future__ import annotations

import math

import numpy as np
import pytest

from navigation.curves import CURVE_STEP_M, aim_point, bend_reach_m, curve_legs, curve_path
from navigation.guidance import segment_axes


def legs_of(
    x: np.ndarray, y: np.ndarray
) -> list[tuple[float, float, float, float, float, float, float]]:
    """The 10 Hz loop's table of legs (leg k from waypoint k-1 to k; leg 0 empty)."""
    out = [(0.0,) * 7]
    for k in range(1, len(x)):
        a = (float(x[k - 1]), float(y[k - 1]), float(x[k]), float(y[k]))
        out.append(a + segment_axes(*a))
    return out  # type: ignore[return-value]


def circle(radius_m: float, step_m: float, turns: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A clockwise circle through the origin heading north, sampled every ``step_m``."""
    n = int(math.ceil(2 * math.pi * radius_m * turns / step_m))
    a = np.linspace(0.0, 2 * math.pi * turns, n + 1)
    return radius_m * (1.0 - np.cos(a)), radius_m * np.sin(a)


def test_a_leg_is_on_a_curve_when_short_and_off_the_tillage_lines() -> None:
    roles = ["start", "line_start", "line_end", "turn", "turn", "line_start", "line_end"]
    lines = [None, 0, 0, None, None, 1, 1]
    lengths = np.array([5.0, 0.3, 0.2, CURVE_STEP_M, 0.6, 0.2])
    # A short tillage line stays the paper's; a long turn leg too; short turn legs are curve.
    assert curve_legs(roles, lines, lengths).tolist() == [
        False,
        False,
        False,
        True,
        True,
        False,
        False,
    ]


def test_the_reach_stops_where_the_path_has_bent_by_the_limit() -> None:
    # North 3 m in 0.1 m steps, then a quarter circle of 0.36 m to the east, then east.
    north = np.arange(0.0, 3.0 + 1e-9, 0.1)
    x = np.concatenate(
        [np.zeros_like(north), 0.36 * (1 - np.cos(np.linspace(0, math.pi / 2, 7)[1:]))]
    )
    y = np.concatenate([north, 3.0 + 0.36 * np.sin(np.linspace(0, math.pi / 2, 7)[1:])])
    x = np.concatenate([x, x[-1] + np.arange(0.1, 3.0, 0.1)])
    y = np.concatenate([y, np.full(29, y[-1])])
    bend = math.radians(30.0)
    reach = bend_reach_m(x, y, bend_rad=bend, lookahead_m=2.5)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    heading = np.unwrap(np.arctan2(np.diff(x), np.diff(y)))
    for k in range(1, len(x)):
        if math.isinf(reach[k]):
            # No leg within the look-ahead turns more than the limit from leg k.
            ahead = (s[:-1] < s[k] + 2.5) & (np.arange(1, len(x)) > k)
            assert not (np.abs(heading[ahead] - heading[k - 1]) > bend).any()
            continue
        j = int(np.searchsorted(s, reach[k]))  # the bent leg starts at waypoint j
        assert abs(heading[j] - heading[k - 1]) > bend  # leg j + 1 turned past the limit
        assert (np.abs(heading[k - 1 : j] - heading[k - 1]) <= bend).all()  # none before
    # On the straight, 3 m from the corner's arc: the reach is infinite (look-ahead rules);
    # 1 m from it, the reach is the arc's first step past 30°.
    assert math.isinf(reach[1])
    assert 3.0 < reach[20] < 3.0 + 0.36 * math.pi / 2


@pytest.mark.parametrize("along_share", [0.0, 0.5, 0.99])
def test_on_a_tight_loop_the_aim_goes_round_it_not_across(along_share: float) -> None:
    # A 0.36 m loop (the hand tractor's corner loop), its legs turning 24° each, then north:
    # a 2.5 m look-ahead along the loop would aim across it at the exit. With a 30° bend
    # limit the aim is the 0.3 m minimum ahead along the loop, wherever the tractor is.
    x, y = circle(0.36, 0.15)
    x = np.concatenate([x, np.zeros(20)])
    y = np.concatenate([y, np.arange(1, 21) * 0.15])
    n = len(x)
    path = curve_path(x, y, ["turn"] * n, [None] * n, bend_rad=math.radians(30.0), lookahead_m=2.5)
    legs = legs_of(x, y)
    s = np.asarray(path.s_m)
    loop_legs = len(circle(0.36, 0.15)[0]) - 1
    for target in range(1, loop_legs - 1):
        along = along_share * legs[target][6]
        aim = aim_point(path, legs, target, along, lookahead_m=2.5, min_aim_m=0.3)
        ahead = s[target - 1] + along + 0.3
        assert aim == pytest.approx((np.interp(ahead, s, x), np.interp(ahead, s, y)), abs=1e-9)


def test_on_a_straight_the_aim_looks_the_whole_lookahead_ahead() -> None:
    y = np.arange(0.0, 10.0 + 1e-9, 0.15)
    x = np.zeros_like(y)
    path = curve_path(
        x, y, ["headland"] * len(x), [None] * len(x), bend_rad=math.radians(30.0), lookahead_m=2.5
    )
    aim = aim_point(path, legs_of(x, y), 10, 0.05, lookahead_m=2.5, min_aim_m=0.3)
    assert aim == pytest.approx((0.0, 9 * 0.15 + 0.05 + 2.5))
    # Near the path's end the aim is its last point.
    aim = aim_point(path, legs_of(x, y), len(x) - 2, 0.0, lookahead_m=2.5, min_aim_m=0.3)
    assert aim == pytest.approx((0.0, y[-1]))
