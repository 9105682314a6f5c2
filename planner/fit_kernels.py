"""Compiled loops for the turns between lines, with the numpy code's arithmetic.

:func:`planner.turns.dubins_words` and :func:`planner.turns._sample` solve and sample every
turn at once in numpy, but a small field has a few turns, so their cost is the ~150 numpy
calls they make on arrays of three values (the paper field: 0.35 ms of a 4 ms plan). These
are the same computations as one loop per turn, compiled by numba (:mod:`planner.kernels`'
conventions: cached on disk, division by zero as numpy): every value comes from the same
operations in the same order, so the turns, and so the plans, are the same to the last bit.

Unlike :mod:`planner.kernels` these call ``sin``, ``cos``, ``atan2``, ``acos`` and
``hypot``: numba calls the C library's, as numpy does for float64 on x86-64 without
AVX-512 (numpy dispatches some to its own SIMD code on AVX-512 machines, where the last bit
could differ). ``tests/planner/test_fit_kernels.py`` compares the two bit for bit on the
machine it runs on.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from planner.kernels import _jit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

_TWO_PI = 2.0 * math.pi
_FLOAT_MAX = float(np.finfo(np.float64).max)


@_jit
def _dubins(
    x0: FloatArray,
    y0: FloatArray,
    yaw0: FloatArray,
    x1: FloatArray,
    y1: FloatArray,
    yaw1: FloatArray,
    radius: float,
    codes: IntArray,
    best: IntArray,
    params: FloatArray,
) -> None:
    """``planner.turns._dubins_words_numpy``, one turn at a time; ``best`` -1: no word.

    ``codes``: the words tried, as indices into :data:`planner.turns.DUBINS_WORDS` (LSL,
    RSR, LSR, RSL, RLR, LRL).
    """
    tpq = np.empty(3)
    for k in range(len(x0)):
        dx, dy = x1[k] - x0[k], y1[k] - y0[k]
        d = math.hypot(dx, dy) / radius
        theta = math.atan2(dy, dx)
        a = (yaw0[k] - theta) % _TWO_PI
        b = (yaw1[k] - theta) % _TWO_PI
        sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
        c_ab = math.cos(a - b)
        dd = d * d
        best_total = math.inf
        best[k] = -1
        for w in range(len(codes)):
            code = codes[w]
            if code == 0:  # LSL
                p_sq = 2.0 + dd - 2.0 * c_ab + 2.0 * d * (sa - sb)
                tmp = math.atan2(cb - ca, d + sa - sb)
                t, p, q = tmp - a, math.sqrt(p_sq) if p_sq >= 0.0 else math.nan, b - tmp
            elif code == 1:  # RSR
                p_sq = 2.0 + dd - 2.0 * c_ab + 2.0 * d * (sb - sa)
                tmp = math.atan2(ca - cb, d - sa + sb)
                t, p, q = a - tmp, math.sqrt(p_sq) if p_sq >= 0.0 else math.nan, tmp - b
            elif code == 2:  # LSR
                p_sq = -2.0 + dd + 2.0 * c_ab + 2.0 * d * (sa + sb)
                p = math.sqrt(p_sq) if p_sq >= 0.0 else math.nan
                tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
                t, q = tmp - a, tmp - b
            elif code == 3:  # RSL
                p_sq = -2.0 + dd + 2.0 * c_ab - 2.0 * d * (sa + sb)
                p = math.sqrt(p_sq) if p_sq >= 0.0 else math.nan
                tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
                t, q = a - tmp, b - tmp
            elif code == 4:  # RLR
                c = (6.0 - dd + 2.0 * c_ab + 2.0 * d * (sa - sb)) / 8.0
                phi = math.atan2(ca - cb, d - sa + sb)
                p = _TWO_PI - (math.acos(c) if -1.0 <= c <= 1.0 else math.nan)
                t = (a - phi + p / 2.0) % _TWO_PI
                q = a - b - t + p
            else:  # LRL
                c = (6.0 - dd + 2.0 * c_ab + 2.0 * d * (sb - sa)) / 8.0
                phi = math.atan2(ca - cb, d + sa - sb)
                p = _TWO_PI - (math.acos(c) if -1.0 <= c <= 1.0 else math.nan)
                t = (-a - phi + p / 2.0) % _TWO_PI
                q = b - a - t + p
            t, q = t % _TWO_PI, q % _TWO_PI
            total = t + p + q  # tpq.sum(axis=1): in this order
            if total != total:
                total = math.inf
            elif total > _FLOAT_MAX:
                total = _FLOAT_MAX
            elif total < -_FLOAT_MAX:
                total = -_FLOAT_MAX
            if total < best_total or best[k] < 0 and total == best_total:
                best_total = total
                best[k] = w
                tpq[0], tpq[1], tpq[2] = t, p, q
        if best_total == math.inf:  # no finite word (np.argmin: the first)
            best[k] = -1
        params[k, 0], params[k, 1], params[k, 2] = tpq[0], tpq[1], tpq[2]


@_jit
def _advance(
    x: float, y: float, yaw: float, sign: int, length: float, radius: float
) -> tuple[float, float, float]:
    """``planner.turns._advance`` of one pose."""
    kappa = sign / radius
    new_yaw = yaw + kappa * length
    if sign == 0:
        return x + length * math.cos(yaw), y + length * math.sin(yaw), new_yaw
    return (
        x + (math.sin(new_yaw) - math.sin(yaw)) / kappa,
        y - (math.cos(new_yaw) - math.cos(yaw)) / kappa,
        new_yaw,
    )


@_jit
def _sample(
    x0: FloatArray,
    y0: FloatArray,
    yaw0: FloatArray,
    x1: FloatArray,
    y1: FloatArray,
    signs: IntArray,
    lengths: FloatArray,
    radius: float,
    arc_step: float,
    step: float,
) -> tuple[FloatArray, IntArray]:
    """Return the points and offsets of ``planner.turns._sample_numpy``."""
    n, m = signs.shape
    pieces = np.zeros((n, m), dtype=np.int64)
    offsets = np.zeros(n + 1, dtype=np.int64)
    for k in range(n):
        count = 1
        for s in range(m):
            size = abs(lengths[k, s])
            if size > 1e-12:
                pieces[k, s] = np.int64(math.ceil(size / (arc_step if signs[k, s] != 0 else step)))
            count += pieces[k, s]
        offsets[k + 1] = offsets[k] + count
    xy = np.empty((offsets[n], 2))
    for k in range(n):
        at = offsets[k]
        xy[at, 0], xy[at, 1] = x0[k], y0[k]
        at += 1
        x, y, yaw = x0[k], y0[k], yaw0[k]
        for s in range(m):
            sign, length, count = signs[k, s], lengths[k, s], pieces[k, s]
            for j in range(count):
                px, py, _ = _advance(x, y, yaw, sign, length * ((j + 1) / count), radius)
                xy[at, 0], xy[at, 1] = px, py
                at += 1
            x, y, yaw = _advance(x, y, yaw, sign, length, radius)
        last = offsets[k + 1] - 1
        xy[last, 0], xy[last, 1] = x1[k], y1[k]
    return xy, offsets


def _floats(values: FloatArray) -> FloatArray:
    return np.ascontiguousarray(values, dtype=np.float64)


def dubins_words(
    x0: FloatArray,
    y0: FloatArray,
    yaw0: FloatArray,
    x1: FloatArray,
    y1: FloatArray,
    yaw1: FloatArray,
    radius_m: float,
    codes: IntArray,
) -> tuple[IntArray, FloatArray]:
    """Index into ``codes`` of each turn's shortest word (-1: none) and its lengths / radius."""
    n = len(x0)
    best = np.empty(n, dtype=np.int64)
    params = np.empty((n, 3))
    f = _floats
    _dubins(
        f(x0),
        f(y0),
        f(yaw0),
        f(x1),
        f(y1),
        f(yaw1),
        float(radius_m),
        np.ascontiguousarray(codes, dtype=np.int64),
        best,
        params,
    )
    return best, params


def sample_turns(
    x0: FloatArray,
    y0: FloatArray,
    yaw0: FloatArray,
    x1: FloatArray,
    y1: FloatArray,
    signs: IntArray,
    lengths: FloatArray,
    radius_m: float,
    arc_step_m: float,
    step_m: float,
) -> tuple[FloatArray, IntArray]:
    """Points of every turn (start and end included) and each turn's offsets into them."""
    f = _floats
    return _sample(
        f(x0),
        f(y0),
        f(yaw0),
        f(x1),
        f(y1),
        np.ascontiguousarray(signs, dtype=np.int64),
        f(lengths),
        float(radius_m),
        float(arc_step_m),
        float(step_m),
    )


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on one U-turn."""
    one = np.zeros(1)
    best, params = dubins_words(
        one, one, one + math.pi / 2.0, one + 1.0, one, one - math.pi / 2.0, 0.5, np.arange(6)
    )
    signs = np.array([[1, 0, 1]], dtype=np.int64)
    sample_turns(one, one, one, one + 1.0, one, signs, params * 0.5, 0.5, 0.1, 0.5)
