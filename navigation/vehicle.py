"""The walk-behind tractor as a differential drive with clutch steering.

Both wheels are driven at the engine's speed ``v``. Pulling a clutch handle disengages and
brakes that wheel: the other wheel keeps going and the tractor pivots about the stopped wheel,
at ``v / track_width`` rad/s, its axle centre moving at ``v / 2`` on a circle of radius
``track_width / 2``. The motion over a step is integrated exactly (a rotation about the pivot),
so the step size does not bend the arcs.
"""

from __future__ import annotations

import math

import numpy as np

from navigation.types import LEFT, RIGHT, STRAIGHT, NavigationError, VehicleParams, VehicleState

TWO_PI = 2.0 * math.pi


def wrap_angle(angle_rad: float) -> float:
    """Wrap an angle to [-π, π).

    Examples
    --------
    >>> round(wrap_angle(3.5 * math.pi), 6)
    -1.570796
    >>> wrap_angle(-math.pi) == -math.pi
    True
    """
    return (angle_rad + math.pi) % TWO_PI - math.pi


def yaw_rate(clutch: int, *, speed_mps: float, track_width_m: float) -> float:
    """Turn rate [rad/s, clockwise positive] for a clutch command.

    Examples
    --------
    >>> round(yaw_rate(RIGHT, speed_mps=0.56, track_width_m=1.8), 4)
    0.3111
    """
    if clutch == STRAIGHT:
        return 0.0
    return clutch * speed_mps / track_width_m


def step(
    state: VehicleState, clutch: int, dt_s: float, *, speed_mps: float, track_width_m: float
) -> VehicleState:
    """Advance the tractor by ``dt_s`` with ``clutch`` engaged.

    Parameters
    ----------
    state : VehicleState
        State at the start of the step.
    clutch : int
        ``LEFT`` (-1), ``STRAIGHT`` (0) or ``RIGHT`` (1), as engaged during the step.
    dt_s : float
        Step length [s].
    speed_mps : float
        Wheel ground speed [m/s].
    track_width_m : float
        Distance between the wheels [m].

    Returns
    -------
    VehicleState
        With ``clutch`` recorded as engaged.

    Examples
    --------
    >>> s = step(VehicleState(0.0, 0.0, 0.0), STRAIGHT, 10.0, speed_mps=0.5, track_width_m=1.8)
    >>> (round(s.x_m, 9), round(s.y_m, 9))     # 5 m due north
    (0.0, 5.0)
    """
    sin_h = math.sin(state.heading_rad)
    cos_h = math.cos(state.heading_rad)
    if clutch == STRAIGHT:
        d = speed_mps * dt_s
        return VehicleState(state.x_m + d * sin_h, state.y_m + d * cos_h, state.heading_rad, 0)
    # The braked wheel: half a track to the left (clutch -1) or right (+1) of the axle centre.
    # "Right" of a heading h (clockwise from north) is (cos h, -sin h) in (east, north).
    half = 0.5 * track_width_m * clutch
    px = state.x_m + half * cos_h
    py = state.y_m - half * sin_h
    dtheta = clutch * speed_mps / track_width_m * dt_s
    c = math.cos(dtheta)
    s = math.sin(dtheta)
    rx = state.x_m - px
    ry = state.y_m - py
    # Clockwise rotation by dtheta in (east, north): (x, y) -> (x c + y s, -x s + y c).
    return VehicleState(
        px + rx * c + ry * s,
        py - rx * s + ry * c,
        (state.heading_rad + dtheta) % TWO_PI,
        clutch,
    )


def disturb(
    state: VehicleState, rng: np.random.Generator, dt_s: float, *, yaw_noise_deg_per_sqrt_s: float
) -> VehicleState:
    """Add the heading random walk of uneven ground over one step."""
    if yaw_noise_deg_per_sqrt_s <= 0.0:
        return state
    dtheta = math.radians(yaw_noise_deg_per_sqrt_s) * math.sqrt(dt_s) * rng.standard_normal()
    return VehicleState(state.x_m, state.y_m, (state.heading_rad + dtheta) % TWO_PI, state.clutch)


def validate_vehicle(params: VehicleParams) -> None:
    """Raise :class:`NavigationError` if the tractor's parameters make no sense."""
    if not (math.isfinite(params.speed_mps) and 0.0 < params.speed_mps <= 10.0):
        raise NavigationError(
            "speed_mps", f"must be a speed in (0, 10] m/s, got {params.speed_mps}"
        )
    if not (math.isfinite(params.track_width_m) and 0.1 <= params.track_width_m <= 10.0):
        raise NavigationError(
            "track_width_m", f"must be in [0.1, 10] m, got {params.track_width_m}"
        )
    if not (math.isfinite(params.clutch_delay_s) and 0.0 <= params.clutch_delay_s <= 5.0):
        raise NavigationError("clutch_delay_s", f"must be in [0, 5] s, got {params.clutch_delay_s}")
    if not (math.isfinite(params.speed_noise) and 0.0 <= params.speed_noise < 1.0):
        raise NavigationError("speed_noise", f"must be in [0, 1), got {params.speed_noise}")
    if not (
        math.isfinite(params.yaw_noise_deg_per_sqrt_s) and params.yaw_noise_deg_per_sqrt_s >= 0
    ):
        raise NavigationError(
            "yaw_noise_deg_per_sqrt_s", f"must be ≥ 0, got {params.yaw_noise_deg_per_sqrt_s}"
        )


__all__ = [
    "LEFT",
    "RIGHT",
    "STRAIGHT",
    "disturb",
    "step",
    "validate_vehicle",
    "wrap_angle",
    "yaw_rate",
]
