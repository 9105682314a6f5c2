"""Score any track against a plan: simulated, uploaded from a logger or streamed live.

:func:`score_track` takes timestamps and WGS84 positions (nothing simulation-specific) and
returns :class:`TrackMetrics`: whether the route was completed, its time and distance, the
cross-track error on the tillage lines (max, RMS, 95th percentile, and the stretches where it
exceeded a threshold), each waypoint's closest approach (the paper's "waypoint error", 2.61 m
at most in its field trial), and the coverage ratio of the track's footprint.

Everything is vectorised (numpy, scipy's cKDTree, a raster for the footprint), so that a day's
10 Hz log (hundreds of thousands of fixes) scores in a fraction of a second.

How the figures are defined
---------------------------
- A fix is *on a tillage line* when the nearest piece of the plan is a tillage line and the
  fix projects inside that line (not past its ends, where the tractor is turning). Its
  cross-track error is its distance to that line. A fix more than ``interval_m / 2`` off its
  line is nearer the neighbouring line and is measured against that one, as any track-to-plan
  matcher must without knowing the tractor's intent.
- A waypoint's error is its distance to the nearest point of the track polyline.
- The footprint is the track swept by the implement, ``interval_m`` wide. It is computed on a
  raster (cells of at most ``interval_m / 8``, finer for small fields) as every cell whose
  centre lies within ``interval_m / 2`` of the track: the same as buffering the track with
  round joins, except at the track's two very ends (round here, flat in a buffer with flat
  caps), which usually lie outside the field at the start and finish points.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import shapely
from scipy import ndimage  # type: ignore[import-untyped]
from scipy.spatial import cKDTree  # type: ignore[import-untyped]

from navigation.types import NavigationError
from planner.projection import LocalFrame, field_frame
from planner.types import CoveragePlan

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Raster cells for the footprint: aimed at, and never more than (memory and time).
TARGET_RASTER_CELLS = 250_000
MAX_RASTER_CELLS = 4_000_000
#: Cells are at most this fraction of the interval.
RASTER_CELLS_PER_INTERVAL = 8


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
        Cross-track error on tillage lines [m]; None if no fix was on a line.
    waypoint_error_max_m, waypoint_error_mean_m : float
        Closest approach of the track to each waypoint: largest and mean [m].
    waypoint_errors_m : tuple of float
        Closest approach per waypoint, in route order [m].
    coverage_ratio : float
        Field area inside the track's footprint over field area.
    threshold_m : float
        Cross-track error above which a stretch is reported [m].
    stretches : tuple of Stretch
        Runs on tillage lines with the error above ``threshold_m``.
    filter_rms_m, gps_rms_m : float or None
        Simulation only: RMS distance of the filter's estimate and of the raw GPS fixes from
        the true position [m].
    """

    completed: bool
    time_s: float
    distance_m: float
    fix_count: int
    on_line_share: float
    cross_track_max_m: float | None
    cross_track_rms_m: float | None
    cross_track_p95_m: float | None
    waypoint_error_max_m: float
    waypoint_error_mean_m: float
    waypoint_errors_m: tuple[float, ...]
    coverage_ratio: float
    threshold_m: float
    stretches: tuple[Stretch, ...]
    filter_rms_m: float | None = None
    gps_rms_m: float | None = None

    def as_dict(self) -> dict[str, Any]:
        """Return the metrics as plain JSON-ready values, stretches as dicts."""
        return asdict(self)


@dataclass(frozen=True, slots=True)
class PlanPieces:
    """The plan cut into straight pieces in a local frame, for matching fixes.

    Attributes
    ----------
    frame : LocalFrame
        The field's frame.
    ax, ay, bx, by : arrays
        Piece ends [m].
    is_line : bool array
        The piece belongs to a tillage line.
    line : int array
        Tillage line index, -1 for other pieces.
    spacing_m : float
        Distance between neighbouring tillage lines (the plan's interval) [m].
    """

    frame: LocalFrame
    ax: FloatArray
    ay: FloatArray
    bx: FloatArray
    by: FloatArray
    is_line: npt.NDArray[np.bool_]
    line: IntArray
    spacing_m: float


def plan_pieces(plan: CoveragePlan, frame: LocalFrame | None = None) -> PlanPieces:
    """Cut ``plan``'s segments (or, if it has none, its waypoint legs) into straight pieces.

    Without segments, a leg is a tillage line when it runs from a ``line_start`` to a
    ``line_end`` waypoint of the same line.
    """
    frame = frame or field_frame(plan.field_lonlat)
    polylines: list[tuple[list[tuple[float, float]], int]] = []
    if plan.segments:
        for seg in plan.segments:
            line = seg.index if seg.kind == "line" and seg.index is not None else -1
            polylines.append((list(seg.lonlat), line))
    else:
        wps = plan.waypoints
        for a, b in zip(wps[:-1], wps[1:], strict=True):
            is_line = (
                a.role == "line_start"
                and b.role == "line_end"
                and a.line is not None
                and a.line == b.line
            )
            line = a.line if is_line and a.line is not None else -1
            polylines.append(([(a.lon, a.lat), (b.lon, b.lat)], line))
    pieces: list[tuple[float, float, float, float, int]] = []
    for coords, line in polylines:
        if len(coords) < 2:
            continue
        lon, lat = zip(*coords, strict=True)
        x, y = frame.to_local_xy(lon, lat)
        for i in range(len(x) - 1):
            if x[i] != x[i + 1] or y[i] != y[i + 1]:
                pieces.append((x[i], y[i], x[i + 1], y[i + 1], line))
    if not pieces:
        raise NavigationError("plan", "has no path to follow (fewer than two distinct points)")
    arr = np.array(pieces, dtype=float)
    line_idx = arr[:, 4].astype(np.int64)
    return PlanPieces(
        frame=frame,
        ax=arr[:, 0],
        ay=arr[:, 1],
        bx=arr[:, 2],
        by=arr[:, 3],
        is_line=line_idx >= 0,
        line=line_idx,
        spacing_m=float(plan.interval_m),
    )


def _point_segment(
    px: FloatArray, py: FloatArray, ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Distance from points to segments (broadcast) and the unclamped projection parameter."""
    dx = bx - ax
    dy = by - ay
    len2 = np.maximum(dx * dx + dy * dy, 1e-18)
    t = ((px - ax) * dx + (py - ay) * dy) / len2
    tc = np.clip(t, 0.0, 1.0)
    return np.hypot(px - (ax + tc * dx), py - (ay + tc * dy)), t


#: Fixes whose nearest tillage line is looked for at once (bounds the memory of a long log).
_XTE_BLOCK = 50_000


def cross_track_errors(
    pieces: PlanPieces, x_m: FloatArray, y_m: FloatArray
) -> tuple[FloatArray, IntArray]:
    """Cross-track error of each position on the tillage lines [m] and its line index.

    Returns
    -------
    error_m : array
        Distance to the tillage line, NaN where the position is not on a tillage line.
    line : int array
        That line's index, -1 where not on a line.
    """
    n_pieces = len(pieces.ax)
    lengths = np.hypot(pieces.bx - pieces.ax, pieces.by - pieces.ay)
    # Sample the pieces every ``spacing`` metres; the pieces owning the nearest samples are
    # the candidates, whose exact distances are then compared. The spacing is a quarter of
    # the typical distance between pieces, so the nearest piece is always among them.
    spacing = max(pieces.spacing_m / 4.0, float(lengths.sum()) / 400_000.0)
    counts = np.maximum(np.ceil(lengths / spacing).astype(np.int64), 1) + 1
    owner = np.repeat(np.arange(n_pieces), counts)
    starts = np.cumsum(counts) - counts
    frac = (np.arange(owner.size) - starts[owner]) / (counts[owner] - 1)
    sx = pieces.ax[owner] + frac * (pieces.bx - pieces.ax)[owner]
    sy = pieces.ay[owner] + frac * (pieces.by - pieces.ay)[owner]
    k = int(min(6, owner.size))
    tree = cKDTree(np.column_stack([sx, sy]))
    piece = np.empty(len(x_m), dtype=np.int64)
    d = np.empty(len(x_m))
    tb = np.empty(len(x_m))
    # In blocks of fixes, so that the candidates' arrays (k per fix) stay small for a long log.
    for lo in range(0, len(x_m), _XTE_BLOCK):
        hi = min(lo + _XTE_BLOCK, len(x_m))
        bx, by = x_m[lo:hi], y_m[lo:hi]
        _, idx = tree.query(np.column_stack([bx, by]), k=k, workers=-1)
        cand = owner[idx.reshape(hi - lo, k)]
        dist, t = _point_segment(
            bx[:, None],
            by[:, None],
            pieces.ax[cand],
            pieces.ay[cand],
            pieces.bx[cand],
            pieces.by[cand],
        )
        best = np.argmin(dist, axis=1)
        rows = np.arange(hi - lo)
        piece[lo:hi] = cand[rows, best]
        d[lo:hi] = dist[rows, best]
        tb[lo:hi] = t[rows, best]
    # Inside the line by more than a millimetre: a fix abeam a line's end is turning.
    margin = 1e-3 / np.maximum(lengths[piece], 1e-9)
    on_line = pieces.is_line[piece] & (tb > margin) & (tb < 1.0 - margin)
    return np.where(on_line, d, np.nan), np.where(on_line, pieces.line[piece], -1)


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
    dist, _ = _point_segment(
        wx[:, None], wy[:, None], x_m[seg], y_m[seg], x_m[seg + 1], y_m[seg + 1]
    )
    return np.asarray(dist.min(axis=1))


def coverage_ratio(
    frame: LocalFrame, plan: CoveragePlan, x_m: FloatArray, y_m: FloatArray
) -> float:
    """Share of the field within ``interval_m / 2`` of the track (raster, see module doc)."""
    field = frame.to_local(plan.field_lonlat)
    half = 0.5 * plan.interval_m
    min_x, min_y, max_x, max_y = field.bounds
    min_x -= half
    min_y -= half
    max_x += half
    max_y += half
    area = (max_x - min_x) * (max_y - min_y)
    cell = min(
        plan.interval_m / RASTER_CELLS_PER_INTERVAL,
        max(math.sqrt(area / TARGET_RASTER_CELLS), 0.005),
    )
    cell = max(cell, math.sqrt(area / MAX_RASTER_CELLS))
    nx = int(math.ceil((max_x - min_x) / cell))
    ny = int(math.ceil((max_y - min_y) / cell))
    in_field = _polygon_mask(field, min_x, min_y, cell, nx, ny)
    n_field = int(in_field.sum())
    if n_field == 0:
        return 0.0
    # Densify the track to half a cell, then mark the cells it passes through.
    steps = np.hypot(np.diff(x_m), np.diff(y_m))
    s = np.concatenate([[0.0], np.cumsum(steps)])
    samples = np.linspace(0.0, s[-1], max(int(s[-1] / (0.5 * cell)) + 2, len(x_m)))
    px = np.interp(samples, s, x_m) if s[-1] > 0 else x_m
    py = np.interp(samples, s, y_m) if s[-1] > 0 else y_m
    ix = np.floor((px - min_x) / cell).astype(np.int64)
    iy = np.floor((py - min_y) / cell).astype(np.int64)
    keep = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny)
    if not keep.any():
        return 0.0
    free = np.ones((ny, nx), dtype=bool)
    free[iy[keep], ix[keep]] = False
    dist = ndimage.distance_transform_edt(free, sampling=cell)
    covered = dist <= half
    return float((covered & in_field).sum() / n_field)


def _polygon_mask(
    polygon: shapely.Polygon, min_x: float, min_y: float, cell: float, nx: int, ny: int
) -> npt.NDArray[np.bool_]:
    """Cells of an ``ny × nx`` grid whose centres lie inside ``polygon`` (scanline, even-odd).

    Each row's centre line crosses the polygon's edges (holes included) at sorted x; the
    centres between the first and second crossing, the third and fourth, … are inside.
    """
    rings = [polygon.exterior, *polygon.interiors]
    coords = [np.asarray(r.coords) for r in rings]
    x1 = np.concatenate([c[:-1, 0] for c in coords])
    y1 = np.concatenate([c[:-1, 1] for c in coords])
    x2 = np.concatenate([c[1:, 0] for c in coords])
    y2 = np.concatenate([c[1:, 1] for c in coords])
    cy = min_y + (np.arange(ny) + 0.5) * cell
    row_idx, edge_idx = np.nonzero((y1[None, :] <= cy[:, None]) != (y2[None, :] <= cy[:, None]))
    yr = cy[row_idx]
    xe1, ye1, xe2, ye2 = x1[edge_idx], y1[edge_idx], x2[edge_idx], y2[edge_idx]
    xc = xe1 + (yr - ye1) * (xe2 - xe1) / (ye2 - ye1)
    order = np.lexsort((xc, row_idx))
    rows = row_idx[order]
    # First column whose centre is right of the crossing.
    cols = np.clip(np.ceil((xc[order] - min_x) / cell - 0.5), 0, nx).astype(np.int64)
    diff = np.zeros((ny, nx + 1), dtype=np.int32)
    sign = np.where(np.arange(len(rows)) % 2 == 0, 1, -1)
    np.add.at(diff, (rows, cols), sign)
    return np.cumsum(diff[:, :nx], axis=1) > 0


def score_track(
    plan: CoveragePlan,
    time_s: npt.ArrayLike,
    lon: npt.ArrayLike,
    lat: npt.ArrayLike,
    *,
    threshold_m: float = 1.0,
    completion_radius_m: float = 5.0,
    completed: bool | None = None,
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

    pieces = plan_pieces(plan)
    frame = pieces.frame
    x, y = frame.to_local_xy(lon_a, lat_a)
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)

    xte, line = cross_track_errors(pieces, x, y)
    on = ~np.isnan(xte)
    xte_max: float | None = None
    xte_rms: float | None = None
    xte_p95: float | None = None
    if on.any():
        err = xte[on]
        xte_max = float(err.max())
        xte_rms = float(np.sqrt(np.mean(err**2)))
        xte_p95 = float(np.percentile(err, 95))

    wp_err = waypoint_errors(frame, plan, x, y)
    if completed is None:
        end_gap = math.hypot(
            *np.subtract(
                frame.to_local_xy(plan.waypoints[-1].lon, plan.waypoints[-1].lat), (x[-1], y[-1])
            )
        )
        completed = bool(wp_err.max() <= completion_radius_m and end_gap <= completion_radius_m)

    return TrackMetrics(
        completed=completed,
        time_s=float(t[-1] - t[0]),
        distance_m=float(np.hypot(np.diff(x), np.diff(y)).sum()),
        fix_count=len(t),
        on_line_share=float(on.mean()),
        cross_track_max_m=xte_max,
        cross_track_rms_m=xte_rms,
        cross_track_p95_m=xte_p95,
        waypoint_error_max_m=float(wp_err.max()),
        waypoint_error_mean_m=float(wp_err.mean()),
        waypoint_errors_m=tuple(float(v) for v in wp_err),
        coverage_ratio=coverage_ratio(frame, plan, x, y),
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
