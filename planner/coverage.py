"""Coverage (R4): how much of a cell the lines' footprints till, computed exactly.

A footprint is a line buffered by ``interval/2`` with flat caps: in the sweep frame, the
rectangle ``[u - d/2, u + d/2] × [v_lo, v_hi]``. The covered area of a cell is the integral,
across the sweep, of the length of ``[lo(u), hi(u)] ∩ [v_lo, v_hi]``, where ``lo`` and ``hi``
are the cell's lower and upper chains. Both chains are piecewise linear, so the integral is
exact when cut at their vertices and where they cross the footprint's ends. This costs
O(lines + vertices), where intersecting 1,000 footprints with shapely costs ~25 ms; the hot
paths run as compiled loops (:mod:`planner.coverage_kernels`), this numpy code their reference.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Vertices this close across the sweep count as one end of the cell [m].
_TIE_M = 1e-9


@dataclass(frozen=True, slots=True)
class Chains:
    """A sweep-monotone cell as its lower and upper boundary, in one sweep frame [m].

    Attributes
    ----------
    lo_u, lo_v : ndarray
        Lower chain, ``u`` non-decreasing.
    hi_u, hi_v : ndarray
        Upper chain, ``u`` non-decreasing.
    packed : ndarray or None
        ``[len(lo_u), len(hi_u), *lo_u, *lo_v, *hi_u, *hi_v]``, whose views the four arrays
        are, for the compiled loops (:mod:`planner.coverage_kernels`): set by
        :func:`convex_chains` only (not an argument, so ``dataclasses.replace`` drops it).
    """

    lo_u: FloatArray
    lo_v: FloatArray
    hi_u: FloatArray
    hi_v: FloatArray
    packed: FloatArray | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def u_min(self) -> float:
        """Left end of the cell."""
        return float(min(self.lo_u[0], self.hi_u[0]))

    @property
    def u_max(self) -> float:
        """Right end of the cell."""
        return float(max(self.lo_u[-1], self.hi_u[-1]))


def convex_chains(u_ring: FloatArray, v_ring: FloatArray) -> Chains:
    """Split a counter-clockwise convex ring (sweep frame, not closed) into its chains.

    Examples
    --------
    >>> c = convex_chains(np.array([0.0, 4.0, 4.0, 0.0]), np.array([0.0, 0.0, 3.0, 3.0]))
    >>> c.lo_v.tolist(), c.hi_v.tolist()
    ([0.0, 0.0], [3.0, 3.0])
    """
    from planner import coverage_kernels  # numba: imported by the first plan that needs it

    fast = coverage_kernels.packed_chains(u_ring, v_ring)
    if fast is None:
        return convex_chains_numpy(u_ring, v_ring)
    n_lo, n_hi, p = fast
    lo, hi = 2 + n_lo, 2 + 2 * n_lo
    chains = Chains(p[2:lo], p[lo:hi], p[hi : hi + n_hi], p[hi + n_hi :])
    object.__setattr__(chains, "packed", p)  # frozen: set once, here
    return chains


def convex_chains_numpy(u_ring: FloatArray, v_ring: FloatArray) -> Chains:
    """:func:`convex_chains` in numpy: the reference for the compiled loop."""
    # An edge parallel to the lines at either end belongs to neither chain: the lower chain
    # runs bottom-left to bottom-right, the upper one top-left to top-right.
    at_min = np.flatnonzero(u_ring <= u_ring.min() + _TIE_M)
    at_max = np.flatnonzero(u_ring >= u_ring.max() - _TIE_M)
    lo_start = int(at_min[np.argmin(v_ring[at_min])])
    lo_end = int(at_max[np.argmin(v_ring[at_max])])
    hi_start = int(at_max[np.argmax(v_ring[at_max])])
    hi_end = int(at_min[np.argmax(v_ring[at_min])])
    lo_u, lo_v = _ring_run(u_ring, lo_start, lo_end), _ring_run(v_ring, lo_start, lo_end)
    hi_u, hi_v = _ring_run(u_ring, hi_start, hi_end), _ring_run(v_ring, hi_start, hi_end)
    # Rounding can make a chain step back by 1e-15 m; np.interp needs it monotone.
    return Chains(
        lo_u=np.maximum.accumulate(lo_u),
        lo_v=lo_v,
        hi_u=np.maximum.accumulate(hi_u[::-1]),
        hi_v=hi_v[::-1],
    )


def _ring_run(values: FloatArray, start: int, end: int) -> FloatArray:
    """Return ``values[start], ..., values[end]`` round the ring (from ``start`` on, cyclic)."""
    if end >= start:
        return values[start : end + 1]
    return np.concatenate([values[start:], values[: end + 1]])


def covered_area(
    chains: Chains, u: FloatArray, v_lo: FloatArray, v_hi: FloatArray, interval_m: float
) -> float:
    """Area of the cell covered by the footprints of its lines [m²].

    Parameters
    ----------
    chains : Chains
        The cell.
    u, v_lo, v_hi : ndarray, shape (n,)
        Its lines, left to right, as :func:`planner.lines.scan_cell` places them.
    interval_m : float
        Footprint width [m]: the implement's working width (R4), which may be wider or
        narrower than the spacing of the lines.

    Returns
    -------
    float

    Examples
    --------
    A 16 m × 20 m rectangle with four lines is covered completely:

    >>> c = convex_chains(np.array([0.0, 16.0, 16.0, 0.0]), np.array([0.0, 0.0, 20.0, 20.0]))
    >>> covered_area(c, np.array([2.0, 6.0, 10.0, 14.0]), np.zeros(4), np.full(4, 20.0), 4.0)
    320.0
    """
    d = float(interval_m)
    half = d / 2.0
    n = len(u)
    if n == 0:
        return 0.0
    s0, s1 = u - half, u + half
    if n > 2 and bool((np.diff(u)[:-1] < d - _TIE_M).any()):
        # An implement wider than the interval: every footprint overlaps its neighbours.
        return _covered_overlapping(chains, u, v_lo, v_hi, d)
    if n == 1 or u[n - 1] - u[n - 2] >= d:
        return _covered(chains, s0, s1, v_lo, v_hi)
    # The last line sits nearer its neighbour (R2), so their strips overlap on
    # [s0[n-1], s1[n-2]]. Where their intervals overlap too (the usual case) the union there
    # is one interval, and all strips become disjoint: one pass. Otherwise add both and
    # subtract the common part.
    a2, b2 = v_lo[n - 2 :], v_hi[n - 2 :]
    if max(a2) <= min(b2):
        cut0 = np.concatenate([s0[: n - 1], s0[n - 1 :], s1[n - 2 : n - 1]])
        cut1 = np.concatenate([s1[: n - 2], s0[n - 1 :], s1[n - 2 : n - 1], s1[n - 1 :]])
        low = np.concatenate([v_lo[: n - 1], [min(a2)], v_lo[n - 1 :]])
        high = np.concatenate([v_hi[: n - 1], [max(b2)], v_hi[n - 1 :]])
        return _covered(chains, cut0, cut1, low, high)
    first = _covered(chains, s0[: n - 1], s1[: n - 1], v_lo[: n - 1], v_hi[: n - 1])
    last = _covered(chains, s0[n - 1 :], s1[n - 1 :], v_lo[n - 1 :], v_hi[n - 1 :])
    overlap = _covered(chains, s0[n - 1 :], s1[n - 2 : n - 1], [max(a2)], [min(b2)])
    return first + last - overlap


def _covered_overlapping(
    chains: Chains, u: FloatArray, v_lo: FloatArray, v_hi: FloatArray, width_m: float
) -> float:
    """Covered area when footprints overlap their neighbours (implement wider than interval).

    Cut the sweep where any footprint begins or ends; in each piece the footprints over it
    overlap along the lines, so their union is one interval from the lowest start to the
    highest end.
    """
    order = np.argsort(u, kind="stable")
    u, v_lo, v_hi = u[order], v_lo[order], v_hi[order]
    half = width_m / 2.0
    s0, s1 = u - half, u + half
    cuts = np.unique(np.concatenate([s0, s1]))
    left, right = cuts[:-1], cuts[1:]
    mid = (left + right) / 2.0
    first = np.searchsorted(s1, mid, side="right")  # first footprint ending after mid
    last = np.searchsorted(s0, mid, side="right") - 1  # last one starting before it
    covered = last >= first
    left, right, first, last = left[covered], right[covered], first[covered], last[covered]
    low = v_lo[first].copy()
    high = v_hi[first].copy()
    for step in range(1, int((last - first).max(initial=0)) + 1):
        k = np.minimum(first + step, last)
        low = np.minimum(low, v_lo[k])
        high = np.maximum(high, v_hi[k])
    return _covered(chains, left, right, low, high)


def cell_area(chains: Chains) -> float:
    """Area between the chains [m²] (the cell's area)."""
    grid = np.unique(np.concatenate([chains.lo_u, chains.hi_u]))
    height = np.interp(grid, chains.hi_u, chains.hi_v) - np.interp(grid, chains.lo_u, chains.lo_v)
    return float(np.sum((height[1:] + height[:-1]) / 2.0 * np.diff(grid)))


def _covered(
    chains: Chains,
    s0: npt.ArrayLike,
    s1: npt.ArrayLike,
    a: npt.ArrayLike,
    b: npt.ArrayLike,
) -> float:
    """Σ_k ∫_{s0_k}^{s1_k} max(0, min(hi, b_k) − max(lo, a_k)) du, for disjoint sorted strips."""
    s0, s1 = np.asarray(s0, dtype=float), np.asarray(s1, dtype=float)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    u_min, u_max = chains.u_min, chains.u_max
    cuts = np.concatenate([chains.lo_u, chains.hi_u, s0, s1])
    cuts = np.unique(np.clip(cuts, u_min, u_max))
    left, right = cuts[:-1], cuts[1:]
    mid = (left + right) / 2.0
    k = np.searchsorted(s0, mid, side="right") - 1
    inside = (k >= 0) & (mid < s1[np.maximum(k, 0)])
    left, right, k = left[inside], right[inside], k[inside]
    width = right - left
    # Each piece lies within one edge of each chain: take that edge's line (found at the
    # piece's middle), since a chain may step straight across the sweep at a vertex (an
    # edge parallel to the lines) and interpolating at the step would take the far side.
    mid = (left + right) / 2.0
    lo0, lo1 = _edge_values(chains.lo_u, chains.lo_v, mid, left, right)
    hi0, hi1 = _edge_values(chains.hi_u, chains.hi_v, mid, left, right)
    return float(_integrate(width, lo0, lo1, hi0, hi1, a[k], b[k]).sum())


def _integrate(
    width: FloatArray,
    lo0: FloatArray,
    lo1: FloatArray,
    hi0: FloatArray,
    hi1: FloatArray,
    ak: FloatArray,
    bk: FloatArray,
) -> FloatArray:
    """∫ max(0, min(hi, b) − max(lo, a)) over each piece: chains linear over each piece.

    Returns the integral over each of the piece's three stretches, shape (pieces, 3).
    """
    # Cut each piece where hi crosses b or lo crosses a: between cuts the covered height
    # min(hi, b) − max(lo, a) is linear, and its positive part integrates in closed form.
    with np.errstate(divide="ignore", invalid="ignore"):
        # fmax/fmin drop a NaN (an edge level with its bound): 0, as clipping +-inf does.
        t_hi = np.fmin(np.fmax((bk - hi0) / (hi1 - hi0), 0.0), 1.0)
        t_lo = np.fmin(np.fmax((ak - lo0) / (lo1 - lo0), 0.0), 1.0)
    # Both crossings lie in [0, 1]: sorted, the four cut points are 0, the earlier, the later, 1.
    t = np.empty((len(t_hi), 4))
    t[:, 0], t[:, 3] = 0.0, 1.0
    np.minimum(t_hi, t_lo, out=t[:, 1])
    np.maximum(t_hi, t_lo, out=t[:, 2])
    height = np.minimum(hi0[:, None] + t * (hi1 - hi0)[:, None], bk[:, None]) - np.maximum(
        lo0[:, None] + t * (lo1 - lo0)[:, None], ak[:, None]
    )
    g0, g1 = height[:, :-1], height[:, 1:]
    dt = np.diff(t, axis=1) * width[:, None]
    high, low = np.maximum(g0, g1), np.minimum(g0, g1)
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing = np.where(high > 0, dt * high * high / (2.0 * (high - low)), 0.0)
    area = np.where(low >= 0, dt * (g0 + g1) / 2.0, np.where(high <= 0, 0.0, crossing))
    return area


def _edge_values(
    chain_u: FloatArray, chain_v: FloatArray, mid: FloatArray, left: FloatArray, right: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Values at ``left`` and ``right`` of the chain edge that holds each ``mid``."""
    if len(chain_u) < 2:
        value = np.full(len(mid), float(chain_v[0]) if len(chain_v) else 0.0)
        return value, value
    k = np.clip(np.searchsorted(chain_u, mid, side="right") - 1, 0, len(chain_u) - 2)
    du = chain_u[k + 1] - chain_u[k]
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(du > 0.0, (chain_v[k + 1] - chain_v[k]) / du, 0.0)
    return chain_v[k] + slope * (left - chain_u[k]), chain_v[k] + slope * (right - chain_u[k])


def covered_cells(
    chains: list[Chains],
    offsets: IntArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    interval_m: float,
) -> float:
    """Total of :func:`covered_area` over many cells at once [m²], for lines an interval apart.

    Cell ``c`` has the lines ``offsets[c]:offsets[c + 1]`` (left to right, as
    :func:`planner.lines.scan_cells` places them: ``interval_m`` apart but the last, which
    may sit nearer). The cells are laid end to end along one axis, each shifted by its own
    offset, so that one pass of :func:`_covered`'s closed form integrates all of them: a few
    dozen numpy calls for a heading instead of that many per cell. A cell whose footprints
    do not fit that form (lines nearer than the interval elsewhere, or two overlapping
    footprints whose intervals along the lines do not meet) is measured on its own.

    Examples
    --------
    >>> a = convex_chains(np.array([0.0, 16.0, 16.0, 0.0]), np.array([0.0, 0.0, 20.0, 20.0]))
    >>> b = convex_chains(np.array([20.0, 26.0, 20.0]), np.array([0.0, 0.0, 6.0]))
    >>> u = np.array([2.0, 6.0, 10.0, 14.0, 22.0, 24.0])
    >>> lo, hi = np.zeros(6), np.array([20.0, 20.0, 20.0, 20.0, 4.0, 2.0])
    >>> total = covered_cells([a, b], np.array([0, 4, 6]), u, lo, hi, 4.0)
    >>> bool(np.isclose(total, covered_area(a, u[:4], lo[:4], hi[:4], 4.0)
    ...                 + covered_area(b, u[4:], lo[4:], hi[4:], 4.0)))
    True
    """
    if len(chains) == 0 or int(offsets[-1]) == 0:
        return 0.0
    odd, area, _ = _laid_out(chains, offsets, u, v_lo, v_hi, interval_m)
    total = 0.0
    for covered in odd.values():
        total += covered
    return total + float(area.sum())


def covered_each_cell(
    chains: list[Chains],
    offsets: IntArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    interval_m: float,
) -> FloatArray:
    """:func:`covered_cells`, cell by cell [m²]: what each cell's own lines cover.

    Examples
    --------
    >>> a = convex_chains(np.array([0.0, 16.0, 16.0, 0.0]), np.array([0.0, 0.0, 20.0, 20.0]))
    >>> b = convex_chains(np.array([20.0, 26.0, 20.0]), np.array([0.0, 0.0, 6.0]))
    >>> u = np.array([2.0, 6.0, 10.0, 14.0, 22.0, 24.0])
    >>> lo, hi = np.zeros(6), np.array([20.0, 20.0, 20.0, 20.0, 4.0, 2.0])
    >>> covered_each_cell([a, b], np.array([0, 4, 6]), u, lo, hi, 4.0).round(9).tolist()
    [320.0, 16.0]
    """
    cells = len(chains)
    each = np.zeros(cells)
    if cells == 0 or int(offsets[-1]) == 0:
        return each
    odd, area, cell = _laid_out(chains, offsets, u, v_lo, v_hi, interval_m)
    each += np.bincount(cell, weights=area.sum(axis=1), minlength=cells)
    for c, covered in odd.items():
        each[c] = covered
    return each


def _laid_out(
    chains: list[Chains],
    offsets: IntArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    interval_m: float,
) -> tuple[dict[int, float], FloatArray, IntArray]:
    """Measure :func:`covered_cells`' pieces: cells on their own, the rest laid out.

    Returns
    -------
    odd : dict
        Covered area of each cell whose footprints do not fit the laid-out form [m²].
    area : ndarray, shape (pieces, 3)
        The laid-out cells' pieces (:func:`_integrate`) [m²].
    cell : ndarray of int, shape (pieces,)
        The cell of each piece.
    """
    from planner import coverage_kernels  # numba: imported by the first plan that needs it

    d = float(interval_m)
    offsets = np.asarray(offsets)
    fast = None
    if len(offsets) == len(chains) + 1 and offsets[0] == 0 and offsets[-1] == len(u):
        fast = coverage_kernels.laid_out(
            np.concatenate([packed(c) for c in chains]),
            offsets,
            u,
            v_lo,
            v_hi,
            d,
        )
    if fast is None:
        return _laid_out_numpy(chains, offsets, u, v_lo, v_hi, d)
    odd, area, cell = fast
    alone: dict[int, float] = {}
    for c in odd.tolist():
        k = slice(int(offsets[c]), int(offsets[c + 1]))
        alone[c] = covered_area(chains[c], u[k], v_lo[k], v_hi[k], d)
    return alone, area, cell


def packed(chains: Chains) -> FloatArray:
    """Return ``chains`` as the compiled loops take them: :attr:`Chains.packed`, or made."""
    return _packed(chains) if chains.packed is None else chains.packed


def _packed(chains: Chains) -> FloatArray:
    """``chains.packed`` for chains not made by :func:`convex_chains`' compiled loop."""
    sizes = np.array([len(chains.lo_u), len(chains.hi_u)], dtype=np.float64)
    return np.concatenate([sizes, chains.lo_u, chains.lo_v, chains.hi_u, chains.hi_v])


def _laid_out_numpy(
    chains: list[Chains],
    offsets: IntArray,
    u: FloatArray,
    v_lo: FloatArray,
    v_hi: FloatArray,
    interval_m: float,
) -> tuple[dict[int, float], FloatArray, IntArray]:
    """:func:`_laid_out` in numpy: the reference for the compiled loop."""
    d = float(interval_m)
    half = d / 2.0
    cells = len(chains)
    counts = np.diff(offsets)
    u_min = np.array([c.u_min for c in chains])
    u_max = np.array([c.u_max for c in chains])
    # Each cell's own stretch of the axis, an interval and a metre clear of the next.
    base = np.concatenate(([0.0], np.cumsum(u_max - u_min + d + 1.0)[:-1])) - u_min
    cell_of_line = np.repeat(np.arange(cells), counts)
    x = u + base[cell_of_line]
    s0, s1 = x - half, x + half
    # Strips: each footprint up to the next one's start, and where two overlap, their union.
    same = cell_of_line[1:] == cell_of_line[:-1]
    overlap = same & (s1[:-1] > s0[1:] + _TIE_M)
    begin, end = s0.copy(), s1.copy()
    end[:-1] = np.where(overlap, s0[1:], s1[:-1])
    begin[1:] = np.where(overlap, s1[:-1], s0[1:])
    meets = np.maximum(v_lo[:-1], v_lo[1:]) <= np.minimum(v_hi[:-1], v_hi[1:])
    # Lines nearer than the interval anywhere but at a cell's last line, or overlapping
    # footprints apart along the lines: that cell on its own.
    last_pair = np.zeros(len(u) - 1, dtype=bool)
    ends = offsets[1:] - 2
    last_pair[ends[counts >= 2]] = True
    odd = overlap & (~last_pair | ~meets)
    odd_cells = np.unique(cell_of_line[:-1][odd])
    alone: dict[int, float] = {}
    if len(odd_cells):
        skip = np.zeros(cells, dtype=bool)
        skip[odd_cells] = True
        for c in odd_cells.tolist():
            k = slice(int(offsets[c]), int(offsets[c + 1]))
            alone[c] = covered_area(chains[c], u[k], v_lo[k], v_hi[k], d)
        keep = ~skip[cell_of_line]
        overlap = overlap & keep[:-1]
    else:
        keep = np.ones(len(u), dtype=bool)
    i = np.nonzero(overlap)[0]
    strip0 = np.concatenate([begin[keep], s0[i + 1]])
    strip1 = np.concatenate([end[keep], s1[i]])
    low = np.concatenate([v_lo[keep], np.minimum(v_lo[i], v_lo[i + 1])])
    high = np.concatenate([v_hi[keep], np.maximum(v_hi[i], v_hi[i + 1])])
    if not len(strip0):
        return alone, np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
    order = np.argsort(strip0, kind="stable")
    lo_u = np.concatenate([c.lo_u + b for c, b in zip(chains, base.tolist(), strict=True)])
    lo_v = np.concatenate([c.lo_v for c in chains])
    hi_u = np.concatenate([c.hi_u + b for c, b in zip(chains, base.tolist(), strict=True)])
    hi_v = np.concatenate([c.hi_v for c in chains])
    strips = (strip0[order], strip1[order], low[order], high[order])
    chain = (lo_u, lo_v, hi_u, hi_v)
    area, cell = _covered_laid_out(*chain, u_min + base, u_max + base, *strips)
    return alone, area, cell


def _covered_laid_out(
    lo_u: FloatArray,
    lo_v: FloatArray,
    hi_u: FloatArray,
    hi_v: FloatArray,
    cell_lo: FloatArray,
    cell_hi: FloatArray,
    s0: FloatArray,
    s1: FloatArray,
    a: FloatArray,
    b: FloatArray,
) -> tuple[FloatArray, IntArray]:
    """:func:`_covered` of cells laid end to end (chains concatenated, each cell's own span).

    Returns each piece's :func:`_integrate` and its cell.
    """
    cuts = np.unique(np.concatenate([lo_u, hi_u, s0, s1]))
    left, right = cuts[:-1], cuts[1:]
    mid = (left + right) / 2.0
    cell = np.searchsorted(cell_lo, mid, side="right") - 1
    k = np.searchsorted(s0, mid, side="right") - 1
    inside = (cell >= 0) & (k >= 0)
    inside &= (mid < cell_hi[np.maximum(cell, 0)]) & (mid < s1[np.maximum(k, 0)])
    left, right, mid, k, cell = left[inside], right[inside], mid[inside], k[inside], cell[inside]
    width = right - left
    lo0, lo1 = _laid_out_edge_values(lo_u, lo_v, cell_lo, mid, left, right, cell)
    hi0, hi1 = _laid_out_edge_values(hi_u, hi_v, cell_lo, mid, left, right, cell)
    return _integrate(width, lo0, lo1, hi0, hi1, a[k], b[k]), cell


def _laid_out_edge_values(
    chain_u: FloatArray,
    chain_v: FloatArray,
    cell_lo: FloatArray,
    mid: FloatArray,
    left: FloatArray,
    right: FloatArray,
    cell: IntArray,
) -> tuple[FloatArray, FloatArray]:
    """:func:`_edge_values` on concatenated chains: each piece within its own cell's chain."""
    starts = np.searchsorted(chain_u, cell_lo, side="left")
    stops = np.concatenate([starts[1:], [len(chain_u)]])
    first, top = starts[cell], np.maximum(stops[cell] - 2, starts[cell])
    k = np.clip(np.searchsorted(chain_u, mid, side="right") - 1, first, top)
    nxt = np.minimum(k + 1, len(chain_u) - 1)
    du = chain_u[nxt] - chain_u[k]
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(du > 0.0, (chain_v[nxt] - chain_v[k]) / du, 0.0)
    return chain_v[k] + slope * (left - chain_u[k]), chain_v[k] + slope * (right - chain_u[k])
