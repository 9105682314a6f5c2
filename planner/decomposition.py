"""Boustrophedon cell decomposition (Choset 1998): split a field into sweep-monotone cells.

For a line heading, every tillage line is ``u = const`` in the sweep frame of
:func:`planner.lines.to_sweep`. A cell is a polygon that every such line crosses once, so it
can be covered back and forth as in the convex case. The field's boundary (exterior and
holes) changes how many times a line crosses it only at *critical* vertices, where the
boundary turns back across the sweep. Cutting the field at the ``u`` of every critical
vertex gives slabs whose pieces are monotone; neighbouring pieces are merged wherever the
connection is one-to-one (one piece on each side), because one set of lines then runs through
both. What is left are Choset's cells: a notch that does not turn the boundary back across
the sweep adds no cell at all.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import shapely
from shapely import Polygon

from planner.coverage import convex_chains
from planner.lines import from_sweep, to_sweep

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Critical ``u`` values closer than this are one cut, and pieces touching a cut within this
#: distance touch it [m].
_SNAP_M = 1e-6
#: Cells smaller than this are rounding slivers, dropped [m²].
_MIN_CELL_M2 = 1e-6
#: How far short of each cut the slabs stop [m].
_HAIR_M = 1e-7
#: A vertex this close to a slab's side was made by the clipping [m].
_ON_SIDE_M = 1e-9


def decompose(field_local: Polygon, heading_deg: float) -> list[Polygon]:
    """Split ``field_local`` into cells that every line of ``heading_deg`` crosses once.

    Parameters
    ----------
    field_local : Polygon
        Field (holes allowed), local frame [m]; valid.
    heading_deg : float
        Line heading, degrees clockwise from north.

    Returns
    -------
    list of Polygon
        Cells, local frame, exteriors counter-clockwise and without holes, ordered left to
        right across the sweep (then bottom to top). They tile ``field_local``.

    Examples
    --------
    North-west lines beyond the inner corner of an L-shaped field cross both arms, so the
    corner splits the sweep; north-south lines cross the L once each:

    >>> from shapely import Polygon
    >>> ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    >>> sorted(round(c.area) for c in decompose(ell, 135.0)), len(decompose(ell, 0.0))
    ([450, 450, 1800], 1)
    >>> len(decompose(Polygon([(0, 0), (10, 0), (10, 10), (0, 10)]), 30.0))
    1
    """
    return [
        _to_local(ring_u, ring_v, heading_deg)
        for ring_u, ring_v in decompose_sweep(field_local, heading_deg)
    ]


@dataclass(frozen=True, slots=True)
class SweepRings:
    """A field's rings as arrays, ready to be decomposed at any heading.

    Attributes
    ----------
    field : Polygon
        The field, oriented (exterior counter-clockwise, holes clockwise), local [m].
    x, y : ndarray
        Every ring's vertices, the exterior first, not closed [m].
    sizes, first : ndarray of int
        Vertices per ring, and where each ring begins.
    ring_of, local, nxt, prv : ndarray of int
        Per vertex: its ring, its place in it, and the next and previous vertex round it.
    """

    field: Polygon
    x: FloatArray
    y: FloatArray
    sizes: IntArray
    first: IntArray
    ring_of: IntArray
    local: IntArray
    nxt: IntArray
    prv: IntArray


def sweep_rings(field_local: Polygon) -> SweepRings:
    """Prepare ``field_local`` for :func:`decompose_sweep` at many headings."""
    field_local = shapely.orient_polygons(field_local)
    rings = shapely.get_rings(field_local)
    coords = shapely.get_coordinates(rings)
    sizes = (shapely.get_num_coordinates(rings) - 1).astype(np.int64)
    keep = np.ones(len(coords), dtype=bool)
    keep[np.cumsum(sizes + 1) - 1] = False
    first = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    ring_of = np.repeat(np.arange(len(sizes)), sizes)
    local = np.arange(int(sizes.sum())) - first[ring_of]
    nxt = first[ring_of] + (local + 1) % sizes[ring_of]
    prv = first[ring_of] + (local - 1) % sizes[ring_of]
    xy = coords[keep]
    return SweepRings(field_local, xy[:, 0], xy[:, 1], sizes, first, ring_of, local, nxt, prv)


def decompose_sweep(
    field_local: Polygon | SweepRings, heading_deg: float
) -> list[tuple[FloatArray, FloatArray]]:
    """Return the cells of :func:`decompose` as counter-clockwise rings in the sweep frame.

    The boundary is split into its ``u``-monotone runs (between the vertices where it turns
    back across the sweep). Within a slab between two cuts, the runs that span it alternate
    lower chain, upper chain from the bottom up, so each consecutive pair bounds a piece;
    pieces are then merged across the cuts. Everything but the merging is numpy over all
    runs at once, without clipping polygons. A boundary too degenerate for that (runs that
    do not alternate, or that end off the cuts) is clipped into slabs by shapely instead.

    Parameters
    ----------
    field_local : Polygon or SweepRings
        The field, or it prepared by :func:`sweep_rings` (for many headings).
    heading_deg : float

    Returns
    -------
    list of (ndarray, ndarray)
        ``(u, v)`` of each cell's exterior [m], not closed, in :func:`decompose` order.
    """
    r = field_local if isinstance(field_local, SweepRings) else sweep_rings(field_local)
    u, v = to_sweep(r.x, r.y, heading_deg)
    turn = (u - u[r.prv]) * (u[r.nxt] - u) <= 0.0
    cuts = _cuts(u[turn])
    if len(cuts) <= 2:
        return [(u[: r.sizes[0]].copy(), v[: r.sizes[0]].copy())]
    from planner import cell_kernels  # numba: imported by the first plan that needs it

    status, cell_u, cell_v, cell_sizes = cell_kernels.sweep_cells(
        u, v, turn, cuts, r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv
    )
    if status == 1:
        return _rings(cell_u, cell_v, cell_sizes)
    if status == 0:
        return _decompose_clipped(r.field, heading_deg)
    return decompose_sweep_numpy(r, heading_deg)


def decompose_sweep_numpy(r: SweepRings, heading_deg: float) -> list[tuple[FloatArray, FloatArray]]:
    """:func:`decompose_sweep` in numpy: the reference for its compiled loops.

    :func:`planner.cell_kernels.sweep_cells` computes the same cells;
    ``tests/planner/test_cell_kernels.py`` holds them equal bit for bit.
    """
    u, v = to_sweep(r.x, r.y, heading_deg)
    turn = (u - u[r.prv]) * (u[r.nxt] - u) <= 0.0
    cuts = _cuts(u[turn])
    if len(cuts) <= 2:
        return [(u[: r.sizes[0]].copy(), v[: r.sizes[0]].copy())]
    pieces = _pieces(u, v, turn, cuts, r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv)
    if pieces is None:
        return _decompose_clipped(r.field, heading_deg)
    return _cells(pieces, cuts)


def _cuts(critical_u: FloatArray) -> FloatArray:
    """Sorted, snapped ``u`` of the critical vertices (where a ring turns back)."""
    cuts = np.unique(critical_u)
    keep_cut = np.concatenate(([True], np.diff(cuts) > _SNAP_M))
    keep_cut[-1] = True
    cuts = cuts[keep_cut]
    if len(cuts) >= 2 and cuts[-1] - cuts[-2] <= _SNAP_M:
        cuts = np.delete(cuts, -2)
    return cuts


@dataclass(frozen=True, slots=True)
class _Pieces:
    """Every piece of every slab, bottom-up per slab, as its lower and upper chain.

    A chain is points ``start:stop`` of ``u, v`` (``u`` increasing, ends on the slab's cuts).
    """

    slab: IntArray
    lo_start: IntArray
    lo_stop: IntArray
    hi_start: IntArray
    hi_stop: IntArray
    u: FloatArray
    v: FloatArray


def _pieces(
    u: FloatArray,
    v: FloatArray,
    turn: npt.NDArray[np.bool_],
    cuts: FloatArray,
    sizes: IntArray,
    first: IntArray,
    ring_of: IntArray,
    local: IntArray,
    nxt: IntArray,
    prv: IntArray,
) -> _Pieces | None:
    """Cut the rings into monotone runs and the runs into the slabs' pieces (None: degenerate)."""
    # Vertices within a hair of a cut go onto it (critical ones always), so that every run
    # begins and ends exactly on a cut.
    at = np.clip(np.searchsorted(cuts, u), 1, len(cuts) - 1)
    nearer = np.where(u - cuts[at - 1] <= cuts[at] - u, at - 1, at)
    gap = np.abs(u - cuts[nearer])
    if float(gap[turn].max()) > 100.0 * _SNAP_M:
        return None
    u = np.where(turn | (gap <= _SNAP_M), cuts[nearer], u)
    sign = np.sign(u[nxt] - u).astype(np.int64)  # of the edge from each vertex to the next
    begins = (sign != 0) & (sign != sign[prv])
    # Each ring rotated to begin with a run, so that runs are contiguous.
    shift = np.minimum.reduceat(np.where(begins, local, sizes[ring_of]), first)
    if (shift >= sizes).any():
        return None
    order = first[ring_of] + (local + shift[ring_of]) % sizes[ring_of]
    edge = order[sign[order] != 0]
    run = np.cumsum(begins[edge]) - 1
    runs = int(run[-1]) + 1
    last = np.concatenate((run[1:] != run[:-1], [True]))
    # Points of every run: its edges' starts and its last edge's end.
    count = np.bincount(run, minlength=runs) + 1
    offsets = np.concatenate(([0], np.cumsum(count)))
    k = np.arange(len(edge))
    point = np.concatenate([edge, [0] * runs])
    at_point = np.concatenate([k + run, np.nonzero(last)[0] + run[last] + 1])
    point[at_point] = np.concatenate([edge, nxt[edge[last]]])
    run_sign = sign[edge[np.concatenate(([True], run[1:] != run[:-1]))]]
    # Upper chains (runs towards -u) reversed, so that every run's u increases.
    run_of_point = np.repeat(np.arange(runs), count)
    j = np.arange(len(point)) - offsets[run_of_point]
    flip = run_sign[run_of_point] < 0
    point = point[
        np.where(
            flip, offsets[run_of_point] + count[run_of_point] - 1 - j, offsets[run_of_point] + j
        )
    ]
    pu, pv = u[point], v[point]
    step = np.diff(pu)
    inner = run_of_point[1:] == run_of_point[:-1]
    if not (step[inner] > 0.0).all():
        return None
    u_first, u_last = pu[offsets[:-1]], pu[offsets[1:] - 1]
    i0 = np.searchsorted(cuts, u_first)
    i1 = np.searchsorted(cuts, u_last)
    if not (
        (cuts[np.minimum(i0, len(cuts) - 1)] == u_first).all()
        and (cuts[np.minimum(i1, len(cuts) - 1)] == u_last).all()
    ):
        return None
    # Every (run, slab) it spans; found in the runs by one search over runs laid end to end.
    base = np.concatenate(([0.0], np.cumsum(u_last - u_first + 1.0)[:-1]))
    key = pu - u_first[run_of_point] + base[run_of_point]
    span = i1 - i0
    pair_run = np.repeat(np.arange(runs), span)
    pair_slab = i0[pair_run] + np.arange(int(span.sum())) - np.repeat(np.cumsum(span) - span, span)
    left, right = cuts[pair_slab], cuts[pair_slab + 1]
    pair_first, pair_base = u_first[pair_run], base[pair_run]
    a = np.searchsorted(key, left - pair_first + pair_base, side="right")
    b = np.searchsorted(key, right - pair_first + pair_base, side="left")
    middle = (left + right) / 2.0
    mid = np.searchsorted(key, middle - pair_first + pair_base, side="right")

    def value(i: IntArray, at_u: FloatArray) -> FloatArray:
        slope = (pv[i] - pv[i - 1]) / (pu[i] - pu[i - 1])
        return np.asarray(pv[i - 1] + (at_u - pu[i - 1]) * slope)

    v_left, v_right = value(a, left), value(b, right)
    v_mid = value(mid, middle)
    ranked = np.lexsort((v_mid, pair_slab))
    slab_sorted = pair_slab[ranked]
    group = np.searchsorted(slab_sorted, slab_sorted, side="left")
    position = np.arange(len(ranked)) - group
    expected = np.where(position % 2 == 0, 1, -1)
    if not (run_sign[pair_run[ranked]] == expected).all():
        return None
    lower, upper = ranked[0::2], ranked[1::2]
    if len(lower) != len(upper) or not (pair_slab[lower] == pair_slab[upper]).all():
        return None
    # Each pair's chain: its left end, the run's points inside the slab, its right end.
    length = b - a + 2
    chain_at = np.concatenate(([0], np.cumsum(length)[:-1]))
    total = int(length.sum())
    cu = np.empty(total)
    cv = np.empty(total)
    cu[chain_at], cv[chain_at] = left, v_left
    cu[chain_at + length - 1], cv[chain_at + length - 1] = right, v_right
    inside = b - a
    owner = np.repeat(np.arange(len(a)), inside)
    within = np.arange(int(inside.sum())) - np.repeat(np.cumsum(inside) - inside, inside)
    cu[chain_at[owner] + 1 + within] = pu[a[owner] + within]
    cv[chain_at[owner] + 1 + within] = pv[a[owner] + within]
    return _Pieces(
        slab=pair_slab[lower],
        lo_start=chain_at[lower],
        lo_stop=chain_at[lower] + length[lower],
        hi_start=chain_at[upper],
        hi_stop=chain_at[upper] + length[upper],
        u=cu,
        v=cv,
    )


def _cells(pieces: _Pieces, cuts: FloatArray) -> list[tuple[FloatArray, FloatArray]]:
    """Merge the pieces along one-to-one connections across the cuts; return the cells' rings."""
    slab = pieces.slab.tolist()
    cv = pieces.v
    lo_first = cv[pieces.lo_start].tolist()
    hi_first = cv[pieces.hi_start].tolist()
    lo_last = cv[pieces.lo_stop - 1].tolist()
    hi_last = cv[pieces.hi_stop - 1].tolist()
    n = len(slab)
    right_of: list[list[int]] = [[] for _ in range(n)]
    left_of: list[list[int]] = [[] for _ in range(n)]
    bounds = np.searchsorted(pieces.slab, np.arange(len(cuts))).tolist()
    for s in range(len(cuts) - 2):
        here = range(bounds[s], bounds[s + 1])
        there = range(bounds[s + 1], bounds[s + 2])
        for a in here:
            a0, a1 = lo_last[a], hi_last[a]
            for b in there:
                if min(a1, hi_first[b]) - max(a0, lo_first[b]) > _SNAP_M:
                    right_of[a].append(b)
                    left_of[b].append(a)
    index: list[FloatArray] = []
    cell_sizes: list[int] = []
    for k in range(n):
        if len(left_of[k]) == 1 and len(right_of[left_of[k][0]]) == 1:
            continue  # continues the cell of its left neighbour
        run = [k]
        while len(right_of[run[-1]]) == 1 and len(left_of[right_of[run[-1]][0]]) == 1:
            run.append(right_of[run[-1]][0])
        parts = [np.arange(pieces.lo_start[j], pieces.lo_stop[j]) for j in run]
        parts += [np.arange(pieces.hi_stop[j] - 1, pieces.hi_start[j] - 1, -1) for j in run[::-1]]
        ring = np.concatenate(parts)
        index.append(ring)
        cell_sizes.append(len(ring))
    flat = np.concatenate(index)
    # Drop repeated vertices (the chains of neighbouring pieces share their ends).
    return _rings(*_drop_repeats(pieces.u[flat], cv[flat], np.asarray(cell_sizes)))


def _rings(u: FloatArray, v: FloatArray, sizes: IntArray) -> list[tuple[FloatArray, FloatArray]]:
    """Split rings laid end to end, dropping those of under three vertices or no area."""
    ring = np.repeat(sizes >= 3, sizes)
    u, v, sizes = u[ring], v[ring], sizes[sizes >= 3]
    if not len(sizes):
        return []
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    nxt = np.arange(len(u)) + 1
    nxt[starts + sizes - 1] = starts
    twice = np.add.reduceat(u * v[nxt] - v * u[nxt], starts)
    out = []
    for start, size, twice_m2 in zip(starts.tolist(), sizes.tolist(), twice.tolist(), strict=True):
        if twice_m2 / 2.0 > _MIN_CELL_M2:  # slivers of rounding at a cut are no cells
            out.append((u[start : start + size], v[start : start + size]))
    return out


def _drop_repeats(
    u: FloatArray, v: FloatArray, sizes: IntArray
) -> tuple[FloatArray, FloatArray, IntArray]:
    """Drop every vertex that repeats the next one of its ring (cyclically)."""
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    nxt = np.arange(len(u)) + 1
    nxt[starts + sizes - 1] = starts
    keep = np.hypot(u[nxt] - u, v[nxt] - v) > 1e-9
    cell_of = np.repeat(np.arange(len(sizes)), sizes)
    return u[keep], v[keep], np.bincount(cell_of[keep], minlength=len(sizes))


def _decompose_clipped(
    field_local: Polygon, heading_deg: float
) -> list[tuple[FloatArray, FloatArray]]:
    """:func:`decompose_sweep` by clipping the field into slabs with shapely (the fallback)."""
    field_sweep = _rotate(field_local, heading_deg)
    cuts = _critical_u(field_sweep)
    if len(cuts) <= 2:
        return [_ring_of(field_sweep)]
    _, v_min, _, v_max = field_sweep.bounds
    # Slabs stop a hair short of the cuts: pieces that touch only at a critical vertex on a
    # cut (the tips of a saw-tooth edge) come apart, and the chains' ends are put back on
    # the cut afterwards.
    slabs = shapely.box(  # type: ignore[call-overload]
        cuts[:-1] + _HAIR_M, v_min - 1.0, cuts[1:] - _HAIR_M, v_max + 1.0
    )
    pieces_per_slab = shapely.intersection(field_sweep, slabs)

    # Every piece as its lower and upper chain, and the v-interval it shows at each side.
    slab_of: list[int] = []
    chains = []
    for slab, geometry in enumerate(pieces_per_slab):
        parts = [p for p in shapely.get_parts(geometry) if isinstance(p, Polygon) and p.area > 0.0]
        parts.sort(key=lambda p: (p.bounds[1], p.bounds[3]))
        for part in parts:
            u, v = _ring_of(shapely.orient_polygons(part))
            # Only the vertices the clipping made (on a slab's side) go back onto the cut.
            u = np.where(u <= cuts[slab] + _HAIR_M + _ON_SIDE_M, cuts[slab], u)
            u = np.where(u >= cuts[slab + 1] - _HAIR_M - _ON_SIDE_M, cuts[slab + 1], u)
            chains.append(convex_chains(u, v))
            slab_of.append(slab)
    n = len(chains)
    slab_arr = np.asarray(slab_of)

    def side(k: int, at_u: float) -> tuple[float, float]:
        c = chains[k]
        uu = np.concatenate([c.lo_u, c.hi_u])
        vv = np.concatenate([c.lo_v, c.hi_v])
        near = np.abs(uu - at_u) <= _SNAP_M
        if not near.any():
            return (np.inf, -np.inf)
        return float(vv[near].min()), float(vv[near].max())

    right_of: list[list[int]] = [[] for _ in range(n)]
    left_of: list[list[int]] = [[] for _ in range(n)]
    for slab in range(len(cuts) - 2):
        here = np.nonzero(slab_arr == slab)[0]
        there = np.nonzero(slab_arr == slab + 1)[0]
        at = float(cuts[slab + 1])
        right_sides = {int(a): side(int(a), at) for a in here}
        left_sides = {int(b): side(int(b), at) for b in there}
        for a, (a0, a1) in right_sides.items():
            for b, (b0, b1) in left_sides.items():
                if min(a1, b1) - max(a0, b0) > _SNAP_M:
                    right_of[a].append(b)
                    left_of[b].append(a)

    # Merge along one-to-one connections: each cell is a run of pieces across slabs.
    rings = []
    for k in range(n):
        if len(left_of[k]) == 1 and len(right_of[left_of[k][0]]) == 1:
            continue  # continues the cell of its left neighbour
        run = [k]
        while len(right_of[run[-1]]) == 1 and len(left_of[right_of[run[-1]][0]]) == 1:
            run.append(right_of[run[-1]][0])
        lo_u = np.concatenate([chains[j].lo_u for j in run])
        lo_v = np.concatenate([chains[j].lo_v for j in run])
        hi_u = np.concatenate([chains[j].hi_u for j in run])
        hi_v = np.concatenate([chains[j].hi_v for j in run])
        u = np.concatenate([lo_u, hi_u[::-1]])
        v = np.concatenate([lo_v, hi_v[::-1]])
        u, v = _clean_ring(u, v)
        area = 0.5 * float(np.dot(u, np.roll(v, -1)) - np.dot(v, np.roll(u, -1)))
        if len(u) >= 3 and area > _MIN_CELL_M2:  # slivers of rounding at a cut are no cells
            rings.append((u, v))
    return rings


def _rotate(field_local: Polygon, heading_deg: float) -> Polygon:
    def rotate(xy: FloatArray) -> FloatArray:
        u, v = to_sweep(xy[:, 0], xy[:, 1], heading_deg)
        return np.stack([u, v], axis=1)

    rotated: Polygon = shapely.transform(field_local, rotate)
    return rotated


def _to_local(u: FloatArray, v: FloatArray, heading_deg: float) -> Polygon:
    x, y = from_sweep(u, v, heading_deg)
    return Polygon(np.stack([x, y], axis=1))


def _ring_of(polygon: Polygon) -> tuple[FloatArray, FloatArray]:
    coords = np.asarray(polygon.exterior.coords)[:-1]
    return coords[:, 0].copy(), coords[:, 1].copy()


def _critical_u(field_sweep: Polygon) -> FloatArray:
    """Sorted ``u`` of the vertices where a ring turns back across the sweep (and its ends)."""
    rings = shapely.get_rings(field_sweep)
    coords = shapely.get_coordinates(rings)
    sizes = shapely.get_num_coordinates(rings)
    ends = np.cumsum(sizes)
    starts = ends - sizes
    # Per ring, without its closing vertex: previous and next vertex, cyclically.
    keep = np.ones(len(coords), dtype=bool)
    keep[ends - 1] = False
    u = coords[keep, 0]
    m = sizes - 1
    first = np.repeat(starts - np.arange(len(sizes)), m)  # index of each ring's first vertex
    local = np.arange(len(u)) - first
    ring_m = np.repeat(m, m)
    prev_u = u[first + (local - 1) % ring_m]
    next_u = u[first + (local + 1) % ring_m]
    turn = (u - prev_u) * (next_u - u) <= 0.0
    return _cuts(u[turn])


def _clean_ring(u: FloatArray, v: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Drop repeated vertices (the chains of neighbouring pieces share their ends)."""
    step = np.hypot(np.diff(u, append=u[0]), np.diff(v, append=v[0]))
    keep = step > 1e-9
    return u[keep], v[keep]
