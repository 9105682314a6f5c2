"""Compiled loops for a non-convex heading's cells and lines, with the numpy code's arithmetic.

A non-convex field is planned at about eight headings, and each is decomposed into cells
(:func:`planner.decomposition.decompose_sweep`) and its lines scanned
(:func:`planner.lines.scan_cells`). The numpy code is vectorised, but a field has a few cells
of a few dozen vertices, so its cost is the ~200 numpy calls per heading (a few µs apiece) and
the per-cell calls. These kernels do the same computations in loops, compiled by numba: every
value is computed by the same operations in the same order (the searches run on the same keys,
ties sort as ``np.lexsort`` sorts them, the last of two writes to a line wins as in numpy's
fancy assignment), so the cells and lines, and so the plans, are the same to the last bit. The
rotation into the sweep frame, the critical cuts (``np.unique``) and the cells' areas stay in
numpy. Every kernel takes one array type (C-contiguous, writable), so :func:`warm_up` compiles
all that the plans call. The cells' order searches are :mod:`planner.order_kernels`; the
heading scores' terms and the router's corner test are :mod:`planner.edge_kernels`.

The numpy code stays the reference: ``tests/planner/test_cell_kernels.py`` compares the two
bit for bit on random fields and the real ones. Like :mod:`planner.kernels`, the kernels are
cached on disk (``cache=True``) and compiled, or loaded, by :func:`warm_up`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import _jit, _left, _line_count, _right

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

_SNAP_M = 1e-6  # planner.decomposition._SNAP_M
_REPEAT_M = 1e-9  # planner.decomposition._drop_repeats


@_jit
def _sweep_cells(
    u_in: FloatArray,
    v: FloatArray,
    turn: BoolArray,
    cuts: FloatArray,
    sizes: IntArray,
    first: IntArray,
    ring_of: IntArray,
    local: IntArray,
    nxt: IntArray,
    prv: IntArray,
) -> tuple[int, FloatArray, FloatArray, IntArray]:
    """:func:`planner.decomposition._pieces` then ``_cells`` up to ``_drop_repeats``.

    Returns ``(status, u, v, sizes)``: status 1 with the cells' rings laid end to end (before
    the size and area filters), 0 where ``_pieces`` returns None (degenerate: the clipping
    fallback), -1 where the numpy code is to decide (no pieces at all).
    """
    empty_f = np.empty(0)
    empty_i = np.empty(0, dtype=np.int64)
    nv = len(u_in)
    nc = len(cuts)
    # Vertices within a hair of a cut go onto it (critical ones always).
    u = np.empty(nv)
    worst = -np.inf
    for i in range(nv):
        at = _left(cuts, 0, nc, u_in[i])
        at = min(max(at, 1), nc - 1)
        nearer = at - 1 if u_in[i] - cuts[at - 1] <= cuts[at] - u_in[i] else at
        gap = abs(u_in[i] - cuts[nearer])
        if turn[i]:
            worst = max(worst, gap)
        u[i] = cuts[nearer] if (turn[i] or gap <= _SNAP_M) else u_in[i]
    if worst > 100.0 * _SNAP_M:
        return 0, empty_f, empty_f, empty_i
    sign = np.empty(nv, dtype=np.int64)
    for i in range(nv):
        step = u[nxt[i]] - u[i]
        sign[i] = 1 if step > 0.0 else (-1 if step < 0.0 else 0)
    begins = np.zeros(nv, dtype=np.bool_)
    for i in range(nv):
        begins[i] = sign[i] != 0 and sign[i] != sign[prv[i]]
    # Each ring rotated to begin with a run, so that runs are contiguous.
    n_rings = len(sizes)
    edge = np.empty(nv, dtype=np.int64)
    n_edges = 0
    for r in range(n_rings):
        shift = sizes[r]
        for j in range(sizes[r]):
            if begins[first[r] + j]:
                shift = j
                break
        if shift >= sizes[r]:
            return 0, empty_f, empty_f, empty_i
        for j in range(sizes[r]):
            k = first[r] + (j + shift) % sizes[r]
            if sign[k] != 0:
                edge[n_edges] = k
                n_edges += 1
    runs = 0
    for e in range(n_edges):
        if begins[edge[e]]:
            runs += 1
    # Points of every run: its edges' starts and its last edge's end; upper chains reversed.
    count = np.zeros(runs, dtype=np.int64)
    run_sign = np.empty(runs, dtype=np.int64)
    r = -1
    for e in range(n_edges):
        if begins[edge[e]]:
            r += 1
            run_sign[r] = sign[edge[e]]
        count[r] += 1
    offsets = np.zeros(runs + 1, dtype=np.int64)
    for r in range(runs):
        count[r] += 1
        offsets[r + 1] = offsets[r] + count[r]
    n_points = offsets[runs]
    point = np.empty(n_points, dtype=np.int64)
    e = 0
    for r in range(runs):
        m = count[r] - 1
        for j in range(m):
            point[offsets[r] + j] = edge[e + j]
        point[offsets[r] + m] = nxt[edge[e + m - 1]]
        e += m
        if run_sign[r] < 0:
            lo, hi = offsets[r], offsets[r + 1] - 1
            while lo < hi:
                point[lo], point[hi] = point[hi], point[lo]
                lo += 1
                hi -= 1
    pu = np.empty(n_points)
    pv = np.empty(n_points)
    for p in range(n_points):
        pu[p] = u[point[p]]
        pv[p] = v[point[p]]
    u_first = np.empty(runs)
    u_last = np.empty(runs)
    i0 = np.empty(runs, dtype=np.int64)
    i1 = np.empty(runs, dtype=np.int64)
    for r in range(runs):
        for p in range(offsets[r] + 1, offsets[r + 1]):
            if not pu[p] - pu[p - 1] > 0.0:
                return 0, empty_f, empty_f, empty_i
    for r in range(runs):
        u_first[r] = pu[offsets[r]]
        u_last[r] = pu[offsets[r + 1] - 1]
        i0[r] = _left(cuts, 0, nc, u_first[r])
        i1[r] = _left(cuts, 0, nc, u_last[r])
        if cuts[min(i0[r], nc - 1)] != u_first[r] or cuts[min(i1[r], nc - 1)] != u_last[r]:
            return 0, empty_f, empty_f, empty_i
    # Every (run, slab) it spans, found by the numpy code's searches over its keys.
    base = np.empty(runs)
    total = 0.0
    for r in range(runs):
        base[r] = total
        total = total + (u_last[r] - u_first[r] + 1.0)
    key = np.empty(n_points)
    for r in range(runs):
        for p in range(offsets[r], offsets[r + 1]):
            key[p] = pu[p] - u_first[r] + base[r]
    n_pairs = 0
    for r in range(runs):
        n_pairs += i1[r] - i0[r]
    pair_slab = np.empty(n_pairs, dtype=np.int64)
    pair_run = np.empty(n_pairs, dtype=np.int64)
    pa = np.empty(n_pairs, dtype=np.int64)
    pb = np.empty(n_pairs, dtype=np.int64)
    v_left = np.empty(n_pairs)
    v_right = np.empty(n_pairs)
    v_mid = np.empty(n_pairs)
    q = 0
    for r in range(runs):
        for s in range(i0[r], i1[r]):
            left, right = cuts[s], cuts[s + 1]
            a = _right(key, 0, n_points, left - u_first[r] + base[r])
            b = _left(key, 0, n_points, right - u_first[r] + base[r])
            middle = (left + right) / 2.0
            mid = _right(key, 0, n_points, middle - u_first[r] + base[r])
            pair_slab[q], pair_run[q], pa[q], pb[q] = s, r, a, b
            v_left[q] = _value(pu, pv, a, left)
            v_right[q] = _value(pu, pv, b, right)
            v_mid[q] = _value(pu, pv, mid, middle)
            q += 1
    # np.lexsort((v_mid, pair_slab)): by slab, then v_mid, ties in pair order.
    per_slab = np.zeros(nc + 1, dtype=np.int64)
    for q in range(n_pairs):
        per_slab[pair_slab[q] + 1] += 1
    for s in range(nc):
        per_slab[s + 1] += per_slab[s]
    ranked = np.empty(n_pairs, dtype=np.int64)
    fill = per_slab.copy()
    for q in range(n_pairs):
        ranked[fill[pair_slab[q]]] = q
        fill[pair_slab[q]] += 1
    for s in range(nc):
        for i in range(per_slab[s] + 1, per_slab[s + 1]):
            x = ranked[i]
            j = i - 1
            while j >= per_slab[s] and v_mid[x] < v_mid[ranked[j]]:
                ranked[j + 1] = ranked[j]
                j -= 1
            ranked[j + 1] = x
    for s in range(nc):
        for i in range(per_slab[s], per_slab[s + 1]):
            expected = 1 if (i - per_slab[s]) % 2 == 0 else -1
            if run_sign[pair_run[ranked[i]]] != expected:
                return 0, empty_f, empty_f, empty_i
    if n_pairs % 2 != 0:
        return 0, empty_f, empty_f, empty_i
    n = n_pairs // 2
    if n == 0:
        return -1, empty_f, empty_f, empty_i
    lower = np.empty(n, dtype=np.int64)
    upper = np.empty(n, dtype=np.int64)
    for k in range(n):
        lower[k], upper[k] = ranked[2 * k], ranked[2 * k + 1]
        if pair_slab[lower[k]] != pair_slab[upper[k]]:
            return 0, empty_f, empty_f, empty_i
    # _cells: the pieces' connections across the cuts (piece k: lower[k] below upper[k]).
    slab_start = np.zeros(nc + 1, dtype=np.int64)
    for k in range(n):
        slab_start[pair_slab[lower[k]] + 1] += 1
    for s in range(nc):
        slab_start[s + 1] += slab_start[s]
    right_count = np.zeros(n, dtype=np.int64)
    left_count = np.zeros(n, dtype=np.int64)
    right_one = np.full(n, -1, dtype=np.int64)
    left_one = np.full(n, -1, dtype=np.int64)
    for s in range(nc - 2):
        for a in range(slab_start[s], slab_start[s + 1]):
            a0, a1 = v_right[lower[a]], v_right[upper[a]]
            for b in range(slab_start[s + 1], slab_start[s + 2]):
                b0, b1 = v_left[lower[b]], v_left[upper[b]]
                top = b1 if b1 < a1 else a1
                bottom = b0 if b0 > a0 else a0
                if top - bottom > _SNAP_M:
                    if right_count[a] == 0:
                        right_one[a] = b
                    right_count[a] += 1
                    if left_count[b] == 0:
                        left_one[b] = a
                    left_count[b] += 1
    # Each cell: the lower chains of its run of pieces, then the upper ones backwards.
    length = np.empty(n_pairs, dtype=np.int64)
    for q in range(n_pairs):
        length[q] = pb[q] - pa[q] + 2
    ring_u = np.empty(2 * int(length.sum()))
    ring_v = np.empty(len(ring_u))
    cell_sizes = np.empty(n, dtype=np.int64)
    run = np.empty(n, dtype=np.int64)
    n_cells = 0
    at = 0
    for k in range(n):
        if left_count[k] == 1 and right_count[left_one[k]] == 1:
            continue
        run[0] = k
        m = 1
        while right_count[run[m - 1]] == 1 and left_count[right_one[run[m - 1]]] == 1:
            run[m] = right_one[run[m - 1]]
            m += 1
        begin = at
        for j in range(m):
            q = lower[run[j]]
            ring_u[at], ring_v[at] = cuts[pair_slab[q]], v_left[q]
            at += 1
            for i in range(pa[q], pb[q]):
                ring_u[at], ring_v[at] = pu[i], pv[i]
                at += 1
            ring_u[at], ring_v[at] = cuts[pair_slab[q] + 1], v_right[q]
            at += 1
        for j in range(m - 1, -1, -1):
            q = upper[run[j]]
            ring_u[at], ring_v[at] = cuts[pair_slab[q] + 1], v_right[q]
            at += 1
            for i in range(pb[q] - 1, pa[q] - 1, -1):
                ring_u[at], ring_v[at] = pu[i], pv[i]
                at += 1
            ring_u[at], ring_v[at] = cuts[pair_slab[q]], v_left[q]
            at += 1
        cell_sizes[n_cells] = at - begin
        n_cells += 1
    # _drop_repeats: every vertex that repeats the next one of its ring (cyclically).
    out_u = np.empty(at)
    out_v = np.empty(at)
    kept = np.zeros(n_cells, dtype=np.int64)
    begin = 0
    w = 0
    for c in range(n_cells):
        size = cell_sizes[c]
        for i in range(begin, begin + size):
            j = i + 1 if i + 1 < begin + size else begin
            if np.hypot(ring_u[j] - ring_u[i], ring_v[j] - ring_v[i]) > _REPEAT_M:
                out_u[w], out_v[w] = ring_u[i], ring_v[i]
                w += 1
                kept[c] += 1
        begin += size
    return 1, out_u[:w], out_v[:w], kept


@_jit
def _value(pu: FloatArray, pv: FloatArray, i: int, at_u: float) -> float:
    """Return the chain ``pu, pv`` at ``at_u``, on its edge ending at point ``i`` (``_pieces``)."""
    slope = (pv[i] - pv[i - 1]) / (pu[i] - pu[i - 1])
    return float(pv[i - 1] + (at_u - pu[i - 1]) * slope)


def sweep_cells(
    u: FloatArray,
    v: FloatArray,
    turn: BoolArray,
    cuts: FloatArray,
    sizes: IntArray,
    first: IntArray,
    ring_of: IntArray,
    local: IntArray,
    nxt: IntArray,
    prv: IntArray,
) -> tuple[int, FloatArray, FloatArray, IntArray]:
    """Cut the rings at ``cuts`` and merge the pieces into cells, compiled.

    Parameters
    ----------
    u, v : ndarray
        Every ring's vertices in the sweep frame, not snapped [m].
    turn : ndarray of bool
        The critical vertices.
    cuts : ndarray
        Sorted, snapped ``u`` of the critical vertices (at least three) [m].
    sizes, first, ring_of, local, nxt, prv : ndarray of int
        The rings' layout (:class:`planner.decomposition.SweepRings`).

    Returns
    -------
    status : int
        1: the cells follow; 0: degenerate (``_pieces`` returns None); -1: let the numpy
        code decide.
    u, v : ndarray
        The cells' rings laid end to end, repeated vertices dropped [m].
    sizes : ndarray of int
        Vertices per cell (before dropping cells of fewer than three).
    """
    return _sweep_cells(u, v, turn, cuts, sizes, first, ring_of, local, nxt, prv)


@_jit
def _scan(
    u1: FloatArray,
    v1: FloatArray,
    starts: IntArray,
    sizes: IntArray,
    d: float,
    edge: float,
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray]:
    """:func:`planner.lines.scan_cells` on rings laid end to end."""
    m = len(sizes)
    n = np.empty(m, dtype=np.int64)
    first = np.empty(m)
    last = np.empty(m)
    offsets = np.zeros(m + 1, dtype=np.int64)
    for c in range(m):
        lo = u1[starts[c]]
        hi = u1[starts[c]]
        for i in range(starts[c] + 1, starts[c] + sizes[c]):
            if u1[i] < lo:
                lo = u1[i]
            if u1[i] > hi:
                hi = u1[i]
        width = hi - lo
        w = width - 2.0 * edge + d
        n[c] = _line_count(w, d)
        if width - 2.0 * edge <= 0.0:
            first[c] = (lo + hi) / 2.0
            last[c] = first[c]
        else:
            first[c] = lo + edge
            last[c] = hi - edge
        offsets[c + 1] = offsets[c] + n[c]
    total = offsets[m]
    u = np.empty(total)
    for c in range(m):
        for k in range(n[c]):
            u[offsets[c] + k] = last[c] if k == n[c] - 1 else first[c] + k * d
    v_lo = np.empty(total)
    v_hi = np.empty(total)
    for lower in (True, False):
        target = v_lo if lower else v_hi
        for c in range(m):
            end = starts[c] + sizes[c]
            for i in range(starts[c], end):
                j = i + 1 if i + 1 < end else starts[c]
                if lower:
                    if not u1[j] > u1[i]:
                        continue
                    lo, hi = u1[i], u1[j]
                else:
                    if not u1[j] < u1[i]:
                        continue
                    lo, hi = u1[j], u1[i]
                k1 = _lines_left_of(lo, first[c], last[c], n[c], d)
                k2 = _lines_left_of(hi, first[c], last[c], n[c], d)
                for k in range(k1, k2):
                    line = offsets[c] + k
                    target[line] = v1[i] + (u[line] - u1[i]) * (v1[j] - v1[i]) / (u1[j] - u1[i])
    return offsets, u, v_lo, v_hi


@_jit
def _lines_left_of(value: float, first: float, last: float, n: int, d: float) -> int:
    """:func:`planner.lines._lines_left_of` of one value."""
    regular = np.ceil((value - first) / d)
    top = float(n - 1)
    if regular != regular:
        clipped = regular
    else:
        clipped = regular if regular > 0.0 else 0.0
        clipped = clipped if clipped < top else top
    return int(clipped) + (1 if last < value else 0)


def scan_rings(
    u: FloatArray, v: FloatArray, sizes: IntArray, interval_m: float, edge_m: float
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray]:
    """:func:`planner.lines.scan_cells` of rings laid end to end, compiled.

    Returns
    -------
    offsets : ndarray of int
    u, v_lo, v_hi : ndarray
        The lines, as the :class:`planner.lines.LineScan` fields.
    """
    starts = np.zeros(len(sizes), dtype=np.int64)
    np.cumsum(sizes[:-1], out=starts[1:])
    return _scan(u, v, starts, sizes, float(interval_m), float(edge_m))


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on a tiny field."""
    # An L: one cut through its inner corner, three cells at 135°.
    from shapely import Polygon

    from planner.decomposition import decompose_sweep

    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    rings = decompose_sweep(ell, 135.0)
    u = np.concatenate([r[0] for r in rings])
    v = np.concatenate([r[1] for r in rings])
    sizes = np.array([len(r[0]) for r in rings], dtype=np.int64)
    scan_rings(u, v, sizes, 4.0, 2.0)
