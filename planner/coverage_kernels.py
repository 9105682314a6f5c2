"""Compiled loops for :mod:`planner.coverage`, with the numpy code's arithmetic.

:func:`planner.coverage.convex_chains` and :func:`planner.coverage.covered_cells` (with
:func:`~planner.coverage.covered_each_cell`) run for every cell and every heading planned,
on arrays of a few to a few hundred values, so their cost is the ~20 and ~120 numpy calls
each makes (a few µs apiece). These are the same computations as loops compiled by numba:
every value is computed by the same operations in the same order (``np.cumsum`` adds in
order, ``np.unique`` and a stable ``np.argsort`` give the same sequence whatever the sort,
``searchsorted`` finds the same index by a pointer walk over sorted keys), so the covered
areas, and so the plans, are the same to the last bit. The only freedom numpy leaves, the
sign of a zero at a tie of ``np.minimum``/``np.fmax``, never reaches a covered area (a sum
that starts at +0). The sums themselves (``area.sum()``, ``np.bincount``) stay in numpy.

The numpy code stays the reference: ``tests/planner/test_coverage_kernels.py`` compares the
two bit for bit, and input the kernels cannot vouch for (NaN, keys out of order, which
:func:`~planner.coverage.convex_chains` never makes) is measured by the numpy code instead.
Loaded with :mod:`planner.kernels` (same cache rules); ``warm_up`` compiles them.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from planner.kernel_helpers import _jit, read_only

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

_TIE_M = 1e-9  # planner.coverage._TIE_M


@_jit
def _chains(u_ring: FloatArray, v_ring: FloatArray) -> tuple[int, int, FloatArray]:
    """:func:`planner.coverage.convex_chains` of a ring of ≥ 1 vertex, packed.

    Returns the chains' lengths and ``[n_lo, n_hi, lo_u, lo_v, hi_u, hi_v]`` (see
    ``Chains.packed``); -1 and an empty array if the ring holds a NaN.
    """
    n = len(u_ring)
    u_lo_ring, u_hi_ring = u_ring[0], u_ring[0]
    for i in range(n):
        if u_ring[i] != u_ring[i] or v_ring[i] != v_ring[i]:
            return -1, -1, np.empty(0)
        u_lo_ring = min(u_lo_ring, u_ring[i])
        u_hi_ring = max(u_hi_ring, u_ring[i])
    near_min = u_lo_ring + _TIE_M
    near_max = u_hi_ring - _TIE_M
    # np.argmin / np.argmax over the vertices at either end: the first of the extreme value.
    lo_start = hi_end = lo_end = hi_start = -1
    for i in range(n):
        v = v_ring[i]
        if u_ring[i] <= near_min:
            if lo_start < 0 or v < v_ring[lo_start]:
                lo_start = i
            if hi_end < 0 or v > v_ring[hi_end]:
                hi_end = i
        if u_ring[i] >= near_max:
            if lo_end < 0 or v < v_ring[lo_end]:
                lo_end = i
            if hi_start < 0 or v > v_ring[hi_start]:
                hi_start = i
    n_lo = lo_end - lo_start + 1 if lo_end >= lo_start else n - lo_start + lo_end + 1
    n_hi = hi_end - hi_start + 1 if hi_end >= hi_start else n - hi_start + hi_end + 1
    packed = np.empty(2 + 2 * (n_lo + n_hi))
    packed[0], packed[1] = n_lo, n_hi
    lo_u, lo_v = packed[2 : 2 + n_lo], packed[2 + n_lo : 2 + 2 * n_lo]
    hi_u, hi_v = packed[2 + 2 * n_lo : 2 + 2 * n_lo + n_hi], packed[2 + 2 * n_lo + n_hi :]
    # np.maximum.accumulate (no NaN here): the running maximum, the later value on a tie.
    for j in range(n_lo):
        i = (lo_start + j) % n
        lo_v[j] = v_ring[i]
        lo_u[j] = u_ring[i] if j == 0 or u_ring[i] >= lo_u[j - 1] else lo_u[j - 1]
    # The upper chain runs right to left round the ring: reversed.
    for j in range(n_hi):
        i = (hi_end - j) % n
        hi_v[j] = v_ring[i]
        hi_u[j] = u_ring[i] if j == 0 or u_ring[i] >= hi_u[j - 1] else hi_u[j - 1]
    return n_lo, n_hi, packed


@_jit
def _positive(dt: float, g0: float, g1: float) -> float:
    """``coverage._integrate``'s closed form over one stretch: height linear, ``g0`` to ``g1``."""
    # np.maximum / np.minimum propagate a NaN.
    high = g0 if (g0 > g1 or g0 != g0) else g1
    low = g0 if (g0 < g1 or g0 != g0) else g1
    if low >= 0.0:
        return dt * (g0 + g1) / 2.0
    if high > 0.0:
        return dt * high * high / (2.0 * (high - low))
    return 0.0


@_jit
def _height(
    t: float, lo0: float, d_lo: float, hi0: float, d_hi: float, a: float, b: float
) -> float:
    """``min(hi, b) − max(lo, a)`` at ``t`` along the piece (np.minimum/np.maximum, NaN kept)."""
    top = hi0 + t * d_hi
    bottom = lo0 + t * d_lo
    top = top if (top < b or top != top) else b
    bottom = bottom if (bottom > a or bottom != bottom) else a
    return top - bottom


@_jit
def _piece_area(
    w: float, lo0: float, lo1: float, hi0: float, hi1: float, a: float, b: float
) -> tuple[float, float, float]:
    """``coverage._integrate`` of one piece: the areas of its three stretches."""
    d_hi, d_lo = hi1 - hi0, lo1 - lo0
    # np.fmax(q, 0) then np.fmin(., 1): a NaN becomes 0.
    q_hi, q_lo = (b - hi0) / d_hi, (a - lo0) / d_lo
    t_hi = q_hi if q_hi > 0.0 else 0.0
    t_hi = t_hi if t_hi < 1.0 else 1.0
    t_lo = q_lo if q_lo > 0.0 else 0.0
    t_lo = t_lo if t_lo < 1.0 else 1.0
    t1 = t_hi if t_hi < t_lo else t_lo
    t2 = t_hi if t_hi > t_lo else t_lo
    g0 = _height(0.0, lo0, d_lo, hi0, d_hi, a, b)
    g1 = _height(t1, lo0, d_lo, hi0, d_hi, a, b)
    g2 = _height(t2, lo0, d_lo, hi0, d_hi, a, b)
    g3 = _height(1.0, lo0, d_lo, hi0, d_hi, a, b)
    return (
        _positive((t1 - 0.0) * w, g0, g1),
        _positive((t2 - t1) * w, g1, g2),
        _positive((1.0 - t2) * w, g2, g3),
    )


@_jit
def _edge(
    chain_u: FloatArray,
    chain_v: FloatArray,
    first: int,
    stop: int,
    at: int,
    left: float,
    right: float,
) -> tuple[float, float]:
    """``coverage._laid_out_edge_values`` of one piece: ``at`` is searchsorted(mid) − 1."""
    top = max(stop - 2, first)
    at = min(max(at, first), top)
    nxt = min(at + 1, len(chain_u) - 1)
    du = chain_u[nxt] - chain_u[at]
    slope = (chain_v[nxt] - chain_v[at]) / du if du > 0.0 else 0.0
    return chain_v[at] + slope * (left - chain_u[at]), chain_v[at] + slope * (right - chain_u[at])


@_jit
def _sorted(keys: FloatArray) -> bool:
    """Whether ``keys`` is non-decreasing and free of NaN."""
    for i in range(1, len(keys)):
        if not keys[i - 1] <= keys[i]:
            return False
    return len(keys) == 0 or keys[0] == keys[0]


@_jit
def _merge(a: FloatArray, b: FloatArray) -> FloatArray:
    """Two sorted arrays as one sorted array (the values of np.sort of both)."""
    out = np.empty(len(a) + len(b))
    i = j = 0
    for k in range(len(out)):
        if j >= len(b) or (i < len(a) and a[i] <= b[j]):
            out[k] = a[i]
            i += 1
        else:
            out[k] = b[j]
            j += 1
    return out


@_jit
def _laid_out(
    packed: FloatArray,
    offsets: IntArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    d: float,
) -> tuple[bool, IntArray, FloatArray, IntArray]:
    """``coverage._laid_out`` but the odd cells' own measure (see there).

    ``packed`` holds each cell's ``Chains.packed`` in turn. Returns whether the kernel could
    vouch for the result (False: NaN, or keys out of order), the odd cells in order
    (measured on their own by the caller), each piece's three areas end to end (flat, so the
    screen sums them without a copy) and each piece's cell.
    """
    cells = len(offsets) - 1
    n = len(u)
    half = d / 2.0
    no_area, no_cell = np.zeros(0), np.zeros(0, dtype=np.int64)
    odd_cell = np.zeros(cells, dtype=np.bool_)
    sizes = np.empty((cells, 2), dtype=np.int64)
    n_lo, n_hi, p = 0, 0, 0
    for c in range(cells):
        if p + 2 > len(packed):
            return False, no_cell, no_area, no_cell
        sizes[c, 0], sizes[c, 1] = int(packed[p]), int(packed[p + 1])
        p += 2 + 2 * (sizes[c, 0] + sizes[c, 1])
        if sizes[c, 0] < 1 or sizes[c, 1] < 1 or offsets[c + 1] < offsets[c]:
            return False, no_cell, no_area, no_cell
        n_lo += sizes[c, 0]
        n_hi += sizes[c, 1]
    if p != len(packed):
        return False, no_cell, no_area, no_cell
    lo_x, lo_v, hi_x, hi_v = np.empty(n_lo), np.empty(n_lo), np.empty(n_hi), np.empty(n_hi)
    # Each cell's own stretch of the axis, an interval and a metre clear of the next.
    u_min, u_max, base = np.empty(cells), np.empty(cells), np.empty(cells)
    cell_lo, cell_hi = np.empty(cells), np.empty(cells)
    lo_start, hi_start = np.empty(cells + 1, np.int64), np.empty(cells + 1, np.int64)
    total = 0.0
    p, i_lo, i_hi = 2, 0, 0
    for c in range(cells):
        m_lo, m_hi = sizes[c, 0], sizes[c, 1]
        first_lo, first_hi = packed[p], packed[p + 2 * m_lo]
        last_lo, last_hi = packed[p + m_lo - 1], packed[p + 2 * m_lo + m_hi - 1]
        u_min[c] = first_hi if first_hi < first_lo else first_lo  # Python's min()
        u_max[c] = last_hi if last_hi > last_lo else last_lo
        base[c] = total - u_min[c]
        total = total + (u_max[c] - u_min[c] + d + 1.0)
        cell_lo[c], cell_hi[c] = u_min[c] + base[c], u_max[c] + base[c]
        lo_start[c], hi_start[c] = i_lo, i_hi
        for j in range(m_lo):
            lo_x[i_lo] = packed[p + j] + base[c]
            lo_v[i_lo] = packed[p + m_lo + j]
            i_lo += 1
        for j in range(m_hi):
            hi_x[i_hi] = packed[p + 2 * m_lo + j] + base[c]
            hi_v[i_hi] = packed[p + 2 * m_lo + m_hi + j]
            i_hi += 1
        p += 2 * (m_lo + m_hi) + 2
    lo_start[cells], hi_start[cells] = n_lo, n_hi
    if not (_sorted(lo_x) and _sorted(hi_x) and _sorted(cell_lo)):
        return False, no_cell, no_area, no_cell  # searchsorted's own answer
    # Each chain's run per cell: np.searchsorted(chain_u, cell_lo, side="left"). The runs
    # are sorted, each past the last, so that is where the run starts but for a cell whose
    # chain starts left of its own u_min, which a chain never does: checked.
    for c in range(cells):
        if (lo_start[c] > 0 and not lo_x[lo_start[c] - 1] < cell_lo[c]) or not (
            lo_x[lo_start[c]] >= cell_lo[c]
        ):
            return False, no_cell, no_area, no_cell
        if (hi_start[c] > 0 and not hi_x[hi_start[c] - 1] < cell_lo[c]) or not (
            hi_x[hi_start[c]] >= cell_lo[c]
        ):
            return False, no_cell, no_area, no_cell
    cell_of_line = np.empty(n, dtype=np.int64)
    for c in range(cells):
        for i in range(offsets[c], offsets[c + 1]):
            cell_of_line[i] = c
    s0, s1 = np.empty(n), np.empty(n)
    for i in range(n):
        x = u[i] + base[cell_of_line[i]]
        s0[i], s1[i] = x - half, x + half
    # Strips: each footprint up to the next one's start, and where two overlap, their union.
    overlap = np.zeros(max(n - 1, 0), dtype=np.bool_)
    last_pair = np.zeros(max(n - 1, 0), dtype=np.bool_)
    for c in range(cells):
        if offsets[c + 1] - offsets[c] >= 2:
            last_pair[offsets[c + 1] - 2] = True
    for i in range(n - 1):
        overlap[i] = cell_of_line[i + 1] == cell_of_line[i] and s1[i] > s0[i + 1] + _TIE_M
        if overlap[i]:
            a = v_lo[i] if (v_lo[i] > v_lo[i + 1] or v_lo[i] != v_lo[i]) else v_lo[i + 1]
            b = v_hi[i] if (v_hi[i] < v_hi[i + 1] or v_hi[i] != v_hi[i]) else v_hi[i + 1]
            if not last_pair[i] or not a <= b:
                odd_cell[cell_of_line[i]] = True
    strips = 0
    for i in range(n):
        if not odd_cell[cell_of_line[i]]:
            strips += 1 + (i < n - 1 and overlap[i])
    odd = np.flatnonzero(odd_cell)
    if strips == 0:
        return True, odd, no_area, no_cell
    # Each kept line's strip, then the overlaps' unions (np.concatenate's order).
    r0, r1 = np.empty(strips), np.empty(strips)
    r_a, r_b = np.empty(strips), np.empty(strips)
    j = 0
    for i in range(n):
        if not odd_cell[cell_of_line[i]]:
            r0[j] = s1[i - 1] if i > 0 and overlap[i - 1] else s0[i]
            r1[j] = s0[i + 1] if i < n - 1 and overlap[i] else s1[i]
            r_a[j], r_b[j] = v_lo[i], v_hi[i]
            j += 1
    kept = j
    for i in range(n - 1):
        if overlap[i] and not odd_cell[cell_of_line[i]]:
            r0[j], r1[j] = s0[i + 1], s1[i]
            a0, a1, b0, b1 = v_lo[i], v_lo[i + 1], v_hi[i], v_hi[i + 1]
            r_a[j] = a0 if (a0 < a1 or a0 != a0) else a1
            r_b[j] = b0 if (b0 > b1 or b0 != b0) else b1
            j += 1
    # np.argsort(kind="stable") of the starts: both runs are in order (lines left to right),
    # so merge them, the first run first on a tie; else an insertion sort.
    merged = _sorted(r0[:kept]) and _sorted(r0[kept:])
    if merged:
        order = np.empty(strips, dtype=np.int64)
        i, j = 0, kept
        for q in range(strips):
            if j >= strips or (i < kept and r0[i] <= r0[j]):
                order[q] = i
                i += 1
            else:
                order[q] = j
                j += 1
    else:
        order = np.arange(strips)
        for i in range(1, strips):
            key = order[i]
            if r0[key] != r0[key]:
                return False, no_cell, no_area, no_cell
            at = i
            while at > 0 and r0[order[at - 1]] > r0[key]:
                order[at] = order[at - 1]
                at -= 1
            order[at] = key
    if merged and kept == strips:  # no overlaps: the merge keeps the lines' order
        s0s, s1s, a_s, b_s = r0, r1, r_a, r_b
    else:
        s0s, s1s, a_s, b_s = r0[order], r1[order], r_a[order], r_b[order]
    # The cuts: np.unique of the chains and the strips' ends (all sorted, so merged).
    if not (_sorted(s0s) and _sorted(s1s)):
        if not _sorted(s0s):
            return False, no_cell, no_area, no_cell
        ends = np.sort(s1s)
        if ends[-1] != ends[-1]:
            return False, no_cell, no_area, no_cell
    else:
        ends = s1s
    cuts = _merge(_merge(lo_x, hi_x), _merge(s0s, ends))
    m = 1
    for i in range(1, len(cuts)):
        if cuts[i] != cuts[m - 1]:
            cuts[m] = cuts[i]
            m += 1
    area = np.empty(3 * max(m - 1, 0))
    cell_of = np.empty(max(m - 1, 0), dtype=np.int64)
    pieces = 0
    # Walk the sorted keys: the number at or below mid is searchsorted(side="right").
    p_cell = p_strip = p_lo = p_hi = 0
    for q in range(m - 1):
        left, right = cuts[q], cuts[q + 1]
        mid = (left + right) / 2.0
        while p_cell < cells and cell_lo[p_cell] <= mid:
            p_cell += 1
        while p_strip < strips and s0s[p_strip] <= mid:
            p_strip += 1
        while p_lo < n_lo and lo_x[p_lo] <= mid:
            p_lo += 1
        while p_hi < n_hi and hi_x[p_hi] <= mid:
            p_hi += 1
        c, k = p_cell - 1, p_strip - 1
        if c < 0 or k < 0 or not (mid < cell_hi[c] and mid < s1s[k]):
            continue
        lo0, lo1 = _edge(lo_x, lo_v, lo_start[c], lo_start[c + 1], p_lo - 1, left, right)
        hi0, hi1 = _edge(hi_x, hi_v, hi_start[c], hi_start[c + 1], p_hi - 1, left, right)
        area[3 * pieces], area[3 * pieces + 1], area[3 * pieces + 2] = _piece_area(
            right - left, lo0, lo1, hi0, hi1, a_s[k], b_s[k]
        )
        cell_of[pieces] = c
        pieces += 1
    return True, odd, area[: 3 * pieces], cell_of[:pieces]


def packed_chains(u_ring: FloatArray, v_ring: FloatArray) -> tuple[int, int, FloatArray] | None:
    """Return :func:`planner.coverage.convex_chains` packed (``_chains``), or None for numpy."""
    u = read_only(u_ring, np.float64)
    v = read_only(v_ring, np.float64)
    if len(u) == 0 or len(u) != len(v):
        return None
    n_lo, n_hi, packed = _chains(u, v)
    return (n_lo, n_hi, packed) if n_lo >= 0 else None


def laid_out(
    packed: FloatArray,
    offsets: IntArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    interval_m: float,
) -> tuple[IntArray, FloatArray, IntArray] | None:
    """Return ``coverage._laid_out``'s odd cells, pieces' areas and pieces' cells (or None).

    ``packed``: each cell's ``Chains.packed`` in turn. ``offsets`` must start at 0 and end at
    ``len(u)``; ``v_lo`` and ``v_hi`` as long as ``u`` (else None: the numpy code decides);
    ``interval_m`` the line spacing [m].
    """
    if not len(v_lo) == len(v_hi) == len(u):
        return None
    ok, odd, area, cell = _laid_out(
        read_only(packed, np.float64),
        read_only(offsets, np.int64),
        read_only(u, np.float64),
        read_only(v_lo, np.float64),
        read_only(v_hi, np.float64),
        float(interval_m),
    )
    return (odd, area.reshape(-1, 3), cell) if ok else None


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on a tiny cell."""
    from planner import coverage

    chains = coverage.convex_chains(np.array([0.0, 2.0, 2.0, 0.0]), np.array([0.0, 0.0, 1.0, 1.0]))
    coverage.covered_cells(
        [chains], np.array([0, 1]), np.array([1.0]), np.zeros(1), np.ones(1), 1.0
    )
