"""Which corners see each other: kept answers equal fresh tests (planner.visibility)."""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import LineString, Polygon

from planner import visibility
from planner.visibility import GRAZE_M, CornerVisibility, FieldInterior
from tests.planner.random_fields import fields_with_holes, star_field

SETTINGS = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def corners_of(field: Polygon) -> CornerVisibility:
    oriented = shapely.orient_polygons(field)
    return CornerVisibility(oriented, FieldInterior(oriented))


def fresh_answers(corners: CornerVisibility, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Tangent at both corners and in sight, tested afresh (nothing kept)."""
    interior = corners._interior
    return corners.tangent_numpy(i, j) & interior.segments(corners.nodes[i], corners.nodes[j])


@pytest.mark.parametrize("dense_corners", [2048, 8, 0])
@given(field=fields_with_holes(min_vertices=12, max_holes=3), seed=st.integers(0, 2**16))
@SETTINGS
def test_kept_answers_equal_fresh_tests_query_after_query(
    dense_corners: int, field: Polygon, seed: int
) -> None:
    """Overlapping subsets, as a router's moves ask them: the matrix (also when it fills up
    and starts afresh, at 8 corners; larger subsets there go by the dict) and the dict (0)
    give the answers of fresh tests."""
    with mock.patch.object(visibility, "_DENSE_CORNERS", dense_corners):
        corners = corners_of(field)
        n = len(corners.nodes)
        if n < 2:
            return
        rng = np.random.default_rng(seed)
        for _ in range(12):
            subset = rng.choice(n, size=int(rng.integers(2, min(n, 12) + 1)), replace=False)
            i, j = np.triu_indices(len(subset), k=1)
            # Each pair asked both ways round: the second answer is a kept one.
            for ordered in (subset, subset[::-1]):
                got = corners.in_sight(ordered, i, j)
                assert np.array_equal(got, fresh_answers(corners, ordered[i], ordered[j]))


@given(field=fields_with_holes(min_vertices=6, max_holes=3))
@SETTINGS
def test_graph_joins_exactly_the_tangent_pairs_in_sight(field: Polygon) -> None:
    corners = corners_of(field)
    n = len(corners.nodes)
    i, j = np.triu_indices(n, k=1)
    expected = fresh_answers(corners, i, j)
    graph = corners.graph().tocoo()
    assert sorted(zip(graph.row.tolist(), graph.col.tolist(), strict=True)) == sorted(
        zip(i[expected].tolist(), j[expected].tolist(), strict=True)
    )
    lengths = np.hypot(*(corners.nodes[graph.row] - corners.nodes[graph.col]).T)
    assert np.array_equal(graph.data, lengths)


def test_corners_are_the_reflex_corners_of_the_free_space() -> None:
    """The L's inner corner and every corner of its square hole; no convex outer corner."""
    hole = [(10, 10), (20, 10), (20, 20), (10, 20)]
    field = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)], [hole])
    got = {tuple(p) for p in corners_of(field).nodes.tolist()}
    assert got == {(30.0, 30.0), *((float(x), float(y)) for x, y in hole)}


@pytest.mark.parametrize("seed", range(4))
def test_interior_answers_as_the_grown_field_covers(seed: int) -> None:
    """Segments, polylines and points: as shapely on the field grown by GRAZE_M, whichever
    way round (x, y or swapped) the tests run."""
    field = star_field(30, seed, 100.0, 2)
    for candidate in (field, shapely.transform(field, lambda xy: xy[:, ::-1])):
        interior = FieldInterior(shapely.orient_polygons(candidate))
        grown = candidate.buffer(GRAZE_M, join_style="mitre")
        rng = np.random.default_rng(seed)
        starts, ends = rng.uniform(-100, 100, (2, 200, 2))
        expected = [
            grown.contains_properly(LineString([a, b])) for a, b in zip(starts, ends, strict=True)
        ]
        assert interior.segments(starts, ends).tolist() == expected
        paths = [np.stack([a, (a + b) / 2, b]) for a, b in zip(starts, ends, strict=True)]
        assert interior.polylines(paths).tolist() == expected
        assert [interior.polyline(p) for p in paths] == expected
        covered = [grown.covers(shapely.Point(p)) for p in starts]
        assert interior.covers(starts).tolist() == covered
