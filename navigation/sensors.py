"""The tractor's sensors: a GPS receiver with time-correlated error, and a magnetometer.

GPS error is modelled the way receiver errors behave (multipath, atmosphere, satellite
geometry wander slowly): a first-order Gauss–Markov process per axis, with time constant
``correlation_time_s``, plus white noise from fix to fix. The sum's per-axis sigma sets the CEP
(``CEP = 1.1774 σ`` for a circular Gaussian). All randomness comes from the ``rng`` passed in.
"""

from __future__ import annotations

import math

import numpy as np

from navigation.types import (
    GPS_PRESETS,
    CompassParams,
    CompassReading,
    GpsFix,
    GpsParams,
    NavigationError,
    VehicleState,
)


def gps_params(gps: str | GpsParams) -> GpsParams:
    """Resolve a preset name (``m8n``, ``rtk``) or check a custom model.

    Raises
    ------
    NavigationError
        For an unknown preset or a model with non-positive rate or negative sigmas.

    Examples
    --------
    >>> round(gps_params("m8n").cep_m, 3)
    2.5
    """
    if isinstance(gps, str):
        if gps not in GPS_PRESETS:
            raise NavigationError(
                "gps", f"unknown preset {gps!r}; choose one of {', '.join(GPS_PRESETS)}"
            )
        return GPS_PRESETS[gps]
    if not (math.isfinite(gps.rate_hz) and 0.0 < gps.rate_hz <= 100.0):
        raise NavigationError("gps.rate_hz", f"must be in (0, 100] Hz, got {gps.rate_hz}")
    for name in ("correlated_sigma_m", "white_sigma_m"):
        value = getattr(gps, name)
        if not (math.isfinite(value) and value >= 0.0):
            raise NavigationError(f"gps.{name}", f"must be ≥ 0, got {value}")
    if not (math.isfinite(gps.correlation_time_s) and gps.correlation_time_s > 0.0):
        raise NavigationError(
            "gps.correlation_time_s", f"must be > 0, got {gps.correlation_time_s}"
        )
    if gps.sigma_m <= 0.0:
        raise NavigationError("gps", "a receiver with no error at all is not a GPS model")
    return gps


class GpsReceiver:
    """A GPS receiver whose error wanders (Gauss–Markov) and jitters (white).

    Parameters
    ----------
    params : GpsParams
        The error model.
    rng : numpy.random.Generator
        Source of all randomness; the wander starts from its stationary distribution.
    """

    def __init__(self, params: GpsParams, rng: np.random.Generator) -> None:
        self.params = params
        self.rng = rng
        self.period_s = 1.0 / params.rate_hz
        # Discrete first-order Gauss–Markov: b' = φ b + σ √(1 - φ²) w keeps sigma stationary.
        self._phi = math.exp(-self.period_s / params.correlation_time_s)
        self._drive = params.correlated_sigma_m * math.sqrt(1.0 - self._phi**2)
        self.bias_x_m, self.bias_y_m = rng.standard_normal(2) * params.correlated_sigma_m

    def read(self, state: VehicleState, time_s: float) -> GpsFix:
        """Return the next fix for the true ``state``; advances the wander by one period."""
        return GpsFix(time_s, *self.read_xy(state.x_m, state.y_m))

    def read_xy(self, x_m: float, y_m: float) -> tuple[float, float]:
        """:meth:`read` for the true position ``(x_m, y_m)``: the fix's ``(x, y)`` [m]."""
        w0, w1, w2, w3 = self.rng.standard_normal(4).tolist()
        self.bias_x_m = self._phi * self.bias_x_m + self._drive * w0
        self.bias_y_m = self._phi * self.bias_y_m + self._drive * w1
        white = self.params.white_sigma_m
        return x_m + self.bias_x_m + white * w2, y_m + self.bias_y_m + white * w3


def read_compass(
    state: VehicleState,
    rng: np.random.Generator,
    time_s: float,
    *,
    declination_deg: float,
    params: CompassParams,
) -> CompassReading:
    """Read the magnetometer on the tractor in ``state``.

    The sensor sees magnetic north, which lies ``declination_deg`` east of true north, so its
    heading reads ``true − declination``, plus a constant bias and white noise.

    Parameters
    ----------
    state : VehicleState
        True state.
    rng : numpy.random.Generator
        Noise source.
    time_s : float
        Simulation time [s].
    declination_deg : float
        True magnetic declination at the field, east positive [deg].
    params : CompassParams
        Noise and bias.
    """
    mag_x, mag_y = read_magnetometer(
        state.heading_rad, rng, declination_deg=declination_deg, params=params
    )
    return CompassReading(time_s, mag_x, mag_y)


def read_magnetometer(
    heading_rad: float,
    rng: np.random.Generator,
    *,
    declination_deg: float,
    params: CompassParams,
) -> tuple[float, float]:
    """:func:`read_compass` for the true heading [rad]: ``(mag_x, mag_y)``, for the 10 Hz loop."""
    magnetic_deg = (
        math.degrees(heading_rad)
        - declination_deg
        + params.bias_deg
        + params.noise_deg * rng.standard_normal()
    )
    rad = math.radians(magnetic_deg)
    return math.cos(rad), math.sin(rad)


def validate_compass(params: CompassParams) -> None:
    """Raise :class:`NavigationError` if the compass parameters make no sense."""
    if not (math.isfinite(params.noise_deg) and 0.0 <= params.noise_deg <= 90.0):
        raise NavigationError("compass.noise_deg", f"must be in [0, 90], got {params.noise_deg}")
    if not (math.isfinite(params.bias_deg) and abs(params.bias_deg) <= 90.0):
        raise NavigationError("compass.bias_deg", f"must be in [-90, 90], got {params.bias_deg}")
    if not (math.isfinite(params.rate_hz) and 0.0 < params.rate_hz <= 100.0):
        raise NavigationError("compass.rate_hz", f"must be in (0, 100] Hz, got {params.rate_hz}")
