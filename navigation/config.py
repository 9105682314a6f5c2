"""What a simulated run is configured with: its tractor, and the checks on its settings."""

from __future__ import annotations

import math

from navigation.sensors import gps_params, validate_compass
from navigation.types import (
    GUIDANCE_MODES,
    GpsParams,
    NavigationError,
    SimulationConfig,
    VehicleParams,
)
from navigation.vehicle import validate_vehicle, vehicle_params_for
from planner.types import CoveragePlan
from planner.vehicles import resolve_vehicle


def plan_vehicle_params(plan: CoveragePlan) -> VehicleParams:
    """Return the simulator's tractor for ``plan``: its vehicle (default ``hand_tractor``)."""
    return vehicle_params_for(resolve_vehicle(getattr(plan, "vehicle", None)))


def validate_config(config: SimulationConfig) -> GpsParams:
    """Check ``config``; return its GPS model.

    Raises
    ------
    NavigationError
        Naming the first bad setting.
    """
    if config.vehicle is not None:
        validate_vehicle(config.vehicle)
    validate_compass(config.compass)
    gps = gps_params(config.gps)
    g = config.guidance
    if g.mode not in GUIDANCE_MODES:
        raise NavigationError(
            "guidance", f"unknown mode {g.mode!r}; choose one of {', '.join(GUIDANCE_MODES)}"
        )
    for name in ("heading_tolerance_deg", "line_tolerance_deg", "curve_tolerance_deg"):
        value = getattr(g, name)
        if not (math.isfinite(value) and 0.0 < value < 90.0):
            raise NavigationError(name, f"must be in (0, 90) degrees, got {value}")
    for name in ("acceptance_radius_m", "line_acceptance_radius_m"):
        value = getattr(g, name)
        if not (math.isfinite(value) and 0.0 < value <= 50.0):
            raise NavigationError(name, f"must be in (0, 50] m, got {value}")
    if not (math.isfinite(g.curve_bend_deg) and 0.0 < g.curve_bend_deg <= 180.0):
        raise NavigationError(
            "curve_bend_deg", f"must be in (0, 180] degrees, got {g.curve_bend_deg}"
        )
    if not (math.isfinite(g.lookahead_m) and 0.0 < g.lookahead_m <= 100.0):
        raise NavigationError("lookahead_m", f"must be in (0, 100] m, got {g.lookahead_m}")
    if not (math.isfinite(config.dt_s) and 0.001 <= config.dt_s <= 1.0):
        raise NavigationError("dt_s", f"must be in [0.001, 1] s, got {config.dt_s}")
    if config.time_limit_s is not None and not (
        math.isfinite(config.time_limit_s) and config.time_limit_s > 0
    ):
        raise NavigationError("time_limit_s", f"must be > 0, got {config.time_limit_s}")
    k = config.kalman
    if not (
        k.position_sigma_m_per_sqrt_s > 0 and k.heading_sigma_deg_per_sqrt_s > 0
    ):  # NaN fails too
        raise NavigationError("kalman", "process noise sigmas must be > 0")
    if not (
        math.isfinite(config.initial_heading_sigma_deg)
        and 0.0 <= config.initial_heading_sigma_deg <= 180.0
    ):
        raise NavigationError(
            "initial_heading_sigma_deg",
            f"must be in [0, 180], got {config.initial_heading_sigma_deg}",
        )
    return gps


__all__ = ["plan_vehicle_params", "validate_config"]
