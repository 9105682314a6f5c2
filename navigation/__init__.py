"""tillpath's navigation simulator: the tractor's GPS, compass and Kalman waypoint loop.

Pure and seeded: a plan, a :class:`SimulationConfig` and an ``np.random.Generator`` in, a
:class:`SimulationLog` with metrics out. :func:`score_track` scores any track (simulated or
recorded) against a plan. Modules: ``types``, ``vehicle``, ``sensors``, ``compass``,
``filters``, ``guidance``, ``curves``, ``config``, ``simulator``, ``metrics``, ``export``,
``plot`` (import it explicitly: it loads matplotlib).
"""

from navigation.metrics import Stretch, TrackMetrics, score_track
from navigation.simulator import SimulationLog, simulate, validate_config
from navigation.types import (
    GPS_PRESETS,
    GUIDANCE_MODES,
    CompassParams,
    FilterParams,
    GpsParams,
    GuidanceParams,
    NavigationError,
    SimulationConfig,
    VehicleParams,
)

__all__ = [
    "GPS_PRESETS",
    "GUIDANCE_MODES",
    "CompassParams",
    "FilterParams",
    "GpsParams",
    "GuidanceParams",
    "NavigationError",
    "SimulationConfig",
    "SimulationLog",
    "Stretch",
    "TrackMetrics",
    "VehicleParams",
    "score_track",
    "simulate",
    "validate_config",
]
