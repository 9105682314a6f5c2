"""Shortest moves inside a field, around its holes: a visibility graph over its corners.

A shortest path inside a polygon bends only at *reflex* corners of the free space: reflex
vertices of the exterior and convex vertices of the holes. The graph joins every pair of such
corners that see each other and are tangent there (a path only bends round a corner it wraps);
lengths come from Dijkstra (``scipy.sparse.csgraph``). A move searches only the corners its
ellipse bound admits (a few dozen of a field's thousands), and which tangent pairs see each
other is kept for later moves; :meth:`FieldRouter.distances` builds the whole graph, once,
and so does a field of a few hundred corners that many moves search (a real field's
machine area): its moves then test only which corners their ends see.
Which moves stay inside and which corners see each other is :mod:`planner.visibility`'s.
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
from planner.visibility import GRAZE_M, CornerVisibility, FieldInterior

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: An end point this close outside the field (a headland ring built on the machine area's
#: boundary, off by buffer rounding) is routed from its nearest point of the field [m].
SNAP_M = 5e-3
#: Corners whose visibility a query tests first (nearest the straight move by the ellipse).
_FIRST_CORNERS = 32
#: A pair of corners is left out of a search only if every path through it is this much
#: longer than one found (the bound's rounding is some 1e-13 m) [m].
_REACH_SLACK_M = 1e-6
#: A field of at most this many corners has its whole visibility graph built once it has
#: searched :data:`_WHOLE_GRAPH_AFTER` moves, and every search then runs over it, with only
#: what the move's two ends see tested: a real field's machine area has a few hundred
#: corners and about one edge per corner (germany_2018_2019-47's 724 corners: 20 ms for the
#: graph and 30 ms for the paths between every two corners; its 252 searches with the small
#: tractor took 1.6 s over pairs tested query by query, 0.5 s over the whole graph). A larger
#: field's graph costs too much to build whole (29 s for the 1,999-vertex wavy field's
#: 19,636 corners, 0.7 s for the 50 holes' 4,800), and its searches test the pairs of the
#: corners they rank, as do a field's first searches. The paths take n² × 12 bytes: 12 MiB
#: at 1,024 corners (4.6 GB at the wavy field's 19,636).
_WHOLE_GRAPH_CORNERS = 1024
#: Searches over ranked pairs before the whole graph is built: 8 of them, at 1–6 ms each on
#: the real fields, cost about what the graph and its paths do (10–50 ms).
_WHOLE_GRAPH_AFTER = 8


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
        self._interior = FieldInterior(self.field)
        # The corners and their pairs' visibility, made by the first move that searches.
        self._visibility: CornerVisibility | None = None
        self._tree: cKDTree | None = None
        self.nodes = np.empty((0, 2))
        # The shortest paths between every two corners, for the searches of a field of up to
        # _WHOLE_GRAPH_CORNERS corners, made by the search after its first _WHOLE_GRAPH_AFTER.
        self._whole: _WholeGraph | None = None
        self._searched = 0

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
        return self._interior.segments(starts, ends)

    def inside_path(self, points: FloatArray) -> bool:
        """Whether the polyline through ``points`` (shape (k, 2), k ≥ 2) stays inside the field.

        The same answer as :meth:`inside` on its every segment, in one test (a turn's curve
        has hundreds of points).
        """
        return self._interior.polyline(points)

    def inside_paths(self, paths: list[FloatArray]) -> npt.NDArray[np.bool_]:
        """:meth:`inside_path` of each polyline of ``paths`` (each shape (k, 2), k ≥ 2).

        One GEOS call for them all: a jagged field's hundreds of moves between cells each try
        the vehicle's own turn first.
        """
        return self._interior.polylines(paths)

    def holds_points(self, points: FloatArray) -> npt.NDArray[np.bool_]:
        """Whether each of ``points`` (shape (k, 2), local [m]) lies inside the field.

        A quick screen of many curves' points (no point objects made) before
        :meth:`inside_paths` tests the few that pass, chords and all.
        """
        return self._interior.holds(points)

    def _snap(self, point: FloatArray, covered: bool | None = None) -> FloatArray:
        """Return ``point``, or its nearest point of the field if it lies just outside.

        ``covered``: whether the field covers ``point``, if known (:meth:`FieldInterior.covers`).
        """
        here = shapely.Point(point)
        if covered is None:
            covered = bool(self._interior.covers(point[None])[0])
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
        covered = self._interior.covers(np.concatenate([starts[searched], ends[searched]]))
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
        corners = self._corners()
        n = len(self.nodes)
        if n == 0:
            return np.stack([a, b])
        self._searched += 1
        if (
            self._whole is None
            and n <= _WHOLE_GRAPH_CORNERS
            and self._searched > _WHOLE_GRAPH_AFTER
        ):
            self._whole = _WholeGraph(corners.graph())
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
            if self._whole is not None:
                found = self._whole_path(a, b, subset[see_a], subset[see_b])
            else:
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
        keep = self._corners().in_sight(subset, i, j)
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

    def _whole_path(
        self, a: FloatArray, b: FloatArray, seen_a: IntArray, seen_b: IntArray
    ) -> tuple[FloatArray, float] | None:
        """Shortest path from ``a`` to ``b`` over the whole graph, entered by sight.

        ``seen_a``, ``seen_b``: the corners ``a`` and ``b`` see (of those ranked so far). A
        path leaves ``a`` for one of them and reaches ``b`` from one, so the search is
        exact once every corner it could leave ``a`` for or reach ``b`` from is ranked (as
        :meth:`_subset_path`'s), while the corners between are all the field's
        (:class:`_WholeGraph`). The same length as :meth:`_subset_path`'s path; where two
        paths tie, perhaps the other one (their lengths are summed in another order).
        """
        assert self._whole is not None
        if len(seen_a) == 0 or len(seen_b) == 0:
            return None
        from_a = np.hypot(*(self.nodes[seen_a] - a).T)
        to_b = np.hypot(*(self.nodes[seen_b] - b).T)
        through_m = from_a[:, None] + self._whole.lengths_m[np.ix_(seen_a, seen_b)] + to_b
        best = int(np.argmin(through_m))
        if not np.isfinite(through_m.flat[best]):
            return None
        first, last = divmod(best, len(seen_b))
        corners = self._whole.corners_between(int(seen_a[first]), int(seen_b[last]))
        points = np.vstack([a, self.nodes[corners], b])
        # Summed leg by leg from a, as a search would: the same length to the last bit.
        return points, float(np.cumsum(np.hypot(*np.diff(points, axis=0).T))[-1])

    def _corners(self) -> CornerVisibility:
        """Return the field's corners and their pairs' visibility, made on first use."""
        if self._visibility is None:
            self._visibility = CornerVisibility(self.field, self._interior)
            self.nodes = self._visibility.nodes
        return self._visibility

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
        corners = self._corners().graph()
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


class _WholeGraph:
    """Shortest paths between every two corners of a field (its whole visibility graph).

    Parameters
    ----------
    graph : csr_matrix
        :meth:`planner.visibility.CornerVisibility.graph`.
    """

    def __init__(self, graph: csr_matrix) -> None:
        lengths_m, previous = shortest_path(
            graph, method="D", directed=False, return_predecessors=True
        )
        #: ``lengths_m[i, j]``: corner i to corner j [m] (inf where no path joins them).
        self.lengths_m: FloatArray = lengths_m
        self._previous: npt.NDArray[np.int32] = previous

    def corners_between(self, first: int, last: int) -> IntArray:
        """Return the corners of the shortest path from corner ``first`` to ``last``, both in."""
        chain = [last]
        while chain[-1] != first:
            before = int(self._previous[first, chain[-1]])
            if before < 0:  # scipy's -9999: no path (the caller asks only for joined corners)
                raise ValueError(f"no path joins corners {first} and {last}")
            chain.append(before)
        return np.asarray(chain[::-1], dtype=np.int64)


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


def path_length(points: FloatArray) -> float:
    """Length of a polyline [m]."""
    return float(np.hypot(*np.diff(points, axis=0).T).sum())
