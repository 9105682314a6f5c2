"""Score any track against a plan: simulated, uploaded from a logger or streamed live.

:func:`score_track` takes timestamps and WGS84 positions (nothing simulation-specific) and
returns :class:`TrackMetrics`: whether the route was completed, its time and distance, the
cross-track error to the line being driven (on tillage lines and on turns separately, with the
stretches over a threshold), each waypoint's closest approach, and the coverage ratio of the
track's implement footprint. The simulator adds what only it knows (the filter's errors and
consistency, the waypoint error as the filter saw it).

How the figures are defined
---------------------------
- Every position is first matched to the piece of the route being driven
  (:mod:`navigation.route`): the simulator passes the waypoint it steered to; a recorded track
  is matched in route order. The cross-track error is the distance to that piece, so a tractor
  that strays onto the neighbouring line has an error of about one interval there, not zero.
- A position is *on a tillage line* when its piece is a tillage line and it projects inside it
  (not past its ends). *On a turn* likewise for turn pieces.
- A waypoint's error is its distance to the nearest point of the track polyline. With
  ``live=True`` only the waypoints the track has reached (matched in route order) have one;
  the others are None, and ``coverage_of_driven_ratio`` compares the footprint with what the
  plan's driven part would till.
- Coverage: :mod:`navigation.coverage`, with the implement width.

Everything is vectorised, so a day's 10 Hz log (hundreds of thousands of fixes) scores in
about a second.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree  # type: ignore[import-untyped]

from navigation.coverage import coverage_ratio, implement_width_m
from navigation.coverage import polygon_mask as _polygon_mask
from navigation.route import (
    CHUNK_FIXES,
    LINE,
    TURN,
    Route,
    build_route,
    match_by_leg,
    match_monotone,
    point_segment,
)
from navigation.types import NavigationError
from planner.projection import LocalFrame
from planner.types import CoveragePlan

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

__all__ = [
    "Stretch",
    "TrackMetrics",
    "coverage_ratio",
    "cross_track_errors",
    "score_track",
    "waypoint_errors",
    "_polygon_mask",
]


@dataclass(frozen=True, slots=True)
class Stretch:
    """A run of consecutive on-line fixes whose cross-track error exceeded the threshold.

    Attributes
    ----------
    start_s, end_s : float
        Time of the first and last fix of the run, from the track's start [s].
    duration_s : float
        ``end_s - start_s`` [s].
    max_error_m : float
        Largest cross-track error in the run [m].
    line : int
        Index of the tillage line of the worst fix.
    """

    start_s: float
    end_s: float
    duration_s: float
    max_error_m: float
    line: int


@dataclass(frozen=True, slots=True)
class TrackMetrics:
    """How well a track followed a plan (product.md §7 and §8).

    Attributes
    ----------
    completed : bool
        The route was driven to its end (see :func:`score_track`).
    time_s : float
        Duration of the track [s].
    distance_m : float
        Length of the track [m].
    fix_count : int
        Number of positions scored.
    on_line_share : float
        Share of fixes on tillage lines.
    cross_track_max_m, cross_track_rms_m, cross_track_p95_m : float or None
        Distance to the tillage line being driven [m]; None if no fix was on a line.
    turn_cross_track_max_m, turn_cross_track_rms_m : float or None
        Distance to the turn being driven, for fixes on turns [m].
    waypoint_error_max_m, waypoint_error_mean_m : float or None
        Closest approach of the track to each (reached) waypoint: largest and mean [m].
    line_waypoint_error_max_m : float or None
        The same, largest over the line ends only (the paper's 8-waypoint block).
    waypoint_errors_m : tuple of (float or None)
        Closest approach per waypoint, in route order [m]; None where not reached (live).
    waypoints_reached : int
        Waypoints the track has reached in route order.
    plan_progress : float
        Share of the route's length up to the piece the track reached last.
    coverage_ratio : float
        Field area inside the track's implement footprint over field area.
    coverage_of_driven_ratio : float or None
        Live runs: the footprint over what the plan's driven part would till.
    implement_width_m : float
        Width of the footprint [m].
    threshold_m : float
        Cross-track error above which a stretch is reported [m].
    stretches : tuple of Stretch
        Runs on tillage lines with the error above ``threshold_m``.
    filter_rms_m, gps_rms_m : float or None
        Simulation only: RMS distance of the filter's estimate and of the raw GPS fixes from
        the true position [m].
    waypoint_error_estimate_max_m, waypoint_error_estimate_mean_m : float or None
        Simulation only: the paper's measure — distance from the filter's estimate to the
        waypoint at the moment the tractor switched to the next one [m].
    line_waypoint_error_estimate_max_m : float or None
        The same, largest over the line ends [m].
    waypoint_errors_estimate_m : tuple of (float or None) or None
        Per waypoint [m].
    nees_mean, nis_mean : float or None
        Simulation only: mean normalised estimation error squared of the position (2 degrees
        of freedom) and mean normalised innovation squared of the GPS/compass updates.
    nees_dof, nis_dof : int or None
        Their degrees of freedom.
    nees_bounds_95, nis_bounds_95 : tuple of float or None
        Two-sided 95 % χ² bounds of the means (:mod:`navigation.consistency`).
    nees_within_bounds, nis_within_bounds : bool or None
        Whether the mean lies within its bounds.
    compass_bias_estimate_deg, compass_bias_true_deg : float or None
        Simulation only: the filter's final compass-bias estimate and the simulated bias [deg].
    """

    completed: bool
    time_s: float
    distance_m: float
    fix_count: int
    on_line_share: float
    cross_track_max_m: float | None
    cross_track_rms_m: float | None
    cross_track_p95_m: float | None
    turn_cross_track_max_m: float | None
    turn_cross_track_rms_m: float | None
    waypoint_error_max_m: float | None
    waypoint_error_mean_m: float | None
    line_waypoint_error_max_m: float | None
    waypoint_errors_m: tuple[float | None, ...]
    waypoints_reached: int
    plan_progress: float
    coverage_ratio: float
    coverage_of_driven_ratio: float | None
    implement_width_m: float
    threshold_m: float
    stretches: tuple[Stretch, ...]
    filter_rms_m: float | None = None
    gps_rms_m: float | None = None
    waypoint_error_estimate_max_m: float | None = None
    waypoint_error_estimate_mean_m: float | None = None
    line_waypoint_error_estimate_max_m: float | None = None
    waypoint_errors_estimate_m: tuple[float | None, ...] | None = None
    nees_mean: float | None = None
    nees_dof: int | None = None
    nees_bounds_95: tuple[float, float] | None = None
    nees_within_bounds: bool | None = None
    nis_mean: float | None = None
    nis_dof: int | None = None
    nis_bounds_95: tuple[float, float] | None = None
    nis_within_bounds: bool | None = None
    compass_bias_estimate_deg: float | None = None
    compass_bias_true_deg: float | None = None

    def as_dict(self) -> dict[str, Any]:
        """Return the metrics as plain JSON-ready values, stretches as dicts."""
        return asdict(self)


def to_local_xy(
    frame: LocalFrame, lon: FloatArray, lat: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Project a track to the local frame [m], :data:`CHUNK_FIXES` fixes at a time."""
    n = len(lon)
    x = np.empty(n)
    y = np.empty(n)
    for start in range(0, n, CHUNK_FIXES):
        part = slice(start, min(start + CHUNK_FIXES, n))
        x[part], y[part] = frame.to_local_xy(lon[part], lat[part])
    return x, y


def path_length_m(x_m: FloatArray, y_m: FloatArray) -> float:
    """Length of the polyline through the positions [m], in blocks (bounded temporaries)."""
    total = 0.0
    for start in range(0, max(len(x_m) - 1, 0), CHUNK_FIXES):
        part = slice(start, min(start + CHUNK_FIXES + 1, len(x_m)))
        total += float(np.hypot(np.diff(x_m[part]), np.diff(y_m[part])).sum())
    return total


def cross_track_errors(
    route: Route, x_m: FloatArray, y_m: FloatArray, piece: IntArray
) -> tuple[FloatArray, FloatArray, IntArray]:
    """Cross-track error of each position to its matched piece.

    Returns
    -------
    line_error_m : array
        Distance to the tillage line driven, NaN where the position is not on a line.
    turn_error_m : array
        Distance to the turn driven, NaN where not on a turn.
    line : int array
        The tillage line's index, -1 where not on a line.
    """
    n = len(x_m)
    line_error = np.empty(n)
    turn_error = np.empty(n)
    lines = np.empty(n, dtype=np.int64)
    lengths = route.lengths_m
    for start in range(0, n, CHUNK_FIXES):  # in blocks: bounded temporaries
        part = slice(start, min(start + CHUNK_FIXES, n))
        p = piece[part]
        d, t = point_segment(
            x_m[part], y_m[part], route.ax[p], route.ay[p], route.bx[p], route.by[p]
        )
        # Inside the piece by more than a millimetre: a fix abeam a line's end is turning.
        margin = 1e-3 / np.maximum(lengths[p], 1e-9)
        inside = (t > margin) & (t < 1.0 - margin)
        kind = route.kind[p]
        on_line = inside & (kind == LINE)
        on_turn = (kind == TURN) & (t >= 0.0) & (t <= 1.0)
        line_error[part] = np.where(on_line, d, np.nan)
        turn_error[part] = np.where(on_turn, d, np.nan)
        lines[part] = np.where(on_line, route.line[p], -1)
    return line_error, turn_error, lines


def waypoint_errors(
    frame: LocalFrame, plan: CoveragePlan, x_m: FloatArray, y_m: FloatArray
) -> FloatArray:
    """Closest approach of the track polyline to each waypoint [m]."""
    wx, wy = frame.to_local_xy([w.lon for w in plan.waypoints], [w.lat for w in plan.waypoints])
    if len(x_m) == 1:
        return np.asarray(np.hypot(wx - x_m[0], wy - y_m[0]))
    k = int(min(16, len(x_m)))
    _, idx = cKDTree(np.column_stack([x_m, y_m])).query(np.column_stack([wx, wy]), k=k, workers=-1)
    idx = np.asarray(idx).reshape(len(wx), k)
    # The segments on either side of each of the k nearest vertices.
    seg = np.concatenate([np.clip(idx - 1, 0, len(x_m) - 2), np.clip(idx, 0, len(x_m) - 2)], 1)
    dist, _ = point_segment(
        wx[:, None], wy[:, None], x_m[seg], y_m[seg], x_m[seg + 1], y_m[seg + 1]
    )
    return np.asarray(dist.min(axis=1))


def line_waypoints(plan: CoveragePlan) -> npt.NDArray[np.bool_]:
    """Which waypoints are line ends (``line_start``/``line_end``)."""
    return np.array([w.role in ("line_start", "line_end") for w in plan.waypoints], dtype=bool)


def _max_mean(values: FloatArray) -> tuple[float | None, float | None]:
    finite = values[np.isfinite(values)]
    if not len(finite):
        return None, None
    return float(finite.max()), float(finite.mean())


def optional_tuple(values: FloatArray) -> tuple[float | None, ...]:
    """Floats, None where NaN."""
    return tuple(float(v) if math.isfinite(v) else None for v in values)


def _route_polyline_upto(
    route: Route, piece: int, x: float, y: float
) -> tuple[FloatArray, FloatArray]:
    """Return the route from its start to the projection of ``(x, y)`` on ``piece``."""
    d, t = point_segment(
        np.array([x]),
        np.array([y]),
        route.ax[piece : piece + 1],
        route.ay[piece : piece + 1],
        route.bx[piece : piece + 1],
        route.by[piece : piece + 1],
    )
    tc = float(np.clip(t[0], 0.0, 1.0))
    end_x = route.ax[piece] + tc * (route.bx[piece] - route.ax[piece])
    end_y = route.ay[piece] + tc * (route.by[piece] - route.ay[piece])
    return (
        np.append(route.ax[: piece + 1], end_x),
        np.append(route.ay[: piece + 1], end_y),
    )


def score_track(
    plan: CoveragePlan,
    time_s: npt.ArrayLike,
    lon: npt.ArrayLike,
    lat: npt.ArrayLike,
    *,
    threshold_m: float = 1.0,
    completion_radius_m: float = 5.0,
    completed: bool | None = None,
    leg: npt.ArrayLike | None = None,
    live: bool = False,
) -> TrackMetrics:
    """Score a track (any source) against ``plan``.

    Parameters
    ----------
    plan : CoveragePlan
        The plan the track was meant to follow.
    time_s : array of float
        Time of each fix [s], non-decreasing (any origin).
    lon, lat : array of float
        Positions, WGS84 [deg].
    threshold_m : float
        Cross-track error above which a stretch is reported [m].
    completion_radius_m : float
        Without ``completed``, the track counts as complete when it came this close to every
        waypoint and ends this close to the last one [m].
    completed : bool or None
        Known completion (the simulator knows); None to judge from the geometry.
    leg : array of int or None
        For each fix, the waypoint being steered to (the simulator knows); None to infer the
        piece being driven from the track (:func:`navigation.route.match_monotone`).
    live : bool
        The run is still going: waypoints not yet reached get no error, and the coverage of
        the driven part of the plan is reported.

    Returns
    -------
    TrackMetrics

    Raises
    ------
    NavigationError
        For an empty track, arrays of different lengths, non-finite values or time running
        backwards, or a plan with nothing to follow.
    """
    t = np.asarray(time_s, dtype=float).ravel()
    lon_a = np.asarray(lon, dtype=float).ravel()
    lat_a = np.asarray(lat, dtype=float).ravel()
    if not (len(t) == len(lon_a) == len(lat_a)):
        raise NavigationError(
            "track", f"time, lon and lat differ in length ({len(t)}, {len(lon_a)}, {len(lat_a)})"
        )
    if len(t) == 0:
        raise NavigationError("track", "has no fixes")
    if not (np.isfinite(t).all() and np.isfinite(lon_a).all() and np.isfinite(lat_a).all()):
        raise NavigationError("track", "has a time or coordinate that is not a finite number")
    if (np.diff(t) < 0).any():
        raise NavigationError("track", "time must not run backwards")
    if not (math.isfinite(threshold_m) and threshold_m > 0):
        raise NavigationError("threshold_m", f"must be > 0, got {threshold_m}")
    if not plan.waypoints:
        raise NavigationError("plan", "has no waypoints")

    route = build_route(plan)
    frame = route.frame
    x, y = to_local_xy(frame, lon_a, lat_a)

    if leg is not None:
        legs = np.asarray(leg, dtype=np.int64).ravel()
        if len(legs) != len(x):
            raise NavigationError("leg", f"has {len(legs)} entries for {len(x)} fixes")
        piece = match_by_leg(route, x, y, legs)
    else:
        piece = match_monotone(route, x, y)
    xte, turn_err, line = cross_track_errors(route, x, y, piece)
    # Progress: the furthest piece driven. A waypoint is reached once the track has been
    # matched to a piece that starts at or after it.
    furthest = int(piece.max())
    del piece  # (arrays of the track's length are dropped once used: a day's log is large)
    on = ~np.isnan(xte)
    on_line_share = float(on.mean())
    xte_max = xte_rms = xte_p95 = None
    if on.any():
        err = xte[on]
        xte_max = float(err.max())
        xte_rms = float(np.sqrt(np.mean(err**2)))
        xte_p95 = float(np.percentile(err, 95))
        del err
    del on
    on_turn = ~np.isnan(turn_err)
    turn_max = turn_rms = None
    if on_turn.any():
        turn_max = float(turn_err[on_turn].max())
        turn_rms = float(np.sqrt(np.mean(turn_err[on_turn] ** 2)))
    del on_turn, turn_err

    wp_err = waypoint_errors(frame, plan, x, y)
    if completed is None:
        end_gap = math.hypot(
            float(route.waypoint_x[-1] - x[-1]), float(route.waypoint_y[-1] - y[-1])
        )
        completed = bool(wp_err.max() <= completion_radius_m and end_gap <= completion_radius_m)
    reached = route.waypoint_piece <= furthest
    # The waypoint that ends the piece driven last counts once the track came near it.
    ahead = route.waypoint_piece == furthest + 1
    reached |= ahead & (wp_err <= completion_radius_m)
    if completed:
        reached[:] = True
    if live:
        wp_err = np.where(reached, wp_err, np.nan)
    wp_max, wp_mean = _max_mean(wp_err)
    line_wp_max, _ = _max_mean(np.where(line_waypoints(plan), wp_err, np.nan))

    lengths = route.lengths_m
    progress = 1.0 if completed else float(lengths[: furthest + 1].sum() / lengths.sum())
    driven = None
    if live:
        reference = _route_polyline_upto(route, furthest, float(x[-1]), float(y[-1]))
        driven = coverage_ratio(frame, plan, x, y, reference=reference)

    return TrackMetrics(
        completed=completed,
        time_s=float(t[-1] - t[0]),
        distance_m=path_length_m(x, y),
        fix_count=len(t),
        on_line_share=on_line_share,
        cross_track_max_m=xte_max,
        cross_track_rms_m=xte_rms,
        cross_track_p95_m=xte_p95,
        turn_cross_track_max_m=turn_max,
        turn_cross_track_rms_m=turn_rms,
        waypoint_error_max_m=wp_max,
        waypoint_error_mean_m=wp_mean,
        line_waypoint_error_max_m=line_wp_max,
        waypoint_errors_m=optional_tuple(wp_err),
        waypoints_reached=int(reached.sum()),
        plan_progress=progress,
        coverage_ratio=coverage_ratio(frame, plan, x, y),
        coverage_of_driven_ratio=driven,
        implement_width_m=implement_width_m(plan),
        threshold_m=threshold_m,
        stretches=_stretches(t - t[0], xte, line, threshold_m),
    )


def _stretches(
    t: FloatArray, xte: FloatArray, line: IntArray, threshold_m: float
) -> tuple[Stretch, ...]:
    over = np.nan_to_num(xte, nan=0.0) > threshold_m
    if not over.any():
        return ()
    # A run also ends where the line changes.
    edges = np.diff(over.astype(np.int8), prepend=0, append=0)
    changes = np.flatnonzero(np.diff(line) != 0) + 1
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1)
    out: list[Stretch] = []
    for a, b in zip(starts, ends, strict=True):
        inner = changes[np.searchsorted(changes, a, "right") : np.searchsorted(changes, b, "left")]
        bounds = [int(a), *inner.tolist(), int(b)]
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=False):
            seg = xte[lo:hi]
            worst = lo + int(np.argmax(seg))
            out.append(
                Stretch(
                    start_s=float(t[lo]),
                    end_s=float(t[hi - 1]),
                    duration_s=float(t[hi - 1] - t[lo]),
                    max_error_m=float(xte[worst]),
                    line=int(line[worst]),
                )
            )
    return tuple(out)
