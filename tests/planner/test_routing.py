"""Moves inside the field: shortest paths round corners and holes, never outside (R1)."""

from __future__ import annotations

import contextlib
import math
from unittest import mock

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.sparse import csr_matrix  # type: ignore[import-untyped]
from scipy.sparse.csgraph import shortest_path  # type: ignore[import-untyped]
from shapely import LineString, Polygon, box

from planner import routing, visibility
from planner.routing import GRAZE_M, FieldRouter, path_length
from tests.planner.random_fields import fields_with_holes

TOLERANCE_M = 0.01
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
#: How a router searches: over its whole graph (a field of up to _WHOLE_GRAPH_CORNERS corners,
#: after its first _WHOLE_GRAPH_AFTER searches), or over the pairs of the corners each search
#: ranks (larger fields, and a field's first searches).
SEARCHES = ("whole graph", "ranked pairs")


def searching(how: str) -> contextlib.AbstractContextManager[object]:
    """Routers made and searching within this context search ``how`` (:data:`SEARCHES`)."""
    whole = how == "whole graph"
    return mock.patch.multiple(
        routing,
        _WHOLE_GRAPH_CORNERS=routing._WHOLE_GRAPH_CORNERS if whole else 0,
        _WHOLE_GRAPH_AFTER=0,
    )


def assert_inside(field: Polygon, path: np.ndarray) -> None:
    grown = field.buffer(TOLERANCE_M)
    assert grown.covers(LineString(path)), f"leaves the field: {LineString(path).difference(grown)}"


def test_straight_when_the_straight_move_stays_inside() -> None:
    router = FieldRouter(box(0, 0, 100, 50))
    assert router.path((10.0, 10.0), (90.0, 40.0)).tolist() == [[10.0, 10.0], [90.0, 40.0]]


def test_round_a_square_hole_by_the_shorter_side() -> None:
    field = Polygon(box(0, 0, 100, 60).exterior, [box(40, 20, 60, 50).exterior.coords[::-1]])
    router = FieldRouter(field)
    path = router.path((20.0, 30.0), (80.0, 30.0))
    # Below the hole: 20 m down-and-across to each lower corner, 20 m between them.
    assert path.tolist() == [[20.0, 30.0], [40.0, 20.0], [60.0, 20.0], [80.0, 30.0]]
    assert path_length(path) == pytest.approx(2 * math.hypot(20, 10) + 20)
    assert_inside(field, path)


def test_reuses_one_graph_for_every_query() -> None:
    field = Polygon(box(0, 0, 100, 60).exterior, [box(40, 20, 60, 50).exterior.coords[::-1]])
    router = FieldRouter(field)
    router.path((20.0, 30.0), (80.0, 30.0))
    nodes = router.nodes
    router.path((30.0, 55.0), (70.0, 25.0))
    assert router.nodes is nodes


def _points_inside(field: Polygon, rng: np.random.Generator, k: int) -> list[tuple[float, float]]:
    x0, y0, x1, y1 = field.bounds
    points: list[tuple[float, float]] = []
    while len(points) < k:
        p = (float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1)))
        if field.contains(shapely.Point(p)):
            points.append(p)
    return points


@SETTINGS
@given(field=fields_with_holes(), seed=st.integers(0, 2**32 - 1))
def test_paths_stay_inside_and_are_no_longer_than_a_detour_inside(
    field: Polygon, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    router = FieldRouter(field)
    a, b, c = _points_inside(field, rng, 3)
    ab = router.path(a, b)
    assert ab[0].tolist() == list(a) and ab[-1].tolist() == list(b)
    assert_inside(field, ab)
    # Shortest: never shorter than straight, never longer than going by way of c.
    assert path_length(ab) >= math.dist(a, b) - 1e-9
    assert path_length(ab) <= path_length(router.path(a, c)) + path_length(router.path(c, b)) + 1e-6
    # Symmetric.
    assert path_length(router.path(b, a)) == pytest.approx(path_length(ab), abs=1e-6)


@SETTINGS
@given(field=fields_with_holes())
def test_paths_between_boundary_points_stay_inside(field: Polygon) -> None:
    """Line ends lie on the boundary: moves between them must not cut across it."""
    rings = [field.exterior, *field.interiors]
    router = FieldRouter(field)
    points = [ring.interpolate(t, normalized=True) for ring in rings for t in (0.1, 0.37, 0.74)]
    for p, q in zip(points, points[1:], strict=False):
        assert_inside(field, router.path((p.x, p.y), (q.x, q.y)))


@SETTINGS
@given(field=fields_with_holes(), seed=st.integers(0, 2**32 - 1))
def test_distance_matrix_equals_the_lengths_of_the_paths(field: Polygon, seed: int) -> None:
    rng = np.random.default_rng(seed)
    router = FieldRouter(field)
    starts = np.asarray(_points_inside(field, rng, 3))
    ends = np.asarray(_points_inside(field, rng, 2))
    matrix = router.distances(starts, ends)
    for i, a in enumerate(starts):
        for j, b in enumerate(ends):
            expected = path_length(router.path(tuple(a), tuple(b)))
            assert matrix[i, j] == pytest.approx(expected, abs=1e-6)


def _reference_lengths(
    field: Polygon, nodes: np.ndarray, queries: list[tuple[tuple[float, float], ...]]
) -> list[tuple[float, float]]:
    """Shortest a → b by the plain visibility graph on ``nodes``: every pair tested, Dijkstra.

    For each query ``(a, b)``, the length with moves allowed to graze the boundary by
    ``GRAZE_M`` (no path the router may take is shorter) and the length with moves held to
    the field exactly (the router's, grazing allowed, is no longer).
    """
    grown = field.buffer(GRAZE_M, join_style="mitre")
    exact = shapely.from_wkb(shapely.to_wkb(field))  # a copy, to prepare
    shapely.prepare([grown, exact])

    def seen(starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        segments = shapely.linestrings(np.stack([starts, ends], axis=1))
        grazing = shapely.contains_properly(grown, segments)
        held = grazing.copy()  # a move held to the field grazes it by nothing
        held[grazing] = shapely.covers(exact, segments[grazing])
        return grazing, held

    i, j = np.triu_indices(len(nodes), k=1)
    between = seen(nodes[i], nodes[j])
    k = np.arange(len(nodes))
    out = []
    for a, b in queries:
        ends = np.asarray([a, b])
        legs = seen(np.repeat(ends, len(nodes), axis=0), np.tile(nodes, (2, 1)))
        straight = seen(ends[:1], ends[1:])
        lengths = []
        for mask, leg, direct in zip(between, legs, straight, strict=True):
            # Nodes 0 … n-1 the corners, n the start, n+1 the end.
            rows = np.concatenate([i[mask], np.repeat([len(nodes), len(nodes) + 1], len(nodes))])
            cols = np.concatenate([j[mask], k, k])
            keep = np.concatenate([np.ones(int(mask.sum()), dtype=bool), leg])
            rows, cols = np.append(rows[keep], len(nodes)), np.append(cols[keep], len(nodes) + 1)
            points = np.vstack([nodes, ends])
            weight = np.hypot(*(points[rows] - points[cols]).T)
            weight[-1] = weight[-1] if direct[0] else np.inf
            graph = csr_matrix((weight, (rows, cols)), shape=(len(points), len(points)))
            lengths.append(float(shortest_path(graph, directed=False, indices=len(nodes))[-1]))
        out.append((lengths[0], lengths[1]))
    return out


def _reflex_corners(field: Polygon) -> np.ndarray:
    """Corners a shortest path can bend at: reflex on the exterior, convex on the holes."""
    field = shapely.orient_polygons(field)
    corners = []
    for ring in (field.exterior, *field.interiors):
        xy = np.asarray(ring.coords)[:-1]
        before, after = np.roll(xy, 1, axis=0), np.roll(xy, -1, axis=0)
        turn = (xy - before)[:, 0] * (after - xy)[:, 1] - (xy - before)[:, 1] * (after - xy)[:, 0]
        corners.append(xy[turn < 0.0])
    return np.concatenate(corners)


@pytest.mark.parametrize("how", SEARCHES)
@SETTINGS
@given(field=fields_with_holes(), seed=st.integers(0, 2**32 - 1))
def test_paths_are_as_short_as_a_plain_visibility_graph_over_every_vertex(
    how: str, field: Polygon, seed: int
) -> None:
    """No corner pruned (tangency, ellipse bound) that a shortest path needs."""
    rng = np.random.default_rng(seed)
    router = FieldRouter(field)
    vertices = np.concatenate(
        [np.asarray(r.coords)[:-1] for r in (field.exterior, *field.interiors)]
    )
    queries = list(zip(*[iter(_points_inside(field, rng, 6))] * 2, strict=True))
    with searching(how):
        for (a, b), (grazing, exact) in zip(
            queries, _reference_lengths(field, vertices, queries), strict=True
        ):
            assert grazing - 1e-9 <= path_length(router.path(a, b)) <= exact + 1e-9
    if router._visibility is not None:  # some move was searched
        assert (router._whole is not None) == (how == "whole graph" and len(router.nodes) > 0)


@settings(SETTINGS, max_examples=8)
@given(field=fields_with_holes(max_holes=3), seed=st.integers(0, 2**32 - 1))
def test_paths_on_fields_of_many_corners_are_as_short_as_a_plain_visibility_graph(
    field: Polygon, seed: int
) -> None:
    """A machine area's rounded corners: so many that a move ranks only those near it."""

    def rounded(quad_segs: int) -> Polygon:
        area = field.buffer(-0.5, quad_segs=quad_segs)
        return max(shapely.get_parts(area), key=lambda p: p.area)  # type: ignore[no-any-return]

    # About 600 corners: FieldRouter ranks them by a k-d tree past 4 * 4 * 32.
    few = len(_reflex_corners(rounded(16)))
    assume(few > 0)
    area = rounded(min(512, math.ceil(16 * 600 / few)))
    corners = _reflex_corners(area)
    assume(520 < len(corners) < 800)
    rng = np.random.default_rng(seed)
    router = FieldRouter(area)
    # Moves that cannot go straight, the longest first: those search far beyond their ends.
    points = np.asarray(_points_inside(area, rng, 30))
    i, j = np.triu_indices(len(points), k=1)
    blocked = ~router.inside(points[i], points[j])
    far = np.argsort(-np.hypot(*(points[i] - points[j]).T) * blocked, kind="stable")[:3]
    queries = [(tuple(points[i[k]]), tuple(points[j[k]])) for k in far]
    lengths = _reference_lengths(area, corners, queries)
    # Over the whole graph (up to 1,024 corners); over ranked pairs, their states in a dense
    # matrix (up to 2,048 corners) and in a dict (beyond).
    for whole, dense in ((True, True), (False, True), (False, False)):
        with (
            searching("whole graph" if whole else "ranked pairs"),
            mock.patch.object(visibility, "_DENSE_CORNERS", 2048 if dense else 0),
        ):
            router = FieldRouter(area)
            for (a, b), (grazing, exact) in zip(queries, lengths, strict=True):
                path = router.path(a, b)
                assert_inside(area, path)
                assert grazing - 1e-9 <= path_length(path) <= exact + 1e-9
            corners = router._visibility
            if corners is not None:  # some move was searched
                assert (router._whole is not None) == whole
                assert (corners._states is not None) == (dense and not whole)


@SETTINGS
@given(field=fields_with_holes(), seed=st.integers(0, 2**32 - 1))
def test_the_whole_graph_finds_the_paths_ranked_pairs_find(field: Polygon, seed: int) -> None:
    """The two ways of searching take the same paths, to the last bit (ties aside)."""
    rng = np.random.default_rng(seed)
    points = np.asarray(_points_inside(field, rng, 8))
    i, j = np.triu_indices(len(points), k=1)
    paths = {}
    for how in SEARCHES:
        with searching(how):
            router = FieldRouter(field)
            paths[how] = router.paths(points[i], points[j])
    searched = 0
    for whole, ranked in zip(paths["whole graph"], paths["ranked pairs"], strict=True):
        searched += len(ranked) > 2
        if whole.shape != ranked.shape or not np.array_equal(whole, ranked):
            # Another path only where it ties with the ranked pairs' path.
            assert path_length(whole) == pytest.approx(path_length(ranked), abs=1e-9)
    assume(searched > 0)


def test_the_whole_graph_is_built_for_a_field_of_few_corners_after_its_first_searches() -> None:
    """Beyond _WHOLE_GRAPH_CORNERS, or for a few searches, it would cost more than it saves."""
    hole = shapely.Point(50, 50).buffer(10.0, quad_segs=8)
    field = Polygon(box(0, 0, 100, 100).exterior, [hole.exterior.coords[::-1]])
    corners = len(_reflex_corners(field))  # the hole's 32
    after = routing._WHOLE_GRAPH_AFTER
    with searching("ranked pairs"):
        reference = FieldRouter(field)
    for most_corners, whole in ((corners, True), (corners - 1, False)):
        with mock.patch.object(routing, "_WHOLE_GRAPH_CORNERS", most_corners):
            router = FieldRouter(field)
            for searched in range(1, after + 3):
                a, b = (20.0, 50.0 + searched / 10), (80.0, 50.0 - searched / 7)
                path = router.path(a, b)
                assert len(path) > 2  # round the hole: searched
                assert (router._whole is not None) == (whole and searched > after)
                # As production searches: ranked pairs first, then the whole graph.
                assert np.array_equal(path, reference.path(a, b))
        assert len(router.nodes) == corners
