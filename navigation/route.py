"""The plan as a route of straight pieces in driving order, and which piece a track is driving.

Cross-track error means the distance to the line *being driven*, not to whichever line is
nearest: measured to the nearest line it can never exceed half the interval, however far the
tractor strays onto its neighbour. So every position is matched to a piece of the route first:

- :func:`match_by_leg`: the simulator knows the waypoint it is steering to, so a position is
  matched to the nearest piece between the previous waypoint and that one (the leg).
- :func:`match_monotone`: a recorded track carries no intent, so it is inferred. The track is
  resampled every few decimetres of travel and matched to the route by dynamic programming:
  the piece index never decreases along the track (a tractor drives its route in order, and
  may skip parts of it), and each sample costs its distance to the piece plus a penalty for
  driving against the piece's direction (``2 × interval`` for the opposite direction). A
  tractor that drifts onto the neighbouring line keeps its own line, because that line's
  direction and everything after it fit only that way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from navigation.types import NavigationError
from planner.projection import LocalFrame, field_frame
from planner.types import CoveragePlan

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Piece kinds.
LINE, TURN, TRANSIT, HEADLAND = 0, 1, 2, 3
_KIND_CODES = {"line": LINE, "turn": TURN, "transit": TRANSIT, "headland": HEADLAND}

#: Resampling of a recorded track for :func:`match_monotone`: at most this many samples, and
#: at most this many (sample × piece) cells in the dynamic programme (memory and time).
MAX_MATCH_SAMPLES = 6000
MAX_MATCH_CELLS = 24_000_000
#: Most pieces between two samples a fix is refined over.
MAX_REFINE_SPAN = 64
#: Fixes processed at a time where each fix is scored on its own (bounded temporaries).
CHUNK_FIXES = 65_536


@dataclass(frozen=True, slots=True)
class Route:
    """The plan's path cut into straight pieces, in driving order, in a local frame.

    Attributes
    ----------
    frame : LocalFrame
        The field's frame (x east, y true north, metres).
    ax, ay, bx, by : arrays
        Piece ends [m].
    kind : int array
        ``LINE`` (0), ``TURN`` (1), ``TRANSIT`` (2) or ``HEADLAND`` (3; rounds too).
    line : int array
        Tillage line index of ``LINE`` pieces, -1 for the others.
    waypoint_piece : int array
        For each waypoint, the index of the first piece that starts at it (the number of
        pieces for the last waypoint): the pieces of leg ``k`` (waypoint ``k-1`` to ``k``) are
        ``waypoint_piece[k-1] : waypoint_piece[k]``.
    waypoint_x, waypoint_y : arrays
        The waypoints [m].
    spacing_m : float
        The plan's interval [m].
    """

    frame: LocalFrame
    ax: FloatArray
    ay: FloatArray
    bx: FloatArray
    by: FloatArray
    kind: IntArray
    line: IntArray
    waypoint_piece: IntArray
    waypoint_x: FloatArray
    waypoint_y: FloatArray
    spacing_m: float

    @property
    def is_line(self) -> npt.NDArray[np.bool_]:
        """Pieces on tillage lines."""
        return np.asarray(self.kind == LINE)

    @property
    def lengths_m(self) -> FloatArray:
        """Length of each piece [m]."""
        return np.asarray(np.hypot(self.bx - self.ax, self.by - self.ay))

    def leg_pieces(self, leg: int) -> tuple[int, int]:
        """Piece range ``[lo, hi)`` of leg ``leg`` (waypoint ``leg-1`` to ``leg``), never empty."""
        n = len(self.ax)
        lo = int(self.waypoint_piece[max(leg - 1, 0)])
        hi = int(self.waypoint_piece[min(leg, len(self.waypoint_piece) - 1)])
        lo = min(lo, n - 1)
        return lo, max(hi, lo + 1)


def build_route(plan: CoveragePlan, frame: LocalFrame | None = None) -> Route:
    """Cut ``plan``'s segments (or, without segments, its waypoint legs) into pieces.

    Without segments, a leg is a tillage line when it runs from a ``line_start`` to a
    ``line_end`` waypoint of the same line, a transit leg when it touches the start or the
    finish, else a turn.

    Raises
    ------
    NavigationError
        If the plan has fewer than two distinct points.
    """
    frame = frame or field_frame(plan.field_lonlat)
    wps = plan.waypoints
    if not wps:
        raise NavigationError("plan", "has no waypoints")
    polylines: list[tuple[list[tuple[float, float]], int, int]] = []
    if plan.segments:
        for seg in plan.segments:
            kind = _KIND_CODES.get(seg.kind, HEADLAND)
            line = seg.index if kind == LINE and seg.index is not None else -1
            polylines.append((list(seg.lonlat), kind, line))
    else:
        for a, b in zip(wps[:-1], wps[1:], strict=True):
            is_line = (
                a.role == "line_start"
                and b.role == "line_end"
                and a.line is not None
                and a.line == b.line
            )
            if is_line:
                kind = LINE
            elif a.role == "start" or b.role == "finish":
                kind = TRANSIT
            else:
                kind = TURN
            line = a.line if is_line and a.line is not None else -1
            polylines.append(([(a.lon, a.lat), (b.lon, b.lat)], kind, line))
    pieces: list[tuple[float, float, float, float, int, int]] = []
    for coords, kind, line in polylines:
        if len(coords) < 2:
            continue
        lon, lat = zip(*coords, strict=True)
        x, y = frame.to_local_xy(lon, lat)
        for i in range(len(x) - 1):
            if x[i] != x[i + 1] or y[i] != y[i + 1]:
                pieces.append((x[i], y[i], x[i + 1], y[i + 1], kind, line))
    if not pieces:
        raise NavigationError("plan", "has no path to follow (fewer than two distinct points)")
    arr = np.array(pieces, dtype=float)
    wx, wy = frame.to_local_xy([w.lon for w in wps], [w.lat for w in wps])
    wx = np.asarray(wx, dtype=float)
    wy = np.asarray(wy, dtype=float)
    return Route(
        frame=frame,
        ax=arr[:, 0],
        ay=arr[:, 1],
        bx=arr[:, 2],
        by=arr[:, 3],
        kind=arr[:, 4].astype(np.int64),
        line=arr[:, 5].astype(np.int64),
        waypoint_piece=_waypoint_pieces(arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3], wx, wy),
        waypoint_x=wx,
        waypoint_y=wy,
        spacing_m=float(plan.interval_m),
    )


def _waypoint_pieces(
    ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray, wx: FloatArray, wy: FloatArray
) -> IntArray:
    """Locate each waypoint, in order, on the route's vertices (the first within 1 cm)."""
    vx = np.append(ax, bx[-1])
    vy = np.append(ay, by[-1])
    out = np.zeros(len(wx), dtype=np.int64)
    pointer = 0
    for k in range(len(wx)):
        d = np.hypot(vx[pointer:] - wx[k], vy[pointer:] - wy[k])
        close = np.flatnonzero(d < 0.01)
        pointer += int(close[0]) if len(close) else int(np.argmin(d))
        out[k] = pointer
    return out


def point_segment(
    px: FloatArray, py: FloatArray, ax: FloatArray, ay: FloatArray, bx: FloatArray, by: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Distance from points to segments (broadcast) and the unclamped projection parameter."""
    dx = bx - ax
    dy = by - ay
    len2 = np.maximum(dx * dx + dy * dy, 1e-18)
    t = ((px - ax) * dx + (py - ay) * dy) / len2
    tc = np.clip(t, 0.0, 1.0)
    return np.hypot(px - (ax + tc * dx), py - (ay + tc * dy)), t


def distance_along(x_m: FloatArray, y_m: FloatArray) -> FloatArray:
    """Distance travelled from the first position to each [m] (in blocks: one array's memory).

    Examples
    --------
    >>> distance_along(np.array([0.0, 3.0, 3.0]), np.array([0.0, 4.0, 5.0])).tolist()
    [0.0, 5.0, 6.0]
    """
    n = len(x_m)
    s = np.zeros(n)
    done = 0.0
    for start in range(0, max(n - 1, 0), CHUNK_FIXES):
        stop = min(start + CHUNK_FIXES, n - 1)
        part = np.hypot(np.diff(x_m[start : stop + 1]), np.diff(y_m[start : stop + 1]))
        np.cumsum(part, out=s[start + 1 : stop + 1])
        s[start + 1 : stop + 1] += done
        done = float(s[stop])
    return s


def match_by_leg(route: Route, x_m: FloatArray, y_m: FloatArray, leg: IntArray) -> IntArray:
    """Match each position to the nearest piece of the leg being driven.

    Parameters
    ----------
    route : Route
    x_m, y_m : arrays
        Positions, local frame [m].
    leg : int array
        For each position, the waypoint being steered to (leg ``k`` runs from waypoint
        ``k-1`` to ``k``).

    Returns
    -------
    int array
        The piece of each position.
    """
    n = len(x_m)
    out = np.zeros(n, dtype=np.int64)
    if n == 0:
        return out
    # Positions steering to the same waypoint come in runs: one broadcast per run.
    bounds = np.flatnonzero(np.diff(leg)) + 1
    starts = np.concatenate([[0], bounds])
    ends = np.concatenate([bounds, [n]])
    for s, e in zip(starts, ends, strict=True):
        lo, hi = route.leg_pieces(int(leg[s]))
        if hi - lo == 1:
            out[s:e] = lo
            continue
        d, _ = point_segment(
            x_m[s:e, None],
            y_m[s:e, None],
            route.ax[None, lo:hi],
            route.ay[None, lo:hi],
            route.bx[None, lo:hi],
            route.by[None, lo:hi],
        )
        out[s:e] = lo + np.argmin(d, axis=1)
    return out


def match_monotone(route: Route, x_m: FloatArray, y_m: FloatArray) -> IntArray:
    """Infer the piece each position of a recorded track was driving (see the module doc).

    Parameters
    ----------
    route : Route
    x_m, y_m : arrays
        The track in time order, local frame [m].

    Returns
    -------
    int array
        The piece of each position, never decreasing along the track.
    """
    n = len(x_m)
    m = len(route.ax)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    s = distance_along(x_m, y_m)
    total = float(s[-1])
    max_samples = max(2, min(MAX_MATCH_SAMPLES, MAX_MATCH_CELLS // max(m, 1)))
    spacing = max(route.spacing_m / 4.0, total / max_samples, 0.05)
    n_samples = max(int(total / spacing) + 1, 1)
    grid = np.linspace(0.0, total, n_samples) if total > 0 else np.zeros(1)
    # np.interp needs increasing abscissae: drop the fixes that did not move.
    moved = np.concatenate([[True], np.diff(s) > 0])
    if moved.all():
        s_moved, x_moved, y_moved = s, x_m, y_m
    else:
        s_moved, x_moved, y_moved = s[moved], x_m[moved], y_m[moved]
    del moved
    sx = np.interp(grid, s_moved, x_moved)
    sy = np.interp(grid, s_moved, y_moved)
    # Direction of travel over ±2 m (or ± one sample), NaN where the track did not move.
    half = max(2.0, spacing)
    ahead = np.minimum(grid + half, total)
    behind = np.maximum(grid - half, 0.0)
    hx = np.interp(ahead, s_moved, x_moved) - np.interp(behind, s_moved, x_moved)
    hy = np.interp(ahead, s_moved, y_moved) - np.interp(behind, s_moved, y_moved)
    del s_moved, x_moved, y_moved
    hn = np.hypot(hx, hy)
    ux = np.where(hn > 0, hx / np.maximum(hn, 1e-12), 0.0)
    uy = np.where(hn > 0, hy / np.maximum(hn, 1e-12), 0.0)
    lengths = np.maximum(route.lengths_m, 1e-12)
    px = (route.bx - route.ax) / lengths
    py = (route.by - route.ay) / lengths
    weight = 2.0 * route.spacing_m

    path = _monotone_path(route, sx, sy, ux, uy, px, py, weight)
    if total == 0:
        return np.full(n, path[0], dtype=np.int64)
    # Each fix lies between two samples: it takes the nearest of the pieces between theirs
    # (samples are up to a few metres apart on a long track, turns may be shorter).
    step_s = grid[1] - grid[0] if len(grid) > 1 else 1.0
    out = np.empty(n, dtype=np.int64)
    # In blocks of fixes: the temporaries of a day's log at once would take ~15 × 8 bytes a fix.
    for start in range(0, n, CHUNK_FIXES):
        stop = min(start + CHUNK_FIXES, n)
        out[start:stop] = _refine(
            route, x_m[start:stop], y_m[start:stop], s[start:stop], step_s, path
        )
    return out


def _refine(
    route: Route,
    x_m: FloatArray,
    y_m: FloatArray,
    s: FloatArray,
    step_s: float,
    path: IntArray,
) -> IntArray:
    """Match fixes to the nearest of the pieces between those of the samples around them."""
    before = np.clip(np.floor(s / step_s).astype(np.int64), 0, len(path) - 1)
    after = np.clip(before + 1, 0, len(path) - 1)
    lo = path[before]
    hi = path[after]
    best_piece = lo.copy()
    best_d, _ = point_segment(x_m, y_m, route.ax[lo], route.ay[lo], route.bx[lo], route.by[lo])
    span = int(min((hi - lo).max(initial=0), MAX_REFINE_SPAN))
    for offset in range(1, span + 1):
        cand = np.minimum(lo + offset, hi)
        d, _ = point_segment(
            x_m, y_m, route.ax[cand], route.ay[cand], route.bx[cand], route.by[cand]
        )
        better = d < best_d
        best_piece = np.where(better, cand, best_piece)
        best_d = np.where(better, d, best_d)
    return np.asarray(best_piece, dtype=np.int64)


def _monotone_path(
    route: Route,
    sx: FloatArray,
    sy: FloatArray,
    ux: FloatArray,
    uy: FloatArray,
    px: FloatArray,
    py: FloatArray,
    weight: float,
) -> IntArray:
    """Least-cost non-decreasing piece sequence for the samples (dynamic programming)."""
    n = len(sx)
    m = len(route.ax)
    pointer_type = np.int16 if m < 2**15 else np.int32
    back = np.zeros((n, m), dtype=pointer_type)
    best = np.zeros(m)
    columns = np.arange(m)
    block = max(1, 2_000_000 // max(m, 1))
    for lo in range(0, n, block):
        hi = min(lo + block, n)
        d, _ = point_segment(
            sx[lo:hi, None],
            sy[lo:hi, None],
            route.ax[None, :],
            route.ay[None, :],
            route.bx[None, :],
            route.by[None, :],
        )
        cos = ux[lo:hi, None] * px[None, :] + uy[lo:hi, None] * py[None, :]
        cost = d + weight * 0.5 * (1.0 - cos)
        for i in range(lo, hi):
            if i == 0:
                best = cost[0].copy()
                back[0] = columns
                continue
            prefix = np.minimum.accumulate(best)
            # The last column where the prefix minimum was attained is its argmin.
            arg = np.maximum.accumulate(np.where(best == prefix, columns, 0))
            back[i] = arg
            best = cost[i - lo] + prefix
    path = np.zeros(n, dtype=np.int64)
    j = int(np.argmin(best))
    for i in range(n - 1, -1, -1):
        path[i] = j
        j = int(back[i, j])
    return path
