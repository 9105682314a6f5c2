"""The compiled coverage loops (planner.coverage_kernels) equal their numpy code bit for bit."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from planner import coverage, coverage_kernels, parse_field_geojson, plan_coverage
from planner.coverage import Chains, convex_chains, convex_chains_numpy
from planner.decomposition import decompose_sweep
from planner.lines import scan_cells, to_sweep
from tests.conftest import FIELDS_DIR, PAPER_FIELD
from tests.planner.random_fields import fields_with_holes
from tests.planner.test_kernels import convex_rings, same_bits

FloatArray = np.ndarray
LaidOut = tuple[dict[int, float], FloatArray, FloatArray]


def same_chains(a: Chains, b: Chains) -> bool:
    """Same four arrays; and ``a.packed`` (if any) holds them."""
    packed = a.packed is None or same_bits(a.packed, coverage._packed(a))
    return packed and all(
        same_bits(getattr(a, k), getattr(b, k)) for k in ("lo_u", "lo_v", "hi_u", "hi_v")
    )


def same_float(a: float, b: float) -> bool:
    return same_bits(np.array([a]), np.array([b]))


def assert_same_laid_out(fast: LaidOut, slow: LaidOut) -> None:
    """Same pieces (a zero's sign aside), and the same sums to the last bit."""
    odd, area, cell = fast
    odd_ref, area_ref, cell_ref = slow
    assert list(odd.items()) == list(odd_ref.items())
    assert area.flags.c_contiguous and area.shape == area_ref.shape
    # np.minimum/np.fmax leave a tie's zero sign to the loop numpy picks: compare values.
    assert np.array_equal(area, area_ref)
    assert np.array_equal(cell, cell_ref)
    assert same_float(float(area.sum()), float(area_ref.sum()))
    each = np.bincount(cell, weights=area.sum(axis=1))
    assert same_bits(each, np.bincount(cell_ref, weights=area_ref.sum(axis=1)))


def both_ways(
    chains: list[Chains],
    offsets: FloatArray,
    u: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    d: float,
) -> None:
    packed = np.concatenate([coverage._packed(c) for c in chains])
    assert coverage_kernels.laid_out(packed, offsets, u, lo, hi, d) is not None
    assert_same_laid_out(
        coverage._laid_out(chains, offsets, u, lo, hi, d),
        coverage._laid_out_numpy(chains, offsets, u, lo, hi, d),
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_chains_kernel_equals_numpy(seed: int) -> None:
    rng = np.random.default_rng(300 + seed)
    for ring in convex_rings(seed, 150):
        for heading in rng.uniform(0.0, 180.0, 4).tolist() + [0.0, 90.0]:
            u, v = to_sweep(ring[:, 0], ring[:, 1], heading)
            assert same_chains(convex_chains(u, v), convex_chains_numpy(u, v))


def test_chains_kernel_on_rings_with_ties_and_one_vertex() -> None:
    # Edges parallel to the lines at both ends, several vertices level with the lowest.
    u = np.array([0.0, 2.0, 4.0, 4.0, 4.0, 2.0, 0.0, 0.0])
    v = np.array([0.0, 0.0, 0.0, 1.0, 3.0, 3.0, 3.0, 1.0])
    for shift in range(len(u)):
        ru, rv = np.roll(u, shift), np.roll(v, shift)
        assert same_chains(convex_chains(ru, rv), convex_chains_numpy(ru, rv))
    one = np.array([5.0])
    assert same_chains(convex_chains(one, one), convex_chains_numpy(one, one))


def test_chains_kernel_declines_nan() -> None:
    assert coverage_kernels.packed_chains(np.array([0.0, np.nan, 1.0]), np.zeros(3)) is None
    assert coverage_kernels.packed_chains(np.zeros(0), np.zeros(0)) is None


@settings(max_examples=120, deadline=None)
@given(
    field=fields_with_holes(),
    heading=st.floats(0, 179.999),
    frac=st.floats(0.005, 0.2),
    inset=st.sampled_from([0.25, 0.5]),
    width=st.sampled_from([0.5, 0.9, 1.0, 1.0 + 1e-12, 1.3, 2.5]),
)
def test_laid_out_kernel_equals_numpy(
    field: shapely.Polygon, heading: float, frac: float, inset: float, width: float
) -> None:
    """Every heading's cells, lines at one interval, footprints narrower or wider."""
    d = frac * float(np.sqrt(field.area))
    rings = decompose_sweep(shapely.orient_polygons(field), heading)
    scan = scan_cells(rings, d, edge_m=inset * d)
    if not rings or scan.offsets[-1] == 0:
        return
    chains = [convex_chains(u, v) for u, v in rings]
    both_ways(chains, scan.offsets, scan.u, scan.v_lo, scan.v_hi, width * d)


def test_laid_out_kernel_with_footprints_apart_along_the_lines() -> None:
    # Two cells; the first's last two lines overlap without meeting along the lines (odd),
    # the second's overlap and meet (one strip more).
    a = convex_chains(np.array([0.0, 16.0, 16.0, 0.0]), np.array([0.0, 0.0, 20.0, 20.0]))
    b = convex_chains(np.array([20.0, 26.0, 20.0]), np.array([0.0, 0.0, 6.0]))
    u = np.array([2.0, 6.0, 10.0, 13.0, 22.0, 23.5])
    lo = np.array([0.0, 0.0, 0.0, 12.0, 0.0, 0.0])
    hi = np.array([20.0, 20.0, 20.0, 20.0, 4.0, 2.0])
    offsets = np.array([0, 4, 6])
    both_ways([a, b], offsets, u, lo, hi, 4.0)
    lo[3] = 11.0  # now they meet
    hi[2] = 10.0
    both_ways([a, b], offsets, u, lo, hi, 4.0)


def test_laid_out_kernel_declines_chains_out_of_order() -> None:
    # The lower chain steps back (u = 0, 2, 1): searchsorted's answer is numpy's to give.
    packed = np.array([3.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 2.0, 2.0, 1.0, 1.0])
    one = np.ones(1)
    assert coverage_kernels.laid_out(packed, np.array([0, 1]), one, one * 0, one, 1.0) is None
    # A header that does not match the arrays.
    packed[0] = 4.0
    assert coverage_kernels.laid_out(packed, np.array([0, 1]), one, one * 0, one, 1.0) is None


def real_fields() -> list[shapely.Polygon]:
    """The paper field and every tenth of the 223 real fields."""
    paper = parse_field_geojson(json.loads(PAPER_FIELD.read_text(encoding="utf-8")))
    fields: list[shapely.Geometry] = [paper.field_lonlat]
    for name in ("rwanda_2021", "south_africa_2017", "germany_2018_2019", "netherlands_f2c"):
        collection = json.loads((FIELDS_DIR / f"{name}.geojson").read_text(encoding="utf-8"))
        fields += [shapely.geometry.shape(f["geometry"]) for f in collection["features"]]
    return [f for i, f in enumerate(fields) if i % 10 == 0 and isinstance(f, shapely.Polygon)]


@pytest.mark.parametrize("vehicle", ["hand_tractor", "small_tractor"])
def test_kernels_equal_numpy_on_real_fields(vehicle: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every chain and every laid-out measure that planning real fields asks for."""
    rings: list[tuple[FloatArray, FloatArray]] = []
    calls: list[tuple[object, ...]] = []
    chains_kernel = coverage_kernels.packed_chains
    laid_out = coverage._laid_out

    def record_rings(u: FloatArray, v: FloatArray) -> object:
        rings.append((np.array(u), np.array(v)))
        return chains_kernel(u, v)

    def record_calls(*args: object) -> LaidOut:
        calls.append(args)
        return laid_out(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(coverage_kernels, "packed_chains", record_rings)
    monkeypatch.setattr(coverage, "_laid_out", record_calls)
    for field in real_fields():
        plan_coverage(field, interval_m=4.0, vehicle=vehicle)
    monkeypatch.undo()
    assert len(rings) > 500 and len(calls) > 50
    for u, v in rings:
        assert same_chains(convex_chains(u, v), convex_chains_numpy(u, v))
    for args in calls:
        assert_same_laid_out(laid_out(*args), coverage._laid_out_numpy(*args))  # type: ignore[arg-type]


@pytest.mark.parametrize("short", ["v_lo", "v_hi"])
def test_laid_out_kernel_leaves_short_lines_to_numpy(short: str) -> None:
    """``v_lo``/``v_hi`` shorter than ``u``: the kernel would read past them, numpy decides."""
    chains = convex_chains(np.array([0.0, 8.0, 8.0, 0.0]), np.array([0.0, 0.0, 4.0, 4.0]))
    offsets, u = np.array([0, 2]), np.array([2.0, 6.0])
    lo, hi = np.zeros(2), np.full(2, 4.0)
    if short == "v_lo":
        lo = np.empty(0)
    else:
        hi = np.empty(0)
    packed = coverage._packed(chains)
    assert coverage_kernels.laid_out(packed, offsets, u, lo, hi, 4.0) is None
    # What a caller gets is the numpy code's answer (here its exception).
    with pytest.raises(IndexError) as numpy_error:
        coverage._laid_out_numpy([chains], offsets, u, lo, hi, 4.0)
    with pytest.raises(type(numpy_error.value)):
        coverage._laid_out([chains], offsets, u, lo, hi, 4.0)
