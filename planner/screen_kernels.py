"""Compiled loop over many headings of one field: each heading's cells, lines and cover.

:func:`planner.cell_plans.cover_heading` decomposes the field at a heading into cells, scans
their lines and measures what the lines cover. Its cores are compiled
(:mod:`planner.cell_kernels`, :mod:`planner.coverage_kernels`); :func:`_screen` runs the
whole of it for every heading in one compiled loop that calls those same cores, with the
numpy glue around them compiled with the numpy code's arithmetic: the decomposition's
(:mod:`planner.decomposition_kernels`), the measure of a cell whose footprints the laid-out
form cannot take (``coverage.covered_area``: :func:`_covered_area`) and the total
(``covered_cells``, whose ``area.sum()`` adds by numpy's pairwise rule). So the figures are
``cover_heading``'s to the last bit (but the sign of a zero, as in :mod:`planner.cell_kernels`);
a heading whose cells the cores leave to numpy or shapely is marked for ``cover_heading``.

:func:`_screen` also keeps the cells of the headings that may be fitted next, and
:func:`_fit_kept` fits those (:mod:`planner.fit_screen`), so no heading is decomposed twice;
it returns every heading's cells and lines too, for the plan's own covers. Asked for the
``rank`` best only, it decomposes every heading first and measures covers from the fewest
turns up, until no heading left can rank.
The Python entries are :mod:`planner.heading_screen`'s.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from planner.cell_kernels import _scan
from planner.coverage_kernels import _chains, _edge, _laid_out, _piece_area
from planner.decomposition import SweepRings
from planner.decomposition_kernels import _part_cells
from planner.kernel_helpers import _clip, _jit, _pairwise_sum, _right
from planner.parity_kernels import _parity_losses, cell_loss_m2

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

_TIE_M = 1e-9  # planner.coverage._TIE_M

#: A heading's status: screened here, left to :func:`planner.cell_plans.cover_heading`, or
#: left unmeasured because it cannot rank (:func:`_screen`'s ``rank``).
_SCREENED = 0
_BY_PYTHON = 1
_UNRANKED = 2


@_jit
def _grown(buffer: npt.NDArray[Any], used: int, more: int) -> npt.NDArray[Any]:
    """Return ``buffer`` with room for ``more`` values after ``used`` (else a longer copy)."""
    if used + more <= len(buffer):
        return buffer
    out = np.empty(max(2 * len(buffer), used + more), dtype=buffer.dtype)
    out[:used] = buffer[:used]
    return out


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


#: A heading estimated more than this below the ``keep``-th best so far cannot rank among the
#: best ``keep``: :func:`planner.cover_picks.cover_picks` ranks the estimates rounded to a
#: µm², and this is a thousand of them [m²].
_KEEP_MARGIN_M2 = 1e-3

#: The cells cover at most the field's area; this share more allows for the sums' rounding.
_AREA_ROUNDING_SHARE = 1e-9


@_jit
def _stage(
    staged: npt.NDArray[Any], at: IntArray, a: int, values: npt.NDArray[Any]
) -> npt.NDArray[Any]:
    """Append heading ``a``'s ``values`` to ``staged`` (``at[a]:at[a + 1]``), grown as needed."""
    staged = _grown(staged, at[a], len(values))
    staged[at[a] : at[a] + len(values)] = values
    at[a + 1] = at[a] + len(values)
    return staged


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
    reach_m: float,
    keep: int,
    rank: int,
    area_m2: float,
) -> tuple[
    tuple[IntArray, FloatArray, IntArray, IntArray],
    tuple[
        IntArray, IntArray, IntArray, IntArray,
        FloatArray, IntArray, IntArray, FloatArray, FloatArray, FloatArray,
    ],
    tuple[
        npt.NDArray[np.bool_], IntArray, IntArray, IntArray, IntArray, FloatArray, FloatArray,
        IntArray, IntArray, FloatArray, FloatArray, FloatArray,
    ],
]:  # fmt: skip
    """Screen every heading: status, covered area, lines and turns; cells kept to fit; cells.

    Returns three groups: the figures per heading; the kept cells (below); and every
    heading's cells and lines as decomposed and scanned (``staged[a]``: it was; its cells'
    rings ``staged_u``, ``staged_v`` ``[vertex_at[a]:vertex_at[a + 1]]`` of sizes
    ``staged_sizes[size_at[a]:size_at[a + 1]]``, their line offsets
    ``staged_offsets[offset_at[a]:offset_at[a + 1]]`` and lines ``staged_lu``,
    ``staged_lo``, ``staged_hi`` ``[scan_at[a]:scan_at[a + 1]]``), bit for bit
    :func:`planner.cell_plans.cover_heading`'s.

    The cells and lines of each heading with lines that may rank among the ``keep`` best by
    the estimate ``covered - 2 * turns * reach_m * d`` (:func:`planner.fitted_cells.estimate_m2`)
    are kept for :func:`_fit_kept`, laid end to end: ``kept_of[a]`` is heading ``a``'s index
    ``k`` among them (-1: not kept), its chains ``kept_chains[chain_at[k]:chain_at[k + 1]]``,
    its cells' starts in them and line offsets ``kept_chains_at`` and ``kept_offsets``
    ``[cell_at[k]:cell_at[k + 1]]``, its lines ``kept_u``, ``kept_v_lo``, ``kept_v_hi``
    ``[line_at[k]:line_at[k + 1]]``. A heading is kept unless ``keep`` headings measured
    before it are estimated more than :data:`_KEEP_MARGIN_M2` higher: those rank before it.

    ``rank > 0``: only the ``rank`` best by the estimate are needed. Every heading is
    decomposed and its lines scanned first (which counts its turns); then the covers are
    measured, the fewest turns first, until the field's area (``area_m2``, the most any
    heading's cells can cover) less the next heading's turns is more than
    :data:`_KEEP_MARGIN_M2` below the ``rank``-th best estimate: that heading and the rest
    cannot rank, and are left unmeasured (status ``_UNRANKED``, covered NaN, their lines and
    turns counted). With a turning radius the turns' term is large and most headings are
    left so; the figures of the measured ones do not depend on the order.
    """
    headings = len(cos_t)
    parts = len(part_vertices) - 1
    status = np.full(headings, _BY_PYTHON, dtype=np.int64)
    covered = np.full(headings, np.nan)
    line_count = np.full(headings, -1, dtype=np.int64)
    turn_count = np.full(headings, -1, dtype=np.int64)
    # Scratch for one heading's cells (rings), grown as needed.
    all_u, all_v = np.empty(2 * len(x)), np.empty(2 * len(x))
    all_sizes = np.empty(16, dtype=np.int64)
    # Every heading's cells and lines, laid end to end (heading a's at [*_at[a]:*_at[a + 1]]).
    staged = np.zeros(headings, dtype=np.bool_)
    vertex_at, size_at = np.zeros(headings + 1, np.int64), np.zeros(headings + 1, np.int64)
    offset_at, scan_at = np.zeros(headings + 1, np.int64), np.zeros(headings + 1, np.int64)
    staged_u, staged_v = np.empty(4 * len(x)), np.empty(4 * len(x))
    staged_sizes, staged_offsets = np.empty(64, np.int64), np.empty(64, np.int64)
    staged_lu, staged_lo, staged_hi = np.empty(64), np.empty(64), np.empty(64)
    for a in range(headings):
        vertex_at[a + 1], size_at[a + 1] = vertex_at[a], size_at[a]
        offset_at[a + 1], scan_at[a + 1] = offset_at[a], scan_at[a]
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
        with_lines = 0
        for c in range(cells):
            with_lines += offsets[c + 1] > offsets[c]
        staged[a] = True
        line_count[a] = len(line_u)
        turn_count[a] = max(len(line_u) - with_lines, 0)
        staged_u = _stage(staged_u, vertex_at, a, ring_u)
        staged_v = _stage(staged_v, vertex_at, a, ring_v)
        staged_sizes = _stage(staged_sizes, size_at, a, ring_sizes)
        staged_offsets = _stage(staged_offsets, offset_at, a, offsets)
        staged_lu = _stage(staged_lu, scan_at, a, line_u)
        staged_lo = _stage(staged_lo, scan_at, a, v_lo)
        staged_hi = _stage(staged_hi, scan_at, a, v_hi)
    # The most each heading's estimate can be; measured from the highest down when ranking.
    bound = area_m2 * (1.0 + _AREA_ROUNDING_SHARE) - 2.0 * turn_count * reach_m * d
    order = np.arange(headings)
    if rank > 0:
        order = order[np.argsort(-bound, kind="mergesort")]
    # Scratch for one heading's chains.
    all_chains = np.empty(8 * len(x))
    chains_at = np.empty(17, dtype=np.int64)
    # The kept headings' cells, and the best estimates so far (greatest first).
    kept_of = np.full(headings, -1, dtype=np.int64)
    chain_at, cell_at = np.zeros(headings + 1, np.int64), np.zeros(headings + 1, np.int64)
    line_at = np.zeros(headings + 1, np.int64)
    kept_chains = np.empty(0)
    kept_chains_at, kept_offsets = np.empty(0, np.int64), np.empty(0, np.int64)
    kept_u, kept_v_lo, kept_v_hi = np.empty(0), np.empty(0), np.empty(0)
    kept = 0
    best = np.full(max(keep, rank, 1), -np.inf)
    for place in range(headings):
        a = int(order[place])
        if not staged[a]:
            continue
        if rank > 0 and bound[a] < best[rank - 1] - _KEEP_MARGIN_M2:
            status[a] = _UNRANKED
            continue
        ring_u = staged_u[vertex_at[a] : vertex_at[a + 1]]
        ring_v = staged_v[vertex_at[a] : vertex_at[a + 1]]
        ring_sizes = staged_sizes[size_at[a] : size_at[a + 1]]
        offsets = staged_offsets[offset_at[a] : offset_at[a + 1]]
        line_u = staged_lu[scan_at[a] : scan_at[a + 1]]
        v_lo = staged_lo[scan_at[a] : scan_at[a + 1]]
        v_hi = staged_hi[scan_at[a] : scan_at[a + 1]]
        cells, lines = len(ring_sizes), len(line_u)
        # Each cell's chains (coverage.convex_chains), packed end to end for _laid_out.
        ok = True
        chains_at = _grown(chains_at, 0, cells + 1)
        chains_at[0] = 0
        s = 0
        for c in range(cells):
            n_lo, _, packed = _chains(ring_u[s : s + ring_sizes[c]], ring_v[s : s + ring_sizes[c]])
            s += ring_sizes[c]
            if n_lo < 0:
                ok = False
                break
            all_chains = _grown(all_chains, chains_at[c], len(packed))
            all_chains[chains_at[c] : chains_at[c] + len(packed)] = packed
            chains_at[c + 1] = chains_at[c] + len(packed)
        if not ok:
            line_count[a] = turn_count[a] = -1
            continue
        area = 0.0
        if lines > 0:
            vouched, odd, pieces, _ = _laid_out(
                all_chains[: chains_at[cells]], offsets, line_u, v_lo, v_hi, d
            )
            if not vouched:
                line_count[a] = turn_count[a] = -1
                continue
            # covered_cells: the cells measured on their own first, in order, then the rest.
            for c in odd:
                k0, k1 = offsets[c], offsets[c + 1]
                chains = all_chains[chains_at[c] : chains_at[c + 1]]
                ok, alone_m2 = _covered_area(chains, line_u[k0:k1], v_lo[k0:k1], v_hi[k0:k1], d)
                if not ok:
                    break
                area += alone_m2
            if not ok:
                line_count[a] = turn_count[a] = -1
                continue
            # area.sum() of the pieces' areas, already flat in their order.
            area = area + (0.0 + _pairwise_sum(pieces, 0, len(pieces)))
        status[a] = _SCREENED
        covered[a] = area
        estimate = area - 2.0 * turn_count[a] * reach_m * d
        if keep > 0 and lines > 0 and not estimate < best[keep - 1] - _KEEP_MARGIN_M2:
            kept_of[a] = kept
            n_chains = chains_at[cells]
            kept_chains = _grown(kept_chains, chain_at[kept], n_chains)
            kept_chains[chain_at[kept] : chain_at[kept] + n_chains] = all_chains[:n_chains]
            chain_at[kept + 1] = chain_at[kept] + n_chains
            c0 = cell_at[kept]
            kept_chains_at = _grown(kept_chains_at, c0, cells + 1)
            kept_offsets = _grown(kept_offsets, c0, cells + 1)
            kept_chains_at[c0 : c0 + cells + 1] = chains_at[: cells + 1]
            kept_offsets[c0 : c0 + cells + 1] = offsets
            cell_at[kept + 1] = c0 + cells + 1
            k0 = line_at[kept]
            kept_u = _grown(kept_u, k0, lines)
            kept_v_lo = _grown(kept_v_lo, k0, lines)
            kept_v_hi = _grown(kept_v_hi, k0, lines)
            kept_u[k0 : k0 + lines] = line_u
            kept_v_lo[k0 : k0 + lines] = v_lo
            kept_v_hi[k0 : k0 + lines] = v_hi
            line_at[kept + 1] = k0 + lines
            kept += 1
        i = len(best) - 1
        if estimate > best[i]:  # into the best so far, in order
            while i > 0 and estimate > best[i - 1]:
                best[i] = best[i - 1]
                i -= 1
            best[i] = estimate
    return (
        (status, covered, line_count, turn_count),
        (
            kept_of, chain_at[: kept + 1], cell_at[: kept + 1], line_at[: kept + 1],
            kept_chains, kept_chains_at, kept_offsets, kept_u, kept_v_lo, kept_v_hi,
        ),
        (
            staged, vertex_at, size_at, offset_at, scan_at, staged_u, staged_v,
            staged_sizes, staged_offsets, staged_lu, staged_lo, staged_hi,
        ),
    )  # fmt: skip


@_jit
def _fit_kept(
    kept_of: IntArray,
    chain_at: IntArray,
    cell_at: IntArray,
    line_at: IntArray,
    kept_chains: FloatArray,
    kept_chains_at: IntArray,
    kept_offsets: IntArray,
    kept_u: FloatArray,
    kept_v_lo: FloatArray,
    kept_v_hi: FloatArray,
    covered: FloatArray,
    which: IntArray,
    d: float,
    table_offsets: IntArray,
    table_u: FloatArray,
    table_v: FloatArray,
    table_u_lo: FloatArray,
    table_u_hi: FloatArray,
    table_beyond_m: FloatArray,
    table_scalars: FloatArray,
    parity_slack_m2: float,
) -> tuple[FloatArray, IntArray, FloatArray]:
    """Estimate the fitted coverage of the headings ``which`` from their kept cells [m²].

    NaN at a heading whose cells were not kept. ``parity_slack_m2``: as
    :func:`planner.parity_kernels.cell_loss_m2` takes it. Also returns what fitting takes
    off each cell of them both ways round (:func:`planner.parity_kernels._parity_losses`):
    heading ``which[i]``'s cells are the rows ``losses[loss_at[i]:loss_at[i + 1]]`` (none if
    not kept).
    """
    fitted = np.full(len(which), np.nan)
    table = (table_offsets, table_u, table_v, table_u_lo, table_u_hi)
    loss_at = np.zeros(len(which) + 1, dtype=np.int64)
    for i in range(len(which)):
        k = kept_of[which[i]]
        loss_at[i + 1] = loss_at[i] + (cell_at[k + 1] - cell_at[k] - 1 if k >= 0 else 0)
    losses = np.empty((loss_at[-1], 2))
    for i in range(len(which)):
        k = kept_of[which[i]]
        if k < 0:
            continue
        c0, c1 = cell_at[k], cell_at[k + 1]
        k0, k1 = line_at[k], line_at[k + 1]
        cells = _parity_losses(
            kept_chains[chain_at[k] : chain_at[k + 1]], kept_chains_at[c0:c1],
            kept_offsets[c0:c1], kept_u[k0:k1], kept_v_lo[k0:k1], kept_v_hi[k0:k1], d,
            table, table_beyond_m, table_scalars,
        )  # fmt: skip
        losses[loss_at[i] : loss_at[i + 1]] = cells
        fitted[i] = covered[which[i]] - _fitted_m2(cells, kept_offsets[c0:c1], parity_slack_m2)
    return fitted, loss_at, losses


@_jit
def _fitted_m2(losses: FloatArray, offsets: IntArray, parity_slack_m2: float) -> float:
    """Return what fitting takes off one heading's cover [m²].

    Each cell fitted both ways round (``losses``: :func:`planner.parity_kernels._parity_losses`)
    is counted as the plan will drive it (:func:`planner.parity_kernels.cell_loss_m2`).
    """
    total = 0.0
    for c in range(len(offsets) - 1):
        if offsets[c + 1] - offsets[c] >= 2:  # one line: no turn
            total += cell_loss_m2(losses[c, 0], losses[c, 1], parity_slack_m2)
    return total


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


def _sweep_cosines(headings: FloatArray) -> tuple[FloatArray, FloatArray]:
    """planner.lines.to_sweep's cosines and sines of ``headings`` [deg].

    numpy's of each heading's radians, one at a time: an array's may take another SIMD path,
    and differ in the last bit, on some CPUs.
    """
    theta = np.radians(headings)
    return np.array([np.cos(t) for t in theta]), np.array([np.sin(t) for t in theta])


def warm_up() -> None:
    """Compile the kernels, or load them from the disk cache, on a tiny field (one cut, 3 cells).

    Both ways: screening alone, and keeping the cells to fit with a small tractor's turns.
    """
    from shapely import Polygon

    from planner.decomposition import sweep_rings
    from planner.fit_screen import turn_table
    from planner.vehicles import resolve_vehicle

    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    rings = _ring_arrays([sweep_rings(ell)])
    assert rings is not None
    x, y, sizes, first, ring_of, local, nxt, prv, part_vertices, part_rings = rings
    cos_t, sin_t = _sweep_cosines(np.array([0.0, 135.0]))
    for keep, rank in ((0, 0), (2, 2)):
        (
            (_, covered, _, _),
            (kept_of, chain_at, cell_at, line_at, chains, chains_at, offsets, u, v_lo, v_hi),
            _,
        ) = _screen(
            x, y, sizes, first, ring_of, local, nxt, prv, part_vertices, part_rings,
            cos_t, sin_t, 4.0, 2.0, 1.0, keep, rank, ell.area,
        )  # fmt: skip
    t = turn_table(resolve_vehicle("small_tractor"), 4.0)
    _fit_kept(
        kept_of, chain_at, cell_at, line_at, chains, chains_at, offsets, u, v_lo, v_hi,
        covered, np.arange(2), 4.0, t.offsets, t.u, t.v, t.u_lo, t.u_hi, t.beyond_m, t.scalars,
        100.0,
    )  # fmt: skip
