"""Shortest moves inside a field, around its holes: a visibility graph over its corners.

A shortest path inside a polygon bends only at *reflex* corners of the free space: reflex
vertices of the exterior and convex vertices of the holes. The graph joins every pair of such
corners that see each other and are tangent there (a path only bends round a corner it wraps);
lengths come from Dijkstra (``scipy.sparse.csgraph``). A move searches only the corners its
ellipse bound admits (a few dozen of a field's thousands), and which tangent pairs see each
other is kept for later moves; :meth:`FieldRouter.distances` builds the whole graph, once.
"""

from __future__ import annotations

import functools
import heapq
import math

import numpy as np
import numpy.typing as npt
import shapely
import shapely.ops
from scipy.sparse import csr_matrix  # type: ignore[import-untyped]
from scipy.sparse.csgraph import shortest_path  # type: ignore[import-untyped]
from scipy.spatial import cKDTree  # type: ignore[import-untyped]
from shapely import Polygon

from planner.errors import PlannerError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: A move may graze the boundary by this much and still count as inside [m]; R1 allows 1 cm.
GRAZE_M = 1e-3
#: An end point this close outside the field (a headland ring built on the machine area's
#: boundary, off by buffer rounding) is routed from its nearest point of the field [m].
SNAP_M = 5e-3
#: Corners whose visibility a query tests first (nearest the straight move by the ellipse).
_FIRST_CORNERS = 32
#: Corners up to which pair states are kept in a dense matrix (4 MB), beyond in a dict.
_DENSE_CORNERS = 2048
#: A pair of corners is left out of a search only if every path through it is this much
#: longer than one found (the bound's rounding is some 1e-13 m) [m].
_REACH_SLACK_M = 1e-6
#: Sine below which a corner's neighbour counts as on a line through the corner.
_COLLINEAR = 1e-9


class FieldRouter:
    """Shortest paths between points of one field, staying inside it and outside its holes.

    Parameters
    ----------
    field_local : Polygon
        The field, local frame [m], holes allowed.

    Examples
    --------
    Round the inner corner of an L-shaped field:

    >>> from shapely import Polygon
    >>> router = FieldRouter(Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)]))
    >>> router.path((50.0, 20.0), (20.0, 50.0)).tolist()
    [[50.0, 20.0], [30.0, 30.0], [20.0, 50.0]]
    """

    def __init__(self, field_local: Polygon) -> None:
        self.field = shapely.orient_polygons(field_local)
        self._grown = self.field.buffer(GRAZE_M, join_style="mitre")
        # GEOS locates a point by the edges a horizontal line through it crosses: a comb
        # whose teeth run along y crosses them all. With |dy| the greater over the edges,
        # the tests run on x and y swapped (exact: a reflection, no arithmetic).
        rings = shapely.get_rings(shapely.get_parts(self._grown))
        edges = np.concatenate(
            [
                np.empty((0, 2)),
                *[np.abs(np.diff(shapely.get_coordinates(r), axis=0)) for r in rings],
            ]
        )
        self._swap = bool(edges[:, 1].sum() > edges[:, 0].sum())
        self._test = shapely.transform(self._grown, _swap_xy) if self._swap else self._grown
        shapely.prepare(self._test)
        self._cornered = False
        self._tree: cKDTree | None = None
        self.nodes = np.empty((0, 2))
        # The corners' x and y; the unit vectors from each to its ring neighbours (prev x,
        # prev y, next x, next y): the tangency test, on rows for fast gathers.
        self._xy = np.empty((2, 0))
        self._around = np.empty((4, 0))
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

    def inside(self, starts: FloatArray, ends: FloatArray) -> npt.NDArray[np.bool_]:
        """Whether each straight move ``starts[k] → ends[k]`` stays inside the field.

        Parameters
        ----------
        starts, ends : ndarray, shape (k, 2)
            Local [m].

        Returns
        -------
        ndarray of bool, shape (k,)
        """
        segments = np.stack([starts, ends], axis=1)
        if self._swap:
            segments = segments[..., ::-1]
        return np.asarray(shapely.contains_properly(self._test, shapely.linestrings(segments)))

    def inside_path(self, points: FloatArray) -> bool:
        """Whether the polyline through ``points`` (shape (k, 2), k ≥ 2) stays inside the field.

        The same answer as :meth:`inside` on its every segment, in one test (a turn's curve
        has hundreds of points).
        """
        line = shapely.linestrings(points[:, ::-1] if self._swap else points)
        return bool(shapely.contains_properly(self._test, line))

    def inside_paths(self, paths: list[FloatArray]) -> npt.NDArray[np.bool_]:
        """:meth:`inside_path` of each polyline of ``paths`` (each shape (k, 2), k ≥ 2).

        One GEOS call for them all: a jagged field's hundreds of moves between cells each try
        the vehicle's own turn first.
        """
        if not paths:
            return np.zeros(0, dtype=bool)
        points = np.concatenate(paths)
        owner = np.repeat(np.arange(len(paths)), [len(p) for p in paths])
        lines = shapely.linestrings(points[:, ::-1] if self._swap else points, indices=owner)
        return np.asarray(shapely.contains_properly(self._test, lines))

    def _covers(self, points: FloatArray) -> npt.NDArray[np.bool_]:
        """Whether the (grown) field covers each of ``points`` (shape (k, 2)), in one call."""
        return np.asarray(
            shapely.covers(self._test, shapely.points(points[:, ::-1] if self._swap else points))
        )

    def _snap(self, point: FloatArray, covered: bool | None = None) -> FloatArray:
        """Return ``point``, or its nearest point of the field if it lies just outside.

        ``covered``: whether the field covers ``point``, if known (:meth:`_covers`).
        """
        here = shapely.Point(point)
        if covered is None:
            covered = bool(self._covers(point[None])[0])
        if covered:
            return point
        distance = self.field.distance(here)
        if distance > SNAP_M:
            return point
        # Onto the boundary, then a graze inwards: the search starts inside.
        near = shapely.ops.nearest_points(self.field, here)[0]
        towards = np.asarray(near.coords[0]) - point
        return np.asarray(near.coords[0]) + towards / max(distance, 1e-12) * (GRAZE_M / 2.0)

    def path(self, start_xy: tuple[float, float], end_xy: tuple[float, float]) -> FloatArray:
        """Shortest path from ``start_xy`` to ``end_xy`` inside the field.

        Returns
        -------
        ndarray, shape (k, 2)
            Its vertices, from ``start_xy`` to ``end_xy`` included, local [m].

        Raises
        ------
        PlannerError
            If no path inside the field joins the two points (a point outside the field).
        """
        a = np.asarray(start_xy, dtype=float)
        b = np.asarray(end_xy, dtype=float)
        if self.inside(a[None], b[None])[0]:
            return np.stack([a, b])
        return self._search(a, b)

    def paths(self, starts: FloatArray, ends: FloatArray) -> list[FloatArray]:
        """:meth:`path` from each ``starts[k]`` to ``ends[k]`` (shapes (k, 2)), local [m].

        The straight moves are found in one test of them all; only the others are searched.
        """
        starts, ends = np.asarray(starts, dtype=float), np.asarray(ends, dtype=float)
        straight = self.inside(starts, ends)
        # Whether the field covers each searched move's ends: one test of them all.
        searched = np.flatnonzero(~straight)
        covered = self._covers(np.concatenate([starts[searched], ends[searched]]))
        cover_a = dict(zip(searched.tolist(), covered[: len(searched)].tolist(), strict=True))
        cover_b = dict(zip(searched.tolist(), covered[len(searched) :].tolist(), strict=True))
        return [
            np.stack([a, b]) if seen else self._search(a, b, cover_a[k], cover_b[k])
            for k, (a, b, seen) in enumerate(zip(starts, ends, straight.tolist(), strict=True))
        ]

    def _search(
        self,
        a: FloatArray,
        b: FloatArray,
        covered_a: bool | None = None,
        covered_b: bool | None = None,
    ) -> FloatArray:
        """:meth:`path` of a move whose straight segment leaves the field.

        ``covered_a``, ``covered_b``: whether the field covers ``a`` and ``b``, if known.
        """
        snapped_a, snapped_b = self._snap(a, covered_a), self._snap(b, covered_b)
        if snapped_a is not a or snapped_b is not b:
            inner = self.path(
                (float(snapped_a[0]), float(snapped_a[1])),
                (float(snapped_b[0]), float(snapped_b[1])),
            )
            return np.vstack([a[None], inner, b[None]])
        self._corners()
        n = len(self.nodes)
        if n == 0:
            return np.stack([a, b])
        # A path through corner i is at least |a − i| + |i − b| long (the ellipse bound), so
        # a path of length L is shortest once every corner of bound ≤ L is searched: search
        # the corners of least bound alone, doubling their number until no path is found,
        # then once more with every corner of bound ≤ the length found.
        order, ranked, complete = self._by_bound(a, b, _FIRST_CORNERS)
        count = min(n, _FIRST_CORNERS)
        see_a = np.empty(0, dtype=bool)
        see_b = np.empty(0, dtype=bool)
        reach = math.inf
        while True:
            if count > len(order):
                order, ranked, complete = self._by_bound(a, b, count)
            # Ties in: every corner left out has a greater bound than every one searched.
            count = int(np.searchsorted(ranked, ranked[count - 1], side="right"))
            subset = order[:count]
            # The subsets grow by their far end: see the new corners only.
            see_a = np.concatenate([see_a, self._visible_from(a, subset[len(see_a) :])])
            see_b = np.concatenate([see_b, self._visible_from(b, subset[len(see_b) :])])
            found = self._subset_path(a, b, subset, see_a, see_b, reach=reach)
            if found is not None:
                need = found[1] + 1e-9
                reach = need
                if need >= complete:
                    order, ranked, complete = self._by_bound(a, b, count, reach=need)
                enough = int(np.searchsorted(ranked, need, side="right"))
                if enough <= count:
                    return found[0]
                count = enough
            elif count == n:
                raise PlannerError("field", "no path inside the field joins two points of the plan")
            else:
                count = min(n, 2 * count)

    def _by_bound(
        self, a: FloatArray, b: FloatArray, count: int, *, reach: float = 0.0
    ) -> tuple[IntArray, FloatArray, float]:
        """Corners in order of their ellipse bound ``|a − i| + |i − b|``, ties by index.

        Returns the first of them, at least ``count`` (or all), their bounds, and a bound
        beyond ``reach`` below which none is left out (``inf`` when all are returned).
        """
        n = len(self.nodes)
        if self._tree is None:
            self._tree = cKDTree(self.nodes)
        middle = (a + b) / 2.0
        # |a − i| + |i − b| ≥ 2 |i − middle|: the k corners nearest the middle hold every
        # corner of bound below twice the k-th distance. Most moves need a few dozen corners
        # of a field's thousands: no need to rank them all.
        k = min(n, 4 * count)
        while k < n // 4:
            distance, index = self._tree.query(middle, k=k)
            complete = 2.0 * float(distance[-1]) * (1.0 - 1e-9)
            if complete > reach:
                bound = np.hypot(*(self.nodes[index] - a).T) + np.hypot(*(self.nodes[index] - b).T)
                keep = bound < complete
                if np.count_nonzero(keep) >= count:
                    index, bound = index[keep], bound[keep]
                    order = np.lexsort((index, bound))
                    return index[order].astype(np.int64), bound[order], complete
            k *= 4
        bound = np.hypot(*(self.nodes - a).T) + np.hypot(*(self.nodes - b).T)
        order = np.argsort(bound, kind="stable")
        return order, bound[order], math.inf

    def _subset_path(
        self,
        a: FloatArray,
        b: FloatArray,
        subset: IntArray,
        see_a: npt.NDArray[np.bool_],
        see_b: npt.NDArray[np.bool_],
        *,
        reach: float = math.inf,
    ) -> tuple[FloatArray, float] | None:
        """Shortest path from ``a`` to ``b`` through the corners ``subset`` only.

        ``see_a[k]``, ``see_b[k]``: whether ``a``, ``b`` see corner ``subset[k]``. A path no
        longer than ``reach`` is known: a pair of corners that no path through both could
        keep within it (``|a − i| + |i − j| + |j − b|`` beyond it, either way round) is no
        edge of the shortest path, nor ties with one, so it is not tested at all: the last,
        largest subset of a search tests a fraction of its pairs.
        """
        s = len(subset)
        i, j = _pairs(s)
        pair_m = None
        if reach < math.inf:
            corner_xy = self.nodes[subset]
            from_a = np.hypot(*(corner_xy - a).T)
            to_b = np.hypot(*(corner_xy - b).T)
            pair_m = np.hypot(*(corner_xy[i] - corner_xy[j]).T)
            bound = np.minimum(from_a[i] + to_b[j], from_a[j] + to_b[i]) + pair_m
            near = np.flatnonzero(bound <= reach + _REACH_SLACK_M)
            i, j, pair_m = i[near], j[near], pair_m[near]
        slots = self._slots(subset)
        if slots is None:
            keep = self._seen_pairs(subset[i], subset[j])
        else:
            keep = self._seen_slot_pairs(subset[i], subset[j], slots[i], slots[j])
        i, j = i[keep], j[keep]
        if pair_m is None:
            length = np.hypot(*(self.nodes[subset[i]] - self.nodes[subset[j]]).T)
        else:
            length = pair_m[keep]
        # Nodes 0 … s-1 the corners, s the start, s+1 the end.
        ia, ib = np.nonzero(see_a)[0], np.nonzero(see_b)[0]
        rows = np.concatenate([i, np.full(len(ia), s), ib])
        cols = np.concatenate([j, ia, np.full(len(ib), s + 1)])
        weights = np.concatenate(
            [
                length,
                np.hypot(*(self.nodes[subset[ia]] - a).T),
                np.hypot(*(self.nodes[subset[ib]] - b).T),
            ]
        )
        found = _dijkstra(s + 2, rows, cols, weights, source=s, target=s + 1)
        if found is None:
            return None
        chain, distance = found
        corners = subset[np.asarray(chain[1:-1], dtype=np.int64)]
        return np.vstack([a, self.nodes[corners], b]), distance

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
    ) -> npt.NDArray[np.bool_]:
        """:meth:`_seen_pairs` by the pair matrix: corners ``i, j`` in ``slot_i, slot_j``."""
        assert self._states is not None
        known = self._states[slot_i, slot_j]
        new = np.nonzero(known < 0)[0]
        if len(new):
            i, j = i[new], j[new]
            state = self._tangent_pairs(i, j).astype(np.int8)
            tangent = np.nonzero(state)[0]
            if len(tangent):
                state[tangent] = self.inside(self.nodes[i[tangent]], self.nodes[j[tangent]])
            self._states[slot_i[new], slot_j[new]] = state
            self._states[slot_j[new], slot_i[new]] = state
            known[new] = state
        return np.asarray(known == 1)

    def _seen_pairs(self, i: IntArray, j: IntArray) -> npt.NDArray[np.bool_]:
        """Whether corners ``i[k]`` and ``j[k]`` are tangent and see each other (cached)."""
        ok = self._tangent_pairs(i, j)
        where = np.nonzero(ok)[0]
        if len(where) == 0:
            return ok
        lo, hi = np.minimum(i[where], j[where]), np.maximum(i[where], j[where])
        keys = (lo * len(self.nodes) + hi).tolist()
        seen = self._seen
        known = np.fromiter((seen.get(k, 2) for k in keys), dtype=np.int8, count=len(keys))
        new = np.nonzero(known == 2)[0]
        if len(new):
            fresh = self.inside(self.nodes[lo[new]], self.nodes[hi[new]])
            known[new] = fresh
            seen.update(zip([keys[k] for k in new.tolist()], fresh.tolist(), strict=True))
        ok[where] = known == 1
        return ok

    def _tangent_pairs(self, i: IntArray, j: IntArray) -> npt.NDArray[np.bool_]:
        """Whether the line through corners ``i[k]`` and ``j[k]`` is tangent at both.

        A shortest path only passes a corner it wraps round, so other pairs need no edge.
        Compiled (:func:`planner.edge_kernels.tangent_pairs`, the same arithmetic);
        :meth:`_tangent_pairs_numpy` is the reference.
        """
        from planner import edge_kernels  # numba: imported by the first plan that needs it

        return edge_kernels.tangent_pairs(self._xy, self._around, i, j, _COLLINEAR)

    def _tangent_pairs_numpy(self, i: IntArray, j: IntArray) -> npt.NDArray[np.bool_]:
        """:meth:`_tangent_pairs` in numpy."""
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

    def _corners(self) -> None:
        if self._cornered:
            return
        self._cornered = True
        nodes, prev, nxt = [], [], []
        for ring in (self.field.exterior, *self.field.interiors):
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
        self._xy = np.ascontiguousarray(self.nodes.T)
        self._around = np.ascontiguousarray(np.hstack([to_prev, to_next]).T)

    def distances(self, starts: FloatArray, ends: FloatArray) -> FloatArray:
        """Return the shortest-path lengths inside the field from every start to every end.

        Parameters
        ----------
        starts : ndarray, shape (p, 2)
        ends : ndarray, shape (q, 2)
            Local [m].

        Returns
        -------
        ndarray, shape (p, q)
            Lengths [m]; ``inf`` where no path joins the points.

        Examples
        --------
        >>> from shapely import Polygon
        >>> router = FieldRouter(Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)]))
        >>> router.distances(np.array([[50.0, 20.0]]), np.array([[20.0, 50.0], [40.0, 10.0]]))
        array([[44.72135955, 14.14213562]])
        """
        p, q = len(starts), len(ends)
        a = np.repeat(starts, q, axis=0)
        b = np.tile(ends, (p, 1))
        straight: FloatArray = np.hypot(*(a - b).T).reshape(p, q)
        seen = self.inside(a, b).reshape(p, q)
        if seen.all():
            return straight
        corners = self._corner_graph()
        n = len(self.nodes)
        if n == 0:
            unreachable: FloatArray = np.where(seen, straight, np.inf)
            return unreachable
        # Nodes 0 … n-1 the corners, then the starts, then the ends; a start joins the
        # corners and ends it sees, an end the corners it sees.
        pairs = [
            (np.repeat(np.arange(p), n), np.tile(np.arange(n), p), starts, n),
            (np.repeat(np.arange(q), n), np.tile(np.arange(n), q), ends, n + p),
        ]
        edges = corners.tocoo()
        rows, cols, weights = [edges.row], [edges.col], [edges.data]
        for point, corner, xy, first in pairs:
            visible = self.inside(xy[point], self.nodes[corner])
            rows.append(first + point[visible])
            cols.append(corner[visible])
            weights.append(np.hypot(*(xy[point[visible]] - self.nodes[corner[visible]]).T))
        direct_start, direct_end = np.nonzero(seen)
        rows.append(n + direct_start)
        cols.append(n + p + direct_end)
        weights.append(straight[direct_start, direct_end])
        size = n + p + q
        graph = csr_matrix(
            (np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))),
            shape=(size, size),
        )
        dist = shortest_path(graph, method="D", directed=False, indices=np.arange(n, n + p))
        lengths: FloatArray = np.where(seen, straight, dist[:, n + p :])
        return lengths

    def _visible_from(self, p: FloatArray, which: IntArray) -> npt.NDArray[np.bool_]:
        # No tangency filter here: a query point on the boundary, a hair off an edge, would
        # fail it against that edge's own corner.
        return self.inside(np.repeat(p[None], len(which), axis=0), self.nodes[which])

    def _corner_graph(self) -> csr_matrix:
        """Every pair of corners tangent and in sight, once per field (for :meth:`distances`)."""
        if self._graph is not None:
            return self._graph
        self._corners()
        n = len(self.nodes)
        rows, cols = [np.empty(0, dtype=np.int64)], [np.empty(0, dtype=np.int64)]
        # Rows in blocks of about a million pairs: memory stays small on big fields. Not
        # through the query cache: every pair is met once here.
        step = max(1, 1_000_000 // max(n, 1))
        for first in range(0, n, step):
            i, j = np.nonzero(np.arange(first, min(n, first + step))[:, None] < np.arange(n))
            i += first
            tangent = self._tangent_pairs(i, j)
            i, j = i[tangent], j[tangent]
            visible = self.inside(self.nodes[i], self.nodes[j])
            rows.append(i[visible])
            cols.append(j[visible])
        i, j = np.concatenate(rows), np.concatenate(cols)
        length = np.hypot(*(self.nodes[i] - self.nodes[j]).T)
        self._graph = csr_matrix((length, (i, j)), shape=(n, n))
        return self._graph


#: Subsets up to this many corners share their pair indices (at most 64 sizes, ~1 MB each);
#: larger ones are rare and would pin tens of MB per size in a long-lived worker.
_SHARED_PAIRS_MAX = 512


def _pairs(count: int) -> tuple[IntArray, IntArray]:
    """``np.triu_indices(count, k=1)``, shared for the small sizes queries ask for again."""
    if count <= _SHARED_PAIRS_MAX:
        return _shared_pairs(count)
    i, j = np.triu_indices(count, k=1)
    return i, j


@functools.lru_cache(maxsize=64)
def _shared_pairs(count: int) -> tuple[IntArray, IntArray]:
    """``np.triu_indices(count, k=1)``, read-only: shared between queries."""
    i, j = np.triu_indices(count, k=1)
    i.flags.writeable = False
    j.flags.writeable = False
    return i, j


def _swap_xy(xy: FloatArray) -> FloatArray:
    return xy[:, ::-1]


def _dijkstra(
    count: int,
    rows: IntArray,
    cols: IntArray,
    weights: FloatArray,
    *,
    source: int,
    target: int,
) -> tuple[list[int], float] | None:
    """Shortest path from ``source`` to ``target`` over undirected edges ``rows[k]–cols[k]``.

    A move's graph is a few dozen corners with a few hundred edges, searched once: building
    a sparse matrix for ``scipy.sparse.csgraph`` costs ~0.25 ms a query, more than the
    search itself (measured on the 1,999-vertex wavy field's 1,351 searches: 0.43 s of the
    routing's 1.34 s), so this is the textbook heap search, stopping at ``target``.

    Returns
    -------
    (list of int, float) or None
        The nodes from ``source`` to ``target`` and the path's length, or None if no path.
    """
    neighbours: list[list[tuple[int, float]]] = [[] for _ in range(count)]
    for u, v, w in zip(rows.tolist(), cols.tolist(), weights.tolist(), strict=True):
        neighbours[u].append((v, w))
        neighbours[v].append((u, w))
    best = [math.inf] * count
    previous = [-1] * count
    best[source] = 0.0
    heap = [(0.0, source)]
    while heap:
        distance, node = heapq.heappop(heap)
        if distance > best[node]:
            continue
        if node == target:
            chain = [node]
            while chain[-1] != source:
                chain.append(previous[chain[-1]])
            return chain[::-1], distance
        for other, weight in neighbours[node]:
            reach = distance + weight
            if reach < best[other]:
                best[other] = reach
                previous[other] = node
                heapq.heappush(heap, (reach, other))
    return None


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def path_length(points: FloatArray) -> float:
    """Length of a polyline [m]."""
    return float(np.hypot(*np.diff(points, axis=0).T).sum())
