"""The walk-behind tractor's kinematics against closed-form motion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from navigation.types import LEFT, RIGHT, STRAIGHT, NavigationError, VehicleParams, VehicleState
from navigation.vehicle import (
    disturb,
    disturb_heading,
    step,
    step_pose,
    validate_vehicle,
    wrap_angle,
    yaw_rate,
)

V = 0.56
B = 1.8


def run(state: VehicleState, clutch: int, seconds: float, dt: float) -> VehicleState:
    for _ in range(int(round(seconds / dt))):
        state = step(state, clutch, dt, speed_mps=V, track_width_m=B)
    return state


@pytest.mark.parametrize("heading_deg", [0.0, 37.0, 90.0, 200.0, 333.0])
def test_straight_drive_moves_speed_times_time_along_the_heading(heading_deg: float) -> None:
    h = math.radians(heading_deg)
    end = run(VehicleState(3.0, -2.0, h), STRAIGHT, 25.0, 0.1)
    assert end.x_m == pytest.approx(3.0 + V * 25.0 * math.sin(h), abs=1e-9)
    assert end.y_m == pytest.approx(-2.0 + V * 25.0 * math.cos(h), abs=1e-9)
    assert end.heading_rad == pytest.approx(h)


@pytest.mark.parametrize("clutch", [LEFT, RIGHT])
@pytest.mark.parametrize("heading_deg", [0.0, 45.0, 170.0])
@pytest.mark.parametrize("dt", [0.01, 0.1, 0.5])
def test_pivot_follows_the_closed_form_arc_about_the_braked_wheel(
    clutch: int, heading_deg: float, dt: float
) -> None:
    # Closed form: the braked wheel stays put; the axle centre turns about it on a circle of
    # radius B/2 at v/B rad/s (clockwise for the right clutch).
    h0 = math.radians(heading_deg)
    x0, y0 = 10.0, 5.0
    right = (math.cos(h0), -math.sin(h0))
    wheel = (x0 + clutch * B / 2 * right[0], y0 + clutch * B / 2 * right[1])
    seconds = 4.0
    turned = clutch * V / B * seconds
    h1 = h0 + turned
    right1 = (math.cos(h1), -math.sin(h1))
    expected = (wheel[0] - clutch * B / 2 * right1[0], wheel[1] - clutch * B / 2 * right1[1])

    end = run(VehicleState(x0, y0, h0), clutch, seconds, dt)

    assert end.x_m == pytest.approx(expected[0], abs=1e-9)
    assert end.y_m == pytest.approx(expected[1], abs=1e-9)
    assert wrap_angle(end.heading_rad - h1) == pytest.approx(0.0, abs=1e-12)
    assert end.clutch == clutch


def test_pivot_turns_left_and_right_the_right_way() -> None:
    start = VehicleState(0.0, 0.0, 0.0)  # facing north
    left = step(start, LEFT, 1.0, speed_mps=V, track_width_m=B)
    right = step(start, RIGHT, 1.0, speed_mps=V, track_width_m=B)
    assert left.x_m < 0.0 < right.x_m  # left clutch veers west, right clutch east
    assert left.y_m > 0.0 and right.y_m > 0.0
    assert wrap_angle(left.heading_rad) < 0.0 < wrap_angle(right.heading_rad)
    # The centre moves at half speed while pivoting: the chord of a 1 s arc is about v/2.
    assert math.hypot(right.x_m, right.y_m) == pytest.approx(V / 2, rel=1e-2)


def test_a_full_pivot_returns_to_the_start() -> None:
    seconds = 2 * math.pi * B / V
    end = run(VehicleState(1.0, 2.0, 0.3), RIGHT, seconds, seconds / 1000)
    assert (end.x_m, end.y_m) == pytest.approx((1.0, 2.0), abs=1e-9)


def test_yaw_rate_is_speed_over_track() -> None:
    assert yaw_rate(RIGHT, speed_mps=V, track_width_m=B) == pytest.approx(V / B)
    assert yaw_rate(LEFT, speed_mps=V, track_width_m=B) == pytest.approx(-V / B)
    assert yaw_rate(STRAIGHT, speed_mps=V, track_width_m=B) == 0.0


@pytest.mark.parametrize(
    ("angle", "wrapped"),
    [
        (0.0, 0.0),
        (math.pi + 0.1, -math.pi + 0.1),
        (-math.pi - 0.1, math.pi - 0.1),
        (7.0, 7.0 - 2 * math.pi),
    ],
)
def test_wrap_angle(angle: float, wrapped: float) -> None:
    assert wrap_angle(angle) == pytest.approx(wrapped)


@pytest.mark.parametrize(
    ("params", "name"),
    [
        (VehicleParams(speed_mps=-0.5), "speed_mps"),
        (VehicleParams(speed_mps=0.0), "speed_mps"),
        (VehicleParams(speed_mps=float("nan")), "speed_mps"),
        (VehicleParams(track_width_m=0.0), "track_width_m"),
        (VehicleParams(clutch_delay_s=-1.0), "clutch_delay_s"),
        (VehicleParams(speed_noise=1.5), "speed_noise"),
    ],
)
def test_bad_vehicle_parameters_are_named(params: VehicleParams, name: str) -> None:
    with pytest.raises(NavigationError, match=rf"^{name}: "):
        validate_vehicle(params)


def test_step_is_exact_whatever_the_step_size() -> None:
    coarse = run(VehicleState(0.0, 0.0, 1.0), LEFT, 3.0, 1.0)
    fine = run(VehicleState(0.0, 0.0, 1.0), LEFT, 3.0, 0.001)
    assert np.allclose([coarse.x_m, coarse.y_m], [fine.x_m, fine.y_m], atol=1e-9)


@pytest.mark.parametrize("clutch", [LEFT, STRAIGHT, RIGHT])
def test_the_loops_bare_pose_step_and_disturbance_equal_the_state_ones(clutch: int) -> None:
    rng = np.random.default_rng(8)
    for _ in range(50):
        x, y = (float(v) for v in rng.uniform(-100.0, 100.0, 2))
        h = float(rng.uniform(0.0, 2.0 * math.pi))
        kwargs = {"speed_mps": V, "track_width_m": B, "yaw_rate_rad_s": 0.78, "pivot_m": 0.35}
        s = step(VehicleState(x, y, h), clutch, 0.1, **kwargs)
        assert step_pose(x, y, h, clutch, 0.1, **kwargs) == (s.x_m, s.y_m, s.heading_rad)
        assert s.clutch == clutch
    a, b = np.random.default_rng(9), np.random.default_rng(9)
    for _ in range(20):
        state = disturb(VehicleState(1.0, 2.0, 6.2), a, 0.1, yaw_noise_deg_per_sqrt_s=0.5)
        assert disturb_heading(6.2, b, 0.1, yaw_noise_deg_per_sqrt_s=0.5) == state.heading_rad
    assert disturb_heading(6.2, b, 0.1, yaw_noise_deg_per_sqrt_s=0.0) == 6.2
    assert a.standard_normal() == b.standard_normal()  # no draw without noise
