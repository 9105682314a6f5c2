"""The closed-form heading scorer equals the line-by-line reference."""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.lines import scan_cell
from planner.ordering import ordered_line_ends, score_headings, variant_lengths
from tests.conftest import convex_polygon


@settings(max_examples=120, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(3, 15),
    scale=st.floats(1.0, 800.0),
    aspect=st.floats(0.02, 1.0),
    interval=st.floats(0.2, 50.0),
    start=st.one_of(st.none(), st.tuples(st.floats(-900, 900), st.floats(-900, 900))),
    finish=st.one_of(st.none(), st.tuples(st.floats(-900, 900), st.floats(-900, 900))),
)
def test_score_headings_equals_line_by_line_scoring(
    seed: int, n: int, scale: float, aspect: float, interval: float, start, finish
) -> None:
    rng = np.random.default_rng(seed)
    hull = convex_polygon(rng.uniform(-1, 1, (n, 2)) * [scale, scale * aspect])
    if hull.geom_type != "Polygon" or hull.area < 1.0:
        hull = shapely.box(0, 0, scale, scale * aspect + 1)  # parallel edges: ties at the ends
    ring = np.asarray(shapely.orient_polygons(hull).exterior.coords)[:-1]
    headings = np.concatenate([np.arange(0.0, 180.0, 7.0), rng.uniform(0, 180, 4)])
    scan = scan_cell(ring, headings, interval)
    reference = variant_lengths(scan, start, finish).total
    fast, counts = score_headings(ring, headings, interval, start, finish)
    assert counts.tolist() == scan.counts.tolist()
    assert np.allclose(fast.total, reference, rtol=1e-9, atol=1e-6)


def test_variants_drive_alternately_from_each_side() -> None:
    u = np.array([1.0, 2.0, 3.0])
    lo, hi = np.zeros(3), np.array([10.0, 11.0, 12.0])
    expected = {
        0: ([1, 2, 3], [0, 11, 0], [10, 0, 12]),  # left, first line up
        1: ([1, 2, 3], [10, 0, 12], [0, 11, 0]),  # left, first line down
        2: ([3, 2, 1], [0, 11, 0], [12, 0, 10]),  # right, first line up
        3: ([3, 2, 1], [12, 0, 10], [0, 11, 0]),  # right, first line down
    }
    for variant, (order, v_from, v_to) in expected.items():
        got_u, got_from, got_to, _ = ordered_line_ends(u, lo, hi, variant)
        assert got_u.tolist() == order
        assert got_from.tolist() == pytest.approx(v_from)
        assert got_to.tolist() == pytest.approx(v_to)
