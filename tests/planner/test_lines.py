import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.lines import from_sweep, line_counts, scan_cell, to_sweep
from tests.conftest import convex_polygon


@st.composite
def convex_rings(draw: st.DrawFn) -> np.ndarray:
    n = draw(st.integers(3, 14))
    seed = draw(st.integers(0, 2**32 - 1))
    scale = draw(st.floats(2.0, 2000.0))
    points = np.random.default_rng(seed).uniform(-1, 1, (n, 2)) * scale
    hull = convex_polygon(points)
    if hull.geom_type != "Polygon" or hull.area < 1.0:
        hull = shapely.box(0, 0, scale, scale / 3)
    return np.asarray(shapely.orient_polygons(hull).exterior.coords)[:-1]


def test_sweep_round_trip() -> None:
    x, y = np.array([1.0, -3.0]), np.array([2.0, 5.0])
    u, v = to_sweep(x, y, 33.0)
    x2, y2 = from_sweep(u, v, 33.0)
    assert np.allclose(x2, x) and np.allclose(y2, y)


def test_line_counts_cover_the_width() -> None:
    widths = np.array([0.5, 4.0, 4.0001, 8.0, 39.9, 40.0])
    assert line_counts(widths, 4.0).tolist() == [1, 1, 2, 2, 10, 10]


@settings(max_examples=60, deadline=None)
@given(ring=convex_rings(), heading=st.floats(0, 179.999), frac=st.floats(0.01, 0.4))
def test_each_line_is_the_field_clipped_to_its_position(
    ring: np.ndarray, heading: float, frac: float
) -> None:
    polygon = shapely.Polygon(ring)
    u_ring, v_ring = to_sweep(ring[:, 0], ring[:, 1], heading)
    interval = max((u_ring.max() - u_ring.min()) * frac, 0.05)
    scan = scan_cell(ring, np.array([heading]), interval)
    assert scan.offsets.tolist() == [0, len(scan.u)]
    # Reference: clip a long line at each position with shapely.
    reach = 1e5
    x0, y0 = from_sweep(scan.u, np.full_like(scan.u, -reach), heading)
    x1, y1 = from_sweep(scan.u, np.full_like(scan.u, reach), heading)
    clipped = shapely.intersection(
        polygon, shapely.linestrings(np.stack([np.stack([x0, y0], 1), np.stack([x1, y1], 1)], 1))
    )
    assert np.allclose(shapely.length(clipped), scan.v_hi - scan.v_lo, atol=1e-6)


def test_many_headings_at_once_equal_one_at_a_time() -> None:
    ring = np.array([[0.0, 0.0], [50.0, 5.0], [60.0, 40.0], [10.0, 35.0]])
    headings = np.array([0.0, 17.0, 90.0, 123.4])
    together = scan_cell(ring, headings, 3.0)
    for a, heading in enumerate(headings):
        alone = scan_cell(ring, np.array([heading]), 3.0)
        part = slice(together.offsets[a], together.offsets[a + 1])
        assert np.allclose(together.u[part], alone.u)
        assert np.allclose(together.v_lo[part], alone.v_lo)
        assert np.allclose(together.v_hi[part], alone.v_hi)


def test_narrow_cell_gets_one_line_in_the_middle() -> None:
    ring = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 30.0], [0.0, 30.0]])
    scan = scan_cell(ring, np.array([0.0]), 4.0)
    assert scan.u.tolist() == pytest.approx([1.5])
