"""Value types and configuration of the navigation simulator.

Local coordinates are the planner's field frame (:func:`planner.field_frame`): ``x`` east and
``y`` true north in metres. Headings are clockwise from true north, as a compass reads them:
radians inside the simulator (``heading_rad``), degrees at the edges (``heading_deg``).

A walk-behind tractor has three steering commands: straight, pull the left clutch (the left
wheel stops and the tractor pivots left about it) and pull the right clutch.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, field
from typing import Literal

from planner.types import DEFAULT_SPEED_MPS, DEFAULT_TRACK_WIDTH_M

GuidanceMode = Literal["waypoint", "line"]
GUIDANCE_MODES: tuple[GuidanceMode, ...] = ("waypoint", "line")

#: Steering commands: the clutch that is pulled (or none).
STRAIGHT = 0
LEFT = -1
RIGHT = 1

#: CEP (50 % circle) of a circular 2-D Gaussian is 1.1774 times its per-axis sigma.
CEP_PER_SIGMA = math.sqrt(2.0 * math.log(2.0))


class NavigationError(ValueError):
    """A simulation request that cannot run: bad configuration or an empty plan.

    ``str(error)`` reads ``"<input>: <problem>"``, like :class:`planner.PlannerError`.

    Parameters
    ----------
    input_name : str
        The configuration field or input at fault (``speed_mps``, ``gps``, ``plan`` …).
    problem : str
        What is wrong with it, in plain words.
    """

    def __init__(self, input_name: str, problem: str) -> None:
        super().__init__(f"{input_name}: {problem}")
        self.input_name = input_name
        self.problem = problem


@dataclass(frozen=True, slots=True)
class VehicleState:
    """Where the tractor is and which clutch is engaged.

    Attributes
    ----------
    x_m, y_m : float
        Centre of the axle, local frame [m].
    heading_rad : float
        Clockwise from true north [rad], in [0, 2π).
    clutch : int
        The clutch actually engaged: ``LEFT`` (-1), ``STRAIGHT`` (0) or ``RIGHT`` (1).
    """

    x_m: float
    y_m: float
    heading_rad: float
    clutch: int = STRAIGHT


@dataclass(frozen=True, slots=True)
class GpsFix:
    """One GPS position as the receiver reports it.

    Attributes
    ----------
    time_s : float
        Simulation time [s].
    x_m, y_m : float
        Reported position, local frame [m].
    """

    time_s: float
    x_m: float
    y_m: float


@dataclass(frozen=True, slots=True)
class CompassReading:
    """Horizontal magnetometer components, as the paper's HMC5883L delivers them.

    Attributes
    ----------
    time_s : float
        Simulation time [s].
    mag_x, mag_y : float
        Field along the sensor's forward and sideways axes (normalised, so that
        ``atan2(mag_y, mag_x)`` is the magnetic heading, clockwise from magnetic north).
    """

    time_s: float
    mag_x: float
    mag_y: float


@dataclass(frozen=True, slots=True)
class VehicleParams:
    """The walk-behind tractor (product.md §7).

    Attributes
    ----------
    speed_mps : float
        Ground speed of each driven wheel [m/s] (Quick G1000: 0.56).
    track_width_m : float
        Distance between the wheels [m] (1.8).
    clutch_delay_s : float
        Time the clutch servo takes to act on a command [s].
    speed_noise : float
        Wheel slip: relative standard deviation of the speed, per step (mud is uneven).
    yaw_noise_deg_per_sqrt_s : float
        Random walk of the heading from uneven ground [deg/√s].
    turn_rate_dps : float or None
        Yaw rate while a clutch is pulled [deg/s] (the plan's vehicle: the paper's Table 3
        gives π/4 rad/s = 45°/s); None: ``speed / track`` (the free wheel at full speed).
    min_turn_radius_m : float
        0 for a vehicle that pivots about a stopped wheel; else the radius of the arc the
        axle centre drives while turning [m] (the yaw rate is then ``speed / radius``).
    preset : str or None
        The plan vehicle's preset these figures came from, if any.
    """

    speed_mps: float = DEFAULT_SPEED_MPS
    track_width_m: float = DEFAULT_TRACK_WIDTH_M
    clutch_delay_s: float = 0.3
    speed_noise: float = 0.05
    yaw_noise_deg_per_sqrt_s: float = 0.5
    turn_rate_dps: float | None = None
    min_turn_radius_m: float = 0.0
    preset: str | None = None


@dataclass(frozen=True, slots=True)
class GpsParams:
    """A GPS receiver's error model: first-order Gauss–Markov error plus white noise.

    Attributes
    ----------
    name : str
        Preset name.
    rate_hz : float
        Fix rate [Hz].
    correlated_sigma_m : float
        Standard deviation of the slowly wandering error, per axis [m].
    correlation_time_s : float
        Time constant of the Gauss–Markov error [s].
    white_sigma_m : float
        Standard deviation of the fix-to-fix noise, per axis [m].
    """

    name: str
    rate_hz: float
    correlated_sigma_m: float
    correlation_time_s: float
    white_sigma_m: float

    @property
    def sigma_m(self) -> float:
        """Total standard deviation per axis [m]."""
        return math.hypot(self.correlated_sigma_m, self.white_sigma_m)

    @property
    def cep_m(self) -> float:
        """Circular error probable (radius holding 50 % of fixes) [m]."""
        return CEP_PER_SIGMA * self.sigma_m


def _preset(
    name: str, *, rate_hz: float, cep_m: float, white_share: float, tau_s: float
) -> GpsParams:
    sigma = cep_m / CEP_PER_SIGMA
    white = sigma * white_share
    return GpsParams(
        name=name,
        rate_hz=rate_hz,
        correlated_sigma_m=math.sqrt(sigma**2 - white**2),
        correlation_time_s=tau_s,
        white_sigma_m=white,
    )


#: The receivers (sources and assumptions in docs/simulation.md):
#: - ``m8n``: u-blox NEO-M8N, 2.5 m CEP (NEO-M8 data sheet UBX-15031086, GPS & GLONASS,
#:   autonomous; the paper's Table 2), 5 Hz (a configured rate; the data sheet allows up to
#:   10 Hz with two constellations). The error is mostly a slow wander: static tests of
#:   single-frequency receivers show autocorrelations that bend at about a minute (Wilson,
#:   "GPS accuracy", Garmin 12XL 20-day test; Soundy et al., Sensors 2020, 20, 6050, favour an
#:   Ornstein–Uhlenbeck model). The 60 s and the 30 % white share are assumptions of that
#:   order, not an M8N measurement: fit your own with ``tillpath simulate --gps-from LOG``.
#: - ``rtk``: an RTK fix, 2 cm CEP (u-blox ZED-F9P data sheet: 0.01 m + 1 ppm CEP, i.e. a
#:   baseline of about 10 km), 5 Hz, mostly white; its 10 s correlation is an assumption.
GPS_PRESETS: dict[str, GpsParams] = {
    "m8n": _preset("m8n", rate_hz=5.0, cep_m=2.5, white_share=0.3, tau_s=60.0),
    "rtk": _preset("rtk", rate_hz=5.0, cep_m=0.02, white_share=0.7, tau_s=10.0),
}


@dataclass(frozen=True, slots=True)
class CompassParams:
    """The magnetometer (the paper's algorithm 2).

    Attributes
    ----------
    noise_deg : float
        Standard deviation of each reading's heading [deg].
    bias_deg : float
        Constant heading error left after calibration (hard/soft iron, local anomaly) [deg].
    rate_hz : float
        Reading rate [Hz].
    """

    noise_deg: float = 2.0
    bias_deg: float = 1.5
    rate_hz: float = 10.0


@dataclass(frozen=True, slots=True)
class GuidanceParams:
    """How the controller steers.

    Attributes
    ----------
    mode : str
        ``waypoint`` (the paper: aim at the next waypoint) or ``line`` (pure pursuit along the
        planned segment between the previous and the next waypoint).
    heading_tolerance_deg : float
        Heading error within which the tractor drives straight (waypoint mode) [deg].
    line_tolerance_deg : float
        The same in line mode [deg]; tighter, since the aim point is steadier.
    acceptance_radius_m : float
        Waypoint mode: a waypoint is reached when the estimate comes this close [m].
    line_acceptance_radius_m : float
        Line mode: the same [m]. In both modes a waypoint also counts as reached when the
        estimate passes the perpendicular through it, so a near miss never makes the tractor
        circle back (as ArduPilot does).
    lookahead_m : float
        Pure-pursuit look-ahead along the segment (line mode), and along a curve (both
        modes) [m].
    curve_tolerance_deg : float
        Heading error within which the tractor drives straight on a curve of the plan (a
        turn, a round, a corner loop), in both modes (:mod:`navigation.curves`) [deg].
    curve_bend_deg : float
        On a curve, the aim looks no further ahead than where the path has bent by this much
        from the leg being driven [deg].
    """

    mode: GuidanceMode = "waypoint"
    heading_tolerance_deg: float = 8.0
    line_tolerance_deg: float = 3.0
    acceptance_radius_m: float = 1.0
    line_acceptance_radius_m: float = 1.0
    lookahead_m: float = 2.5
    curve_tolerance_deg: float = 3.0
    curve_bend_deg: float = 30.0


@dataclass(frozen=True, slots=True)
class FilterParams:
    """Process noise of the Kalman filter (measurement noise comes from the sensors).

    Attributes
    ----------
    position_sigma_m_per_sqrt_s : float
        Random walk of the position the motion model does not explain [m/√s]: the simulated
        wheel slip (5 % of 0.56 m/s per 0.1 s step) is 0.009 m/√s.
    heading_sigma_deg_per_sqrt_s : float
        Random walk of the heading the motion model does not explain [deg/√s] (the simulated
        ground adds 0.5°/√s, slip during pivots about as much again).
    augmented : bool
        Estimate the compass bias and the receiver's wander as states (the default). False
        gives the plain ``[x, y, θ]`` filter that treats the whole GPS error as white noise
        (kept to show how overconfident that is).
    compass_bias_sigma_deg : float
        Prior standard deviation of the compass bias [deg].
    compass_bias_drift_deg_per_sqrt_s : float
        Random walk allowed to the compass bias [deg/√s].
    """

    position_sigma_m_per_sqrt_s: float = 0.012
    heading_sigma_deg_per_sqrt_s: float = 1.0
    augmented: bool = True
    compass_bias_sigma_deg: float = 3.0
    compass_bias_drift_deg_per_sqrt_s: float = 0.001


@dataclass(frozen=True, slots=True)
class SimulationConfig:
    """Everything a simulation run needs besides the plan and the random generator.

    Attributes
    ----------
    vehicle : VehicleParams or None
        The tractor; None: the plan's vehicle (its track, turn rate and turning radius;
        ``hand_tractor`` for a plan without one), at the default speed and noise.
    compass, guidance, kalman : params
        See their classes.
    gps : str or GpsParams
        A preset name (``m8n``, ``rtk``) or a custom error model.
    dt_s : float
        Control loop period [s] (10 Hz).
    time_limit_s : float or None
        Simulated time after which the run stops, incomplete [s]; None: three times the
        plan's path length at working speed plus 300 s.
    date : datetime.date
        Date of the run, for the magnetic declination.
    initial_heading_sigma_deg : float
        Spread of the tractor's initial heading about the bearing to the first line [deg].
    """

    vehicle: VehicleParams | None = None
    gps: str | GpsParams = "m8n"
    compass: CompassParams = field(default_factory=CompassParams)
    guidance: GuidanceParams = field(default_factory=GuidanceParams)
    kalman: FilterParams = field(default_factory=FilterParams)
    dt_s: float = 0.1
    time_limit_s: float | None = None
    date: dt.date = dt.date(2026, 1, 1)
    initial_heading_sigma_deg: float = 5.0


@dataclass(frozen=True, slots=True)
class SteerCommand:
    """What the guidance law decided, and why.

    Attributes
    ----------
    clutch : int
        ``LEFT`` (-1), ``STRAIGHT`` (0) or ``RIGHT`` (1).
    heading_error_deg : float
        Desired minus current heading, wrapped to [-180, 180) [deg].
    distance_m : float
        Distance to the target waypoint [m].
    """

    clutch: int
    heading_error_deg: float
    distance_m: float
