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

import numpy as np
import numpy.typing as npt
import shapely
from shapely import Polygon

from planner.coverage import convex_chains
from planner.lines import from_sweep, to_sweep

FloatArray = npt.NDArray[np.float64]

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


def decompose_sweep(
    field_local: Polygon, heading_deg: float
) -> list[tuple[FloatArray, FloatArray]]:
    """Return the cells of :func:`decompose` as counter-clockwise rings in the sweep frame.

    Returns
    -------
    list of (ndarray, ndarray)
        ``(u, v)`` of each cell's exterior [m], not closed, in :func:`decompose` order.
    """
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
    cuts = np.unique(u[turn])
    keep_cut = np.concatenate(([True], np.diff(cuts) > _SNAP_M))
    keep_cut[-1] = True
    cuts = cuts[keep_cut]
    if len(cuts) >= 2 and cuts[-1] - cuts[-2] <= _SNAP_M:
        cuts = np.delete(cuts, -2)
    return cuts


def _clean_ring(u: FloatArray, v: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Drop repeated vertices (the chains of neighbouring pieces share their ends)."""
    step = np.hypot(np.diff(u, append=u[0]), np.diff(v, append=v[0]))
    keep = step > 1e-9
    return u[keep], v[keep]
