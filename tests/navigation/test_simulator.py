"""The simulator on the paper's scenario and on hand-built plans."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from navigation import (
    GuidanceParams,
    NavigationError,
    SimulationConfig,
    VehicleParams,
    simulate,
)
from navigation.types import CompassParams


@pytest.mark.parametrize("mode", ["waypoint", "line"])
@pytest.mark.parametrize("gps", ["m8n", "rtk"])
def test_the_paper_scenario_completes(paper_plan, mode: str, gps: str) -> None:  # type: ignore[no-untyped-def]
    log = simulate(
        paper_plan,
        SimulationConfig(gps=gps, guidance=GuidanceParams(mode=mode)),
        np.random.default_rng(0),
    )
    m = log.metrics
    assert log.completed and m.completed
    assert not np.isnan(log.reached_s).any()
    assert np.all(np.diff(log.reached_s) >= 0)  # waypoints reached in order
    # At 0.56 m/s the ~101 m route takes 180 s; each of the 9 waypoints may be cut by up to
    # the 1 m acceptance radius on either side, and pivots and detours add time.
    assert (101.0 - 2 * 9 * 1.0) / 0.56 < m.time_s < 2.0 * 101.0 / 0.56
    assert m.coverage_ratio > 0.7
    # The logs keep true, estimated and measured states side by side.
    n = len(log.time_s)
    assert len(log.true_x_m) == len(log.est_x_m) == len(log.clutch) == n
    assert len(log.gps_time_s) == pytest.approx(m.time_s * 5 + 1, abs=2)  # 5 Hz


def test_rtk_holds_the_lines_to_centimetres_in_line_mode(paper_plan) -> None:  # type: ignore[no-untyped-def]
    config = SimulationConfig(gps="rtk", guidance=GuidanceParams(mode="line"))
    m = simulate(paper_plan, config, np.random.default_rng(1)).metrics
    assert m.cross_track_rms_m < 0.2
    assert m.filter_rms_m < 0.05


def test_runs_are_reproducible_per_seed(paper_plan) -> None:  # type: ignore[no-untyped-def]
    config = SimulationConfig()
    a = simulate(paper_plan, config, np.random.default_rng(42))
    b = simulate(paper_plan, config, np.random.default_rng(42))
    c = simulate(paper_plan, config, np.random.default_rng(43))
    assert np.array_equal(a.true_x_m, b.true_x_m) and np.array_equal(a.gps_y_m, b.gps_y_m)
    assert a.metrics == b.metrics
    assert not np.array_equal(a.gps_x_m[:10], c.gps_x_m[:10])


def test_line_mode_holds_tillage_lines_tighter_than_waypoint_mode(paper_plan) -> None:  # type: ignore[no-untyped-def]
    rms = {}
    for mode in ("waypoint", "line"):
        config = SimulationConfig(guidance=GuidanceParams(mode=mode))
        rms[mode] = np.array(
            [
                simulate(paper_plan, config, np.random.default_rng(s)).metrics.cross_track_rms_m
                for s in range(20)
            ]
        )
    # With the driven pivot turns of issue 9 the two modes differ mostly on the lines' first
    # metres after a turn: over 60 seeds the mean is 3 % lower in line mode (1.44 vs 1.48 m)
    # and the medians are within 1 % (1.22 m both), so only the mean is asserted.
    assert rms["line"].mean() < rms["waypoint"].mean()


def test_time_limit_ends_an_unfinished_run(paper_plan) -> None:  # type: ignore[no-untyped-def]
    log = simulate(paper_plan, SimulationConfig(time_limit_s=30.0), np.random.default_rng(0))
    assert not log.completed and not log.metrics.completed
    assert log.time_s[-1] == pytest.approx(30.0)
    assert np.isnan(log.reached_s[-1])


def test_a_tractor_that_cannot_steer_never_finishes_but_stops(straight_plan) -> None:  # type: ignore[no-untyped-def]
    # A compass off by 90° sends the tractor the wrong way: the time limit must end the run.
    config = SimulationConfig(compass=CompassParams(bias_deg=90.0), time_limit_s=120.0)
    log = simulate(straight_plan, config, np.random.default_rng(0))
    assert not log.completed
    assert log.time_s[-1] == pytest.approx(120.0)


def test_clutch_servo_delay_shows_in_the_log(two_line_plan) -> None:  # type: ignore[no-untyped-def]
    config = SimulationConfig(
        gps="rtk", vehicle=dataclasses.replace(VehicleParams(), clutch_delay_s=1.0)
    )
    log = simulate(two_line_plan, config, np.random.default_rng(0))
    assert log.completed
    # The tractor pivots at the turn; the engaged clutch never changes within 1 s of the start.
    assert (log.clutch[:10] == 0).all()
    assert (log.clutch != 0).any()


@pytest.mark.parametrize(
    ("config", "match"),
    [
        (SimulationConfig(vehicle=VehicleParams(speed_mps=-0.56)), "^speed_mps: "),
        (SimulationConfig(gps="ublox-9000"), "^gps: unknown preset 'ublox-9000'"),
        (SimulationConfig(guidance=GuidanceParams(mode="teleport")), "^guidance: unknown mode"),  # type: ignore[arg-type]
        (
            SimulationConfig(guidance=GuidanceParams(acceptance_radius_m=0.0)),
            "^acceptance_radius_m: ",
        ),
        (
            SimulationConfig(guidance=GuidanceParams(curve_tolerance_deg=0.0)),
            "^curve_tolerance_deg: ",
        ),
        (SimulationConfig(guidance=GuidanceParams(curve_bend_deg=0.0)), "^curve_bend_deg: "),
        (SimulationConfig(dt_s=0.0), "^dt_s: "),
        (SimulationConfig(time_limit_s=-5.0), "^time_limit_s: "),
        (SimulationConfig(compass=CompassParams(rate_hz=0.0)), "^compass.rate_hz: "),
    ],
)
def test_bad_configurations_give_clear_errors(paper_plan, config, match) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(NavigationError, match=match):
        simulate(paper_plan, config, np.random.default_rng(0))


def test_a_plan_with_no_waypoints_is_refused(paper_plan) -> None:  # type: ignore[no-untyped-def]
    empty = dataclasses.replace(paper_plan, waypoints=())
    with pytest.raises(NavigationError, match="^plan: needs at least two waypoints"):
        simulate(empty, SimulationConfig(), np.random.default_rng(0))
    same = dataclasses.replace(paper_plan, waypoints=(paper_plan.waypoints[0],) * 3)
    with pytest.raises(NavigationError, match="^plan: all its waypoints are at the same place"):
        simulate(same, SimulationConfig(), np.random.default_rng(0))


def test_the_simulator_drives_the_plans_vehicle(paper_plan) -> None:  # type: ignore[no-untyped-def]
    from navigation.config import plan_vehicle_params

    # A plan without a vehicle is driven by hand_tractor: 0.7 m track, π/4 rad/s pivots.
    default = plan_vehicle_params(paper_plan)
    assert (default.preset, default.track_width_m, default.turn_rate_dps) == (
        "hand_tractor",
        0.7,
        45.0,
    )
    log = simulate(paper_plan, SimulationConfig(gps="rtk"), np.random.default_rng(3))
    assert log.config.vehicle == default
    # While a clutch is pulled the true heading turns at the vehicle's rate (45°/s, give or
    # take the 5 % wheel slip), not at speed / track.
    turning = (log.clutch[1:] != 0) & (log.clutch[:-1] == log.clutch[1:])
    rate = np.abs(np.diff(np.unwrap(log.true_heading_rad)))[turning]
    assert np.median(np.degrees(rate) / 0.1) == pytest.approx(45.0, rel=0.1)
    # A slower-turning vehicle takes longer over the same plan.
    slow = dataclasses.replace(default, turn_rate_dps=10.0)
    slow_log = simulate(
        paper_plan, SimulationConfig(gps="rtk", vehicle=slow), np.random.default_rng(3)
    )
    assert slow_log.metrics.time_s > log.metrics.time_s


@pytest.mark.parametrize("mode", ["waypoint", "line"])
def test_an_rtk_run_of_the_paper_spiral_drives_its_rounds_and_loops_as_planned(  # type: ignore[no-untyped-def]
    paper_spiral, mode: str
) -> None:
    # The spiral's rounds carry a 0.72 m loop at every corner (planner/round_corners.py).
    # Reaching each point within the 1 m radius cut them: 106 m of 123 m, 98.7 % covered.
    plan = paper_spiral
    config = SimulationConfig(gps="rtk", guidance=GuidanceParams(mode=mode))
    m = simulate(plan, config, np.random.default_rng(0)).metrics
    assert m.completed
    assert m.distance_m == pytest.approx(plan.stats.path_length_m, rel=0.03)
    assert m.coverage_ratio >= plan.stats.coverage_ratio - 0.005
    assert m.time_s == pytest.approx(plan.stats.estimated_time_s, rel=0.05)
    # Every point of every round, loop and join was driven over, not cut (RTK: 2 cm).
    roles = np.array([w.role for w in plan.waypoints])
    on_curve = (roles == "headland") | (roles == "turn")
    assert np.array(m.waypoint_errors_m, dtype=float)[on_curve].max() < 0.25


def test_a_hand_tractor_drives_a_loop_shorter_than_the_acceptance_radius(make_plan) -> None:  # type: ignore[no-untyped-def]
    # North 6 m, a full clockwise loop of 0.36 m (the hand tractor's pivot about its outer
    # wheel, 0.72 m across), north 4 m, the finish 2 m on; points every 0.15 m.
    step = 0.15
    approach = [(0.0, y) for y in np.arange(-6.0 + step, 1e-9, step)]
    a = np.linspace(0.0, 2.0 * math.pi, 16)[1:-1]
    loop = [(0.36 * (1.0 - math.cos(t)), 0.36 * math.sin(t)) for t in a]
    leave = [(0.0, y) for y in np.arange(0.0, 4.0 + 1e-9, step)]
    points = [(0.0, -6.0), *approach, *loop, *leave, (0.0, 6.0)]
    n = len(points)
    plan = make_plan(
        points,
        ["start"] + ["turn"] * (n - 2) + ["finish"],
        [None] * n,
        field_m=[(-5.0, -8.0), (5.0, -8.0), (5.0, 8.0), (-5.0, 8.0)],
    )
    planned = float(np.hypot(*np.diff(np.array(points), axis=0).T).sum())
    log = simulate(plan, SimulationConfig(gps="rtk"), np.random.default_rng(0))
    m = log.metrics
    assert log.completed
    # The run ends within the 1 m acceptance radius of the finish, the paper's way.
    assert m.distance_m == pytest.approx(planned - 1.0, abs=0.3)
    errors = np.array(m.waypoint_errors_m, dtype=float)
    loop_points = slice(1 + len(approach), 1 + len(approach) + len(loop))
    assert errors[loop_points].max() < 0.1  # the far side of the loop too (0.72 m away)


@pytest.mark.parametrize("radius_m", [1.0, 0.5])
def test_line_ends_keep_the_papers_acceptance_radius(paper_plan, radius_m: float) -> None:  # type: ignore[no-untyped-def]
    # The paper's law steers along each line to its end and switches within the radius
    # (from the filter's estimate); the turn that follows is then driven as planned.
    guidance = GuidanceParams(acceptance_radius_m=radius_m)
    log = simulate(
        paper_plan, SimulationConfig(gps="rtk", guidance=guidance), np.random.default_rng(0)
    )
    roles = np.array([w.role for w in paper_plan.waypoints])
    at_switch = np.array(log.metrics.waypoint_errors_estimate_m, dtype=float)[roles == "line_end"]
    assert len(at_switch) == 4
    # At 0.56 m/s and 10 Hz the estimate moves 0.056 m a step: it switches within it.
    assert ((at_switch > radius_m - 0.1) & (at_switch <= radius_m + 1e-9)).all()


def test_the_curve_law_leaves_a_plan_without_curves_alone(two_line_plan, paper_plan) -> None:  # type: ignore[no-untyped-def]
    # Legs longer than 0.5 m are the paper's: the curve settings change nothing on them.
    other = GuidanceParams(curve_tolerance_deg=20.0, curve_bend_deg=90.0)
    for plan, changes in ((two_line_plan, False), (paper_plan, True)):
        a = simulate(plan, SimulationConfig(gps="rtk"), np.random.default_rng(0))
        b = simulate(plan, SimulationConfig(gps="rtk", guidance=other), np.random.default_rng(0))
        same = np.array_equal(a.true_x_m, b.true_x_m) and np.array_equal(a.true_y_m, b.true_y_m)
        assert same is not changes  # the paper plan's turns are curves: they do change
