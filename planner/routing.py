"""Shortest moves inside a field, around its holes: a visibility graph over its corners.

A shortest path inside a polygon bends only at *reflex* corners of the free space: reflex
vertices of the exterior and convex vertices of the holes. The graph joins every pair of such
corners that see each other and are tangent there (a path only bends round a corner it wraps);
all-pairs distances come from Dijkstra (``scipy.sparse.csgraph``). The graph is built once per
field, on the first move that cannot go straight, and serves every later query.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import shapely
import shapely.ops
from scipy.sparse import csr_matrix  # type: ignore[import-untyped]
from scipy.sparse.csgraph import shortest_path  # type: ignore[import-untyped]
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
        shapely.prepare(self._grown)
        self._built = False
        self._cornered = False
        self._seen = np.empty((0, 0), dtype=np.int8)
        self.nodes = np.empty((0, 2))
        self._prev = np.empty((0, 2))
        self._next = np.empty((0, 2))
        self._dist = np.empty((0, 0))
        self._pred = np.empty((0, 0), dtype=np.int64)

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
        segments = shapely.linestrings(np.stack([starts, ends], axis=1))
        return np.asarray(shapely.contains_properly(self._grown, segments))

    def _snap(self, point: FloatArray) -> FloatArray:
        """Return ``point``, or its nearest point of the field if it lies just outside."""
        here = shapely.Point(point)
        if self._grown.covers(here):
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
        snapped_a, snapped_b = self._snap(a), self._snap(b)
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
        # a shortest path no longer than U uses only corners with that bound ≤ U: search the
        # graph of those corners alone, widening U until the path found is within it.
        bound = np.hypot(*(self.nodes - a).T) + np.hypot(*(self.nodes - b).T)
        order = np.argsort(bound, kind="stable")
        limit = float(bound[order[min(n, _FIRST_CORNERS) - 1]])
        while True:
            subset = order[: int(np.searchsorted(bound[order], limit, side="right"))]
            found = self._subset_path(a, b, subset)
            if found is not None and found[1] <= limit + 1e-9:
                return found[0]
            if len(subset) == n:
                if found is None:
                    raise PlannerError(
                        "field", "no path inside the field joins two points of the plan"
                    )
                return found[0]
            limit = max(2.0 * limit, found[1] if found is not None else 0.0)

    def _subset_path(
        self, a: FloatArray, b: FloatArray, subset: IntArray
    ) -> tuple[FloatArray, float] | None:
        """Shortest path from ``a`` to ``b`` through the corners ``subset`` only."""
        s = len(subset)
        self._see_pairs(subset)
        sub = self._seen[np.ix_(subset, subset)] == 1
        i, j = np.nonzero(np.triu(sub, k=1))
        length = np.hypot(*(self.nodes[subset[i]] - self.nodes[subset[j]]).T)
        see_a = self._visible_from(a, subset)
        see_b = self._visible_from(b, subset)
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
        graph = csr_matrix((weights, (rows, cols)), shape=(s + 2, s + 2))
        dist, pred = shortest_path(
            graph, method="D", directed=False, indices=s, return_predecessors=True
        )
        if not np.isfinite(dist[s + 1]):
            return None
        chain = [int(pred[s + 1])]
        while chain[-1] != s:
            chain.append(int(pred[chain[-1]]))
        corners = subset[np.asarray(chain[:-1][::-1], dtype=np.int64)]
        return np.vstack([a, self.nodes[corners], b]), float(dist[s + 1])

    def _see_pairs(self, subset: IntArray) -> None:
        """Fill in which pairs of ``subset`` see each other (tangent and inside), once each."""
        sub = np.sort(subset)
        known = self._seen[np.ix_(sub, sub)]
        i, j = np.nonzero(np.triu(known < 0, k=1))
        if len(i) == 0:
            return
        i, j = sub[i], sub[j]
        a, b = self.nodes[i], self.nodes[j]
        ok = _tangent(b, a, self._prev[i], self._next[i]) & _tangent(
            a, b, self._prev[j], self._next[j]
        )
        result = np.zeros(len(i), dtype=np.int8)
        if ok.any():
            result[ok] = self.inside(a[ok], b[ok]).astype(np.int8)
        self._seen[i, j] = result
        self._seen[j, i] = result

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
        self._prev = np.concatenate(prev)
        self._next = np.concatenate(nxt)
        n = len(self.nodes)
        self._seen = np.full((n, n), -1, dtype=np.int8)  # -1 unknown, 0 blocked, 1 seen

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
        self._build()
        n = len(self.nodes)
        if n == 0:
            unreachable: FloatArray = np.where(seen, straight, np.inf)
            return unreachable
        node_seen_a = self.inside(np.repeat(starts, n, axis=0), np.tile(self.nodes, (p, 1)))
        node_seen_b = self.inside(np.repeat(ends, n, axis=0), np.tile(self.nodes, (q, 1)))
        to_node = np.hypot(*(np.repeat(starts, n, axis=0) - np.tile(self.nodes, (p, 1))).T)
        from_node = np.hypot(*(np.repeat(ends, n, axis=0) - np.tile(self.nodes, (q, 1))).T)
        leg_a = np.where(node_seen_a, to_node, np.inf).reshape(p, n)
        leg_b = np.where(node_seen_b, from_node, np.inf).reshape(q, n)
        # Min-plus products: start → node i → (graph) → node j → end.
        via = (leg_a[:, :, None] + self._dist[None, :, :]).min(axis=1)  # (p, n)
        around = (via[:, None, :] + leg_b[None, :, :]).min(axis=2)  # (p, q)
        lengths: FloatArray = np.where(seen, straight, around)
        return lengths

    def _visible_from(self, p: FloatArray, which: IntArray) -> npt.NDArray[np.bool_]:
        # No tangency filter here: a query point on the boundary, a hair off an edge, would
        # fail it against that edge's own corner.
        return self.inside(np.repeat(p[None], len(which), axis=0), self.nodes[which])

    def _build(self) -> None:
        """All-pairs distances between the corners (for :meth:`distances`)."""
        if self._built:
            return
        self._built = True
        self._corners()
        n = len(self.nodes)
        if n == 0:
            return
        everything = np.arange(n)
        self._see_pairs(everything)
        i, j = np.nonzero(np.triu(self._seen == 1, k=1))
        length = np.hypot(*(self.nodes[i] - self.nodes[j]).T)
        graph = csr_matrix((length, (i, j)), shape=(n, n))
        dist, pred = shortest_path(graph, method="D", directed=False, return_predecessors=True)
        self._dist = dist
        self._pred = pred.astype(np.int64)


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _tangent(
    p: FloatArray, corner: FloatArray, before: FloatArray, after: FloatArray
) -> npt.NDArray[np.bool_]:
    """Whether the line from ``p`` through ``corner`` has both ring neighbours on one side.

    A shortest path only passes a corner it wraps round, so other corners need no edge.
    """
    direction = corner - p
    to_before, to_after = before - corner, after - corner
    reach = np.hypot(direction[..., 0], direction[..., 1])
    # Sines of the angles; a neighbour within 1e-9 rad of the line counts as on it.
    s1 = _cross(direction, to_before) / (reach * np.hypot(to_before[..., 0], to_before[..., 1]))
    s2 = _cross(direction, to_after) / (reach * np.hypot(to_after[..., 0], to_after[..., 1]))
    s1 = np.where(np.abs(s1) < _COLLINEAR, 0.0, s1)
    s2 = np.where(np.abs(s2) < _COLLINEAR, 0.0, s2)
    with np.errstate(invalid="ignore"):
        return np.asarray((s1 * s2 >= 0.0) | (reach == 0.0))


def path_length(points: FloatArray) -> float:
    """Length of a polyline [m]."""
    return float(np.hypot(*np.diff(points, axis=0).T).sum())
