"""Corner loops: how a pivoting vehicle tills the corner of a round (the ``spiral`` pattern).

A hand tractor turns a round's corner by pivoting about its inner, braked wheel: its axle
centre follows an arc of half the track, and its implement sweeps a quarter disc round that
wheel, so the square corner of the round's band is left (about 1.2 m² a corner of a 4 m
footprint). Turning the other way instead, a pivot about the *outer* wheel by 360° − θ (a
loop), brings the implement over the corner: the loop's footprint is a disc of the
implement's half-width plus the radius round a point just beyond the corner, which holds the
whole square corner of the band up to a right angle.

The loop begins ``r · tan(θ/2)`` past the corner ``M`` of the two legs (where their lines
meet) and ends ``r · tan(θ/2)`` before it on the way out, so it joins both legs tangentially:
with ``t0``, ``t1`` the legs' directions and ``n0`` the left normal of ``t0``, it starts at
``P = M + r tan(θ/2) t0``, circles ``W = P − r n0`` clockwise by ``2π − θ`` and ends at
``Q = M − r tan(θ/2) t1``. A loop is taken only where it keeps the body inside (``allowed``).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import shapely
from shapely import LineString

FloatArray = npt.NDArray[np.float64]

#: Corners turning less than this are left as arcs: the band's corner is small there, and a
#: loop costs a nearly full pivot [rad].
MIN_CORNER_RAD = math.radians(60.0)
#: Corners turning more than this are left as arcs too: the loop's legs reach ``r·tan(θ/2)``
#: past the corner, without bound as θ nears 180° (both ends of a finger 2 r wide count as
#: one turn of about 180°), and its disc holds less of an acute corner [rad].
MAX_CORNER_RAD = math.radians(135.0)
#: A point of the round turns left by more than this when it lies on a corner's arc [rad].
_TURNING_RAD = 0.02
#: A corner's arc is at most this many times the length of an arc of the radius.
_ARC_SPREAD = 2.0


def corner_loops(
    points: FloatArray, *, radius_m: float, allowed: shapely.Geometry, step_m: float
) -> FloatArray:
    """Return a closed round's points with a loop at each sharp left corner that fits.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        The round as driven (interior on the left), evenly spaced, not closed, local [m]; its
        left corners are arcs of ``radius_m``.
    radius_m : float
        The pivot's radius (half the track, with the planning slack) [m].
    allowed : Geometry
        Where the path may run (the field eroded by the body's half-width), prepared.
    step_m : float
        Most distance between the points of a loop and of the legs it lengthens [m].

    Returns
    -------
    ndarray, shape (m, 2)
        The round's points, not closed; ``points`` itself if no loop fits.

    Examples
    --------
    A 12 m square's round with quarter-circle corners of 0.36 m gains four loops; each
    makes the round about 2.57 m longer: a 270° arc instead of a 90° one, and each leg two
    radii longer (``r (3π/2 − π/2) + 4 r``; the arcs are polygons, a little shorter).

    >>> from planner.round_shapes import resample_ring
    >>> square = shapely.box(0, 0, 12, 12).buffer(-0.36).buffer(0.36, quad_segs=32)
    >>> ring = resample_ring(shapely.orient_polygons(square).exterior, 0.15)
    >>> looped = corner_loops(ring, radius_m=0.36, allowed=shapely.box(-2, -2, 14, 14), step_m=0.15)
    >>> length = lambda p: float(np.hypot(*np.diff(np.vstack([p, p[:1]]), axis=0).T).sum())
    >>> round((length(looped) - length(ring)) / 4, 2), round(0.36 * (math.pi + 4), 2)
    (2.56, 2.57)
    """
    n = len(points)
    if n < 6:
        return points
    heading = _headings(points)  # of the edge from each point to the next
    turn = (np.roll(heading, -1) - heading + math.pi) % (2.0 * math.pi) - math.pi
    # turn[i]: at point i + 1, from edge i to edge i + 1. Runs of left turns are corners.
    turning = turn > _TURNING_RAD
    if turning.all() or not turning.any():
        return points
    shift = int(np.argmin(turning))  # start on a straight edge: no run wraps round
    order = np.roll(np.arange(n), -shift)
    pieces: list[FloatArray] = []
    kept_from = 0  # index into ``order`` of the first point not yet emitted
    k = 0
    while k < n:
        if not turning[order[k]]:
            k += 1
            continue
        first = k  # edges order[first] … order[last] turn into their next
        while k < n and turning[order[k]]:
            k += 1
        last = k - 1
        loop = _loop(points, order, first, last, radius_m, step_m)
        if loop is None or not shapely.covers(allowed, LineString(loop)):
            continue
        # Points order[kept_from … first] lead in; the loop replaces those before order[last + 1].
        pieces.append(points[order[kept_from : first + 1]])
        pieces.append(loop[1:-1])
        kept_from = last + 1
    if not pieces:
        return points
    if kept_from < n:
        pieces.append(points[order[kept_from:]])
    return np.vstack(pieces)


def _headings(points: FloatArray) -> FloatArray:
    step = np.roll(points, -1, axis=0) - points
    return np.arctan2(step[:, 1], step[:, 0])


def _loop(
    points: FloatArray, order: npt.NDArray[np.int64], first: int, last: int, r: float, step: float
) -> FloatArray | None:
    """Return the path from the last point before a corner to the first after it, by a loop.

    ``order[first]`` … ``order[last]`` are the edges that turn into their next: the corner
    is replaced from point ``order[first]`` (the start of the last edge in) to point
    ``order[last + 1]`` (the start of the first edge out), indices taken round the ring.
    None if it is no sharp, tight corner.
    """
    n = len(points)
    a = points[order[first]]
    b = points[order[(last + 1) % n]]
    t0 = points[order[(first + 1) % n]] - a  # the leg in: the edge from ``a``
    t1 = points[order[(last + 2) % n]] - b
    t0, t1 = t0 / np.hypot(*t0), t1 / np.hypot(*t1)
    theta = math.atan2(t0[0] * t1[1] - t0[1] * t1[0], float(t0 @ t1))
    if not MIN_CORNER_RAD <= theta <= MAX_CORNER_RAD:
        return None
    arc = float(np.hypot(*np.diff(points[order[np.arange(first, last + 2) % n]], axis=0).T).sum())
    if arc > _ARC_SPREAD * r * theta + 2.0 * step:
        return None  # a long bend, not a corner of the radius
    # The corner M where the legs' lines meet: a + s t0 = b − u t1 (sin θ ≥ 0.7 here).
    cross = t0[0] * t1[1] - t0[1] * t1[0]
    s = ((b - a)[0] * t1[1] - (b - a)[1] * t1[0]) / cross
    reach = r * math.tan(theta / 2.0)
    # M lies about an arc's reach ahead of ``a``: farther, and the arc was no corner of ours.
    if not 0.0 < s <= 2.0 * reach + 2.0 * step:
        return None
    corner = a + s * t0
    start = corner + reach * t0
    end = corner - reach * t1
    if float((b - end) @ t1) <= 0.0:
        return None
    n0 = np.array([-t0[1], t0[0]])
    centre = start - r * n0
    sweep = 2.0 * math.pi - theta
    count = max(8, math.ceil(r * sweep / step))
    phase = math.atan2(n0[1], n0[0]) - np.linspace(0.0, sweep, count + 1)  # clockwise
    circle = centre + r * np.stack([np.cos(phase), np.sin(phase)], axis=1)
    circle[-1] = end  # the same point, to the last bit: the leg out begins there
    lead_in = _straight(a, start, step)
    lead_out = _straight(end, b, step)
    return np.vstack([lead_in, circle[1:], lead_out[1:]])


def _straight(a: FloatArray, b: FloatArray, step: float) -> FloatArray:
    """Points from ``a`` to ``b`` at most ``step`` apart, both included."""
    count = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
    return a + (b - a) * np.linspace(0.0, 1.0, count + 1)[:, None]
