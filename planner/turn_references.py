"""The numpy references of the turn kernels: what :mod:`planner.fit_kernels` computes for turns.

:mod:`planner.turns` runs compiled kernels (:func:`planner.fit_kernels.dubins_words`,
``sample_turns``, ``translate_turns``, ``driving_times``); each function here computes the same
thing in numpy, all turns at once, and is the oracle that ``tests/planner/test_fit_kernels.py``
holds the kernel to bit for bit (one per kernel, and a whole plan with every kernel swapped for
its reference). They are kept apart from :mod:`planner.turns` so that the code a plan runs reads
on its own; no plan calls them, and this module imports :mod:`planner.turns`, not the reverse.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from planner.turns import (
    DUBINS_WORDS,
    SAGITTA_M,
    STEP_M,
    TurnCurves,
    TurnEnds,
    take_turns,
)

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

_TWO_PI = 2.0 * math.pi
_FLOAT_MAX = float(np.finfo(np.float64).max)


def dubins_words_numpy(
    ends: TurnEnds, *, radius_m: float, words: tuple[str, ...] = tuple(DUBINS_WORDS)
) -> tuple[IntArray, FloatArray]:
    """:func:`planner.turns.dubins_words` in numpy, all turns at once: the kernel's reference."""
    dx, dy = ends.x1 - ends.x0, ends.y1 - ends.y0
    d = np.hypot(dx, dy) / radius_m
    theta = np.arctan2(dy, dx)
    a = _mod2pi(ends.yaw0 - theta)
    b = _mod2pi(ends.yaw1 - theta)
    sa, sb, ca, cb = np.sin(a), np.sin(b), np.cos(a), np.cos(b)
    c_ab = np.cos(a - b)
    dd = d * d
    tpq = np.empty((len(words), 3, len(d)))  # (words, 3, T); NaN where a word has no path
    with np.errstate(invalid="ignore"):
        for w, word in enumerate(words):
            if word == "LSL":
                p_sq = 2.0 + dd - 2.0 * c_ab + 2.0 * d * (sa - sb)
                tmp = np.arctan2(cb - ca, d + sa - sb)
                t, p, q = tmp - a, np.sqrt(p_sq), b - tmp
            elif word == "RSR":
                p_sq = 2.0 + dd - 2.0 * c_ab + 2.0 * d * (sb - sa)
                tmp = np.arctan2(ca - cb, d - sa + sb)
                t, p, q = a - tmp, np.sqrt(p_sq), tmp - b
            elif word == "LSR":
                p = np.sqrt(-2.0 + dd + 2.0 * c_ab + 2.0 * d * (sa + sb))
                tmp = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
                t, q = tmp - a, tmp - b
            elif word == "RSL":
                p = np.sqrt(-2.0 + dd + 2.0 * c_ab - 2.0 * d * (sa + sb))
                tmp = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
                t, q = a - tmp, b - tmp
            elif word == "RLR":
                c = (6.0 - dd + 2.0 * c_ab + 2.0 * d * (sa - sb)) / 8.0
                phi = np.arctan2(ca - cb, d - sa + sb)
                p = _TWO_PI - np.arccos(c)  # NaN where |c| > 1: no such path
                t = _mod2pi(a - phi + p / 2.0)
                q = a - b - t + p
            elif word == "LRL":
                c = (6.0 - dd + 2.0 * c_ab + 2.0 * d * (sb - sa)) / 8.0
                phi = np.arctan2(ca - cb, d + sa - sb)
                p = _TWO_PI - np.arccos(c)
                t = _mod2pi(-a - phi + p / 2.0)
                q = b - a - t + p
            else:
                raise ValueError(f"unknown Dubins word {word!r}")
            tpq[w, 0], tpq[w, 1], tpq[w, 2] = _mod2pi(t), p, _mod2pi(q)
    # np.nan_to_num(sums, nan=np.inf) without its Python-level cost (±inf to ±max, as it does).
    sums = tpq.sum(axis=1)
    total = np.where(np.isnan(sums), np.inf, np.clip(sums, -_FLOAT_MAX, _FLOAT_MAX))
    if not np.isfinite(total).any(axis=0).all():
        raise ValueError("no Dubins word joins these poses")  # only if ``words`` is narrowed
    best = np.argmin(total, axis=0)
    turn_index = np.arange(len(d))
    params = tpq[best, :, turn_index]
    signs = np.array([DUBINS_WORDS[w] for w in words], dtype=np.int64)[best]
    return signs, params


def _mod2pi(angle: FloatArray) -> FloatArray:
    return np.mod(angle, _TWO_PI)


def sample_numpy(
    ends: TurnEnds, signs: IntArray, lengths: FloatArray, radius_m: float, step_m: float
) -> TurnCurves:
    """:func:`planner.turns._sample` in numpy, all turns at once: the kernel's reference."""
    n, m = signs.shape
    arc_step = min(step_m, 2.0 * radius_m * math.acos(max(-1.0, 1.0 - SAGITTA_M / radius_m)))
    seg_step = np.where(signs != 0, arc_step, step_m)
    pieces = np.where(np.abs(lengths) > 1e-12, np.ceil(np.abs(lengths) / seg_step), 0)
    pieces = pieces.astype(np.int64)
    # Start pose of every segment.
    x, y, yaw = ends.x0.copy(), ends.y0.copy(), ends.yaw0.copy()
    seg_x, seg_y, seg_yaw = np.empty((n, m)), np.empty((n, m)), np.empty((n, m))
    for s in range(m):
        seg_x[:, s], seg_y[:, s], seg_yaw[:, s] = x, y, yaw
        x, y, yaw = _advance(x, y, yaw, signs[:, s], lengths[:, s], radius_m)
    flat = pieces.ravel()
    seg = np.arange(n * m).repeat(flat)  # array methods: the np.* wrappers cost more here
    within = np.arange(flat.sum()) - (flat.cumsum() - flat).repeat(flat)
    frac = (within + 1) / flat[seg]
    px, py, _ = _advance(
        seg_x.ravel()[seg],
        seg_y.ravel()[seg],
        seg_yaw.ravel()[seg],
        signs.ravel()[seg],
        lengths.ravel()[seg] * frac,
        radius_m,
    )
    per_turn = pieces.sum(axis=1) + 1
    offsets = np.concatenate(([0], per_turn.cumsum())).astype(np.int64)
    xy = np.empty((offsets[-1], 2))
    first = offsets[:-1]
    xy[first, 0], xy[first, 1] = ends.x0, ends.y0
    rest = np.ones(offsets[-1], dtype=bool)
    rest[first] = False
    xy[rest, 0], xy[rest, 1] = px, py
    # The last point is the target exactly (the integration agrees to ~1e-12 m).
    xy[offsets[1:] - 1, 0], xy[offsets[1:] - 1, 1] = ends.x1, ends.y1
    turning = np.where(signs != 0, np.abs(lengths) / radius_m, 0.0).sum(axis=1)
    return TurnCurves(xy, offsets, np.abs(lengths).sum(axis=1), turning, float(radius_m))


def _advance(
    x: FloatArray,
    y: FloatArray,
    yaw: FloatArray,
    sign: IntArray,
    length: FloatArray,
    radius_m: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Drive ``length`` [m] (negative: backwards) on an arc of ``sign`` (0: straight)."""
    kappa = sign / radius_m
    new_yaw = yaw + kappa * length
    with np.errstate(divide="ignore", invalid="ignore"):
        arc_x = x + (np.sin(new_yaw) - np.sin(yaw)) / kappa
        arc_y = y - (np.cos(new_yaw) - np.cos(yaw)) / kappa
    straight = sign == 0
    nx = np.where(straight, x + length * np.cos(yaw), arc_x)
    ny = np.where(straight, y + length * np.sin(yaw), arc_y)
    return nx, ny, new_yaw


def driving_time_numpy(
    x: FloatArray, y: FloatArray, *, speed_mps: float, turn_rate_dps: float
) -> float:
    """:func:`planner.turns.driving_time_s` in numpy: the compiled kernel's reference."""
    dx, dy = x[1:] - x[:-1], y[1:] - y[:-1]  # np.diff, without its wrapper's cost
    step = np.hypot(dx, dy)
    moving = step > 1e-9
    if not moving.any():
        return 0.0
    step = step[moving]
    heading = np.arctan2(dy[moving], dx[moving])
    change = np.abs((heading[1:] - heading[:-1] + np.pi) % (2.0 * np.pi) - np.pi)
    rate = math.radians(turn_rate_dps)
    on_arc = (step[:-1] <= STEP_M + 1e-9) & (step[1:] <= STEP_M + 1e-9)
    share = np.zeros(len(step))
    arc_change = np.where(on_arc, change, 0.0)
    share[:-1] += arc_change / 2.0
    share[1:] += arc_change / 2.0
    corners = float(np.where(on_arc, 0.0, change).sum()) / rate
    return float(np.maximum(step / speed_mps, share / rate).sum()) + corners


def translate_numpy(shapes: TurnCurves, shape_of: IntArray | None, ends: TurnEnds) -> TurnCurves:
    """:func:`planner.turns._translate` in numpy: the compiled kernel's reference."""
    curves = shapes if shape_of is None else take_turns(shapes, shape_of)
    owner = np.arange(len(curves)).repeat(curves.point_counts())
    xy = curves.xy
    xy[:, 0] += ends.x0[owner]
    xy[:, 1] += ends.y0[owner]
    xy[curves.offsets[:-1], 0], xy[curves.offsets[:-1], 1] = ends.x0, ends.y0
    xy[curves.offsets[1:] - 1, 0], xy[curves.offsets[1:] - 1, 1] = ends.x1, ends.y1
    return curves
