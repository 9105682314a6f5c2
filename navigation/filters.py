"""Extended Kalman filter of the tractor's position and heading (filterpy).

State ``x = [x, y, θ]``: position in the local frame [m] and heading clockwise from true north
[rad]. Control ``u = [v, ω]``: axle-centre speed [m/s] and yaw rate [rad/s, clockwise], which
the controller knows from the clutch it pulled (a pivot halves the centre speed). GPS measures
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

from navigation.types import FilterParams
from navigation.vehicle import wrap_angle

FloatArray = npt.NDArray[np.float64]

#: GPS and compass measurement Jacobians: the models are linear in the state.
_H_GPS = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
_H_COMPASS = np.array([[0.0, 0.0, 1.0]])
_H_POSE = np.eye(3)


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

    def __init__(self, x0: FloatArray, P0: FloatArray, *, params: FilterParams) -> None:
        self.ekf = _TractorEKF(dim_x=3, dim_z=3)
        self.ekf.x = np.array(x0, dtype=float)
        self.ekf.P = np.array(P0, dtype=float)
        self.params = params
        self._matrices: dict[tuple[str | float, ...], FloatArray] = {}
        self._reset_interval()

    def _cached(self, kind: str, *args: float) -> FloatArray:
        """Noise matrices, built once per distinct value (they rarely change in a run)."""
        key: tuple[str | float, ...] = (kind, *args)
        matrix = self._matrices.get(key)
        if matrix is None:
            if kind == "Q":
                matrix = Q_process(self.params, args[0])
            elif kind == "R_pose":
                matrix = np.diag([args[0] ** 2, args[0] ** 2, args[1] ** 2])
            elif kind == "R_gps":
                matrix = np.eye(2) * args[0] ** 2
            else:
                matrix = np.array([[args[0] ** 2]])
            self._matrices[key] = matrix
        return matrix

    def _reset_interval(self) -> None:
        self._x = [float(v) for v in self.ekf.x]
        self._f02 = 0.0  # chained Jacobian: [[1, 0, f02], [0, 1, f12], [0, 0, 1]]
        self._f12 = 0.0
        self._elapsed_s = 0.0

    @property
    def x(self) -> FloatArray:
        """The current estimate ``[x, y, θ]`` (dead-reckoned since the last update)."""
        return np.array(self._x)

    @property
    def P(self) -> FloatArray:  # noqa: N802 (filterpy's names)
        """The covariance after the last update."""
        return self.ekf.P  # type: ignore[no-any-return]

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
            Its per-axis standard deviation [m].
        heading_rad : float or None
            Compass heading, clockwise from true north [rad].
        heading_sigma_rad : float
            Its standard deviation [rad].
        """
        ekf = self.ekf
        if self._elapsed_s > 0.0:
            ekf.F = np.array([[1.0, 0.0, self._f02], [0.0, 1.0, self._f12], [0.0, 0.0, 1.0]])
            ekf.Q = self._cached("Q", round(self._elapsed_s, 9))
            ekf.x_dead_reckoned = np.array(self._x)
            ekf.predict()
        if gps_xy_m is not None and heading_rad is not None:
            z = np.array([gps_xy_m[0], gps_xy_m[1], heading_rad])
            R = self._cached("R_pose", gps_sigma_m, heading_sigma_rad)
            ekf.update(z, H_pose, hx_pose, R=R, residual=residual_pose)
        elif gps_xy_m is not None:
            R = self._cached("R_gps", gps_sigma_m)
            ekf.update(np.array(gps_xy_m, dtype=float), H_gps, hx_gps, R=R)
        elif heading_rad is not None:
            R = self._cached("R_compass", heading_sigma_rad)
            ekf.update(
                np.array([heading_rad]), H_compass, hx_compass, R=R, residual=residual_heading
            )
        ekf.x[2] = ekf.x[2] % (2.0 * math.pi)
        self._reset_interval()
