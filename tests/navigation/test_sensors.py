"""GPS presets: CEP, rate and time-correlated error."""

from __future__ import annotations

import numpy as np
import pytest

from navigation.sensors import GpsReceiver, gps_params, read_compass, read_magnetometer
from navigation.types import GPS_PRESETS, CompassParams, GpsParams, NavigationError, VehicleState

STILL = VehicleState(0.0, 0.0, 0.0)


def radial_errors(params: GpsParams, receivers: int, warmup_fixes: int, seed: int) -> np.ndarray:
    """One fix from each of many independent receivers, after a warm-up."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(receivers):
        gps = GpsReceiver(params, rng)
        for _ in range(warmup_fixes):
            fix = gps.read(STILL, 0.0)
        out.append(np.hypot(fix.x_m, fix.y_m))
    return np.asarray(out)


@pytest.mark.parametrize(("name", "cep"), [("m8n", 2.5), ("rtk", 0.02)])
def test_preset_cep_is_the_median_radial_error(name: str, cep: float) -> None:
    params = gps_params(name)
    assert params.cep_m == pytest.approx(cep)
    radial = radial_errors(params, 3000, 20, seed=11)
    # The median of 3000 samples is within ~3 % of the true median (1 sigma).
    assert np.median(radial) == pytest.approx(cep, rel=0.08)


def test_m8n_reports_at_5_hz() -> None:
    assert GPS_PRESETS["m8n"].rate_hz == 5.0
    assert GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(0)).period_s == pytest.approx(0.2)


def test_m8n_error_is_correlated_over_tens_of_seconds() -> None:
    params = gps_params("m8n")
    gps = GpsReceiver(params, np.random.default_rng(12))
    errors = np.array([gps.read(STILL, 0.0).x_m for _ in range(5 * 3600)])  # an hour at 5 Hz

    def autocorrelation(lag: int) -> float:
        return float(np.corrcoef(errors[:-lag], errors[lag:])[0, 1])

    assert autocorrelation(1) > 0.8  # consecutive fixes share most of their error
    assert autocorrelation(5 * 10) > 0.6  # still after 10 s
    assert abs(autocorrelation(5 * 600)) < 0.3  # gone after 10 min
    # ... and there is white noise on top: fix-to-fix jumps are not all tiny.
    assert np.std(np.diff(errors)) > 0.5 * params.white_sigma_m


def test_receivers_are_reproducible_per_seed() -> None:
    a = GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(3))
    b = GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(3))
    c = GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(4))
    fa = [a.read(STILL, 0.0) for _ in range(10)]
    assert fa == [b.read(STILL, 0.0) for _ in range(10)]
    assert fa != [c.read(STILL, 0.0) for _ in range(10)]


def test_unknown_preset_is_refused_with_the_choices() -> None:
    with pytest.raises(NavigationError, match=r"^gps: unknown preset 'zed'.*m8n, rtk"):
        gps_params("zed")


@pytest.mark.parametrize(
    ("params", "field"),
    [
        (GpsParams("x", 0.0, 1.0, 10.0, 0.1), "gps.rate_hz"),
        (GpsParams("x", 5.0, -1.0, 10.0, 0.1), "gps.correlated_sigma_m"),
        (GpsParams("x", 5.0, 1.0, 0.0, 0.1), "gps.correlation_time_s"),
        (GpsParams("x", 5.0, 0.0, 10.0, 0.0), "gps"),
    ],
)
def test_bad_custom_gps_is_refused(params: GpsParams, field: str) -> None:
    with pytest.raises(NavigationError, match=rf"^{field}: "):
        gps_params(params)


def test_the_loops_bare_reads_equal_the_state_ones() -> None:
    a = GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(4))
    b = GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(4))
    compass = CompassParams()
    for i in range(20):
        state = VehicleState(3.0 * i, -2.0 * i, 0.3 * i)
        fix = a.read(state, 0.1 * i)
        assert b.read_xy(state.x_m, state.y_m) == (fix.x_m, fix.y_m)
        reading = read_compass(state, a.rng, 0.1 * i, declination_deg=0.8, params=compass)
        mag = read_magnetometer(state.heading_rad, b.rng, declination_deg=0.8, params=compass)
        assert mag == (reading.mag_x, reading.mag_y)
