"""The compiled cells (planner.cell_kernels) equal their numpy references bit for bit."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import Polygon

from planner import cell_kernels
from planner.cell_plans import _scan_cells, scan_cells_numpy
from planner.decomposition import (
    _cuts,
    _pieces,
    decompose_sweep,
    decompose_sweep_numpy,
    sweep_rings,
)
from planner.lines import to_sweep
from planner.projection import field_frame
from tests.planner.random_fields import fields_with_holes, star_field
from tests.planner.test_real_fields import real_fields

FloatArray = np.ndarray
Rings = list[tuple[FloatArray, FloatArray]]
SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def same_bits(a: FloatArray, b: FloatArray) -> bool:
    """Equal to the last bit, signed zeros included."""
    a, b = np.asarray(a), np.asarray(b)
    return (
        a.dtype == b.dtype
        and a.shape == b.shape
        and np.array_equal(a.view(np.int64), b.view(np.int64))
    )


def assert_same_rings(fast: Rings, slow: Rings) -> None:
    assert len(fast) == len(slow)
    for (fu, fv), (su, sv) in zip(fast, slow, strict=True):
        assert same_bits(fu, su) and same_bits(fv, sv)


def assert_same_cells(rings: Rings, d: float, edge_m: float) -> None:
    fast_scan, fast_cells = _scan_cells(rings, d, edge_m)
    slow_scan, slow_cells = scan_cells_numpy(rings, d, edge_m)
    for name in ("headings_deg", "offsets", "u", "v_lo", "v_hi"):
        assert same_bits(getattr(fast_scan, name), getattr(slow_scan, name)), name
    for fast, slow in zip(fast_cells, slow_cells, strict=True):
        assert fast.lines == slow.lines
        for name in ("lo_u", "lo_v", "hi_u", "hi_v"):
            assert same_bits(getattr(fast.chains, name), getattr(slow.chains, name)), name


def assert_same_at(field: Polygon, heading: float, d: float) -> None:
    """Cells, their lines and chains of ``field`` at ``heading``: compiled == numpy."""
    prepared = sweep_rings(field)
    rings = decompose_sweep(prepared, heading)
    assert_same_rings(rings, decompose_sweep_numpy(prepared, heading))
    # The kernel gives up (the clipping fallback) exactly where the numpy code does.
    r = prepared
    u, v = to_sweep(r.x, r.y, heading)
    turn = (u - u[r.prv]) * (u[r.nxt] - u) <= 0.0
    cuts = _cuts(u[turn])
    if len(cuts) > 2:
        status, *_ = cell_kernels.sweep_cells(
            u, v, turn, cuts, r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv
        )
        pieces = _pieces(u, v, turn, cuts, r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv)
        assert (status == 0) == (pieces is None)
    if rings:
        for edge_m in (d / 2.0, d / 4.0, 0.3 * d):
            assert_same_cells(rings, d, edge_m)


@SETTINGS
@given(
    field=fields_with_holes(max_vertices=60),
    heading=st.floats(0.0, 179.999),
    d=st.sampled_from([0.5, 1.0, 2.5, 4.0, 7.3, 30.0]),
    grid=st.sampled_from([None, 1.0, 5.0]),
)
def test_random_fields_compiled_equal_numpy(
    field: Polygon, heading: float, d: float, grid: float | None
) -> None:
    if grid is not None:
        # Vertices on a grid: edges parallel to the lines, ties at the cuts and in the chains.
        field = shapely.orient_polygons(shapely.set_precision(field, grid))
        if not isinstance(field, Polygon) or field.is_empty or not field.is_valid:
            return
        heading = float(np.round(heading / 45.0) * 45.0)
    assert_same_at(field, heading, d)


@pytest.mark.parametrize("heading", [0.0, 45.0, 90.0, 135.0])
def test_a_saw_tooth_field_compiled_equals_numpy(heading: float) -> None:
    teeth = [(x, 0.0 if i % 2 == 0 else 2.0) for i, x in enumerate(range(0, 62, 2))]
    field = shapely.orient_polygons(Polygon([*teeth, (60, 0), (60, 30), (0, 30)]))
    assert_same_at(field, heading, 4.0)
    assert len(decompose_sweep(field, 90.0)) > 10


@pytest.mark.parametrize(("seed", "heading"), [(31, 0.0), (47, 90.0), (311, 45.0)])
def test_degenerate_fields_fall_back_as_numpy_does(seed: int, heading: float) -> None:
    """Vertices on a 5 m grid where the monotone runs do not end on the cuts: clipping."""
    field = star_field(5 + seed % 50, seed, 50.0 + seed, seed % 4)
    field = shapely.orient_polygons(shapely.set_precision(field, 5.0))
    assert_same_at(field, heading, 4.0)
    r = sweep_rings(field)
    u, v = to_sweep(r.x, r.y, heading)
    turn = (u - u[r.prv]) * (u[r.nxt] - u) <= 0.0
    status, *_ = cell_kernels.sweep_cells(
        u, v, turn, _cuts(u[turn]), r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv
    )
    assert status == 0


@cache
def local_real_fields() -> list[Polygon]:
    fields = []
    for _, field in real_fields():
        local = field_frame(field).to_local(field)
        fields.append(shapely.orient_polygons(local))
    return fields


@pytest.mark.parametrize("part", range(4))
def test_real_fields_compiled_equal_numpy(part: int) -> None:
    rng = np.random.default_rng(part)
    for field in local_real_fields()[part::4]:
        for heading in np.concatenate([[0.0, 90.0], rng.uniform(0.0, 180.0, 6)]):
            assert_same_at(field, float(heading), 4.0)


def test_warm_up_runs() -> None:
    cell_kernels.warm_up()
