"""Fit a GPS error model (CEP, correlation time, rate) from a static log (docs/simulation.md).

A receiver left still on a known-good spot logs its own error: the fixes minus their mean.
:func:`fit_gps_params` fits the simulator's model to it — a first-order Gauss–Markov wander
(autocovariance ``σ_c² exp(-τ_lag/τ)``) plus white noise (``σ_w²`` at lag 0 only):

1. the rate is the inverse of the median interval between fixes;
2. the autocovariance of each axis is computed at lags up to a few correlation times, and
   ``log C(k) = log σ_c² − k Δt / τ`` fitted by least squares over the lags where it is still
   well above its noise (lags 1 … where it first falls below a fifth of ``C(1)``);
3. ``σ_w² = C(0) − σ_c²`` (clamped at 0); the CEP follows from the total per-axis sigma.

Over a log many correlation times long (hours for a u-blox M8N) the fitted figures are
within a few tens of percent; a short log says little about a wander that lasts a minute.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from navigation.types import CEP_PER_SIGMA, GpsParams, NavigationError

FloatArray = npt.NDArray[np.float64]

#: A static log needs at least this many fixes to fit anything.
MIN_STATIC_FIXES = 100


def _autocovariance(e: FloatArray, max_lag: int) -> FloatArray:
    """Biased sample autocovariance at lags 0 … ``max_lag`` (FFT)."""
    n = len(e)
    e = e - e.mean()
    size = 1 << (2 * n - 1).bit_length()
    spectrum = np.fft.rfft(e, size)
    acov = np.fft.irfft(spectrum * np.conj(spectrum), size)[: max_lag + 1] / n
    return np.asarray(acov, dtype=float)


def fit_gps_params(
    time_s: npt.ArrayLike,
    east_m: npt.ArrayLike,
    north_m: npt.ArrayLike,
    *,
    name: str = "fitted",
) -> GpsParams:
    """Fit :class:`GpsParams` to the fixes of a receiver that did not move.

    Parameters
    ----------
    time_s : array of float
        Fix times [s], increasing.
    east_m, north_m : array of float
        Fix positions in any local metric frame [m].
    name : str
        Name of the resulting model.

    Returns
    -------
    GpsParams

    Raises
    ------
    NavigationError
        For fewer than :data:`MIN_STATIC_FIXES` fixes, unequal lengths, or a log that moved
        (more than 50 m from its mean: not a static log).

    Examples
    --------
    >>> import numpy as np
    >>> from navigation.sensors import GpsReceiver
    >>> from navigation.types import GPS_PRESETS, VehicleState
    >>> rx = GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(1))
    >>> fixes = [rx.read(VehicleState(0.0, 0.0, 0.0), i * 0.2) for i in range(36_000)]
    >>> fit = fit_gps_params([f.time_s for f in fixes], [f.x_m for f in fixes],
    ...                      [f.y_m for f in fixes])
    >>> round(fit.rate_hz, 1), 1.8 < fit.cep_m < 3.2, 35 < fit.correlation_time_s < 100
    (5.0, True, True)
    """
    t = np.asarray(time_s, dtype=float).ravel()
    x = np.asarray(east_m, dtype=float).ravel()
    y = np.asarray(north_m, dtype=float).ravel()
    if not (len(t) == len(x) == len(y)):
        raise NavigationError("log", "time and positions differ in length")
    if len(t) < MIN_STATIC_FIXES:
        raise NavigationError(
            "log", f"has {len(t)} fixes; a static log needs at least {MIN_STATIC_FIXES}"
        )
    if not (np.isfinite(t).all() and np.isfinite(x).all() and np.isfinite(y).all()):
        raise NavigationError("log", "has a time or position that is not a finite number")
    dt = np.diff(t)
    if (dt <= 0).any():
        raise NavigationError("log", "times must increase")
    spread = np.hypot(x - x.mean(), y - y.mean())
    if spread.max() > 50.0:
        raise NavigationError(
            "log",
            f"moved {spread.max():.0f} m from its mean position: fit the model from a log of "
            "a receiver standing still",
        )
    period = float(np.median(dt))
    max_lag = max(2, min(len(t) // 4, int(round(600.0 / period))))
    sigma_c2 = []
    taus = []
    c0s = []
    for e in (x, y):
        acov = _autocovariance(e, max_lag)
        c0s.append(acov[0])
        if acov[1] <= 0:
            sigma_c2.append(0.0)
            continue
        below = np.flatnonzero(acov[1:] < 0.2 * acov[1])
        last = int(below[0]) if len(below) else max_lag - 1
        lags = np.arange(1, max(last, 2) + 1)
        slope, intercept = np.polyfit(lags * period, np.log(np.maximum(acov[lags], 1e-12)), 1)
        if slope < 0:
            taus.append(-1.0 / slope)
        sigma_c2.append(min(math.exp(intercept), acov[0]))
    var_c = float(np.mean(sigma_c2))
    var_total = float(np.mean(c0s))
    var_w = max(var_total - var_c, 0.0)
    tau = float(np.mean(taus)) if taus else period
    return GpsParams(
        name=name,
        rate_hz=1.0 / period,
        correlated_sigma_m=math.sqrt(var_c),
        correlation_time_s=tau,
        white_sigma_m=math.sqrt(var_w),
    )


def empirical_cep_m(east_m: npt.ArrayLike, north_m: npt.ArrayLike) -> float:
    """Median horizontal distance from the mean position [m] (what datasheets call CEP)."""
    x = np.asarray(east_m, dtype=float)
    y = np.asarray(north_m, dtype=float)
    return float(np.median(np.hypot(x - x.mean(), y - y.mean())))


__all__ = ["CEP_PER_SIGMA", "MIN_STATIC_FIXES", "empirical_cep_m", "fit_gps_params"]
