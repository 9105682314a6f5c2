"""The walk-behind tractor as a differential drive with clutch steering.

Both wheels are driven at the engine's speed ``v``. Pulling a clutch handle disengages and
brakes that wheel: the other wheel keeps going and the tractor pivots about the stopped wheel,
at ``v / track_width`` rad/s (or the vehicle's own turn rate, the paper's π/4 rad/s), its axle
centre on a circle of radius ``track_width / 2``. A vehicle with a minimum turning radius
``R`` instead drives an arc of radius ``R`` at ``v / R`` rad/s. The motion over a step is
integrated exactly (a rotation about the pivot), so the step size does not bend the arcs.
"""

from __future__ import annotations

import math

import numpy as np

from navigation.types import LEFT, RIGHT, STRAIGHT, NavigationError, VehicleParams, VehicleState
from planner.types import Vehicle

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


def turn_geometry(params: VehicleParams, speed_mps: float) -> tuple[float, float]:
    """Yaw rate [rad/s] and pivot distance from the axle centre [m] while a clutch is pulled.

    Examples
    --------
    >>> rate, radius = turn_geometry(VehicleParams(track_width_m=0.7, turn_rate_dps=45.0), 0.56)
    >>> round(rate, 4), radius                    # π/4 rad/s about the braked wheel
    (0.7854, 0.35)
    >>> rate, radius = turn_geometry(VehicleParams(min_turn_radius_m=3.0), 0.6)
    >>> round(rate, 6), radius                    # v / R on a 3 m arc
    (0.2, 3.0)
    """
    if params.min_turn_radius_m > 0.0:
        return speed_mps / params.min_turn_radius_m, params.min_turn_radius_m
    if params.turn_rate_dps:
        return math.radians(params.turn_rate_dps), 0.5 * params.track_width_m
    return speed_mps / params.track_width_m, 0.5 * params.track_width_m


def vehicle_params_for(vehicle: Vehicle, **overrides: float) -> VehicleParams:
    """Return the simulator's tractor for a plan's :class:`planner.types.Vehicle`.

    Its track, turn rate and minimum turning radius come from the vehicle; speed and noise
    keep their defaults unless ``overrides`` sets them.

    Examples
    --------
    >>> from planner.vehicles import resolve_vehicle
    >>> p = vehicle_params_for(resolve_vehicle("hand_tractor"))
    >>> p.track_width_m, p.turn_rate_dps, p.preset
    (0.7, 45.0, 'hand_tractor')
    """
    return VehicleParams(
        track_width_m=vehicle.track_m,
        turn_rate_dps=vehicle.turn_rate_dps,
        min_turn_radius_m=vehicle.min_turn_radius_m,
        preset=vehicle.preset,
        **overrides,
    )


def step(
    state: VehicleState,
    clutch: int,
    dt_s: float,
    *,
    speed_mps: float,
    track_width_m: float,
    yaw_rate_rad_s: float | None = None,
    pivot_m: float | None = None,
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
    yaw_rate_rad_s : float or None
        Yaw rate while turning [rad/s]; None: ``speed_mps / track_width_m``.
    pivot_m : float or None
        Distance from the axle centre to the point turned about [m]; None: half the track
        (the braked wheel).

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
    return VehicleState(
        *step_pose(
            state.x_m,
            state.y_m,
            state.heading_rad,
            clutch,
            dt_s,
            speed_mps=speed_mps,
            track_width_m=track_width_m,
            yaw_rate_rad_s=yaw_rate_rad_s,
            pivot_m=pivot_m,
        ),
        clutch,
    )


def step_pose(
    x_m: float,
    y_m: float,
    heading_rad: float,
    clutch: int,
    dt_s: float,
    *,
    speed_mps: float,
    track_width_m: float,
    yaw_rate_rad_s: float | None = None,
    pivot_m: float | None = None,
) -> tuple[float, float, float]:
    """:func:`step` on a bare pose: the new ``(x_m, y_m, heading_rad)``, for the 10 Hz loop.

    Examples
    --------
    >>> x, y, h = step_pose(0.0, 0.0, 0.0, STRAIGHT, 10.0, speed_mps=0.5, track_width_m=1.8)
    >>> (round(x, 9), round(y, 9), h)     # 5 m due north
    (0.0, 5.0, 0.0)
    """
    sin_h = math.sin(heading_rad)
    cos_h = math.cos(heading_rad)
    if clutch == STRAIGHT:
        d = speed_mps * dt_s
        return x_m + d * sin_h, y_m + d * cos_h, heading_rad
    # The point turned about: the braked wheel, half a track to the left (clutch -1) or right
    # (+1) of the axle centre, or the centre of the turning circle.
    # "Right" of a heading h (clockwise from north) is (cos h, -sin h) in (east, north).
    half = (0.5 * track_width_m if pivot_m is None else pivot_m) * clutch
    px = x_m + half * cos_h
    py = y_m - half * sin_h
    rate = speed_mps / track_width_m if yaw_rate_rad_s is None else yaw_rate_rad_s
    dtheta = clutch * rate * dt_s
    c = math.cos(dtheta)
    s = math.sin(dtheta)
    rx = x_m - px
    ry = y_m - py
    # Clockwise rotation by dtheta in (east, north): (x, y) -> (x c + y s, -x s + y c).
    return px + rx * c + ry * s, py - rx * s + ry * c, (heading_rad + dtheta) % TWO_PI


def servo_motion(
    commands: tuple[int, ...],
    dt_s: float,
    *,
    speed_mps: float,
    track_width_m: float,
    yaw_rate_rad_s: float,
    pivot_m: float,
) -> tuple[float, float, float]:
    """Where ``commands``, one a step, take the tractor, in its own frame at their start.

    What the controller predicts of the commands still in the clutch servo (no slip, no
    ground): the pose they will have brought the tractor to when a new command acts.

    Returns
    -------
    (float, float, float)
        Displacement to the right and forward [m], and the turn, clockwise [rad, ±π].

    Examples
    --------
    >>> right, forward, turn = servo_motion((RIGHT, RIGHT), 1.0, speed_mps=0.5,
    ...     track_width_m=0.7, yaw_rate_rad_s=math.pi / 4, pivot_m=0.35)
    >>> round(right, 6), round(forward, 6), round(math.degrees(turn), 6)  # 90° about the wheel
    (0.35, 0.35, 90.0)
    """
    x_m = y_m = heading_rad = 0.0
    for clutch in commands:
        x_m, y_m, heading_rad = step_pose(
            x_m,
            y_m,
            heading_rad,
            clutch,
            dt_s,
            speed_mps=speed_mps,
            track_width_m=track_width_m,
            yaw_rate_rad_s=yaw_rate_rad_s,
            pivot_m=pivot_m,
        )
    return x_m, y_m, wrap_angle(heading_rad)


def disturb(
    state: VehicleState, rng: np.random.Generator, dt_s: float, *, yaw_noise_deg_per_sqrt_s: float
) -> VehicleState:
    """Add the heading random walk of uneven ground over one step."""
    if yaw_noise_deg_per_sqrt_s <= 0.0:
        return state
    heading = disturb_heading(
        state.heading_rad, rng, dt_s, yaw_noise_deg_per_sqrt_s=yaw_noise_deg_per_sqrt_s
    )
    return VehicleState(state.x_m, state.y_m, heading, state.clutch)


def disturb_heading(
    heading_rad: float, rng: np.random.Generator, dt_s: float, *, yaw_noise_deg_per_sqrt_s: float
) -> float:
    """:func:`disturb` on a bare heading [rad], for the 10 Hz loop (no draw without noise)."""
    if yaw_noise_deg_per_sqrt_s <= 0.0:
        return heading_rad
    dtheta = math.radians(yaw_noise_deg_per_sqrt_s) * math.sqrt(dt_s) * rng.standard_normal()
    return (heading_rad + dtheta) % TWO_PI


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
    if params.turn_rate_dps is not None and not (
        math.isfinite(params.turn_rate_dps) and 0.0 < params.turn_rate_dps <= 360.0
    ):
        raise NavigationError(
            "turn_rate_dps", f"must be in (0, 360] °/s, got {params.turn_rate_dps}"
        )
    if not (math.isfinite(params.min_turn_radius_m) and 0.0 <= params.min_turn_radius_m <= 50):
        raise NavigationError(
            "min_turn_radius_m", f"must be in [0, 50] m, got {params.min_turn_radius_m}"
        )
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
    "disturb_heading",
    "servo_motion",
    "step",
    "step_pose",
    "turn_geometry",
    "validate_vehicle",
    "vehicle_params_for",
    "wrap_angle",
    "yaw_rate",
]
