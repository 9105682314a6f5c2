"""Area of polygons under a union of sweep-frame boxes, compiled: the band of R4.

The outermost fitted line of a cell may till a strip of the band between the machine area
and the field's boundary (:func:`planner.footprints.cells_and_band_m2`). Its footprint is a
box ``u ± width/2, [v_lo, v_hi]`` in the sweep frame, so the boxes of a heading are all
aligned with its axes, and their union falls into disjoint rectangles: slabs between
consecutive box sides across the sweep, each holding the merged ``v`` intervals of the boxes
that span it. The area of a polygon inside a rectangle ``[u0, u1] × [v0, v1]`` is a sum over
its edges (Green's theorem, ``∮ G dv`` with ``G = (clamp(u, u0, u1) - u0) [v0 < v < v1]``),
each edge integrated exactly in at most three linear pieces. No overlay is built: the boxes'
union, and the field and machine area cut by it (three shapely overlays, about 0.8 ms a
call), become a loop over rectangles and edges (tens of µs).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import _jit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@_jit
def _edge_m2(
    ua: float, va: float, ub: float, vb: float, u0: float, u1: float, v0: float, v1: float
) -> float:
    """``∫ (clamp(u, u0, u1) - u0) [v0 < v < v1] dv`` along the edge ``a → b`` [m²].

    Summed over a positively oriented ring, the area of its inside within the rectangle.
    """
    if va == vb:
        return 0.0  # along the sweep's u: no dv
    sign = 1.0
    if vb < va:
        ua, va, ub, vb = ub, vb, ua, va
        sign = -1.0
    lo = va if va > v0 else v0
    hi = vb if vb < v1 else v1
    if hi <= lo:
        return 0.0
    slope = (ub - ua) / (vb - va)
    u_lo = ua if lo == va else ua + (lo - va) * slope
    u_hi = ub if hi == vb else ua + (hi - va) * slope
    h_lo = min(max(u_lo, u0), u1) - u0
    h_hi = min(max(u_hi, u0), u1) - u0
    # Where the edge crosses u0 or u1 the clamp bends: the pieces between are linear, so a
    # trapezoid each is exact. Crossings are met in the order of u along the edge.
    first, second = (u0, u1) if u_lo < u_hi else (u1, u0)
    total = 0.0
    v_prev, h_prev = lo, h_lo
    for c in (first, second):
        if (u_lo - c) * (u_hi - c) < 0.0:
            v_c = lo + (c - u_lo) / (u_hi - u_lo) * (hi - lo)
            h_c = c - u0
            total += (v_c - v_prev) * (h_prev + h_c) * 0.5
            v_prev, h_prev = v_c, h_c
    total += (hi - v_prev) * (h_prev + h_hi) * 0.5
    return sign * total


@_jit
def _ring_weights(u: FloatArray, v: FloatArray, ends: IntArray, signs: FloatArray) -> FloatArray:
    """``signs`` times each ring's orientation (+1 counter-clockwise in ``u, v``)."""
    weights = np.empty(len(ends))
    start = 0
    for r in range(len(ends)):
        twice = 0.0
        for e in range(start, ends[r] - 1):
            twice += u[e] * v[e + 1] - u[e + 1] * v[e]
        weights[r] = signs[r] if twice > 0.0 else -signs[r]
        start = ends[r]
    return weights


@_jit
def boxes_over_rings_m2(
    u_lo: FloatArray,
    u_hi: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    u: FloatArray,
    v: FloatArray,
    ends: IntArray,
    signs: FloatArray,
) -> float:
    """Weighted area of polygons' insides under the union of boxes, all in one sweep frame [m²].

    Parameters
    ----------
    u_lo, u_hi, v_lo, v_hi : ndarray
        The boxes ``[u_lo, u_hi] × [v_lo, v_hi]``; they may overlap.
    u, v : ndarray
        The rings' vertices, closed (last equals first), one ring after another.
    ends : ndarray of int
        Ring ``r`` is ``ends[r - 1]:ends[r]`` (from 0 for the first).
    signs : ndarray
        Each ring's weight: +1 for an exterior and -1 for a hole of a polygon counted, the
        opposite for one subtracted. Orientation is taken from the ring itself.

    Returns
    -------
    float
        ``Σ signs · area(inside of ring ∩ union of boxes)`` over the rings.
    """
    weights = _ring_weights(u, v, ends, signs)
    n = len(u_lo)
    sides = np.unique(np.concatenate((u_lo, u_hi)))
    starts = np.empty(n)
    stops = np.empty(n)
    total = 0.0
    for k in range(len(sides) - 1):
        s0, s1 = sides[k], sides[k + 1]
        m = 0
        for i in range(n):
            if u_lo[i] <= s0 and u_hi[i] >= s1:
                starts[m] = v_lo[i]
                stops[m] = v_hi[i]
                m += 1
        if m == 0:
            continue
        order = np.argsort(starts[:m])
        a, b = starts[order[0]], stops[order[0]]
        for j in range(1, m + 1):
            if j < m and starts[order[j]] <= b:
                b = max(b, stops[order[j]])  # overlapping boxes: one interval
                continue
            start = 0
            for r in range(len(ends)):
                inside = 0.0
                for e in range(start, ends[r] - 1):
                    inside += _edge_m2(u[e], v[e], u[e + 1], v[e + 1], s0, s1, a, b)
                total += weights[r] * inside
                start = ends[r]
            if j < m:
                a, b = starts[order[j]], stops[order[j]]
    return total


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on a square under two boxes."""
    square = np.array([0.0, 2.0, 2.0, 0.0, 0.0]), np.array([0.0, 0.0, 2.0, 2.0, 0.0])
    boxes_over_rings_m2(
        np.array([-1.0, 0.5]),
        np.array([1.0, 1.5]),
        np.array([-1.0, 0.5]),
        np.array([1.0, 3.0]),
        *square,
        np.array([5], dtype=np.int64),
        np.array([1.0]),
    )
