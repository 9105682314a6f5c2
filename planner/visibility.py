"""What sees what inside a field: straight moves that stay inside, and corners in sight.

The visibility half of :class:`planner.routing.FieldRouter`, which searches shortest moves over
what this module answers. :class:`FieldInterior` tells whether straight moves and polylines stay
inside the field (grazing its boundary by up to :data:`GRAZE_M`); :class:`CornerVisibility`
holds the field's reflex corners and which pairs of them are tangent and see each other, the
edges of the visibility graph, found as queries meet them (or all at once,
:meth:`CornerVisibility.graph`).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import shapely
from scipy.sparse import csr_matrix  # type: ignore[import-untyped]
from shapely import Polygon

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: A move may graze the boundary by this much and still count as inside [m]; R1 allows 1 cm.
GRAZE_M = 1e-3
#: Corners up to which pair states are kept in a dense matrix (4 MB), beyond in a dict.
_DENSE_CORNERS = 2048
#: Sine below which a corner's neighbour counts as on a line through the corner.
_COLLINEAR = 1e-9


class FieldInterior:
    """Whether straight moves and polylines stay inside one field, grazing allowed.

    Parameters
    ----------
    field_local : Polygon
        The field, local frame [m], holes allowed.
    """

    def __init__(self, field_local: Polygon) -> None:
        grown = field_local.buffer(GRAZE_M, join_style="mitre")
        # GEOS locates a point by the edges a horizontal line through it crosses: a comb
        # whose teeth run along y crosses them all. With |dy| the greater over the edges,
        # the tests run on x and y swapped (exact: a reflection, no arithmetic).
        rings = shapely.get_rings(shapely.get_parts(grown))
        edges = np.concatenate(
            [
                np.empty((0, 2)),
                *[np.abs(np.diff(shapely.get_coordinates(r), axis=0)) for r in rings],
            ]
        )
        self._swap = bool(edges[:, 1].sum() > edges[:, 0].sum())
        self._test = shapely.transform(grown, _swap_xy) if self._swap else grown
        shapely.prepare(self._test)

    def segments(self, starts: FloatArray, ends: FloatArray) -> BoolArray:
        """Whether each straight move ``starts[k] → ends[k]`` stays inside.

        ``starts``, ``ends``: shapes (k, 2), local [m].
        """
        segments = np.stack([starts, ends], axis=1)
        if self._swap:
            segments = segments[..., ::-1]
        return np.asarray(shapely.contains_properly(self._test, shapely.linestrings(segments)))

    def polyline(self, points: FloatArray) -> bool:
        """Whether the polyline through ``points`` (shape (k, 2), k ≥ 2) stays inside."""
        line = shapely.linestrings(points[:, ::-1] if self._swap else points)
        return bool(shapely.contains_properly(self._test, line))

    def polylines(self, paths: list[FloatArray]) -> BoolArray:
        """:meth:`polyline` of each of ``paths``, in one GEOS call."""
        if not paths:
            return np.zeros(0, dtype=bool)
        points = np.concatenate(paths)
        owner = np.repeat(np.arange(len(paths)), [len(p) for p in paths])
        lines = shapely.linestrings(points[:, ::-1] if self._swap else points, indices=owner)
        return np.asarray(shapely.contains_properly(self._test, lines))

    def holds(self, points: FloatArray) -> BoolArray:
        """Whether each of ``points`` (shape (k, 2)) lies in the (grown) field's interior."""
        x, y = (points[:, 1], points[:, 0]) if self._swap else (points[:, 0], points[:, 1])
        return np.asarray(shapely.contains_xy(self._test, x, y))

    def covers(self, points: FloatArray) -> BoolArray:
        """Whether the (grown) field covers each of ``points`` (shape (k, 2)), in one call."""
        return np.asarray(
            shapely.covers(self._test, shapely.points(points[:, ::-1] if self._swap else points))
        )


class CornerVisibility:
    """A field's reflex corners and which pairs of them are tangent and see each other.

    A shortest path inside a polygon bends only at reflex corners of the free space (reflex
    vertices of the exterior, convex vertices of the holes), and only round a corner it wraps:
    the visibility graph joins the pairs tangent at both corners and in sight.

    Parameters
    ----------
    field_local : Polygon
        The field, oriented (exterior counter-clockwise, holes clockwise), local [m].
    interior : FieldInterior
        The same field's inside test.

    Attributes
    ----------
    nodes : ndarray, shape (n, 2)
        The corners, local [m], ring by ring.
    """

    def __init__(self, field_local: Polygon, interior: FieldInterior) -> None:
        self._interior = interior
        nodes, prev, nxt = [], [], []
        for ring in (field_local.exterior, *field_local.interiors):
            xy = np.asarray(ring.coords)[:-1]
            before, after = np.roll(xy, 1, axis=0), np.roll(xy, -1, axis=0)
            cross = _cross(xy - before, after - xy)
            # Exterior counter-clockwise, holes clockwise: free space turns right at its
            # reflex corners.
            reflex = cross < 0.0
            nodes.append(xy[reflex])
            prev.append(before[reflex])
            nxt.append(after[reflex])
        self.nodes = np.concatenate(nodes)
        to_prev = np.concatenate(prev) - self.nodes
        to_next = np.concatenate(nxt) - self.nodes
        to_prev /= np.hypot(*to_prev.T)[:, None]
        to_next /= np.hypot(*to_next.T)[:, None]
        # The corners' x and y; the unit vectors from each to its ring neighbours (prev x,
        # prev y, next x, next y): the tangency test, on rows for fast gathers.
        self._xy = np.ascontiguousarray(self.nodes.T)
        self._around = np.ascontiguousarray(np.hstack([to_prev, to_next]).T)
        # Whether two tangent corners see each other, by pair key (lo * n + hi), as
        # queries meet them: a field of 20,000 corners has 2e8 pairs, a query a few hundred.
        self._seen: dict[int, bool] = {}
        # Both tests of every pair met so far in one matrix instead (-1 not yet, 0 no, 1
        # tangent and in sight), over up to _DENSE_CORNERS corners numbered as queries meet
        # them (_slot; -1 not met): fields' moves meet the same pairs again and again, and a
        # jagged field's next move the pairs of the last. When more corners are met, the
        # matrix starts afresh.
        self._states: npt.NDArray[np.int8] | None = None
        self._slot = np.empty(0, dtype=np.int64)
        self._met: list[IntArray] = []
        self._slots_used = 0
        self._graph: csr_matrix | None = None

    def in_sight(self, subset: IntArray, i: IntArray, j: IntArray) -> BoolArray:
        """Whether corners ``subset[i[k]]`` and ``subset[j[k]]`` are tangent and see each other.

        ``subset`` (distinct corners) is a query's: its pairs' answers are kept in the pair
        matrix if it fits, else by pair key.
        """
        slots = self._slots(subset)
        if slots is None:
            return self._seen_pairs(subset[i], subset[j])
        return self._seen_slot_pairs(subset[i], subset[j], slots[i], slots[j])

    def _slots(self, corners: IntArray) -> IntArray | None:
        """Slots of ``corners`` (distinct) in the pair matrix, new ones given slots.

        None if they are more than the matrix holds (that query is cached by pair key).
        """
        size = min(len(self.nodes), _DENSE_CORNERS)
        if len(corners) > size:
            return None
        if self._states is None:
            self._states = np.full((size, size), -1, dtype=np.int8)
            self._slot = np.full(len(self.nodes), -1, dtype=np.int64)
        slots = self._slot[corners]
        new = corners[slots < 0]
        if len(new) == 0:
            return slots
        if self._slots_used + len(new) > size:
            # Full: start afresh (pairs met again are tested again, with the same answers).
            for met in self._met:
                self._slot[met] = -1
            self._met.clear()
            self._states.fill(-1)
            self._slots_used = 0
            new = corners
        self._slot[new] = self._slots_used + np.arange(len(new))
        self._slots_used += len(new)
        self._met.append(new)
        return self._slot[corners]

    def _seen_slot_pairs(
        self, i: IntArray, j: IntArray, slot_i: IntArray, slot_j: IntArray
    ) -> BoolArray:
        """:meth:`_seen_pairs` by the pair matrix: corners ``i, j`` in ``slot_i, slot_j``."""
        assert self._states is not None
        known = self._states[slot_i, slot_j]
        new = np.nonzero(known < 0)[0]
        if len(new):
            i, j = i[new], j[new]
            state = self.tangent(i, j).astype(np.int8)
            tangent = np.nonzero(state)[0]
            if len(tangent):
                state[tangent] = self._interior.segments(
                    self.nodes[i[tangent]], self.nodes[j[tangent]]
                )
            self._states[slot_i[new], slot_j[new]] = state
            self._states[slot_j[new], slot_i[new]] = state
            known[new] = state
        return np.asarray(known == 1)

    def _seen_pairs(self, i: IntArray, j: IntArray) -> BoolArray:
        """Whether corners ``i[k]`` and ``j[k]`` are tangent and see each other (cached)."""
        ok = self.tangent(i, j)
        where = np.nonzero(ok)[0]
        if len(where) == 0:
            return ok
        lo, hi = np.minimum(i[where], j[where]), np.maximum(i[where], j[where])
        keys = (lo * len(self.nodes) + hi).tolist()
        seen = self._seen
        known = np.fromiter((seen.get(k, 2) for k in keys), dtype=np.int8, count=len(keys))
        new = np.nonzero(known == 2)[0]
        if len(new):
            fresh = self._interior.segments(self.nodes[lo[new]], self.nodes[hi[new]])
            known[new] = fresh
            seen.update(zip([keys[k] for k in new.tolist()], fresh.tolist(), strict=True))
        ok[where] = known == 1
        return ok

    def tangent(self, i: IntArray, j: IntArray) -> BoolArray:
        """Whether the line through corners ``i[k]`` and ``j[k]`` is tangent at both.

        A shortest path only passes a corner it wraps round, so other pairs need no edge.
        Compiled (:func:`planner.edge_kernels.tangent_pairs`, the same arithmetic);
        :meth:`tangent_numpy` is the reference.
        """
        from planner import edge_kernels  # numba: imported by the first plan that needs it

        return edge_kernels.tangent_pairs(self._xy, self._around, i, j, _COLLINEAR)

    def tangent_numpy(self, i: IntArray, j: IntArray) -> BoolArray:
        """:meth:`tangent` in numpy."""
        x, y = self._xy
        dx, dy = x[j] - x[i], y[j] - y[i]
        # A neighbour within 1e-9 rad of the line counts as on it (sines, as distances).
        tolerance = _COLLINEAR * np.hypot(dx, dy)
        ok = tolerance == 0.0
        wraps = ~ok
        for k in (i, j):
            prev_x, prev_y, next_x, next_y = self._around[:, k]
            before = dx * prev_y - dy * prev_x
            after = dx * next_y - dy * next_x
            wraps &= (
                (np.abs(before) < tolerance) | (np.abs(after) < tolerance) | (before * after > 0.0)
            )
        return np.asarray(ok | wraps)

    def graph(self) -> csr_matrix:
        """Every pair of corners tangent and in sight, with its length [m], built once."""
        if self._graph is not None:
            return self._graph
        n = len(self.nodes)
        rows, cols = [np.empty(0, dtype=np.int64)], [np.empty(0, dtype=np.int64)]
        # Rows in blocks of about a million pairs: memory stays small on big fields. Not
        # through the query cache: every pair is met once here.
        step = max(1, 1_000_000 // max(n, 1))
        for first in range(0, n, step):
            i, j = np.nonzero(np.arange(first, min(n, first + step))[:, None] < np.arange(n))
            i += first
            tangent = self.tangent(i, j)
            i, j = i[tangent], j[tangent]
            visible = self._interior.segments(self.nodes[i], self.nodes[j])
            rows.append(i[visible])
            cols.append(j[visible])
        i, j = np.concatenate(rows), np.concatenate(cols)
        length = np.hypot(*(self.nodes[i] - self.nodes[j]).T)
        self._graph = csr_matrix((length, (i, j)), shape=(n, n))
        return self._graph


def _swap_xy(xy: FloatArray) -> FloatArray:
    return xy[:, ::-1]


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
