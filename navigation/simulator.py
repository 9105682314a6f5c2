"""The tractor's control loop, simulated at 10 Hz on a plan's waypoints.

Each step: the GPS receiver (5 Hz) and the compass (10 Hz) read the *true* state; the Kalman
filter fuses them into an *estimated* state; guidance turns the estimate into a clutch
command; the clutch servo applies it after its delay; the tractor moves (with wheel slip and
heading disturbance); the filter predicts with the command the controller knows it gave. The
true, measured and estimated states are logged side by side.

The plan's curves (turns, rounds, corner loops: legs of 0.5 m or less) are followed by pursuit
along the path, their points passed abeam (:mod:`navigation.curves`); the paper's law, with its
acceptance radius, keeps the tillage lines and the other legs.

The run ends when the last waypoint is reached (``completed``) or the time limit passes
(``completed`` false): never a hang.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from navigation.compass import compass_heading_deg, magnetic_declination_deg
from navigation.config import plan_vehicle_params, validate_config
from navigation.consistency import chi2_mean_bounds, normalised_squares
from navigation.curves import MIN_AIM_M, aim_point, curve_path
from navigation.filters import PoseFilter, augmented_x0
from navigation.guidance import aim_law, pursuit_law, segment_axes, waypoint_law
from navigation.metrics import TrackMetrics, line_waypoints, optional_tuple, score_track
from navigation.sensors import GpsReceiver, read_compass, read_magnetometer
from navigation.types import STRAIGHT, NavigationError, SimulationConfig, VehicleState
from navigation.vehicle import (
    TWO_PI,
    disturb_heading,
    servo_motion,
    step_pose,
    turn_geometry,
    validate_vehicle,
)
from planner.projection import LocalFrame, field_frame
from planner.types import CoveragePlan

FloatArray = npt.NDArray[np.float64]

#: Floating-point slack when comparing simulation times [s].
_EPS_S = 1e-9


@dataclass(frozen=True, slots=True)
class SimulationLog:
    """A simulated run: true, measured and estimated tracks, and their metrics.

    Positions are in the field's local frame (``frame``; x east, y true north, metres) and
    headings clockwise from true north [rad]; :meth:`lonlat` converts to WGS84.

    Attributes
    ----------
    plan : CoveragePlan
        The plan that was followed.
    config : SimulationConfig
        The configuration, with the GPS preset resolved.
    frame : LocalFrame
        The local frame of the arrays.
    completed : bool
        The last waypoint was reached within the time limit.
    time_s : array
        Time of each control step [s].
    true_x_m, true_y_m, true_heading_rad : arrays
        True state at each step.
    est_x_m, est_y_m, est_heading_rad : arrays
        Filter estimate at each step.
    clutch : int array
        Clutch engaged at each step (-1 left, 0 none, 1 right).
    target : int array
        Index of the waypoint ending the leg being driven at each step: the one steered to,
        but the line's end while the tractor, past it by the acceptance radius, drives on to
        the start of the curve that follows.
    gps_time_s, gps_x_m, gps_y_m : arrays
        The GPS fixes.
    reached_s : array
        Time each waypoint was reached [s] (NaN if never; 0 for the start).
    declination_deg : float
        Magnetic declination used (WMM-2025) [deg].
    metrics : TrackMetrics
        Scores of the true track (:func:`navigation.metrics.score_track`) plus the filter and
        GPS errors.
    """

    plan: CoveragePlan
    config: SimulationConfig
    frame: LocalFrame
    completed: bool
    time_s: FloatArray
    true_x_m: FloatArray
    true_y_m: FloatArray
    true_heading_rad: FloatArray
    est_x_m: FloatArray
    est_y_m: FloatArray
    est_heading_rad: FloatArray
    clutch: npt.NDArray[np.int8]
    target: npt.NDArray[np.int64]
    gps_time_s: FloatArray
    gps_x_m: FloatArray
    gps_y_m: FloatArray
    reached_s: FloatArray
    declination_deg: float
    metrics: TrackMetrics

    def lonlat(self, which: str) -> tuple[FloatArray, FloatArray]:
        """WGS84 ``(lon, lat)`` arrays of the ``true``, ``estimated`` or ``gps`` track."""
        if which == "true":
            return self.frame.to_lonlat_xy(self.true_x_m, self.true_y_m)
        if which == "estimated":
            return self.frame.to_lonlat_xy(self.est_x_m, self.est_y_m)
        if which == "gps":
            return self.frame.to_lonlat_xy(self.gps_x_m, self.gps_y_m)
        raise ValueError(f"which: expected true, estimated or gps, got {which!r}")


def _linearised_lonlat(
    frame: LocalFrame, wp_x: FloatArray, wp_y: FloatArray
) -> Callable[[int, float, float], tuple[float, float]]:
    """Local ``(x, y)`` to WGS84 near each waypoint, for the waypoint law at 10 Hz.

    The planner's projection is linearised about each waypoint once (its Jacobian from two
    one-metre probes); within 100 m of the waypoint the error is below a millimetre, and the
    law only cares about the direction and distance to that waypoint.
    """
    lon0, lat0 = frame.to_lonlat_xy(wp_x, wp_y)
    lon_e, lat_e = frame.to_lonlat_xy(wp_x + 1.0, wp_y)
    lon_n, lat_n = frame.to_lonlat_xy(wp_x, wp_y + 1.0)
    table = [
        (
            float(wp_x[i]),
            float(wp_y[i]),
            float(lon0[i]),
            float(lat0[i]),
            float(lon_e[i] - lon0[i]),
            float(lat_e[i] - lat0[i]),
            float(lon_n[i] - lon0[i]),
            float(lat_n[i] - lat0[i]),
        )
        for i in range(len(wp_x))
    ]

    def lonlat_near(i: int, x_m: float, y_m: float) -> tuple[float, float]:
        x0, y0, lon, lat, dlon_dx, dlat_dx, dlon_dy, dlat_dy = table[i]
        dx = x_m - x0
        dy = y_m - y0
        return lon + dlon_dx * dx + dlon_dy * dy, lat + dlat_dx * dx + dlat_dy * dy

    return lonlat_near


def simulate(
    plan: CoveragePlan,
    config: SimulationConfig,
    rng: np.random.Generator,
    *,
    threshold_m: float = 1.0,
    on_waypoint: Callable[[int, int], None] | None = None,
) -> SimulationLog:
    """Simulate the tractor driving ``plan`` and score the run.

    Parameters
    ----------
    plan : CoveragePlan
        The route; its first waypoint is where the tractor starts.
    config : SimulationConfig
        Vehicle, sensors, filter, guidance and loop settings.
    rng : numpy.random.Generator
        The only source of randomness: the same seed gives the same run.
    threshold_m : float
        Cross-track error threshold for the metrics' stretches [m].
    on_waypoint : callable or None
        Called as ``on_waypoint(reached, total)`` each time a waypoint is reached, for progress
        reporting on long runs.

    Returns
    -------
    SimulationLog

    Raises
    ------
    NavigationError
        For a bad configuration or a plan with fewer than two distinct waypoints.
    """
    gps_model = validate_config(config)
    if len(plan.waypoints) < 2:
        raise NavigationError(
            "plan", f"needs at least two waypoints to drive, has {len(plan.waypoints)}"
        )
    veh = config.vehicle or plan_vehicle_params(plan)
    validate_vehicle(veh)
    config = dataclasses.replace(config, gps=gps_model, vehicle=veh)
    frame = field_frame(plan.field_lonlat)
    wp_lon = np.array([w.lon for w in plan.waypoints])
    wp_lat = np.array([w.lat for w in plan.waypoints])
    wp_x, wp_y = frame.to_local_xy(wp_lon, wp_lat)
    leg = np.hypot(np.diff(wp_x), np.diff(wp_y))
    if not (leg > 0).any():
        raise NavigationError("plan", "all its waypoints are at the same place")
    n_wp = len(wp_x)

    guid = config.guidance
    comp = config.compass
    dt_s = config.dt_s
    speed = veh.speed_mps
    track = veh.track_width_m
    path_length = float(leg.sum())
    time_limit = (
        config.time_limit_s
        if config.time_limit_s is not None
        else 3.0 * path_length / speed + 300.0
    )
    centre = plan.field_lonlat.centroid
    declination = magnetic_declination_deg(centre.x, centre.y, date=config.date)

    # Start at the first waypoint, facing roughly toward the next distinct one.
    first = int(np.argmax(leg > 0)) + 1
    heading0 = (
        math.atan2(wp_x[first] - wp_x[0], wp_y[first] - wp_y[0])
        + math.radians(config.initial_heading_sigma_deg) * rng.standard_normal()
    )
    state = VehicleState(float(wp_x[0]), float(wp_y[0]), heading0 % TWO_PI, STRAIGHT)

    gps = GpsReceiver(gps_model, rng)
    augmented = config.kalman.augmented
    # The augmented filter carries the wander as a state: its fixes have the white noise only.
    gps_sigma = max(gps_model.white_sigma_m, 1e-3) if augmented else gps_model.sigma_m
    compass_sigma = math.radians(max(comp.noise_deg, 0.1))
    fix = gps.read(state, 0.0)
    reading = read_compass(state, rng, 0.0, declination_deg=declination, params=comp)
    heading_meas = math.radians(compass_heading_deg(reading.mag_x, reading.mag_y, declination))
    if augmented:
        x0, p0 = augmented_x0(
            (fix.x_m, fix.y_m),
            heading_meas,
            gps=dataclasses.replace(gps_model, white_sigma_m=gps_sigma),
            heading_sigma_rad=compass_sigma,
            params=config.kalman,
        )
        kf = PoseFilter(x0, p0, params=config.kalman, gps=gps_model)
    else:
        kf = PoseFilter(
            np.array([fix.x_m, fix.y_m, heading_meas]),
            np.diag([gps_sigma**2, gps_sigma**2, compass_sigma**2]),
            params=config.kalman,
        )
    # NEES and NIS samples, solved in one batch after the run.
    nees_err: list[tuple[float, float]] = []
    nees_cov: list[FloatArray] = []
    nis_y: list[FloatArray] = []
    nis_s: list[FloatArray] = []
    ex, ey, eh = fix.x_m, fix.y_m, heading_meas
    gps_period = 1.0 / gps_model.rate_hz
    compass_period = 1.0 / comp.rate_hz
    next_gps = gps_period
    next_compass = compass_period
    gps_t = [0.0]
    gps_x = [fix.x_m]
    gps_y = [fix.y_m]
    # Compass readings since the last filter update, summed as unit vectors (circular mean).
    sum_sin = sum_cos = 0.0
    n_compass = 0

    delay_steps = int(round(veh.clutch_delay_s / dt_s))
    # The commands in the servo, oldest first (a tuple: it keys the memo of their yaw below).
    servo: tuple[int, ...] = (STRAIGHT,) * delay_steps
    reached = np.full(n_wp, np.nan)
    reached[0] = 0.0
    target = 1
    tol_wp = guid.heading_tolerance_deg
    tol_line = guid.line_tolerance_deg
    radius = guid.acceptance_radius_m
    line_radius = guid.line_acceptance_radius_m
    line_mode = guid.mode == "line"
    yaw_noise = veh.yaw_noise_deg_per_sqrt_s
    speed_noise = veh.speed_noise
    omega_turn, pivot = turn_geometry(veh, speed)
    turn_speed = omega_turn * pivot
    # What the controller expects each clutch to do: (centre speed, yaw rate).
    u_by_clutch = {
        -1: (turn_speed, -omega_turn),
        0: (speed, 0.0),
        1: (turn_speed, omega_turn),
    }
    # The controller knows the commands still in the servo: it steers on the heading they
    # will have turned the tractor to when its new command acts (a Smith predictor), or a
    # tractor that turns at π/4 rad/s behind a 0.3 s servo would overshoot every correction.
    yaw_step = {c: u_by_clutch[c][1] * dt_s for c in (-1, 0, 1)}
    # Their summed yaw per servo content: few distinct contents, summed once each.
    servo_yaw: dict[tuple[int, ...], float] = {}
    est_wp_err = np.full(n_wp, np.nan)
    lonlat_near = _linearised_lonlat(frame, wp_x, wp_y) if not line_mode else None
    # Plain floats in the loop (numpy scalars are several times slower); each leg's segment
    # (previous waypoint to target) and its axes, computed once.
    wp_xs: list[float] = wp_x.tolist()
    wp_ys: list[float] = wp_y.tolist()
    wp_lons: list[float] = wp_lon.tolist()
    wp_lats: list[float] = wp_lat.tolist()
    legs = [(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)] + [
        (wp_xs[i - 1], wp_ys[i - 1], wp_xs[i], wp_ys[i])
        + segment_axes(wp_xs[i - 1], wp_ys[i - 1], wp_xs[i], wp_ys[i])
        for i in range(1, n_wp)
    ]
    accept_m = line_radius if line_mode else radius
    # The plan's curves (turns, rounds, corner loops) are followed by pursuit along the path
    # in both modes (navigation.curves); the paper's law keeps the lines and sparse legs.
    curves = curve_path(
        wp_x,
        wp_y,
        [w.role for w in plan.waypoints],
        [w.line for w in plan.waypoints],
        bend_rad=math.radians(guid.curve_bend_deg),
        lookahead_m=guid.lookahead_m,
    )
    on_curve = curves.on_curve
    stop = curves.stop
    tol_curve = guid.curve_tolerance_deg
    # On a curve the controller steers from the pose its commands in the servo will have
    # brought the tractor to: 0.3 s is 0.17 m, half a corner loop's radius. Memoised per
    # servo content, in the tractor's frame.
    servo_pose: dict[tuple[int, ...], tuple[float, float]] = {}
    # The true state as floats: x, y, heading, engaged clutch.
    tx_m, ty_m, th_rad, t_clutch = state.x_m, state.y_m, state.heading_rad, state.clutch

    log_t: list[float] = []
    log_tx: list[float] = []
    log_ty: list[float] = []
    log_th: list[float] = []
    log_ex: list[float] = []
    log_ey: list[float] = []
    log_eh: list[float] = []
    log_cl: list[int] = []
    log_tg: list[int] = []
    completed = False
    n_steps = int(math.ceil(time_limit / dt_s))
    for k in range(n_steps + 1):
        t = k * dt_s
        # Sense: compass readings accumulate; each GPS fix triggers a filter update.
        if t >= next_compass - _EPS_S:
            mag_x, mag_y = read_magnetometer(th_rad, rng, declination_deg=declination, params=comp)
            h = math.radians(compass_heading_deg(mag_x, mag_y, declination))
            sum_sin += math.sin(h)
            sum_cos += math.cos(h)
            n_compass += 1
            next_compass += compass_period
        if t >= next_gps - _EPS_S:
            fix_x, fix_y = gps.read_xy(tx_m, ty_m)
            gps_t.append(t)
            gps_x.append(fix_x)
            gps_y.append(fix_y)
            next_gps += gps_period
            if n_compass:
                kf.update(
                    gps_xy_m=(fix_x, fix_y),
                    gps_sigma_m=gps_sigma,
                    heading_rad=math.atan2(sum_sin, sum_cos),
                    heading_sigma_rad=compass_sigma / math.sqrt(n_compass),
                )
            else:
                kf.update(gps_xy_m=(fix_x, fix_y), gps_sigma_m=gps_sigma)
            sum_sin = sum_cos = 0.0
            n_compass = 0
            ex, ey, eh = kf.pose
            # Consistency: the position error against the filter's own covariance.
            nees_err.append((ex - tx_m, ey - ty_m))
            nees_cov.append(kf.P[:2, :2])
            if kf.innovation is not None:
                nis_y.append(kf.innovation[0])
                nis_s.append(kf.innovation[1])

        # Guide: advance past reached waypoints, then steer to the current one.
        clutch = STRAIGHT
        yaw_ahead = servo_yaw.get(servo)
        if yaw_ahead is None:
            yaw_ahead = servo_yaw[servo] = sum(yaw_step[c] for c in servo)
        eh_pred = (eh + yaw_ahead) % TWO_PI
        while True:
            ax, ay, bx, by, ux, uy, length = legs[target]
            along = (ex - ax) * ux + (ey - ay) * uy  # segment_progress's along-track [m]
            if on_curve[target]:
                # A curve's point is passed abeam; a line end, the start or the finish is
                # also reached within the acceptance radius, the paper's way.
                if along < length and not (
                    stop[target] and math.hypot(bx - ex, by - ey) <= accept_m
                ):
                    moved = servo_pose.get(servo)
                    if moved is None:
                        moved = servo_pose[servo] = servo_motion(
                            servo,
                            dt_s,
                            speed_mps=speed,
                            track_width_m=track,
                            yaw_rate_rad_s=omega_turn,
                            pivot_m=pivot,
                        )[:2]
                    sin_h = math.sin(eh)
                    cos_h = math.cos(eh)
                    px = ex + moved[0] * cos_h + moved[1] * sin_h
                    py = ey - moved[0] * sin_h + moved[1] * cos_h
                    aim_x, aim_y = aim_point(
                        curves,
                        legs,
                        target,
                        (px - ax) * ux + (py - ay) * uy,
                        lookahead_m=guid.lookahead_m,
                        min_aim_m=MIN_AIM_M,
                    )
                    clutch = aim_law(px, py, eh_pred, aim_x, aim_y, tolerance_deg=tol_curve)[0]
                    break
            else:
                if lonlat_near is None:  # line mode
                    cmd_clutch, _, distance = pursuit_law(
                        ex,
                        ey,
                        eh_pred,
                        ax,
                        ay,
                        bx,
                        by,
                        along,
                        length,
                        lookahead_m=guid.lookahead_m,
                        tolerance_deg=tol_line,
                    )
                else:
                    lon, lat = lonlat_near(target, ex, ey)
                    cmd_clutch, _, distance = waypoint_law(
                        lon,
                        lat,
                        math.degrees(eh_pred),
                        wp_lons[target],
                        wp_lats[target],
                        tolerance_deg=tol_wp,
                    )
                if along < length and distance > accept_m:
                    clutch = cmd_clutch
                    break
            reached[target] = t
            est_wp_err[target] = math.hypot(ex - bx, ey - by)
            target += 1
            if on_waypoint is not None:
                on_waypoint(target, n_wp)
            if target == n_wp:
                completed = True
                break

        log_t.append(t)
        log_tx.append(tx_m)
        log_ty.append(ty_m)
        log_th.append(th_rad)
        log_ex.append(ex)
        log_ey.append(ey)
        log_eh.append(eh)
        log_cl.append(t_clutch)
        # A line's end is reached 1 m early, the paper's way; the turn after it is followed
        # from its start, so the tractor drives on to the line's end: until it gets there,
        # the leg it drives is still the line.
        if target < n_wp and on_curve[target] and along < 0.0 and not on_curve[target - 1]:
            log_tg.append(target - 1)
        else:
            log_tg.append(min(target, n_wp - 1))
        if completed or k == n_steps:
            break

        # Act: the servo engages the clutch commanded ``delay_steps`` steps ago.
        servo += (clutch,)
        engaged = servo[0]
        servo = servo[1:]
        slip = 1.0 + speed_noise * rng.standard_normal() if speed_noise else 1.0
        tx_m, ty_m, th_rad = step_pose(
            tx_m,
            ty_m,
            th_rad,
            engaged,
            dt_s,
            speed_mps=speed * slip,
            track_width_m=track,
            yaw_rate_rad_s=omega_turn * slip,
            pivot_m=pivot,
        )
        t_clutch = engaged
        th_rad = disturb_heading(th_rad, rng, dt_s, yaw_noise_deg_per_sqrt_s=yaw_noise)
        ex, ey, eh = kf.propagate(*u_by_clutch[engaged], dt_s)

    time_arr = np.array(log_t)
    tx = np.array(log_tx)
    ty = np.array(log_ty)
    ex_a = np.array(log_ex)
    ey_a = np.array(log_ey)
    g_t = np.array(gps_t)
    g_x = np.array(gps_x)
    g_y = np.array(gps_y)
    lon_true, lat_true = frame.to_lonlat_xy(tx, ty)
    metrics = score_track(
        plan,
        time_arr,
        lon_true,
        lat_true,
        threshold_m=threshold_m,
        completed=completed,
        leg=np.array(log_tg, dtype=np.int64),
    )
    # The true position at each fix time (fixes fall on control steps).
    fix_step = np.clip(np.rint(g_t / dt_s).astype(np.int64), 0, len(tx) - 1)
    est_max = est_mean = line_est_max = None
    if np.isfinite(est_wp_err).any():
        finite = est_wp_err[np.isfinite(est_wp_err)]
        est_max, est_mean = float(finite.max()), float(finite.mean())
        on_lines = est_wp_err[line_waypoints(plan) & np.isfinite(est_wp_err)]
        line_est_max = float(on_lines.max()) if len(on_lines) else None
    nees = normalised_squares(nees_err, nees_cov)
    nis = normalised_squares(nis_y, nis_s)
    nis_dof = [len(y) for y in nis_y]
    nees_mean = float(np.mean(nees)) if len(nees) else None
    nis_mean = float(np.mean(nis)) if len(nis) else None
    # NEES samples of one run are correlated in time (the wander lasts a minute), so one run
    # counts as one sample of its time average: the bounds are those of one 2-dof χ² draw.
    # Innovations of a consistent filter are white, so every update counts for the NIS.
    nees_bounds = chi2_mean_bounds(2, 1)
    nis_bounds = chi2_mean_bounds(round(np.mean(nis_dof)), len(nis)) if len(nis) else None
    metrics = dataclasses.replace(
        metrics,
        filter_rms_m=float(np.sqrt(np.mean((ex_a - tx) ** 2 + (ey_a - ty) ** 2))),
        gps_rms_m=float(np.sqrt(np.mean((g_x - tx[fix_step]) ** 2 + (g_y - ty[fix_step]) ** 2))),
        waypoint_error_estimate_max_m=est_max,
        waypoint_error_estimate_mean_m=est_mean,
        line_waypoint_error_estimate_max_m=line_est_max,
        waypoint_errors_estimate_m=optional_tuple(est_wp_err),
        nees_mean=nees_mean,
        nees_dof=2,
        nees_bounds_95=nees_bounds,
        nees_within_bounds=None
        if nees_mean is None
        else bool(nees_bounds[0] <= nees_mean <= nees_bounds[1]),
        nis_mean=nis_mean,
        nis_dof=round(np.mean(nis_dof)) if nis_dof else None,
        nis_bounds_95=nis_bounds,
        nis_within_bounds=None
        if nis_mean is None or nis_bounds is None
        else bool(nis_bounds[0] <= nis_mean <= nis_bounds[1]),
        compass_bias_estimate_deg=math.degrees(float(kf.ekf.x[3])) if augmented else None,
        compass_bias_true_deg=comp.bias_deg,
    )
    return SimulationLog(
        plan=plan,
        config=config,
        frame=frame,
        completed=completed,
        time_s=time_arr,
        true_x_m=tx,
        true_y_m=ty,
        true_heading_rad=np.array(log_th),
        est_x_m=ex_a,
        est_y_m=ey_a,
        est_heading_rad=np.array(log_eh),
        clutch=np.array(log_cl, dtype=np.int8),
        target=np.array(log_tg, dtype=np.int64),
        gps_time_s=g_t,
        gps_x_m=g_x,
        gps_y_m=g_y,
        reached_s=reached,
        declination_deg=declination,
        metrics=metrics,
    )


__all__ = ["SimulationLog", "simulate", "validate_config"]
