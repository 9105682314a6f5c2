"""Turns (planner.turns): the curves reach their target, respect the radius, and are shortest.

The Dubins closed forms are checked against an independent implementation: ``rsplan``'s
Reeds–Shepp solver. A Reeds–Shepp path is never longer than the Dubins path between the same
poses, and when the shortest Reeds–Shepp path drives forwards only it *is* a Dubins path, so
the two lengths must agree there.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import rsplan
from hypothesis import given, settings
from hypothesis import strategies as st

from planner import PRESETS
from planner.turns import (
    SAGITTA_M,
    STEP_M,
    TurnEnds,
    bulb_turn,
    dubins_turn,
    dubins_turn_length_m,
    pivot_turn,
    reeds_shepp_turn,
    vehicle_turns,
)

coordinate = st.floats(-20.0, 20.0, allow_nan=False)
yaw = st.floats(-math.pi, math.pi, allow_nan=False)
radius = st.floats(0.3, 6.0)


def _ends(*values: float) -> TurnEnds:
    return TurnEnds(*(np.array([v]) for v in values))


def _check_curve(curve: np.ndarray, radius_m: float, target: tuple[float, float]) -> None:
    step = np.hypot(*np.diff(curve, axis=0).T)
    assert (step <= STEP_M + 1e-9).all()
    assert np.allclose(curve[-1], target, atol=1e-6)
    # Discrete curvature: the circle through three consecutive points.
    a, b, c = curve[:-2], curve[1:-1], curve[2:]
    ab, bc, ca = np.hypot(*(b - a).T), np.hypot(*(c - b).T), np.hypot(*(a - c).T)
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    long = (ab > 1e-6) & (bc > 1e-6)
    kappa = 2.0 * cross[long] / (ab * bc * ca)[long]
    assert (kappa <= 1.0 / radius_m * (1 + 1e-6) + 1e-9).all()


def test_dubins_is_never_shorter_than_reeds_shepp_and_equal_when_it_drives_forward() -> None:
    """Random poses (rsplan mishandles exactly degenerate ones, e.g. a straight line)."""
    rng = np.random.default_rng(20261201)
    n = 400
    values = rng.uniform(-20.0, 20.0, (6, n))
    values[2], values[5] = rng.uniform(-math.pi, math.pi, (2, n))
    radii = rng.uniform(0.3, 6.0, n)
    forward_only = 0
    for k in range(n):
        x0, y0, a0, x1, y1, a1 = values[:, k]
        turn = dubins_turn(_ends(x0, y0, a0, x1, y1, a1), radius_m=radii[k])
        _check_curve(turn.curve(0), radii[k], (x1, y1))
        reference = rsplan.path(
            (x0, y0, a0), (x1, y1, a1), radii[k], 0.0, 0.05, length_tolerance=0.0
        )
        rs_length = sum(abs(float(s.length)) for s in reference.segments)
        assert rs_length <= turn.length_m[0] + 1e-6
        if all(s.direction > 0 for s in reference.segments):
            forward_only += 1
            assert turn.length_m[0] == pytest_approx(rs_length)
    assert forward_only > 50  # the comparison happened often enough to mean something


def pytest_approx(value: float) -> object:
    import pytest

    return pytest.approx(value, rel=1e-6, abs=1e-6)


@settings(max_examples=100, deadline=None)
@given(coordinate, coordinate, yaw, coordinate, coordinate, yaw, radius)
def test_dubins_curve_ends_where_integration_says(
    x0: float, y0: float, a0: float, x1: float, y1: float, a1: float, r: float
) -> None:
    """The sampled points before the snapped end lie within one step of the target."""
    turn = dubins_turn(_ends(x0, y0, a0, x1, y1, a1), radius_m=r)
    curve = turn.curve(0)
    if len(curve) > 2:
        assert np.hypot(*(curve[-2] - curve[-1])) <= STEP_M + 1e-6
    # The length of the polyline approaches the path length from below.
    polyline = float(np.hypot(*np.diff(curve, axis=0).T).sum())
    assert polyline <= turn.length_m[0] + 1e-6
    assert polyline >= turn.length_m[0] * 0.98 - 1e-6  # chords within 1 cm of the arcs


@given(st.floats(0.05, 3.0), st.floats(0.2, 2.0))
def test_pivot_turn_shifts_one_track_with_two_pivots(spacing: float, track: float) -> None:
    turn = pivot_turn(_ends(0.0, 0.0, math.pi / 2, spacing, 0.0, -math.pi / 2), track_m=track)
    curve = turn.curve(0)
    _check_curve(curve, track / 2.0, (spacing, 0.0))
    if spacing >= track:
        # Two quarter pivots about the braked wheel, and the straight makes up the rest.
        assert turn.length_m[0] == pytest_approx(math.pi * track / 2.0 + spacing - track)
        assert abs(curve[:, 1].max() - track / 2.0) <= SAGITTA_M
        assert curve[:, 0].min() >= -1e-9 and curve[:, 0].max() <= spacing + 1e-9
    else:
        # The extra manoeuvre: an Ω, swinging out beyond both lines.
        assert curve[:, 0].min() < 0.0 and curve[:, 0].max() > spacing
        assert turn.turn_rad[0] > math.pi


def test_pivot_turn_that_may_reverse_backs_up_below_one_track() -> None:
    forward = pivot_turn(_ends(0.0, 0.0, math.pi / 2, 0.3, 0.0, -math.pi / 2), track_m=0.7)
    backing = pivot_turn(
        _ends(0.0, 0.0, math.pi / 2, 0.3, 0.0, -math.pi / 2), track_m=0.7, can_reverse=True
    )
    assert backing.length_m[0] < forward.length_m[0]
    assert backing.curve(0)[:, 1].max() < forward.curve(0)[:, 1].max()


@given(st.floats(0.1, 5.9), st.floats(3.0, 6.0))
def test_bulb_turn_is_an_omega(spacing: float, r: float) -> None:
    turn = bulb_turn(_ends(0.0, 0.0, math.pi / 2, spacing, 0.0, -math.pi / 2), radius_m=r)
    curve = turn.curve(0)
    _check_curve(curve, r, (spacing, 0.0))
    # Closed form of the symmetric Ω: circles of radius r, the middle one at height h.
    h = math.sqrt(4 * r * r - (spacing / 2 + r) ** 2)
    assert abs(curve[:, 1].max() - (h + r)) <= SAGITTA_M
    assert abs(curve[:, 0].min() - (spacing / 2 - r)) <= SAGITTA_M


@settings(max_examples=40, deadline=None)
@given(coordinate, coordinate, yaw, radius)
def test_reeds_shepp_reaches_the_target(x1: float, y1: float, a1: float, r: float) -> None:
    turn = reeds_shepp_turn(_ends(0.0, 0.0, 0.0, x1, y1, a1), radius_m=r)
    curve = turn.curve(0)
    assert (np.hypot(*np.diff(curve, axis=0).T) <= STEP_M + 1e-9).all()
    # The integrated segments land on the target (before the final point is snapped).
    if len(curve) > 1:
        assert np.hypot(*(curve[-2] - curve[-1])) <= STEP_M + 1e-6


def test_many_turns_at_once_equal_one_at_a_time() -> None:
    rng = np.random.default_rng(3)
    values = rng.uniform(-10, 10, (6, 25))
    ends = TurnEnds(*values)
    together = dubins_turn(ends, radius_m=2.0)
    for k in range(25):
        alone = dubins_turn(TurnEnds(*(v[k : k + 1] for v in values)), radius_m=2.0)
        assert np.allclose(together.curve(k), alone.curve(0))


def test_lengths_without_sampling_and_a_subset_equal_the_sampled_turns() -> None:
    """``dubins_turn_length_m`` is ``dubins_turn``'s length, and ``TurnEnds.take`` a subset."""
    rng = np.random.default_rng(5)
    ends = TurnEnds(*rng.uniform(-10, 10, (6, 40)))
    together = dubins_turn(ends, radius_m=1.5)
    assert np.array_equal(dubins_turn_length_m(ends, radius_m=1.5), together.length_m)
    which = np.array([7, 3, 39, 3])
    subset = dubins_turn(ends.take(which), radius_m=1.5)
    for k, j in enumerate(which):
        assert np.array_equal(subset.curve(k), together.curve(int(j)))


def test_turns_planned_without_shared_shapes_are_the_same_to_the_last_bit() -> None:
    """``shared_shapes=False`` plans each turn alone: the same points, shapes repeated or not."""
    rng = np.random.default_rng(11)
    values = rng.uniform(-10, 10, (6, 40))
    # Coordinates on a 1/64 m grid, so that moving turns 0-9 by whole metres keeps their
    # relative ends to the last bit: turns 20-29 then share 0-9's shapes.
    values[[0, 1, 3, 4]] = np.round(values[[0, 1, 3, 4]] * 64.0) / 64.0
    values[:, 20:30] = values[:, 0:10] + np.array([[5.0], [-3.0], [0.0], [5.0], [-3.0], [0.0]])
    ends = TurnEnds(*values)
    dx, dy = ends.x1 - ends.x0, ends.y1 - ends.y0
    assert np.array_equal(dx[20:30], dx[0:10]) and np.array_equal(dy[20:30], dy[0:10])
    reversing = replace(PRESETS["small_tractor"], can_reverse=True)  # Reeds–Shepp turns
    for vehicle in (PRESETS["small_tractor"], PRESETS["hand_tractor"], PRESETS["rover"], reversing):
        shared = vehicle_turns(ends, vehicle)
        alone = vehicle_turns(ends, vehicle, shared_shapes=False)
        assert np.array_equal(alone.offsets, shared.offsets)
        assert np.array_equal(alone.xy, shared.xy)
        assert np.array_equal(alone.length_m, shared.length_m)
        assert np.array_equal(alone.turn_rad, shared.turn_rad)
