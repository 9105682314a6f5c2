"""Moves inside the field: shortest paths round corners and holes, never outside (R1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import LineString, Polygon, box

from planner.routing import FieldRouter, path_length
from tests.planner.random_fields import fields_with_holes

TOLERANCE_M = 0.01
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


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
