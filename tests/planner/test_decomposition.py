"""Boustrophedon cells: they tile the field, every line crosses each once, few of them."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import LineString, Polygon, box

from planner.decomposition import _decompose_clipped, decompose, decompose_sweep
from planner.lines import from_sweep, to_sweep
from tests.planner.random_fields import fields_with_holes

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def crossings_per_line(cell: Polygon, heading: float, samples: int = 64) -> list[int]:
    """How many separate pieces lines of ``heading`` cut from ``cell``, at sample offsets."""
    xy = np.asarray(cell.exterior.coords)
    u, v = to_sweep(xy[:, 0], xy[:, 1], heading)
    counts = []
    span = u.max() - u.min()
    for t in np.linspace(0.0, 1.0, samples + 2)[1:-1]:
        at = u.min() + t * span
        a = from_sweep(at, v.min() - 1.0, heading)
        b = from_sweep(at, v.max() + 1.0, heading)
        piece = cell.intersection(LineString([a, b]))
        parts = [p for p in shapely.get_parts(piece) if p.length > 1e-6]
        counts.append(len(parts))
    return counts


def assert_tiles(field: Polygon, cells: list[Polygon]) -> None:
    """Cells inside the field, not overlapping, their areas adding up to the field's.

    Checked with predicates on slightly grown and shrunk cells: GEOS overlays (union,
    difference) of polygons whose edges agree to 1e-7 m can lose a whole polygon, a
    robustness problem of the check, not of the cells.
    """
    assert sum(c.area for c in cells) == pytest.approx(field.area, rel=1e-7)
    array = np.array(cells, dtype=object)
    assert shapely.covers(field.buffer(1e-5), array).all(), "a cell leaves the field"
    shrunk = shapely.buffer(array, -1e-5)
    left, right = shapely.STRtree(shrunk).query(shrunk, predicate="intersects")
    assert (left == right).all(), "cells overlap"
    for cell in cells:
        assert cell.is_valid
        assert not cell.interiors
        assert cell.exterior.is_ccw


@SETTINGS
@given(field=fields_with_holes(), heading=st.floats(0.0, 179.999))
def test_cells_tile_the_field_and_each_line_crosses_a_cell_once(
    field: Polygon, heading: float
) -> None:
    cells = decompose(field, heading)
    assert_tiles(field, cells)
    for cell in cells:
        assert set(crossings_per_line(cell, heading)) <= {1}


@SETTINGS
@given(field=fields_with_holes(), heading=st.floats(0.0, 179.999))
def test_decomposition_is_deterministic(field: Polygon, heading: float) -> None:
    first = decompose(field, heading)
    again = decompose(shapely.from_wkb(shapely.to_wkb(field)), heading)
    assert [c.wkb for c in first] == [c.wkb for c in again]


def test_l_shaped_field_is_one_cell_along_its_arms_and_three_across_them() -> None:
    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    # North-south and north-east lines cross the L once each: no cut needed.
    assert len(decompose(ell, 0.0)) == 1
    assert len(decompose(ell, 45.0)) == 1
    # North-west lines beyond the inner corner cross both arms: the corner splits the sweep.
    cells = decompose(ell, 135.0)
    assert len(cells) == 3
    assert_tiles(ell, cells)
    assert sorted(round(c.area) for c in cells) == [450, 450, 1800]


def test_a_hole_splits_the_sweep_around_it() -> None:
    field = Polygon(box(0, 0, 50, 40).exterior, [box(20, 15, 30, 23).exterior.coords[::-1]])
    cells = decompose(field, 0.0)
    # Left of the hut, below it, above it, right of it.
    assert len(cells) == 4
    assert_tiles(field, cells)
    bounds = sorted(tuple(round(b, 6) for b in c.bounds) for c in cells)
    assert bounds == [
        (0, 0, 20, 40),
        (20, 0, 30, 15),
        (20, 23, 30, 40),
        (30, 0, 50, 40),
    ]


@pytest.mark.parametrize("depth", [0.5, 3.0, 15.0])
def test_a_notch_that_does_not_turn_back_adds_no_cell(depth: float) -> None:
    """A V notch in the top edge: every north-south line still crosses the field once."""
    field = Polygon([(0, 0), (60, 0), (60, 40), (32, 40), (30, 40 - depth), (28, 40), (0, 40)])
    assert len(decompose(field, 0.0)) == 1


def test_a_jagged_edge_is_merged_back_into_few_cells() -> None:
    """A saw-tooth bottom edge turns back at every tooth: one cell per tooth, not per slab."""
    teeth = [(x, 0.0 if i % 2 == 0 else 2.0) for i, x in enumerate(range(0, 62, 2))]
    field = Polygon([*teeth, (60, 0), (60, 30), (0, 30)])
    cells = decompose(field, 90.0)  # lines run east-west, across the teeth
    assert_tiles(field, cells)
    # One cell above the teeth, and one per tooth: the slabs between teeth are merged.
    assert len(cells) <= 1 + len(teeth) // 2 + 1


@SETTINGS
@given(field=fields_with_holes(), heading=st.floats(0.0, 179.999))
def test_monotone_runs_give_the_cells_of_clipping_slabs(field: Polygon, heading: float) -> None:
    """The numpy decomposition against shapely's slab clipping (the fallback)."""
    fast = [Polygon(np.stack(r, axis=1)) for r in decompose_sweep(field, heading)]
    clipped = [Polygon(np.stack(r, axis=1)) for r in _decompose_clipped(field, heading)]
    # Two critical vertices within the snap of one cut can split a cell when clipping (its
    # hair between them), never the other way round.
    assert len(fast) <= len(clipped)
    if len(fast) == len(clipped):
        for a, b in zip(fast, clipped, strict=True):
            assert a.area == pytest.approx(b.area, rel=1e-6, abs=1e-6)
            assert a.symmetric_difference(b).area <= 1e-5 * max(1.0, b.area)
