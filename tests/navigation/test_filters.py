"""The Kalman filter: angle-aware updates, agreement with plain filterpy, and error reduction."""
# ruff: noqa: N806  (filterpy notation: P0, R, F)

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from navigation import SimulationConfig, simulate
from navigation.filters import PoseFilter, Q_process, fx
from navigation.types import CompassParams, FilterParams, GpsParams, VehicleParams


def test_compass_update_across_north_moves_the_short_way() -> None:
    f = PoseFilter(
        np.array([0.0, 0.0, math.radians(359.0)]), np.diag([1.0, 1.0, 0.1]), params=FilterParams()
    )
    f.update(heading_rad=math.radians(3.0), heading_sigma_rad=math.sqrt(0.1))
    # Equal variances: halfway between 359° and 3° going through north is 1°, not 181°.
    assert math.degrees(f.x[2]) == pytest.approx(1.0, abs=1e-9)
    f = PoseFilter(
        np.array([0.0, 0.0, math.radians(2.0)]), np.diag([1.0, 1.0, 0.1]), params=FilterParams()
    )
    f.update(heading_rad=math.radians(356.0), heading_sigma_rad=math.sqrt(0.1))
    assert math.degrees(f.x[2]) == pytest.approx(359.0, abs=1e-9)


def test_one_cycle_agrees_with_a_plain_filterpy_kalman_filter() -> None:
    params = FilterParams()
    x0 = np.array([1.0, 2.0, 0.4])
    P0 = np.diag([4.0, 3.0, 0.05])
    u = (0.56, 0.1)
    dt = 0.1
    ours = PoseFilter(x0, P0, params=params)
    for _ in range(2):
        ours.propagate(*u, dt)
    z = np.array([1.3, 2.2, 0.5])
    R = np.diag([4.5, 4.5, 0.001])
    ours.update(
        gps_xy_m=(z[0], z[1]),
        gps_sigma_m=math.sqrt(4.5),
        heading_rad=z[2],
        heading_sigma_rad=math.sqrt(0.001),
    )

    # Reference: filterpy's linear KalmanFilter with the chained Jacobian as F.
    x1 = fx(x0, np.array(u), dt)
    x2 = fx(x1, np.array(u), dt)
    F = np.eye(3)
    for x in (x0, x1):
        mid = x[2] + 0.5 * u[1] * dt
        Fi = np.array(
            [[1, 0, u[0] * dt * math.cos(mid)], [0, 1, -u[0] * dt * math.sin(mid)], [0, 0, 1]]
        )
        F = Fi @ F
    ref = KalmanFilter(dim_x=3, dim_z=3)
    ref.x = x0.copy()
    ref.P = P0.copy()
    ref.F = F
    ref.Q = Q_process(params, 2 * dt)
    ref.H = np.eye(3)
    ref.R = R
    ref.predict()
    ref.x = x2.copy()  # the nonlinear prediction of the mean, as an EKF does
    ref.update(z)
    assert np.allclose(ours.x, ref.x, atol=1e-9)
    assert np.allclose(ours.P, ref.P, atol=1e-9)


def test_filter_beats_raw_gps_on_a_seeded_straight_run(straight_plan) -> None:  # type: ignore[no-untyped-def]
    # 100 m due north with the m8n: the filter's RMS position error must be below the raw
    # fixes' RMS error, on every one of these seeds.
    config = SimulationConfig(gps="m8n", initial_heading_sigma_deg=0.0)
    for seed in range(5):
        log = simulate(straight_plan, config, np.random.default_rng(seed))
        assert log.metrics.filter_rms_m < log.metrics.gps_rms_m


def test_filter_removes_most_white_noise(straight_plan) -> None:  # type: ignore[no-untyped-def]
    # With white GPS noise only (no wander), smoothing along the motion model cuts the error
    # several times over.
    white = GpsParams(
        "white", rate_hz=5.0, correlated_sigma_m=0.0, correlation_time_s=1.0, white_sigma_m=2.0
    )
    config = SimulationConfig(
        gps=white,
        vehicle=dataclasses.replace(VehicleParams(), speed_noise=0.0, yaw_noise_deg_per_sqrt_s=0.1),
        compass=CompassParams(bias_deg=0.0),
    )
    log = simulate(straight_plan, config, np.random.default_rng(7))
    assert log.metrics.gps_rms_m == pytest.approx(2.0 * math.sqrt(2), rel=0.15)
    assert log.metrics.filter_rms_m < 0.5 * log.metrics.gps_rms_m


@pytest.mark.parametrize("gps", ["m8n", "rtk"])
def test_mean_nees_lies_within_its_chi2_bounds_over_a_seeded_batch(paper_plan, gps: str) -> None:  # type: ignore[no-untyped-def]
    from navigation.consistency import batch_consistency

    runs = [
        simulate(paper_plan, SimulationConfig(gps=gps), np.random.default_rng(s)).metrics
        for s in range(10)
    ]
    nees = batch_consistency([m.nees_mean for m in runs], dof=2)
    assert nees["within"], nees
    # The compass bias (1.5° simulated) is estimated, to within a degree on average.
    bias = np.array([m.compass_bias_estimate_deg for m in runs])
    assert abs(bias.mean() - 1.5) < 1.0


def test_the_white_noise_filter_is_overconfident_with_the_m8n(paper_plan) -> None:  # type: ignore[no-untyped-def]
    # Treating the receiver's wander as white noise (the old filter) states an uncertainty
    # far below the real error: its NEES is many times the 2 expected.
    from navigation.consistency import batch_consistency

    config = SimulationConfig(gps="m8n", kalman=FilterParams(augmented=False))
    runs = [simulate(paper_plan, config, np.random.default_rng(s)).metrics for s in range(5)]
    nees = batch_consistency([m.nees_mean for m in runs], dof=2)
    assert nees["mean"] > 5 * nees["high"]


def test_batched_normalised_squares_equal_the_per_sample_solve_bit_for_bit() -> None:
    # The simulator solves a run's NEES and NIS in one batch: the same floats as one
    # ``e @ solve(C, e)`` per sample, whatever the mix of dimensions.
    from navigation.consistency import normalised_squares

    rng = np.random.default_rng(3)
    errors, covariances = [], []
    for i in range(300):
        dim = (2, 3, 2, 1)[i % 4]
        A = rng.standard_normal((dim, dim))
        errors.append(rng.standard_normal(dim) * 10.0 ** rng.uniform(-3, 1))
        covariances.append((A @ A.T + 0.1 * np.eye(dim)) * 10.0 ** rng.uniform(-4, 2))
    expected = [float(e @ np.linalg.solve(C, e)) for e, C in zip(errors, covariances, strict=True)]
    assert normalised_squares(errors, covariances).tolist() == expected
    assert normalised_squares([], []).tolist() == []


def test_the_filter_keeps_its_innovation_and_states_its_nis() -> None:
    f = PoseFilter(np.array([0.0, 0.0, 0.0]), np.eye(3), params=FilterParams())
    assert f.nis is None and f.innovation is None
    f.propagate(0.56, 0.0, 0.1)
    f.update(gps_xy_m=(0.5, 0.2), gps_sigma_m=1.0, heading_rad=0.05, heading_sigma_rad=0.1)
    assert f.innovation is not None
    y, S = f.innovation
    assert f.nis_dof == 3 and f.nis == float(y @ np.linalg.solve(S, y))
    assert f.pose == tuple(f.x[:3].tolist())
