"""Compiled loops over a field's edges and corners, with the numpy code's arithmetic.

Two per-vertex computations that numpy does on whole arrays of a few hundred vertices, at a
few µs a call: the heading search's per-edge score terms
(:func:`planner.heading_search._score_block`, before its sums) at every heading of a block,
and the router's test of whether the line through two corners is tangent at both
(:class:`planner.visibility.CornerVisibility`, for every pair of corners). These kernels do the same
computations in loops, compiled by numba: every value is computed by the same operations in
the same order (``np.minimum`` and ``np.maximum`` keep their NaN rules), so the scores and the
routes, and so the plans, are the same to the last bit. The rotation's ``sin``/``cos`` and the
scores' sums (numpy's pairwise sums) stay in numpy.

The numpy code stays the reference: ``tests/planner/test_cell_kernels.py`` compares the two
bit for bit on random fields and the real ones. Like :mod:`planner.kernels`, the kernels are
cached on disk (``cache=True``) and compiled, or loaded, by :func:`warm_up`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import _jit, _mn, _mx
from planner.order_kernels import _writable

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


@_jit
def _tangent_pairs(
    xy: FloatArray, around: FloatArray, i: IntArray, j: IntArray, collinear: float
) -> BoolArray:
    """``planner.visibility.CornerVisibility.tangent``: one pair at a time."""
    out = np.empty(len(i), dtype=np.bool_)
    for k in range(len(i)):
        a, b = i[k], j[k]
        dx = xy[0, b] - xy[0, a]
        dy = xy[1, b] - xy[1, a]
        tolerance = collinear * np.hypot(dx, dy)
        if tolerance == 0.0:
            out[k] = True
            continue
        wraps = True
        for c in (a, b):
            before = dx * around[1, c] - dy * around[0, c]
            after = dx * around[3, c] - dy * around[2, c]
            wraps = wraps and (
                abs(before) < tolerance or abs(after) < tolerance or before * after > 0.0
            )
        out[k] = wraps
    return out


def tangent_pairs(
    xy: FloatArray, around: FloatArray, i: IntArray, j: IntArray, collinear: float
) -> BoolArray:
    """Whether the line through corners ``i[k]`` and ``j[k]`` is tangent at both, compiled.

    ``xy`` (2, n) and ``around`` (4, n) as :class:`planner.visibility.CornerVisibility` keeps them.
    """
    return _tangent_pairs(
        xy,
        around,
        _writable(i),
        _writable(j),
        collinear,
    )


@_jit
def _score_terms(
    xy: FloatArray,
    nxt: FloatArray,
    cos_t: FloatArray,
    sin_t: FloatArray,
    d: float,
    out: FloatArray,
) -> None:
    """``planner.heading_search._score_block``'s per-edge terms, before its sums.

    ``out[0..4]`` (each (rows, n)) get each edge's working, missed, turn and piece terms
    and its ``du``, every value by the numpy code's operations in its order.
    """
    rows, n = len(cos_t), len(xy)
    half = d / 2.0
    for r in range(rows):
        c, s = cos_t[r], sin_t[r]
        first = np.inf
        for e in range(n):
            u1 = xy[e, 0] * c - xy[e, 1] * s
            first = _mn(first, u1) if e else u1
        first = first + half
        for e in range(n):
            u1 = xy[e, 0] * c - xy[e, 1] * s
            v1 = xy[e, 0] * s + xy[e, 1] * c
            u2 = nxt[e, 0] * c - nxt[e, 1] * s
            v2 = nxt[e, 0] * s + nxt[e, 1] * c
            k1 = _mx(np.ceil((_mn(u1, u2) - first) / d), 0.0)
            k2 = _mx(np.ceil((_mx(u1, u2) - first) / d), 0.0)
            count = k2 - k1
            du = u2 - u1
            slope = 0.0 if du == 0.0 else (v2 - v1) / du
            sum_k = (k1 + k2 - 1.0) * count / 2.0 * d
            t = slope * (count * (first - u1) + sum_k)
            sum_v = count * v1 + t
            out[0, r, e] = -sum_v if du > 0.0 else sum_v
            dv = abs(v2 - v1)
            out[1, r, e] = _mn(count * abs(slope) * d * d / 8.0, dv * d / 2.0)
            edge_m = np.hypot(du, dv)
            out[2, r, e] = _mn(count * d * np.sqrt(1.0 + slope * slope), edge_m)
            out[3, r, e] = count if du > 0.0 else 0.0
            out[4, r, e] = du


def score_terms(
    xy: FloatArray,
    nxt: FloatArray,
    cos_t: FloatArray,
    sin_t: FloatArray,
    interval_m: float,
    scratch: FloatArray,
) -> None:
    """Write the per-edge terms of a block of headings into ``scratch[:5, :rows]``.

    ``xy`` and ``nxt`` (n, 2): every ring's vertices and their next ones [m]; ``cos_t``,
    ``sin_t`` (rows,): the headings' (numpy's) cosines and sines; ``interval_m``: the line
    spacing [m]; ``scratch`` C-contiguous, at least (5, rows, n). Compiled: see
    ``_score_terms``.
    """
    _score_terms(
        np.ascontiguousarray(xy), np.ascontiguousarray(nxt), cos_t, sin_t, interval_m, scratch
    )


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on a tiny ring."""
    pair = np.array([0, 1])
    score_terms(
        np.ones((2, 2)), np.zeros((2, 2)), np.ones(1), np.zeros(1), 1.0, np.empty((5, 1, 2))
    )
    tangent_pairs(np.ones((2, 2)), np.ones((4, 2)), pair, pair[::-1], 1e-9)
