"""Compiled loops for the angle search's two scorers, with the numpy code's arithmetic.

:func:`planner.heading_coverage.convex_coverage` and :func:`planner.ordering.score_headings`
are vectorised over every heading at once, but a small field has a few vertices per heading,
so their cost is the ~150 numpy calls each makes (a few µs apiece), twice per plan. These are
the same computations as one loop per heading, compiled by numba: every value is computed by
the same operations in the same order (sums accumulate in the order ``np.bincount`` adds
them; ``np.minimum``, ``np.maximum`` and ``np.clip`` keep their NaN and tie rules), so the
scores, and so the plans, are the same to the last bit. The rotation into the sweep frame
stays in numpy (its ``sin``/``cos`` are numpy's), and so do the few operations on whole
arrays (the ring's area).

The numpy code stays the reference: ``tests/planner/test_kernels.py`` compares the two bit
for bit, and a ring the kernels cannot vouch for (chain edges out of order, which a convex
ring never has) is scored by the numpy code instead. That equality is tested on the CPU the
tests run on: on another CPU numpy may take other code paths for ``sin``, ``cos``,
``arccos`` and ``arctan2`` (AVX-512 SVML), where the kernels still give a deterministic plan
but may differ from the numpy code in the last bit.

Numba compiles each kernel the first time it runs and caches the machine code on disk
(``cache=True``: in ``NUMBA_CACHE_DIR`` if set, else next to this module, else in the user's
cache directory). A cold cache costs about 9 s of CPU once; a fresh process with a warm cache
pays about 0.35 s (``import numba`` and loading the kernels), deferred to the first plan that
scores a convex ring. Where no cache directory is writable every process compiles again, and
a warning is logged.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import (
    _clip,
    _jit,
    _jit_counted_by_caller,
    _left,
    _line_count,
    _mn,
    _mx,
    _right,
    _sorted_into,
    _stable_order_into,
)

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@_jit
def _positive_part(w: float, g0: float, g1: float) -> float:
    """``heading_coverage._positive_part`` of one piece."""
    high, low = _mx(g0, g1), _mn(g0, g1)
    if low >= 0.0:
        return w * (g0 + g1) / 2.0
    if high > 0.0:
        return w * high * high / (2.0 * (high - low))
    return 0.0


@_jit
def _covered_piece(
    w: float, lo0: float, lo1: float, hi0: float, hi1: float, a: float, b: float
) -> float:
    """``heading_coverage._covered_pieces`` of one piece."""
    d_hi, d_lo = hi1 - hi0, lo1 - lo0
    t_hi = (b - hi0) / d_hi if d_hi != 0.0 else 0.0
    t_lo = (a - lo0) / d_lo if d_lo != 0.0 else 0.0
    t_hi, t_lo = _clip(t_hi, 0.0, 1.0), _clip(t_lo, 0.0, 1.0)
    t1, t2 = _mn(t_hi, t_lo), _mx(t_hi, t_lo)
    g0 = _mn(hi0, b) - _mx(lo0, a)
    g3 = _mn(hi1, b) - _mx(lo1, a)
    g1 = _mn(hi0 + t1 * d_hi, b) - _mx(lo0 + t1 * d_lo, a)
    g2 = _mn(hi0 + t2 * d_hi, b) - _mx(lo0 + t2 * d_lo, a)
    p1 = _positive_part(t1 * w, g0, g1)
    p2 = _positive_part((t2 - t1) * w, g1, g2)
    p3 = _positive_part((1.0 - t2) * w, g2, g3)
    return p1 + p2 + p3


@_jit
def _sum_j(j0: float, c: float) -> float:
    return c * j0 + c * (c - 1.0) / 2.0


@_jit
def _upto(k: float) -> float:
    return (k - 1.0) * k * (2.0 * k - 1.0) / 6.0


@_jit
def _half_strip(h_first: float, step: float, count: float, rate: float, d: float) -> float:
    """``heading_coverage._half_strips`` of one run of strips."""
    full = rate * d / 2.0
    tri_per = 1.0 / (2.0 * rate) if rate != 0.0 else math.inf
    rising = step > 0.0
    flat = step == 0.0
    if flat:
        j_cross = 0.0
    else:
        j_cross = (full - h_first) / step
    if rising:
        n_full = count - _clip(np.ceil(j_cross), 0.0, count)
    else:
        n_full = _clip(np.floor(j_cross) + 1.0, 0.0, count)
    if flat:
        n_full = count if h_first >= full else 0.0
    n_tri = count - n_full
    j0_full = n_tri if rising else 0.0
    j0_tri = 0.0 if rising else n_full
    sum_full = n_full * h_first + step * _sum_j(j0_full, n_full)
    kept = sum_full * (d / 2.0) - n_full * rate * (d * d / 8.0)
    sum_sq = (
        n_tri * h_first * h_first
        + 2.0 * h_first * step * _sum_j(j0_tri, n_tri)
        + step * step * (_upto(j0_tri + n_tri) - _upto(j0_tri))
    )
    tri = sum_sq * (tri_per if rate > 0.0 else 0.0) if n_tri > 0 else 0.0
    return kept + tri


@_jit
def _span_at(
    keys: FloatArray,
    s0: int,
    s1: int,
    sx0: FloatArray,
    slo0: FloatArray,
    sslo: FloatArray,
    shi0: FloatArray,
    sshi: FloatArray,
    base: float,
    u: float,
) -> tuple[float, float]:
    """``_Spans.at``: both chains at ``u``."""
    i = _right(keys, s0, s1, base + u) - 1
    du = u - sx0[i]
    return slo0[i] + sslo[i] * du, shi0[i] + sshi[i] * du


@_jit
def _zone_missed(
    keys: FloatArray,
    s0: int,
    s1: int,
    sx0: FloatArray,
    sx1: FloatArray,
    slo0: FloatArray,
    sslo: FloatArray,
    shi0: FloatArray,
    sshi: FloatArray,
    base: float,
    z0: float,
    z1: float,
    u_a: float,
    u_b: float,
    weight: float,
    acc: float,
) -> float:
    """``_Spans.missed`` of one strip, added piece by piece to ``acc``."""
    lo_a, hi_a = _span_at(keys, s0, s1, sx0, slo0, sslo, shi0, sshi, base, u_a)
    lo_b, hi_b = _span_at(keys, s0, s1, sx0, slo0, sslo, shi0, sshi, base, u_b)
    bottom, top = _mx(lo_a, lo_b), _mn(hi_a, hi_b)
    first = _right(keys, s0, s1, base + z0) - 1
    stop = _left(keys, s0, s1, base + z1)
    for i in range(first, stop):
        x0 = sx0[i]
        p0 = _mx(x0, z0)
        p1 = _mn(sx1[i], z1)
        du0, du1 = p0 - x0, p1 - x0
        lo0 = slo0[i] + sslo[i] * du0
        lo1 = slo0[i] + sslo[i] * du1
        hi0 = shi0[i] + sshi[i] * du0
        hi1 = shi0[i] + sshi[i] * du1
        w = _mx(p1 - p0, 0.0)
        cell = w * ((hi0 - lo0) + (hi1 - lo1)) / 2.0
        acc += weight * (cell - _covered_piece(w, lo0, lo1, hi0, hi1, bottom, top))
    return acc


@_jit_counted_by_caller
def _coverage_excess(
    u_raw: FloatArray,
    v_ring: FloatArray,
    d: float,
    out: FloatArray,
    u_ring: FloatArray,
    width: FloatArray,
    scratch: FloatArray,
) -> bool:
    """Missed area per heading of :func:`planner.heading_coverage.convex_coverage`.

    Writes ``out``; returns False (and leaves ``out`` unusable) if a chain's edges are out of
    order, where ``searchsorted`` would not find what the numpy code's does. ``u_ring``
    (like ``u_raw``), ``width`` (a row of it) and ``scratch`` (14 rows of m) are scratch.
    """
    n_headings, m = u_raw.shape
    for h in range(n_headings):
        u_min = u_raw[h, 0]
        for j in range(1, m):
            u_min = _mn(u_min, u_raw[h, j])  # .min() is exact: any order gives the minimum
        for j in range(m):
            u_ring[h, j] = u_raw[h, j] - u_min
        w_max = u_ring[h, 0]
        for j in range(1, m):
            w_max = _mx(w_max, u_ring[h, j])
        width[h] = w_max
    w_all = width[0]
    for h in range(1, n_headings):
        w_all = _mx(w_all, width[h])  # width.max(): NaN wins, as there
    big = 2.0 * w_all + 1.0
    # Per heading, scratch of at most m entries per chain and m - 1 intervals.
    lk, lc, ls, hk, hc, hs = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4], scratch[5]
    cuts, sk, sx0, sx1 = scratch[6], scratch[7], scratch[8], scratch[9]
    slo0, sslo, shi0, sshi = scratch[10], scratch[11], scratch[12], scratch[13]
    for h in range(n_headings):
        base = h * big
        start = 0
        for j in range(1, m):  # argmin: the first least
            if u_ring[h, j] < u_ring[h, start]:
                start = j
        n_lo = 0
        n_hi = 0
        for t in range(m):  # the lower chain, left to right
            ja, jb = (start + t) % m, (start + t + 1) % m
            ua, ub, va, vb = u_ring[h, ja], u_ring[h, jb], v_ring[h, ja], v_ring[h, jb]
            if ub > ua:
                s = (vb - va) / (ub - ua)
                lk[n_lo], lc[n_lo], ls[n_lo] = base + ua, va - s * ua, s
                n_lo += 1
        for t in range(m - 1, -1, -1):  # the upper chain, left to right
            ja, jb = (start + t + 1) % m, (start + t) % m
            ua, ub, va, vb = u_ring[h, ja], u_ring[h, jb], v_ring[h, ja], v_ring[h, jb]
            if ub > ua:
                s = (vb - va) / (ub - ua)
                hk[n_hi], hc[n_hi], hs[n_hi] = base + ua, va - s * ua, s
                n_hi += 1
        for i in range(1, n_lo):
            if lk[i] < lk[i - 1]:
                return False
        for i in range(1, n_hi):
            if hk[i] < hk[i - 1]:
                return False
        _sorted_into(u_ring[h], cuts)
        n = _line_count(width[h], d)
        narrow = width[h] <= d
        last_regular = -1.0 if narrow else float(n - 3)
        acc = 0.0  # np.bincount(ih, missed): interval by interval
        n_sp = 0
        for j in range(m - 1):
            x0, x1 = cuts[j], cuts[j + 1]
            if not x1 > x0:
                continue
            mid = base + (x0 + x1) / 2.0
            k_lo = _right(lk, 0, n_lo, mid) - 1
            k_hi = _right(hk, 0, n_hi, mid) - 1
            s_lo, s_hi = ls[k_lo], hs[k_hi]
            lo0 = lc[k_lo] + s_lo * x0
            hi0 = hc[k_hi] + s_hi * x0
            sk[n_sp], sx0[n_sp], sx1[n_sp] = base + x0, x0, x1
            slo0[n_sp], sslo[n_sp], shi0[n_sp], sshi[n_sp] = lo0, s_lo, hi0, s_hi
            n_sp += 1
            k1 = np.ceil(x0 / d)
            k2 = _mn(np.floor(x1 / d) - 1.0, last_regular)
            count = _mx(k2 - k1 + 1.0, 0.0)
            u_first = k1 * d + d / 2.0
            h_first = (hi0 - lo0) + (s_hi - s_lo) * (u_first - x0)
            step = (s_hi - s_lo) * d
            ahead = _mx(-s_hi, 0.0) + _mx(s_lo, 0.0)
            behind = _mx(s_hi, 0.0) + _mx(-s_lo, 0.0)
            kept_a = _half_strip(h_first, step, count, ahead, d)
            kept_b = _half_strip(h_first, step, count, behind, d)
            missed = count * d * h_first + d * step * count * (count - 1.0) / 2.0
            missed -= kept_a + kept_b
            acc += missed
        # The strips that hold a vertex, then the last lines' (np.bincount over the zones).
        acc2 = 0.0
        prev_k = math.nan
        for j in range(n_sp):
            x0, x1 = sx0[j], sx1[j]
            k1 = np.ceil(x0 / d)
            z_first, z_last = np.floor(x0 / d), np.ceil(x1 / d) - 1.0
            for which in range(2):
                if which == 0:
                    k, partial = z_first, z_first < k1
                else:
                    k, partial = z_last, z_last > np.floor(x1 / d) - 1.0
                if not (partial and k >= 0 and k <= last_regular):
                    continue
                if k == prev_k:
                    continue
                prev_k = k
                centre = k * d + d / 2.0
                acc2 = _zone_missed(
                    sk, 0, n_sp, sx0, sx1, slo0, sslo, shi0, sshi,
                    base, k * d, k * d + d, centre, centre, 1.0, acc2,
                )  # fmt: skip
        ww = width[h]
        if narrow:
            middle = ww / 2.0
            acc2 = _zone_missed(
                sk, 0, n_sp, sx0, sx1, slo0, sslo, shi0, sshi,
                base, 0.0, ww, middle, middle, 1.0, acc2,
            )  # fmt: skip
        else:
            nw = float(n)
            p_pen, p_last = (nw - 2.0) * d + d / 2.0, ww - d / 2.0
            z_start, overlap_end = (nw - 2.0) * d, (nw - 1.0) * d
            for zone in range(5):
                if zone == 0:
                    z0, z1, u_a, u_b, wt = z_start, ww - d, p_pen, p_pen, 1.0
                elif zone == 1:
                    z0, z1, u_a, u_b, wt = ww - d, overlap_end, p_pen, p_pen, 1.0
                elif zone == 2:
                    z0, z1, u_a, u_b, wt = ww - d, overlap_end, p_last, p_last, 1.0
                elif zone == 3:
                    z0, z1, u_a, u_b, wt = ww - d, overlap_end, p_pen, p_last, -1.0
                else:
                    z0, z1, u_a, u_b, wt = overlap_end, ww, p_last, p_last, 1.0
                acc2 = _zone_missed(
                    sk, 0, n_sp, sx0, sx1, slo0, sslo, shi0, sshi,
                    base, z0, z1, u_a, u_b, wt, acc2,
                )  # fmt: skip
        out[h] = acc + acc2
    return True


@_jit
def _length_aggregates(
    u_ring: FloatArray, v_ring: FloatArray, d: float, counts: IntArray, out: FloatArray
) -> None:
    """:func:`planner.ordering.score_headings`' per-heading aggregates, into ``out``.

    Rows of ``out``: working, top even, top odd, bottom even, bottom odd, u first, lo first,
    hi first, u last, lo last, hi last; ``counts`` gets the lines per heading.
    """
    n_headings, m = u_ring.shape
    k1s = np.empty(m, dtype=np.int64)
    k2s = np.empty(m, dtype=np.int64)
    groups = np.empty(m, dtype=np.int64)
    slopes, intercepts = np.empty(m), np.empty(m)
    used = np.empty(m, dtype=np.int64)
    keys = np.empty(m, dtype=np.int64)
    picks = np.empty(m, dtype=np.int64)
    order = np.empty(m, dtype=np.int64)
    # Per chain: total, even, odd, v first, v penultimate, v last, even and odd jumps (views
    # of one array zeroed per heading: a list literal would allocate eight per heading).
    sums = np.empty((8, 2))
    total, even, odd, v_first = sums[0], sums[1], sums[2], sums[3]
    v_penult, v_last, even2, odd2 = sums[4], sums[5], sums[6], sums[7]
    for h in range(n_headings):
        u_min = u_ring[h, 0]
        u_max = u_ring[h, 0]
        for j in range(1, m):
            u_min = _mn(u_min, u_ring[h, j])
            u_max = _mx(u_max, u_ring[h, j])
        width = u_max - u_min
        n = _line_count(width, d)
        narrow = width <= d
        p0 = (u_min + u_max) / 2.0 if narrow else u_min + d / 2.0
        p_last = p0 if narrow else u_max - d / 2.0
        regular = n - 1
        penult = regular - 1
        p_penult = p0 + penult * d
        # Per chain (0 lower, 1 upper), as np.bincount adds them: edge by edge.
        sums[:] = 0.0
        n_edges = 0
        for e in range(m):
            nx = e + 1 if e + 1 < m else 0
            ua, ub, va, vb = u_ring[h, e], u_ring[h, nx], v_ring[h, e], v_ring[h, nx]
            if ub == ua:
                continue
            g = 1 if ub < ua else 0
            slope = (vb - va) / (ub - ua)
            intercept = va - slope * ua
            lo, hi = _mn(ua, ub), _mx(ua, ub)
            k1 = int(_clip(np.ceil((lo - p0) / d), 0.0, float(regular)))
            k2 = int(_clip(np.ceil((hi - p0) / d), 0.0, float(regular)))
            c = k2 - k1
            total[g] += c * intercept + slope * (c * p0 + d * c * (k1 + k2 - 1) / 2.0)
            same = max(c - 1, 0)
            evens = (k2 - 2) // 2 - (k1 - 1) // 2 if same > 0 else 0
            step = d * np.sqrt(1.0 + slope * slope)
            even[g] += evens * step
            odd[g] += (same - evens) * step
            if lo <= p_last and p_last < hi:
                v_last[g] = intercept + slope * p_last
            if c > 0 and k1 <= penult and penult < k2:
                v_penult[g] = intercept + slope * p_penult
            k1s[n_edges], k2s[n_edges], groups[n_edges] = k1, k2, g
            slopes[n_edges], intercepts[n_edges] = slope, intercept
            n_edges += 1
        v_first[0], v_first[1] = v_last[0], v_last[1]
        for i in range(n_edges):
            if k2s[i] - k1s[i] > 0 and k1s[i] == 0:
                v_first[groups[i]] = intercepts[i] + slopes[i] * p0
        # Turns into an edge's first line from the edge before: edges by (chain, first line),
        # stably (np.lexsort); a merge sort, as a chain runs against the ring's order.
        n_used = 0
        for i in range(n_edges):
            if k2s[i] - k1s[i] > 0:
                keys[n_used] = groups[i] * (regular + 2) + k1s[i]
                picks[n_used] = i
                n_used += 1
        _stable_order_into(keys, n_used, order)
        for j in range(n_used):
            used[j] = picks[order[j]]
        for j in range(1, n_used):
            into, prev = used[j], used[j - 1]
            g = groups[into]
            if groups[prev] != g:
                continue
            p_into = p0 + k1s[into] * d
            jump = math.hypot(
                d,
                (intercepts[into] + slopes[into] * p_into)
                - (intercepts[prev] + slopes[prev] * (p_into - d)),
            )
            jump_even = (k1s[into] - 1) % 2 == 0
            even2[g] += jump * (1.0 if jump_even else 0.0)
            odd2[g] += jump * (0.0 if jump_even else 1.0)
        final_even = penult % 2 == 0
        for g in range(2):
            final = math.hypot(p_last - p_penult, v_last[g] - v_penult[g]) if n >= 2 else 0.0
            e_sum = even[g] + even2[g]
            o_sum = odd[g] + odd2[g]
            even[g] = e_sum + (final if final_even else 0.0)
            odd[g] = o_sum + (0.0 if final_even else final)
            total[g] = total[g] + v_last[g]
        counts[h] = n
        out[0, h] = total[1] - total[0]
        out[1, h], out[2, h], out[3, h], out[4, h] = even[1], odd[1], even[0], odd[0]
        out[5, h], out[6, h], out[7, h] = p0, v_first[0], v_first[1]
        out[8, h], out[9, h], out[10, h] = p_last, v_last[0], v_last[1]


@_jit
def _less_fitting(
    excess: FloatArray,
    width: FloatArray,
    d: float,
    area: float,
    field_m2: float,
    width_m: float,
    reach_m: float,
) -> None:
    """``excess`` becomes :func:`planner.heading_coverage.estimated_coverage`, in place.

    The closed-form coverage less :func:`planner.turn_reach.fitting_loss_m2` per field area,
    with ``width`` each heading's width: numpy's operations on each element, in its order.
    """
    for h in range(len(excess)):
        w = width[h]
        n = float(_line_count(w, d))
        last = _mn(_mx(w - (n - 1.0) * d, 0.0), d)
        strips = _mx(n - 1.0, 0.0) * d + last
        turn_ends = 2.0 * _mx(n - 2.0, 0.0) * d + d + last if n >= 2.0 else 0.0
        loss = (strips * width_m + turn_ends * reach_m) / field_m2
        excess[h] = _clip(1.0 - excess[h] / area, 0.0, 1.0) - loss


def coverage_excess(
    u_raw: FloatArray, v_ring: FloatArray, interval_m: float, widths: FloatArray | None = None
) -> FloatArray | None:
    """Missed area per heading [m²], or None where the numpy code must decide (module doc).

    ``u_raw``, ``v_ring``: the ring in each heading's sweep frame [m]; ``interval_m``: the
    line spacing [m]; ``widths``, if given, receives each heading's width
    ``u.max() - u.min()`` [m].
    """
    if u_raw.size == 0:  # no heading or no vertex: the kernel reads no bounds
        return None
    out = np.empty(len(u_raw))
    ok = _coverage_excess(
        np.ascontiguousarray(u_raw, dtype=np.float64),
        np.ascontiguousarray(v_ring, dtype=np.float64),
        float(interval_m),
        out,
        np.empty(u_raw.shape),
        np.empty(len(u_raw)) if widths is None else widths,
        np.empty((14, u_raw.shape[1])),
    )
    return out if ok else None


def estimated_coverage(
    u_raw: FloatArray,
    v_ring: FloatArray,
    interval_m: float,
    area: float,
    *,
    field_m2: float,
    width_m: float,
    reach_m: float,
) -> FloatArray | None:
    """:func:`planner.heading_coverage.estimated_coverage` compiled, or None (numpy decides)."""
    widths = np.empty(len(u_raw))
    out = coverage_excess(u_raw, v_ring, interval_m, widths)
    if out is not None:
        _less_fitting(
            out, widths, float(interval_m), float(area), float(field_m2), float(width_m),
            float(reach_m),
        )  # fmt: skip
    return out


def length_aggregates(
    u_ring: FloatArray, v_ring: FloatArray, interval_m: float
) -> tuple[IntArray, FloatArray]:
    """Lines per heading and the 11 rows of aggregates (see ``_length_aggregates``).

    ``u_ring``, ``v_ring``: the ring in each heading's sweep frame [m]; ``interval_m``: the
    line spacing [m].
    """
    counts = np.empty(len(u_ring), dtype=np.int64)
    out = np.empty((11, len(u_ring)))
    _length_aggregates(
        np.ascontiguousarray(u_ring, dtype=np.float64),
        np.ascontiguousarray(v_ring, dtype=np.float64),
        float(interval_m),
        counts,
        out,
    )
    return counts, out


def warm_up() -> None:
    """Compile this module's kernels, or load them from the disk cache, on a tiny ring.

    Only these: :func:`planner.warm_up.warm_up` warms every kernel module's (a kernel module
    imports none of the others, only :mod:`planner.kernel_helpers`).
    """
    ring_u = np.array([[0.0, 2.0, 2.0, 0.0]])
    ring_v = np.array([[0.0, 0.0, 1.0, 1.0]])
    coverage_excess(ring_u, ring_v, 1.0)
    estimated_coverage(ring_u, ring_v, 1.0, 2.0, field_m2=2.0, width_m=1.0, reach_m=0.5)
    length_aggregates(ring_u, ring_v, 1.0)
