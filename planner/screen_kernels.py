"""Many headings of one field screened in one compiled call: what each heading's cells cover.

:func:`planner.cell_plans.cover_heading` decomposes the field at a heading into cells, scans
their lines and measures what the lines cover. Its cores are compiled
(:mod:`planner.cell_kernels`, :mod:`planner.coverage_kernels`), but the Python around them (the
rotation, the critical cuts, the cells' rings and chains as objects, the sums) makes it cost
about 0.5 ms a heading on the real fields. :func:`screen_covers` runs the whole of it for
every heading in one compiled loop that calls those same cores, and returns only the figures:
covered area, lines and turns (``bench/screen_speed.py``: about 8 times faster).

The glue that lives in numpy there is compiled here with the numpy code's arithmetic, as
:mod:`planner.cell_kernels` does: the rotation (``to_sweep``'s products, with numpy's own
cosines), the cuts (``decomposition._cuts``), the cells' size and area filter
(``decomposition._rings``, whose ``np.add.reduceat`` adds by numpy's pairwise rule), the
measure of a cell whose footprints the laid-out form cannot take (``coverage.covered_area``)
and the total (``covered_cells``, whose ``area.sum()`` adds by the same pairwise rule). So the
figures are :func:`~planner.cell_plans.cover_heading`'s to the last bit (but the sign of a
zero, as in :mod:`planner.cell_kernels`). What the cores leave to numpy or shapely (a
boundary too degenerate for the sweep, which shapely clips; footprints wider than the lines'
spacing; NaN) is measured by :func:`~planner.cell_plans.cover_heading` itself, for that
heading. ``tests/planner/test_screen_kernels.py`` holds the two equal on real and random
fields, and each compiled twin equal to its numpy original.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
import shapely

from planner.cell_kernels import _scan, _sweep_cells
from planner.coverage_kernels import _chains, _edge, _laid_out, _piece_area
from planner.decomposition import SweepRings
from planner.fit_screen import CACHED_SLIDES, TurnTable, _fit_cell
from planner.kernel_helpers import _clip, _jit, _right

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

_SNAP_M = 1e-6  # planner.decomposition._SNAP_M
_MIN_CELL_M2 = 1e-6  # planner.decomposition._MIN_CELL_M2
_TIE_M = 1e-9  # planner.coverage._TIE_M
#: numpy's pairwise summation: blocks of this many values are added eight ways at once.
_PW_BLOCKSIZE = 128


#: A heading's status: screened here, or left to :func:`planner.cell_plans.cover_heading`.
_SCREENED = 0
_BY_PYTHON = 1


@_jit
def _block_sum(values: FloatArray, start: int, n: int) -> float:
    """Add at most ``_PW_BLOCKSIZE`` values as numpy's ``pairwise_sum`` does: eight ways."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += values[start + i]
        return res
    r0, r1, r2, r3 = values[start], values[start + 1], values[start + 2], values[start + 3]
    r4, r5, r6, r7 = values[start + 4], values[start + 5], values[start + 6], values[start + 7]
    i = 8
    while i < n - n % 8:
        r0 += values[start + i]
        r1 += values[start + i + 1]
        r2 += values[start + i + 2]
        r3 += values[start + i + 3]
        r4 += values[start + i + 4]
        r5 += values[start + i + 5]
        r6 += values[start + i + 6]
        r7 += values[start + i + 7]
        i += 8
    total: float = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        total += values[start + i]
        i += 1
    return total


@_jit
def _pairwise_sum(values: FloatArray, start: int, n: int) -> float:
    """Add ``values[start:start + n]`` as numpy's ``pairwise_sum`` does (``np.add.reduce``).

    ``values.sum()`` is ``0.0 +`` this; a segment of ``np.add.reduceat`` is its first value
    ``+`` this of the rest. Above a block, numpy adds the sums of two halves (the first a
    multiple of 8 long); that recursion runs here on a stack of its own (numba's disk cache
    mishandles recursive functions: they crash when loaded).
    """
    if n <= _PW_BLOCKSIZE:
        return _block_sum(values, start, n)
    # Frames: a span, its phase (0 new, 1 left half pending, 2 right half pending), its left sum.
    depth = 64  # spans halve: 2**64 values
    at, count = np.empty(depth, np.int64), np.empty(depth, np.int64)
    phase, left = np.zeros(depth, np.int64), np.empty(depth)
    top = 0
    at[0], count[0], phase[0] = start, n, 0
    result = 0.0
    while True:
        if phase[top] == 0 and count[top] > _PW_BLOCKSIZE:
            half = count[top] // 2
            half -= half % 8
            phase[top] = 1
            top += 1
            at[top], count[top], phase[top] = at[top - 1], half, 0
            continue
        # This frame's sum is known: a block's, or both halves'.
        result = _block_sum(values, at[top], count[top]) if phase[top] == 0 else left[top] + result
        top -= 1
        if top < 0:
            return result
        if phase[top] == 1:  # the left half is done: on to the right half
            half = count[top] // 2
            half -= half % 8
            left[top] = result
            phase[top] = 2
            top += 1
            at[top], count[top], phase[top] = at[top - 1] + half, count[top - 1] - half, 0
        else:
            phase[top] = 3  # both halves done: its sum is left + result, next round


@_jit
def _cuts(critical_u: FloatArray) -> FloatArray:
    """``planner.decomposition._cuts``: sorted, snapped ``u`` of the critical vertices (no NaN).

    Sorts ``critical_u`` in place and returns a view of it.
    """
    cuts = critical_u
    cuts.sort()
    m = 0
    for i in range(len(cuts)):  # np.unique
        if m == 0 or cuts[i] != cuts[m - 1]:
            cuts[m] = cuts[i]
            m += 1
    keep = np.empty(m, dtype=np.bool_)
    for i in range(m):
        keep[i] = i == 0 or i == m - 1 or cuts[i] - cuts[i - 1] > _SNAP_M
    kept = 0
    for i in range(m):
        if keep[i]:
            cuts[kept] = cuts[i]
            kept += 1
    if kept >= 2 and cuts[kept - 1] - cuts[kept - 2] <= _SNAP_M:
        cuts[kept - 2] = cuts[kept - 1]
        kept -= 1
    return cuts[:kept]


@_jit
def _rings(
    u: FloatArray, v: FloatArray, sizes: IntArray
) -> tuple[FloatArray, FloatArray, IntArray]:
    """``planner.decomposition._rings`` laid end to end: the rings of ≥ 3 vertices and area."""
    out_u, out_v = np.empty(len(u)), np.empty(len(u))
    out_sizes = np.empty(len(sizes), dtype=np.int64)
    twice = np.empty(len(u))
    n_out = w = 0
    start = 0
    for r in range(len(sizes)):
        size = sizes[r]
        if size >= 3:
            for i in range(size):
                j = start + (i + 1 if i + 1 < size else 0)
                twice[i] = u[start + i] * v[j] - v[start + i] * u[j]
            # np.add.reduceat: the segment's first value, then numpy's sum of the rest.
            if (twice[0] + _pairwise_sum(twice, 1, size - 1)) / 2.0 > _MIN_CELL_M2:
                for i in range(start, start + size):
                    out_u[w], out_v[w] = u[i], v[i]
                    w += 1
                out_sizes[n_out] = size
                n_out += 1
        start += size
    return out_u[:w], out_v[:w], out_sizes[:n_out]


@_jit
def _grown(buffer: npt.NDArray[Any], used: int, more: int) -> npt.NDArray[Any]:
    """Return ``buffer`` with room for ``more`` values after ``used`` (else a longer copy)."""
    if used + more <= len(buffer):
        return buffer
    out = np.empty(max(2 * len(buffer), used + more), dtype=buffer.dtype)
    out[:used] = buffer[:used]
    return out


@_jit
def _part_cells(
    x: FloatArray,
    y: FloatArray,
    sizes: IntArray,
    first: IntArray,
    ring_of: IntArray,
    local: IntArray,
    nxt: IntArray,
    prv: IntArray,
    cos_t: float,
    sin_t: float,
) -> tuple[bool, FloatArray, FloatArray, IntArray]:
    """``planner.decomposition.decompose_sweep`` of one part, its rings laid end to end.

    Returns False (and empty arrays) where that function leaves the cells to numpy or shapely.
    """
    n = len(x)
    u, v = np.empty(n), np.empty(n)
    for i in range(n):  # planner.lines.to_sweep
        u[i] = x[i] * cos_t - y[i] * sin_t
        v[i] = x[i] * sin_t + y[i] * cos_t
    turn = np.empty(n, dtype=np.bool_)
    n_turn = 0
    for i in range(n):
        turn[i] = (u[i] - u[prv[i]]) * (u[nxt[i]] - u[i]) <= 0.0
        n_turn += turn[i]
    critical = np.empty(n_turn)
    k = 0
    for i in range(n):
        if turn[i]:
            critical[k] = u[i]
            k += 1
    cuts = _cuts(critical)
    if len(cuts) <= 2:
        outer = sizes[0]
        return True, u[:outer].copy(), v[:outer].copy(), sizes[:1].copy()
    status, cell_u, cell_v, cell_sizes = _sweep_cells(
        u, v, turn, cuts, sizes, first, ring_of, local, nxt, prv
    )
    if status != 1:
        return False, u[:0], v[:0], sizes[:0]
    ring_u, ring_v, ring_sizes = _rings(cell_u, cell_v, cell_sizes)
    return True, ring_u, ring_v, ring_sizes


@_jit
def _covered(
    chains: FloatArray, s0: FloatArray, s1: FloatArray, a: FloatArray, b: FloatArray
) -> float:
    """``planner.coverage._covered`` of one cell's packed chains, for disjoint sorted strips."""
    n_lo, n_hi = int(chains[0]), int(chains[1])
    lo_u, lo_v = chains[2 : 2 + n_lo], chains[2 + n_lo : 2 + 2 * n_lo]
    hi_u = chains[2 + 2 * n_lo : 2 + 2 * n_lo + n_hi]
    hi_v = chains[2 + 2 * n_lo + n_hi :]
    # Chains.u_min and u_max: Python's min() and max() of the chains' ends.
    u_min = hi_u[0] if hi_u[0] < lo_u[0] else lo_u[0]
    u_max = hi_u[-1] if hi_u[-1] > lo_u[-1] else lo_u[-1]
    strips = len(s0)
    cuts = np.empty(n_lo + n_hi + 2 * strips)
    for i in range(n_lo):
        cuts[i] = _clip(lo_u[i], u_min, u_max)
    for i in range(n_hi):
        cuts[n_lo + i] = _clip(hi_u[i], u_min, u_max)
    for i in range(strips):
        cuts[n_lo + n_hi + i] = _clip(s0[i], u_min, u_max)
        cuts[n_lo + n_hi + strips + i] = _clip(s1[i], u_min, u_max)
    cuts = np.sort(cuts)
    m = 0
    for i in range(len(cuts)):  # np.unique
        if m == 0 or cuts[i] != cuts[m - 1]:
            cuts[m] = cuts[i]
            m += 1
    area = np.empty(3 * max(m - 1, 0))
    pieces = 0
    for q in range(m - 1):
        left, right = cuts[q], cuts[q + 1]
        mid = (left + right) / 2.0
        k = _right(s0, 0, strips, mid) - 1
        if not (k >= 0 and mid < s1[max(k, 0)]):
            continue
        # coverage._edge_values of either chain (a chain of one point is level).
        if n_lo < 2:
            lo0 = lo1 = lo_v[0]
        else:
            lo0, lo1 = _edge(lo_u, lo_v, 0, n_lo, _right(lo_u, 0, n_lo, mid) - 1, left, right)
        if n_hi < 2:
            hi0 = hi1 = hi_v[0]
        else:
            hi0, hi1 = _edge(hi_u, hi_v, 0, n_hi, _right(hi_u, 0, n_hi, mid) - 1, left, right)
        area[3 * pieces], area[3 * pieces + 1], area[3 * pieces + 2] = _piece_area(
            right - left, lo0, lo1, hi0, hi1, a[k], b[k]
        )
        pieces += 1
    return 0.0 + _pairwise_sum(area, 0, 3 * pieces)  # area.sum()


@_jit
def _covered_area(
    chains: FloatArray, u: FloatArray, v_lo: FloatArray, v_hi: FloatArray, d: float
) -> tuple[bool, float]:
    """``planner.coverage.covered_area`` of one cell's packed chains and lines.

    Returns False where that function measures footprints wider than the lines' spacing
    (``_covered_overlapping``, left to numpy).
    """
    n = len(u)
    if n == 0:
        return True, 0.0
    half = d / 2.0
    s0, s1 = u - half, u + half
    for i in range(n - 2):
        if u[i + 1] - u[i] < d - _TIE_M:
            return False, np.nan
    if n == 1 or u[n - 1] - u[n - 2] >= d:
        return True, _covered(chains, s0, s1, v_lo, v_hi)
    # The last two lines' footprints overlap (Python's max() and min() of the pairs).
    a0, a1, b0, b1 = v_lo[n - 2], v_lo[n - 1], v_hi[n - 2], v_hi[n - 1]
    max_a, min_a = (a1 if a1 > a0 else a0), (a1 if a1 < a0 else a0)
    max_b, min_b = (b1 if b1 > b0 else b0), (b1 if b1 < b0 else b0)
    if max_a <= min_b:
        cut0, cut1 = np.empty(n + 1), np.empty(n + 1)
        low, high = np.empty(n + 1), np.empty(n + 1)
        cut0[: n - 1], cut0[n - 1], cut0[n] = s0[: n - 1], s0[n - 1], s1[n - 2]
        cut1[: n - 2], cut1[n - 2] = s1[: n - 2], s0[n - 1]
        cut1[n - 1], cut1[n] = s1[n - 2], s1[n - 1]
        low[: n - 1], low[n - 1], low[n] = v_lo[: n - 1], min_a, v_lo[n - 1]
        high[: n - 1], high[n - 1], high[n] = v_hi[: n - 1], max_b, v_hi[n - 1]
        return True, _covered(chains, cut0, cut1, low, high)
    first = _covered(chains, s0[: n - 1], s1[: n - 1], v_lo[: n - 1], v_hi[: n - 1])
    last = _covered(chains, s0[n - 1 :], s1[n - 1 :], v_lo[n - 1 :], v_hi[n - 1 :])
    overlap = _covered(chains, s0[n - 1 :], s1[n - 2 : n - 1], np.full(1, max_a), np.full(1, min_b))
    return True, first + last - overlap


@_jit
def _screen(
    x: FloatArray,
    y: FloatArray,
    sizes: IntArray,
    first: IntArray,
    ring_of: IntArray,
    local: IntArray,
    nxt: IntArray,
    prv: IntArray,
    part_vertices: IntArray,
    part_rings: IntArray,
    cos_t: FloatArray,
    sin_t: FloatArray,
    d: float,
    edge: float,
    table_offsets: IntArray,
    table_u: FloatArray,
    table_v: FloatArray,
    table_u_lo: FloatArray,
    table_u_hi: FloatArray,
    table_beyond_m: FloatArray,
    table_scalars: FloatArray,
) -> tuple[IntArray, FloatArray, IntArray, IntArray, FloatArray]:
    """:func:`screen_covers` per heading: status, covered area, lines and turns.

    Given a turn table (:class:`planner.fit_screen.TurnTable`, else empty arrays), also the
    fitted coverage :func:`screen_fitted` estimates (NaN where not screened).
    """
    headings = len(cos_t)
    fitting = len(table_scalars) > 0
    fitted = np.full(headings, np.nan)
    parts = len(part_vertices) - 1
    status = np.full(headings, _BY_PYTHON, dtype=np.int64)
    covered = np.full(headings, np.nan)
    line_count = np.full(headings, -1, dtype=np.int64)
    turn_count = np.full(headings, -1, dtype=np.int64)
    # Scratch for one heading's cells (rings and chains), grown as needed.
    all_u, all_v = np.empty(2 * len(x)), np.empty(2 * len(x))
    all_sizes = np.empty(16, dtype=np.int64)
    all_chains = np.empty(8 * len(x))
    chains_at = np.empty(17, dtype=np.int64)
    for a in range(headings):
        # The cells of every part, in the parts' order, laid end to end.
        ok = True
        vertices = cells = 0
        for p in range(parts):
            i0, i1 = part_vertices[p], part_vertices[p + 1]
            r0, r1 = part_rings[p], part_rings[p + 1]
            ok, part_u, part_v, part_sizes = _part_cells(
                x[i0:i1],
                y[i0:i1],
                sizes[r0:r1],
                first[r0:r1],
                ring_of[i0:i1],
                local[i0:i1],
                nxt[i0:i1],
                prv[i0:i1],
                cos_t[a],
                sin_t[a],
            )
            if not ok:
                break
            all_u = _grown(all_u, vertices, len(part_u))
            all_v = _grown(all_v, vertices, len(part_v))
            all_sizes = _grown(all_sizes, cells, len(part_sizes))
            all_u[vertices : vertices + len(part_u)] = part_u
            all_v[vertices : vertices + len(part_v)] = part_v
            all_sizes[cells : cells + len(part_sizes)] = part_sizes
            vertices += len(part_u)
            cells += len(part_sizes)
        if not ok:
            continue
        ring_u, ring_v, ring_sizes = all_u[:vertices], all_v[:vertices], all_sizes[:cells]
        # No cells, or an empty one: cell_plans._scan_cells leaves those to numpy.
        if cells == 0 or ring_sizes.min() == 0:
            continue
        starts = np.zeros(cells, dtype=np.int64)
        for c in range(1, cells):
            starts[c] = starts[c - 1] + ring_sizes[c - 1]
        offsets, line_u, v_lo, v_hi = _scan(ring_u, ring_v, starts, ring_sizes, d, edge)
        # Each cell's chains (coverage.convex_chains), packed end to end for _laid_out.
        chains_at = _grown(chains_at, 0, cells + 1)
        chains_at[0] = 0
        for c in range(cells):
            s = starts[c]
            n_lo, _, packed = _chains(ring_u[s : s + ring_sizes[c]], ring_v[s : s + ring_sizes[c]])
            if n_lo < 0:
                ok = False
                break
            all_chains = _grown(all_chains, chains_at[c], len(packed))
            all_chains[chains_at[c] : chains_at[c] + len(packed)] = packed
            chains_at[c + 1] = chains_at[c] + len(packed)
        if not ok:
            continue
        lines = len(line_u)
        with_lines = 0
        for c in range(cells):
            with_lines += offsets[c + 1] > offsets[c]
        area_m2 = 0.0
        if lines > 0:
            vouched, odd, area, _ = _laid_out(
                all_chains[: chains_at[cells]], offsets, line_u, v_lo, v_hi, d
            )
            if not vouched:
                continue
            # covered_cells: the cells measured on their own first, in order, then the rest.
            for c in odd:
                k0, k1 = offsets[c], offsets[c + 1]
                chains = all_chains[chains_at[c] : chains_at[c + 1]]
                ok, alone_m2 = _covered_area(chains, line_u[k0:k1], v_lo[k0:k1], v_hi[k0:k1], d)
                if not ok:
                    break
                area_m2 += alone_m2
            if not ok:
                continue
            flat = np.empty(3 * len(area))
            for i in range(len(area)):
                flat[3 * i], flat[3 * i + 1], flat[3 * i + 2] = area[i, 0], area[i, 1], area[i, 2]
            area_m2 = area_m2 + (0.0 + _pairwise_sum(flat, 0, len(flat)))
        status[a] = _SCREENED
        covered[a] = area_m2
        line_count[a] = lines
        turn_count[a] = max(lines - with_lines, 0)
        if fitting and lines > 0:
            fitted[a] = area_m2 - _fitted_m2(
                all_chains, chains_at, offsets, line_u, v_lo, v_hi, d,
                (table_offsets, table_u, table_v, table_u_lo, table_u_hi),
                table_beyond_m, table_scalars,
            )  # fmt: skip
    return status, covered, line_count, turn_count, fitted


@_jit
def _fitted_m2(
    all_chains: FloatArray,
    chains_at: IntArray,
    offsets: IntArray,
    line_u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    d: float,
    table: tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray],
    table_beyond_m: FloatArray,
    table_scalars: FloatArray,
) -> float:
    """Return what fitting takes off one heading's cover [m²].

    Each cell is fitted both ways (:func:`planner.fit_screen._fit_cell`) and the two averaged.
    """
    work = np.empty((8, len(line_u)))
    flags = np.empty((3, len(line_u)), dtype=np.bool_)
    cache_keys = np.empty(5 * CACHED_SLIDES, dtype=np.int64)
    cache_values = np.empty(2 * CACHED_SLIDES)
    total = 0.0
    for c in range(len(offsets) - 1):
        k0, k1 = offsets[c], offsets[c + 1]
        if k1 - k0 < 2:
            continue  # one line: no turn
        chains = all_chains[chains_at[c] : chains_at[c + 1]]
        for first_up in (True, False):
            total += (
                _fit_cell(
                    chains,
                    line_u[k0:k1],
                    v_lo[k0:k1],
                    v_hi[k0:k1],
                    first_up,
                    table,
                    table_beyond_m,
                    table_scalars,
                    cache_keys,
                    cache_values,
                    work[:, k0:k1],
                    flags[:, k0:k1],
                    d,
                )  # fmt: skip
                / 2.0
            )
    return total


def screen_covers(
    prepared: Sequence[SweepRings], headings_deg: npt.ArrayLike, interval_m: float, edge_m: float
) -> tuple[FloatArray, IntArray, IntArray]:
    """Measure what :func:`planner.cell_plans.cover_heading` does, at many headings at once.

    Parameters
    ----------
    prepared : sequence of SweepRings
        The field's parts, each prepared by :func:`planner.decomposition.sweep_rings`, in the
        order ``cover_heading`` takes them.
    headings_deg : array_like of float
        Line headings, degrees clockwise from north.
    interval_m : float
        Line spacing and footprint width [m].
    edge_m : float
        How far inside each cell its outer lines run [m] (``cover_heading``'s ``edge_m``).

    Returns
    -------
    covered_m2 : ndarray of float
        Per heading, ``cover_heading(...).covered_m2`` to the last bit [m²].
    line_count : ndarray of int
        Per heading, ``cover_heading(...).line_count``.
    turn_count : ndarray of int
        Per heading, the lines less the cells with a line, at least 0
        (``planner.fitted_cells._turn_count`` of the cover).

    A heading ``cover_heading`` raises at gives NaN, -1 and -1.

    Examples
    --------
    An L at 135° has three cells; at 0° one:

    >>> from shapely import Polygon
    >>> from planner.decomposition import sweep_rings
    >>> ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    >>> covered, lines, turns = screen_covers([sweep_rings(ell)], [0.0, 135.0], 4.0, 2.0)
    >>> lines.tolist(), turns.tolist()
    ([15, 23], [14, 20])
    """
    headings = np.atleast_1d(np.asarray(headings_deg, dtype=np.float64)).ravel()
    d, edge = float(interval_m), float(edge_m)
    if not prepared or not len(headings):
        return _by_python(prepared, headings, d, edge, np.arange(len(headings)))
    rings = _ring_arrays(prepared)
    if rings is None:
        return _by_python(prepared, headings, d, edge, np.arange(len(headings)))
    status, covered, line_count, turn_count, _ = _run_screen(rings, headings, d, edge, None)
    left = np.flatnonzero(status != _SCREENED)
    if len(left):
        slow = _by_python(prepared, headings, d, edge, left)
        covered[left], line_count[left], turn_count[left] = (s[left] for s in slow)
    return covered, line_count, turn_count


def screen_fitted(
    prepared: Sequence[SweepRings],
    headings_deg: npt.ArrayLike,
    interval_m: float,
    edge_m: float,
    table: TurnTable,
) -> FloatArray:
    """Estimate the coverage of each heading's cells once fitted for the vehicle [m²].

    The cells and lines of :func:`screen_covers`, each cell's lines fitted from ``table``
    (:mod:`planner.fit_screen`); NaN at a heading it cannot estimate (a turn beyond the
    table, a boundary the compiled decomposition leaves to shapely).

    Examples
    --------
    An L: along its arms the turns fit best.

    >>> from shapely import Polygon
    >>> from planner.decomposition import sweep_rings
    >>> from planner.fit_screen import turn_table
    >>> from planner.vehicles import resolve_vehicle
    >>> ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    >>> table = turn_table(resolve_vehicle("small_tractor"), 4.0)
    >>> fitted = screen_fitted([sweep_rings(ell)], [0.0, 45.0], 4.0, 1.35, table)
    >>> bool(fitted[0] > fitted[1])
    True
    """
    headings = np.atleast_1d(np.asarray(headings_deg, dtype=np.float64)).ravel()
    rings = _ring_arrays(prepared) if len(headings) else None
    if rings is None:
        return np.full(len(headings), np.nan)
    *_, fitted = _run_screen(rings, headings, float(interval_m), float(edge_m), table)
    return fitted


#: The parts' rings laid end to end: ``x, y`` and eight layout arrays (:func:`_ring_arrays`).
_Rings = tuple[
    FloatArray, FloatArray, IntArray, IntArray, IntArray, IntArray, IntArray, IntArray,
    IntArray, IntArray,
]  # fmt: skip


def _ring_arrays(prepared: Sequence[SweepRings]) -> _Rings | None:
    """Return the parts' rings laid end to end, as :func:`_screen` takes them (None: NaN)."""
    if not prepared:
        return None
    x = np.concatenate([r.x for r in prepared])
    y = np.concatenate([r.y for r in prepared])
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        return None
    return (
        x,
        y,
        np.concatenate([r.sizes for r in prepared]).astype(np.int64),
        np.concatenate([r.first for r in prepared]).astype(np.int64),
        np.concatenate([r.ring_of for r in prepared]).astype(np.int64),
        np.concatenate([r.local for r in prepared]).astype(np.int64),
        np.concatenate([r.nxt for r in prepared]).astype(np.int64),
        np.concatenate([r.prv for r in prepared]).astype(np.int64),
        np.cumsum([0] + [len(r.x) for r in prepared], dtype=np.int64),
        np.cumsum([0] + [len(r.sizes) for r in prepared], dtype=np.int64),
    )


def _run_screen(
    rings: _Rings, headings: FloatArray, d: float, edge: float, table: TurnTable | None
) -> tuple[IntArray, FloatArray, IntArray, IntArray, FloatArray]:
    """Call :func:`_screen` on the rings at ``headings``, fitting from ``table`` if given."""
    x, y, sizes, first, ring_of, local, nxt, prv, part_vertices, part_rings = rings
    cos_t, sin_t = _sweep_cosines(headings)
    if table is None:  # empty arrays: fit nothing
        offsets, empty = np.zeros(1, dtype=np.int64), np.zeros(0)
        return _screen(
            x, y, sizes, first, ring_of, local, nxt, prv, part_vertices, part_rings,
            cos_t, sin_t, d, edge, offsets, empty, empty, empty, empty, empty, empty,
        )  # fmt: skip
    return _screen(
        x, y, sizes, first, ring_of, local, nxt, prv, part_vertices, part_rings,
        cos_t, sin_t, d, edge, table.offsets, table.u, table.v, table.u_lo, table.u_hi,
        table.beyond_m, table.scalars,
    )  # fmt: skip


def _sweep_cosines(headings: FloatArray) -> tuple[FloatArray, FloatArray]:
    """planner.lines.to_sweep's cosines and sines of ``headings`` [deg].

    numpy's of each heading's radians, one at a time: an array's may take another SIMD path,
    and differ in the last bit, on some CPUs.
    """
    theta = np.radians(headings)
    return np.array([np.cos(t) for t in theta]), np.array([np.sin(t) for t in theta])


def _by_python(
    prepared: Sequence[SweepRings], headings: FloatArray, d: float, edge: float, which: IntArray
) -> tuple[FloatArray, IntArray, IntArray]:
    """:func:`screen_covers` of the headings ``which`` by ``cover_heading`` itself."""
    from planner.cell_plans import cover_heading  # it imports the planner's stages

    covered = np.full(len(headings), np.nan)
    line_count = np.full(len(headings), -1, dtype=np.int64)
    turn_count = np.full(len(headings), -1, dtype=np.int64)
    for a in which.tolist():
        try:
            cover = cover_heading(prepared, float(headings[a]), d, edge)
        except (ValueError, IndexError, ArithmeticError, shapely.errors.ShapelyError):
            continue  # NaN, -1, -1: no cover at this heading
        with_lines = sum(1 for c in cover.cells if c.lines.stop > c.lines.start)
        covered[a] = cover.covered_m2
        line_count[a] = cover.line_count
        turn_count[a] = max(cover.line_count - with_lines, 0)
    return covered, line_count, turn_count


def warm_up() -> None:
    """Compile the kernel, or load it from the disk cache, on a tiny field (one cut, 3 cells).

    Both ways: screening covers, and fitted covers with a small tractor's turns.
    """
    from shapely import Polygon

    from planner.decomposition import sweep_rings
    from planner.fit_screen import turn_table
    from planner.vehicles import resolve_vehicle

    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    screen_covers([sweep_rings(ell)], np.array([0.0, 135.0]), 4.0, 2.0)
    table = turn_table(resolve_vehicle("small_tractor"), 4.0)
    screen_fitted([sweep_rings(ell)], np.array([0.0, 135.0]), 4.0, 2.0, table)
