"""Compiled loops for the turns between lines and the variants' lengths, with numpy's arithmetic.

A small field has a few lines and turns, so the numpy code that plans and fits them
(:func:`planner.turns.dubins_words`, ``_sample`` and ``_translate``;
:func:`planner.line_ends._fit_turns`) and sums the variants of every heading
(:func:`planner.ordering.combine_variants`) costs its ~300 numpy calls on arrays of a few
values (the paper field: about a fifth of a 4 ms plan). These are the same computations as one
loop per turn or heading, compiled by numba (:mod:`planner.kernels`' conventions: cached on
disk, division by zero as numpy): every value comes from the same operations in the same
order, so the turns, and so the plans, are the same to the last bit. The numpy code stays
the reference (:mod:`planner.turn_references`, :mod:`planner.line_end_references`).

Unlike :mod:`planner.kernels` these call ``sin``, ``cos``, ``atan2``, ``acos`` and
``hypot``: numba calls the C library's, as numpy does for float64 on x86-64 without
AVX-512 (numpy 2.4 dispatches some to its own SIMD code on AVX-512 machines, where the last
bit could differ). ``tests/planner/test_fit_kernels.py`` compares the two bit for bit on
the machine it runs on.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import _jit, _left, _mn, _mx, _right

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
    """``planner.turn_references.dubins_words_numpy``, one turn at a time; ``best`` -1: no word.

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
    """``planner.turn_references._advance`` of one pose."""
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
    """Return the points and offsets of ``planner.turn_references.sample_numpy``."""
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


@_jit
def _translate(
    xy: FloatArray,
    offsets: IntArray,
    x0: FloatArray,
    y0: FloatArray,
    x1: FloatArray,
    y1: FloatArray,
) -> None:
    """``planner.turn_references.translate_numpy``'s moves, in place."""
    for k in range(len(offsets) - 1):
        first, last = offsets[k], offsets[k + 1] - 1
        for i in range(first, last + 1):
            xy[i, 0] += x0[k]
            xy[i, 1] += y0[k]
        xy[first, 0], xy[first, 1] = x0[k], y0[k]
        xy[last, 0], xy[last, 1] = x1[k], y1[k]


def translate_turns(
    xy: FloatArray,
    offsets: IntArray,
    x0: FloatArray,
    y0: FloatArray,
    x1: FloatArray,
    y1: FloatArray,
) -> None:
    """Move turn ``k``'s points (``xy``, in place) by ``(x0, y0)[k]``; its ends exactly on them."""
    f = _floats
    _translate(xy, np.ascontiguousarray(offsets, dtype=np.int64), f(x0), f(y0), f(x1), f(y1))


@_jit
def _interp(x: float, xp: FloatArray, fp: FloatArray) -> float:
    """``np.interp(x, xp, fp)`` of one value, ``xp`` non-decreasing (numpy's algorithm)."""
    n = len(xp)
    if n == 1:
        return float(fp[0])
    if x != x:
        return x
    if x < xp[0]:
        return float(fp[0])
    if x > xp[n - 1]:
        return float(fp[n - 1])
    j = _right(xp, 0, n, x) - 1  # the last xp[j] <= x
    if j == n - 1 or xp[j] == x:
        return float(fp[j])
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    r = slope * (x - xp[j]) + fp[j]
    if r != r:  # NaN one way: try the other
        r = slope * (x - xp[j + 1]) + fp[j + 1]
        if r != r and fp[j] == fp[j + 1]:
            r = float(fp[j])
    return float(r)


@_jit
def _chain_crossings(
    xy: FloatArray,
    pv: FloatArray,
    offsets: IntArray,
    top: npt.NDArray[np.bool_],
    cu: FloatArray,
    cv: FloatArray,
    shift: float,
    delta: FloatArray,
    fits: npt.NDArray[np.bool_],
    tolerance: float,
    reduce_max: bool,
) -> None:
    """``line_end_references._chain_vertices_under`` folded into ``delta`` (max) or ``fits``.

    ``cu``, ``cv``: both chains, the upper's vertices first, the lower's shifted by ``shift``;
    a turn at the top (``top``) meets the upper chain's vertices, others the lower's.
    """
    for k in range(len(offsets) - 1):
        at_top = top[k]
        offset = 0.0 if at_top else shift
        for i in range(offsets[k], offsets[k + 1] - 1):
            ua, ub, va, vb = xy[i, 0], xy[i + 1, 0], pv[i], pv[i + 1]
            lo_u = _mn(ua, ub) + offset
            hi_u = _mx(ua, ub) + offset
            first = _right(cu, 0, len(cu), lo_u)
            stop = _left(cu, 0, len(cu), hi_u)
            a_u, b_u = ua + offset, ub + offset
            for vertex in range(first, stop):
                t = (cu[vertex] - a_u) / (b_u - a_u if b_u != a_u else 1.0)
                curve_v = va + t * (vb - va)
                gap = curve_v - cv[vertex] if at_top else cv[vertex] - curve_v
                if reduce_max:
                    delta[k] = _mx(delta[k], gap)
                else:
                    fits[k] = fits[k] and gap <= tolerance


@_jit
def _fit_turns(
    xy: FloatArray,
    offsets: IntArray,
    top: npt.NDArray[np.bool_],
    lo_u: FloatArray,
    lo_v: FloatArray,
    hi_u: FloatArray,
    hi_v: FloatArray,
    tolerance: float,
    shift_out: FloatArray,
    fits_out: npt.NDArray[np.bool_],
    xy_out: FloatArray,
) -> bool:
    """``line_end_references.fitted_numpy``'s shifts, fits and moved points; False: not done.

    Chains whose ``u`` steps back (which :func:`planner.coverage.convex_chains` never makes)
    are left to the numpy code: ``np.interp`` and ``searchsorted`` answer differently there.
    """
    for chain in (lo_u, hi_u):
        for i in range(1, len(chain)):
            if not chain[i - 1] <= chain[i]:
                return False
    n_turns, n_points = len(offsets) - 1, len(xy)
    # Chains.u_min and u_max: Python's min and max of the two (the first on ties).
    u_min = hi_u[0] if hi_u[0] < lo_u[0] else lo_u[0]
    u_max = hi_u[-1] if hi_u[-1] > lo_u[-1] else lo_u[-1]
    hi = np.empty(n_points)
    lo = np.empty(n_points)
    pv = np.empty(n_points)
    delta = np.zeros(n_turns)
    biggest = 0.0
    for k in range(n_turns):
        for i in range(offsets[k], offsets[k + 1]):
            pu = xy[i, 0]
            pv[i] = xy[i, 1]
            hi[i] = _interp(pu, hi_u, hi_v)
            lo[i] = _interp(pu, lo_u, lo_v)
            if pu < u_min - tolerance or pu > u_max + tolerance:
                need = math.inf
            else:
                need = pv[i] - hi[i] if top[k] else lo[i] - pv[i]
            delta[k] = _mx(delta[k], need)
            biggest = _mx(biggest, abs(pu))
    # Both chains in one sorted array: the lower chain's vertices shifted past every curve.
    shift = 4.0 * (biggest + abs(u_max) + abs(u_min))
    shift += 1.0
    n_hi = len(hi_u)
    cu = np.empty(n_hi + len(lo_u))
    cv = np.empty(n_hi + len(lo_u))
    cu[:n_hi], cv[:n_hi] = hi_u, hi_v
    for i in range(len(lo_u)):
        cu[n_hi + i], cv[n_hi + i] = lo_u[i] + shift, lo_v[i]
    _chain_crossings(xy, pv, offsets, top, cu, cv, shift, delta, fits_out, tolerance, True)
    moved_v = np.empty(n_points)
    for k in range(n_turns):
        reachable = math.isfinite(delta[k])
        d = delta[k] if reachable else 0.0
        shift_out[k] = -d if top[k] else d
        fits_out[k] = reachable
        for i in range(offsets[k], offsets[k + 1]):
            moved = pv[i] + shift_out[k]
            moved_v[i] = moved
            xy_out[i, 0], xy_out[i, 1] = xy[i, 0], moved
            clash = (lo[i] - moved if top[k] else moved - hi[i]) > tolerance
            fits_out[k] = fits_out[k] and not clash
    below = np.empty(n_turns, dtype=np.bool_)
    for k in range(n_turns):
        below[k] = not top[k]
    _chain_crossings(xy, moved_v, offsets, below, cu, cv, shift, delta, fits_out, tolerance, False)
    return True


@_jit
def _fit_turn_groups(
    xy: FloatArray,
    offsets: IntArray,
    top: npt.NDArray[np.bool_],
    turn_at: IntArray,
    chains: FloatArray,
    chain_at: IntArray,
    tolerance: float,
    shift_out: FloatArray,
    fits_out: npt.NDArray[np.bool_],
    xy_out: FloatArray,
    done_out: npt.NDArray[np.bool_],
) -> None:
    """:func:`_fit_turns` of each group of turns on its own machine area.

    Group ``g`` is the turns ``turn_at[g]:turn_at[g + 1]`` on the machine area packed in
    ``chains[chain_at[g]:chain_at[g + 1]]`` (``Chains.packed``). Each group is one call of
    :func:`_fit_turns` as :func:`fit_turns` would make it alone, so its figures are that
    call's to the last bit. ``done_out[g]``: False where the kernel declined the group (an
    empty chain, or one out of order: the numpy code decides).
    """
    for g in range(len(turn_at) - 1):
        t0, t1 = turn_at[g], turn_at[g + 1]
        if t1 == t0:
            done_out[g] = True
            continue
        packed = chains[chain_at[g] : chain_at[g + 1]]
        n_lo, n_hi = int(packed[0]), int(packed[1])
        if n_lo == 0 or n_hi == 0:
            done_out[g] = False
            continue
        p0, p1 = offsets[t0], offsets[t1]
        done_out[g] = _fit_turns(
            xy[p0:p1],
            offsets[t0 : t1 + 1] - p0,
            top[t0:t1],
            packed[2 : 2 + n_lo],
            packed[2 + n_lo : 2 + 2 * n_lo],
            packed[2 + 2 * n_lo : 2 + 2 * n_lo + n_hi],
            packed[2 + 2 * n_lo + n_hi : 2 + 2 * n_lo + 2 * n_hi],
            tolerance,
            shift_out[t0:t1],
            fits_out[t0:t1],
            xy_out[p0:p1],
        )


def fit_turn_groups(
    xy: FloatArray,
    offsets: IntArray,
    top: npt.NDArray[np.bool_],
    turn_at: IntArray,
    chains: FloatArray,
    chain_at: IntArray,
    tolerance_m: float,
) -> tuple[FloatArray, npt.NDArray[np.bool_], FloatArray, npt.NDArray[np.bool_]]:
    """:func:`fit_turns` of many groups of turns, each on its own machine area, in one call.

    Group ``g`` is the turns ``turn_at[g]:turn_at[g + 1]`` and the area packed in
    ``chains[chain_at[g]:chain_at[g + 1]]`` (``[n_lo, n_hi, lo_u, lo_v, hi_u, hi_v]``; ``n_lo``
    or ``n_hi`` 0 for an area the numpy code must take). Returns every turn's shift, fit and
    moved points, and whether each group was done (the others' entries are left unset).
    """
    n, groups = len(offsets) - 1, len(turn_at) - 1
    shift, fits, moved = np.empty(n), np.empty(n, dtype=np.bool_), np.empty((len(xy), 2))
    done = np.empty(groups, dtype=np.bool_)
    _fit_turn_groups(
        _floats(xy),
        np.ascontiguousarray(offsets, dtype=np.int64),
        np.ascontiguousarray(top, dtype=np.bool_),
        np.ascontiguousarray(turn_at, dtype=np.int64),
        _floats(chains),
        np.ascontiguousarray(chain_at, dtype=np.int64),
        float(tolerance_m),
        shift,
        fits,
        moved,
        done,
    )
    return shift, fits, moved, done


def fit_turns(
    xy: FloatArray,
    offsets: IntArray,
    top: npt.NDArray[np.bool_],
    lo_u: FloatArray,
    lo_v: FloatArray,
    hi_u: FloatArray,
    hi_v: FloatArray,
    tolerance_m: float,
) -> tuple[FloatArray, npt.NDArray[np.bool_], FloatArray] | None:
    """Each turn's shift along ``v``, whether it fits, and its points moved by the shift.

    None where the numpy code must decide (chains out of order, see ``_fit_turns``; an empty
    chain or a chain's ``u`` and ``v`` of other lengths, which the kernel would read past).
    """
    if not (0 < len(lo_u) == len(lo_v) and 0 < len(hi_u) == len(hi_v)):
        return None
    n = len(offsets) - 1
    shift, fits, moved = np.empty(n), np.empty(n, dtype=np.bool_), np.empty((len(xy), 2))
    f = _floats
    done = _fit_turns(
        f(xy),
        np.ascontiguousarray(offsets, dtype=np.int64),
        np.ascontiguousarray(top, dtype=np.bool_),
        f(lo_u),
        f(lo_v),
        f(hi_u),
        f(hi_v),
        float(tolerance_m),
        shift,
        fits,
        moved,
    )
    return (shift, fits, moved) if done else None


@_jit
def _combine(
    headings: FloatArray,
    counts: IntArray,
    rows: FloatArray,
    start: FloatArray,
    finish: FloatArray,
    turns: FloatArray,
    transit: FloatArray,
) -> None:
    """``planner.ordering.combine_variants``' turns and transit, one heading at a time.

    ``rows``: the aggregates top_even, top_odd, bottom_even, bottom_odd, u_first, lo_first,
    hi_first, u_last, lo_last, hi_last; ``start``, ``finish``: ``(x, y)``, or empty if none.
    """
    for h in range(len(headings)):
        top_even, top_odd, bottom_even, bottom_odd = rows[0, h], rows[1, h], rows[2, h], rows[3, h]
        u_f, lo_f, hi_f = rows[4, h], rows[5, h], rows[6, h]
        u_l, lo_l, hi_l = rows[7, h], rows[8, h], rows[9, h]
        left_up = top_even + bottom_odd  # line 0 drives up, so it turns at the top
        left_down = bottom_even + top_odd
        n_odd = counts[h] % 2 == 1
        turns[h, 0], turns[h, 1] = left_up, left_down
        turns[h, 2] = left_down if n_odd else left_up
        turns[h, 3] = left_up if n_odd else left_down
        theta = headings[h] * (math.pi / 180.0)  # np.radians
        cos_t, sin_t = math.cos(theta), math.sin(theta)
        ends_up = (counts[h] - 1) % 2 == 0
        # Variants in VARIANTS order: left_up, left_down, right_up, right_down.
        entry_u = (u_f, u_f, u_l, u_l)
        entry_v = (lo_f, hi_f, lo_l, hi_l)
        exit_u = (u_l, u_l, u_f, u_f)
        exit_v = (hi_l, lo_l, hi_f, lo_f) if ends_up else (lo_l, hi_l, lo_f, hi_f)
        for j in range(4):
            total = 0.0
            if len(start):
                pu = start[0] * cos_t - start[1] * sin_t
                pv = start[0] * sin_t + start[1] * cos_t
                total += math.hypot(entry_u[j] - pu, entry_v[j] - pv)
            if len(finish):
                pu = finish[0] * cos_t - finish[1] * sin_t
                pv = finish[0] * sin_t + finish[1] * cos_t
                total += math.hypot(exit_u[j] - pu, exit_v[j] - pv)
            transit[h, j] = total


def combine_variants(
    headings_deg: FloatArray,
    counts: IntArray,
    rows: FloatArray,
    start_xy: tuple[float, float] | None,
    finish_xy: tuple[float, float] | None,
) -> tuple[FloatArray, FloatArray]:
    """Return the four variants' turns and transit per heading, shape (A, 4) each.

    ``rows``: :func:`planner.kernels.length_aggregates`' rows 1 to 10 (see :func:`_combine`).
    """
    n = len(headings_deg)
    turns, transit = np.empty((n, 4)), np.empty((n, 4))
    none = np.zeros(0)
    _combine(
        _floats(headings_deg),
        np.ascontiguousarray(counts, dtype=np.int64),
        _floats(rows),
        none if start_xy is None else np.array(start_xy, dtype=np.float64),
        none if finish_xy is None else np.array(finish_xy, dtype=np.float64),
        turns,
        transit,
    )
    return turns, transit


@_jit
def _driving(
    x: FloatArray, y: FloatArray, speed: float, rate: float, arc_step: float
) -> tuple[FloatArray, FloatArray]:
    """``turn_references.driving_time_numpy``'s time per moving step and corner changes [s, rad]."""
    n = len(x)
    step = np.empty(max(n - 1, 0))
    heading = np.empty(max(n - 1, 0))
    m = 0
    for i in range(n - 1):
        dx, dy = x[i + 1] - x[i], y[i + 1] - y[i]
        length = math.hypot(dx, dy)
        if length > 1e-9:
            step[m] = length
            heading[m] = math.atan2(dy, dx)
            m += 1
    share = np.zeros(m)
    corner = np.empty(max(m - 1, 0))
    for i in range(m - 1):
        change = abs((heading[i + 1] - heading[i] + math.pi) % (2.0 * math.pi) - math.pi)
        on_arc = step[i] <= arc_step and step[i + 1] <= arc_step
        share[i] += (change if on_arc else 0.0) / 2.0
        corner[i] = 0.0 if on_arc else change
    for i in range(1, m):  # after every first half, as numpy adds them
        change = abs((heading[i] - heading[i - 1] + math.pi) % (2.0 * math.pi) - math.pi)
        on_arc = step[i - 1] <= arc_step and step[i] <= arc_step
        share[i] += (change if on_arc else 0.0) / 2.0
    per_step = np.empty(m)
    for i in range(m):
        per_step[i] = _mx(step[i] / speed, share[i] / rate)
    return per_step, corner


def driving_times(
    x: FloatArray, y: FloatArray, speed_mps: float, rate_rps: float, arc_step_m: float
) -> tuple[FloatArray, FloatArray]:
    """Each moving step's time [s] and the heading change at each corner off an arc [rad]."""
    return _driving(_floats(x), _floats(y), float(speed_mps), float(rate_rps), float(arc_step_m))


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
    lengths_m: FloatArray,
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
        f(lengths_m),
        float(radius_m),
        float(arc_step_m),
        float(step_m),
    )


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on one U-turn and one heading."""
    one = np.zeros(1)
    best, params = dubins_words(
        one, one, one + math.pi / 2.0, one + 1.0, one, one - math.pi / 2.0, 0.5, np.arange(6)
    )
    signs = np.array([[1, 0, 1]], dtype=np.int64)
    xy, offsets = sample_turns(one, one, one, one + 1.0, one, signs, params * 0.5, 0.5, 0.1, 0.5)
    translate_turns(xy, offsets, one, one, one + 1.0, one)
    chain = np.array([0.0, 2.0])
    fit_turns(xy, offsets, np.ones(1, dtype=np.bool_), chain, chain * 0.0, chain, chain + 3.0, 1e-6)
    packed = np.concatenate([[2.0, 2.0], chain, chain * 0.0, chain, chain + 3.0])
    fit_turn_groups(
        xy, offsets, np.ones(1, dtype=np.bool_), np.array([0, 1]), packed, np.array([0, 10]), 1e-6
    )
    rows = np.zeros((10, 1))
    combine_variants(one, np.ones(1, dtype=np.int64), rows, (0.0, 1.0), None)
    driving_times(xy[:, 0].copy(), xy[:, 1].copy(), 0.5, 0.8, 0.5)
