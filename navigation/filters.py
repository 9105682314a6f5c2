"""Extended Kalman filter of the tractor's position and heading (filterpy).

State ``x = [x, y, θ]``: position in the local frame [m] and heading clockwise from true north
[rad]; or, augmented (:func:`augmented_x0`), ``x = [x, y, θ, b, e_x, e_y]`` with the compass
bias ``b`` [rad] and the receiver's slowly wandering error ``e`` [m] as states. A u-blox
receiver's error is not white: it wanders over tens of seconds (multipath, atmosphere), and a
filter that treats it as white noise averages it away on paper only and states an uncertainty
ten times too small. Modelled as the first-order Gauss–Markov process it is simulated as
(``e' = φ e + w``, ``φ = exp(-Δt/τ)``, ``var w = σ²(1-φ²)``), the filter's covariance stays
honest: its position NEES matches its χ² bounds (docs/simulation.md). The GPS then measures
``x + e``, the compass ``θ + b``. Control ``u = [v, ω]``: axle-centre speed [m/s] and yaw
rate [rad/s, clockwise], which the controller knows from the clutch it pulled. GPS measures
``[x, y]``; the compass measures ``θ``. Headings are angles, so the compass residual is wrapped
to ±π (filterpy's ``residual=``) and ``x[2]`` is wrapped after every update: a reading of 1°
against an estimate of 359° is a 2° correction, not a 358° one.

Names follow filterpy and the textbook (``x, P, F, Q, H, R, z, u``; ``fx``/``hx`` for the
models, ``F_jacobian``/``H_gps`` for their Jacobians).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from filterpy.kalman import ExtendedKalmanFilter

from navigation.types import FilterParams, GpsParams
from navigation.vehicle import wrap_angle

FloatArray = npt.NDArray[np.float64]

#: GPS and compass measurement Jacobians: the models are linear in the state.
_H_GPS = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
_H_COMPASS = np.array([[0.0, 0.0, 1.0]])
_H_POSE = np.eye(3)
#: The same for the augmented state [x, y, θ, b, e_x, e_y].
_H_GPS6 = np.array([[1.0, 0, 0, 0, 1.0, 0], [0, 1.0, 0, 0, 0, 1.0]])
_H_COMPASS6 = np.array([[0, 0, 1.0, 1.0, 0, 0]])
_H_POSE6 = np.vstack([_H_GPS6, _H_COMPASS6])


def fx(x: FloatArray, u: FloatArray, dt_s: float) -> FloatArray:
    """Motion model: drive at ``u[0]`` along the mid-step heading, turn at ``u[1]``.

    Examples
    --------
    >>> fx(np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0]), 2.0).tolist()
    [0.0, 2.0, 0.0]
    """
    v, omega = u[0], u[1]
    mid = x[2] + 0.5 * omega * dt_s
    return np.array(
        [x[0] + v * dt_s * math.sin(mid), x[1] + v * dt_s * math.cos(mid), x[2] + omega * dt_s]
    )


def F_jacobian(x: FloatArray, u: FloatArray, dt_s: float) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Jacobian of :func:`fx` with respect to the state."""
    v, omega = u[0], u[1]
    mid = x[2] + 0.5 * omega * dt_s
    return np.array(
        [
            [1.0, 0.0, v * dt_s * math.cos(mid)],
            [0.0, 1.0, -v * dt_s * math.sin(mid)],
            [0.0, 0.0, 1.0],
        ]
    )


def hx_gps(x: FloatArray) -> FloatArray:
    """GPS measurement model: the position."""
    return x[:2]


def H_gps(x: FloatArray) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Jacobian of :func:`hx_gps`."""
    return _H_GPS


def hx_compass(x: FloatArray) -> FloatArray:
    """Compass measurement model: the heading."""
    return x[2:3]


def H_compass(x: FloatArray) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Jacobian of :func:`hx_compass`."""
    return _H_COMPASS


def hx_pose(x: FloatArray) -> FloatArray:
    """GPS and compass together: the whole state."""
    return x


def H_pose(x: FloatArray) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Jacobian of :func:`hx_pose`."""
    return _H_POSE


def hx_gps6(x: FloatArray) -> FloatArray:
    """Augmented GPS model: position plus the receiver's wander."""
    return _H_GPS6 @ x


def H_gps6(x: FloatArray) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Jacobian of :func:`hx_gps6`."""
    return _H_GPS6


def hx_compass6(x: FloatArray) -> FloatArray:
    """Augmented compass model: heading plus bias."""
    return _H_COMPASS6 @ x


def H_compass6(x: FloatArray) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Jacobian of :func:`hx_compass6`."""
    return _H_COMPASS6


def hx_pose6(x: FloatArray) -> FloatArray:
    """Augmented GPS and compass together."""
    return _H_POSE6 @ x


def H_pose6(x: FloatArray) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Jacobian of :func:`hx_pose6`."""
    return _H_POSE6


def augmented_x0(
    gps_xy_m: tuple[float, float],
    heading_rad: float,
    *,
    gps: GpsParams,
    heading_sigma_rad: float,
    params: FilterParams,
) -> tuple[FloatArray, FloatArray]:
    """Return the augmented filter's initial state and covariance from the first fix.

    The first fix is ``x + e + w``: taking it as the position (and 0 as the wander) leaves a
    position error ``-(e + w)`` that is correlated with the wander's error ``e``, so ``P0``
    carries that correlation (``-σ_e²``); without it the filter would be inconsistent from
    the start. Likewise the heading error is ``-(b + noise)``, correlated with the bias.
    """
    var_e = gps.correlated_sigma_m**2
    var_w = gps.white_sigma_m**2
    var_b = math.radians(params.compass_bias_sigma_deg) ** 2
    var_h = heading_sigma_rad**2
    x0 = np.array([gps_xy_m[0], gps_xy_m[1], heading_rad, 0.0, 0.0, 0.0])
    P0 = np.zeros((6, 6))
    for i, j in ((0, 4), (1, 5)):
        P0[i, i] = var_e + var_w
        P0[j, j] = var_e
        P0[i, j] = P0[j, i] = -var_e
    P0[2, 2] = var_b + var_h
    P0[3, 3] = var_b
    P0[2, 3] = P0[3, 2] = -var_b
    return x0, P0


def residual_pose(z: FloatArray, z_pred: FloatArray) -> FloatArray:
    """Innovation of ``[x, y, θ]`` with the heading wrapped to [-π, π)."""
    return np.array([z[0] - z_pred[0], z[1] - z_pred[1], wrap_angle(float(z[2] - z_pred[2]))])


def residual_heading(z: FloatArray, z_pred: FloatArray) -> FloatArray:
    """Heading innovation wrapped to [-π, π).

    Examples
    --------
    >>> round(math.degrees(residual_heading(np.radians([1.0]), np.radians([359.0]))[0]), 6)
    2.0
    """
    return np.array([wrap_angle(float(z[0] - z_pred[0]))])


def Q_process(params: FilterParams, dt_s: float) -> FloatArray:  # noqa: N802 (filterpy's names)
    """Process noise over ``dt_s``: random walks of position and heading."""
    q_pos = params.position_sigma_m_per_sqrt_s**2 * dt_s
    q_heading = math.radians(params.heading_sigma_deg_per_sqrt_s) ** 2 * dt_s
    return np.diag([q_pos, q_pos, q_heading])


def Q_augmented(params: FilterParams, gps: GpsParams, dt_s: float) -> FloatArray:  # noqa: N802
    """Process noise of the augmented state over ``dt_s``: the pose's, the bias's, the wander's."""
    phi = math.exp(-dt_s / gps.correlation_time_s)
    q_e = gps.correlated_sigma_m**2 * (1.0 - phi**2)
    q_b = math.radians(params.compass_bias_drift_deg_per_sqrt_s) ** 2 * dt_s
    Q = np.zeros((6, 6))
    Q[:3, :3] = Q_process(params, dt_s)
    Q[3, 3] = q_b
    Q[4, 4] = Q[5, 5] = q_e
    return Q


class _TractorEKF(ExtendedKalmanFilter):  # type: ignore[misc]
    """filterpy's EKF whose prediction is the dead-reckoned state (``predict_x``)."""

    x_dead_reckoned: FloatArray

    def predict_x(self, u: FloatArray = 0) -> None:  # type: ignore[assignment]
        self.x = self.x_dead_reckoned


class PoseFilter:
    """Kalman filter of the tractor's pose from GPS fixes and compass headings.

    The controller runs faster than the GPS: :meth:`propagate` dead-reckons the estimate at
    every control step with :func:`fx` and chains the Jacobians; :meth:`update` then does one
    filterpy predict over the whole interval (``F`` the chained Jacobian, ``Q`` the summed
    process noise) and one update with the GPS fix and the mean compass heading.

    Parameters
    ----------
    x0 : array of 3 floats
        Initial ``[x, y, θ]`` ([m], [m], [rad]), usually the first GPS fix and compass heading.
    P0 : (3, 3) array
        Initial covariance.
    params : FilterParams
        Process noise.

    Examples
    --------
    >>> f = PoseFilter(np.array([0.0, 0.0, 0.0]), np.eye(3), params=FilterParams())
    >>> f.update(heading_rad=math.radians(350.0), heading_sigma_rad=0.01)
    >>> round(math.degrees(f.x[2]) % 360.0, 1)        # pulled toward 350°, not toward 180°
    350.0
    """

    def __init__(
        self, x0: FloatArray, P0: FloatArray, *, params: FilterParams, gps: GpsParams | None = None
    ) -> None:
        dim = len(x0)
        if dim not in (3, 6) or (dim == 6 and gps is None):
            raise ValueError("x0: give [x, y, θ], or the 6 augmented states with the GPS model")
        self.ekf = _TractorEKF(dim_x=dim, dim_z=3)
        self.ekf.x = np.array(x0, dtype=float)
        self.ekf.P = np.array(P0, dtype=float)
        self.params = params
        self.gps = gps
        self.augmented = dim == 6
        #: Degrees of freedom of the last update's innovation (0 before any).
        self.nis_dof = 0
        self._innovation: tuple[FloatArray, FloatArray] | None = None
        self._identity = np.eye(dim)
        self._matrices: dict[tuple[str | float, ...], FloatArray] = {}
        self._reset_interval()

    def _cached(self, kind: str, *args: float) -> FloatArray:
        """Noise matrices, built once per distinct value (they rarely change in a run)."""
        key: tuple[str | float, ...] = (kind, *args)
        matrix = self._matrices.get(key)
        if matrix is None:
            if kind == "Q":
                matrix = (
                    Q_augmented(self.params, self.gps, args[0])
                    if self.augmented and self.gps is not None
                    else Q_process(self.params, args[0])
                )
            elif kind == "R_pose":
                matrix = np.diag([args[0] ** 2, args[0] ** 2, args[1] ** 2])
            elif kind == "R_gps":
                matrix = np.eye(2) * args[0] ** 2
            else:
                matrix = np.array([[args[0] ** 2]])
            self._matrices[key] = matrix
        return matrix

    def _reset_interval(self) -> None:
        self._x = self.ekf.x[:3].tolist()
        self._f02 = 0.0  # chained Jacobian: [[1, 0, f02], [0, 1, f12], [0, 0, 1]]
        self._f12 = 0.0
        self._elapsed_s = 0.0

    @property
    def x(self) -> FloatArray:
        """The current estimate, dead-reckoned since the last update.

        ``[x, y, θ]``, then the augmented states (bias, wander) as of the last update.
        """
        return np.concatenate([self._x, self.ekf.x[3:]])

    @property
    def pose(self) -> tuple[float, float, float]:
        """The current ``(x, y, θ)`` as floats, as :meth:`propagate` returns it."""
        return self._x[0], self._x[1], self._x[2]

    @property
    def P(self) -> FloatArray:  # noqa: N802 (filterpy's names)
        """The covariance after the last update."""
        return self.ekf.P  # type: ignore[no-any-return]

    @property
    def innovation(self) -> tuple[FloatArray, FloatArray] | None:
        """The last update's innovation ``y`` and its covariance ``S`` (None before any).

        For batching the NIS of a run (:func:`navigation.consistency.normalised_squares`).
        """
        return self._innovation

    @property
    def nis(self) -> float | None:
        """Normalised innovation squared of the last update (None before any)."""
        if self._innovation is None:
            return None
        y, S = self._innovation
        return float(y @ np.linalg.solve(S, y))

    def propagate(
        self, v_mps: float, omega_rad_s: float, dt_s: float
    ) -> tuple[float, float, float]:
        """Dead-reckon one control step (:func:`fx` with ``u = [v, ω]``); return ``(x, y, θ)``.

        Parameters
        ----------
        v_mps : float
            Axle-centre speed [m/s].
        omega_rad_s : float
            Yaw rate, clockwise [rad/s].
        dt_s : float
            Step [s].
        """
        # fx and F_jacobian, written out on floats: this runs at every control step.
        x0, y0, h0 = self._x
        v = v_mps
        omega = omega_rad_s
        mid = h0 + 0.5 * omega * dt_s
        dx = v * dt_s * math.sin(mid)
        dy = v * dt_s * math.cos(mid)
        # Chain F_total <- F @ F_total: both are [[1, 0, a], [0, 1, b], [0, 0, 1]], so a and b add.
        self._f02 += dy
        self._f12 -= dx
        self._x = [x0 + dx, y0 + dy, (h0 + omega * dt_s) % (2.0 * math.pi)]
        self._elapsed_s += dt_s
        return self._x[0], self._x[1], self._x[2]

    def update(
        self,
        *,
        gps_xy_m: tuple[float, float] | None = None,
        gps_sigma_m: float = 1.0,
        heading_rad: float | None = None,
        heading_sigma_rad: float = 0.01,
    ) -> None:
        """Predict over the interval since the last update, then fuse the measurements.

        Parameters
        ----------
        gps_xy_m : (float, float) or None
            GPS position, local frame [m].
        gps_sigma_m : float
            Its per-axis standard deviation [m]: the white part only when the filter is
            augmented (the wander is a state).
        heading_rad : float or None
            Compass heading, clockwise from true north [rad].
        heading_sigma_rad : float
            Its standard deviation [rad].
        """
        ekf = self.ekf
        if self._elapsed_s > 0.0:
            F = self._identity.copy()
            F[0, 2] = self._f02
            F[1, 2] = self._f12
            x_pred = np.array(ekf.x, dtype=float)
            x_pred[:3] = self._x
            if self.augmented and self.gps is not None:
                phi = math.exp(-self._elapsed_s / self.gps.correlation_time_s)
                F[4, 4] = F[5, 5] = phi
                x_pred[4:6] *= phi
            ekf.F = F
            ekf.Q = self._cached("Q", round(self._elapsed_s, 9))
            ekf.x_dead_reckoned = x_pred
            ekf.predict()
        six = self.augmented
        if gps_xy_m is not None and heading_rad is not None:
            z = np.array([gps_xy_m[0], gps_xy_m[1], heading_rad])
            R = self._cached("R_pose", gps_sigma_m, heading_sigma_rad)
            ekf.update(
                z,
                H_pose6 if six else H_pose,
                hx_pose6 if six else hx_pose,
                R=R,
                residual=residual_pose,
            )
        elif gps_xy_m is not None:
            R = self._cached("R_gps", gps_sigma_m)
            ekf.update(
                np.array(gps_xy_m, dtype=float),
                H_gps6 if six else H_gps,
                hx_gps6 if six else hx_gps,
                R=R,
            )
        elif heading_rad is not None:
            R = self._cached("R_compass", heading_sigma_rad)
            ekf.update(
                np.array([heading_rad]),
                H_compass6 if six else H_compass,
                hx_compass6 if six else hx_compass,
                R=R,
                residual=residual_heading,
            )
        if gps_xy_m is not None or heading_rad is not None:
            # Kept, not solved: the simulator batches a run's NIS at its end.
            y = np.atleast_1d(np.asarray(ekf.y, dtype=float))
            self._innovation = (y, np.atleast_2d(np.asarray(ekf.S, dtype=float)))
            self.nis_dof = len(y)
        ekf.x[2] = ekf.x[2] % (2.0 * math.pi)
        self._reset_interval()
