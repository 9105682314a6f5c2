"""The compiled scorers (planner.kernels) equal their numpy references bit for bit."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
from shapely import MultiPoint

from planner import kernel_helpers, kernels
from planner.heading_coverage import convex_excess, estimated_coverage, estimated_coverage_numpy
from planner.lines import to_sweep
from planner.ordering import HeadingAggregates, convex_aggregates
from planner.vehicles import resolve_vehicle

FloatArray = np.ndarray


def convex_rings(seed: int, count: int) -> list[FloatArray]:
    """Counter-clockwise convex hulls of random points: thin, wide, tiny, huge, on a grid."""
    rng = np.random.default_rng(seed)
    rings = [np.array([[0.0, 0.0], [16.0, 0.0], [16.0, 20.0], [0.0, 20.0]])]
    while len(rings) < count:
        scale = 10 ** rng.uniform(-0.5, 3.3)
        pts = rng.normal(size=(int(rng.integers(3, 40)), 2)) * scale * rng.uniform(0.05, 1, 2)
        if len(rings) % 3 == 0:
            pts = np.round(pts)  # collinear vertices and edges parallel to the sweep
        hull = shapely.convex_hull(MultiPoint(pts))
        if hull.geom_type == "Polygon" and hull.area > 0:
            ring = np.asarray(shapely.orient_polygons(hull).exterior.coords)[:-1]
            rings.append(ring + rng.normal(size=2) * 1000.0)
    return rings


def headings(rng: np.random.Generator) -> FloatArray:
    return np.unique(np.concatenate([np.arange(0.0, 180.0), rng.uniform(0.0, 180.0, 50)]))


def same_bits(a: FloatArray, b: FloatArray) -> bool:
    """Equal to the last bit, signed zeros included."""
    return a.dtype == b.dtype and np.array_equal(a.view(np.int64), b.view(np.int64))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_coverage_kernel_equals_numpy(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    for ring in convex_rings(seed, 150):
        d = float(rng.choice([0.5, 1.0, 1.5, 2.0, 2.5, 4.0, 7.3, 30.0]))
        u, v = to_sweep(ring[:, 0], ring[:, 1], headings(rng)[:, None])
        fast = kernels.coverage_excess(u, v, d)
        assert fast is not None
        assert same_bits(convex_excess(u, v, d), fast)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_estimated_coverage_kernel_equals_numpy(seed: int) -> None:
    """The search's estimate (coverage less the fitting) and the widths, bit for bit."""
    rng = np.random.default_rng(300 + seed)
    vehicles = [resolve_vehicle("hand_tractor"), resolve_vehicle("small_tractor")]
    for k, ring in enumerate(convex_rings(seed, 100)):
        d = float(rng.choice([0.5, 1.0, 1.5, 2.0, 2.5, 4.0, 7.3, 30.0]))
        h = headings(rng)
        sweep = to_sweep(ring[:, 0], ring[:, 1], h[:, None])
        field_m2 = float(shapely.Polygon(ring).area) * rng.uniform(0.9, 1.1)
        vehicle = vehicles[k % 2]
        fast = estimated_coverage(ring, h, d, sweep, vehicle=vehicle, field_m2=field_m2)
        slow = estimated_coverage_numpy(ring, h, d, sweep, vehicle=vehicle, field_m2=field_m2)
        assert same_bits(slow, fast)
        widths = np.empty(len(h))
        assert kernels.coverage_excess(sweep[0], sweep[1], d, widths) is not None
        assert same_bits(sweep[0].max(axis=1) - sweep[0].min(axis=1), widths)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_length_kernel_equals_numpy(seed: int) -> None:
    rng = np.random.default_rng(200 + seed)
    for ring in convex_rings(seed, 150):
        d = float(rng.choice([0.5, 1.0, 1.5, 2.0, 2.5, 4.0, 7.3, 30.0]))
        h = headings(rng)
        u, v = to_sweep(ring[:, 0], ring[:, 1], h[:, None])
        counts, rows = kernels.length_aggregates(u, v, d)
        fast = HeadingAggregates(h, counts, *rows)
        slow = convex_aggregates(ring, h, d)
        for field in dataclasses.fields(HeadingAggregates):
            assert same_bits(getattr(slow, field.name), getattr(fast, field.name)), field.name


def test_coverage_kernel_declines_chains_out_of_order() -> None:
    # Not convex: the lower chain's edges start at u = 0, 5, 3, so numpy's searchsorted decides.
    ring = np.array([[0, 0], [10, 0], [5, 1], [8, 2], [3, 3], [9, 4], [0, 6]], dtype=float)
    u, v = to_sweep(ring[:, 0], ring[:, 1], np.array([[0.0]]))
    assert kernels.coverage_excess(u, v, 1.0) is None


@pytest.mark.parametrize("n", [0, 1, 2, 5, 32, 33, 80, 257])
def test_sorts_without_allocating_equal_numpy(n: int) -> None:
    """The kernels' in-place sorts give np.sort's values and the stable argsort's order."""
    rng = np.random.default_rng(n)
    for _ in range(20):
        values = np.round(rng.normal(size=n), 1)  # ties
        if n > 2:
            values[rng.integers(n, size=1 + n // 40)] = np.nan  # np.sort puts NaN last
        out = np.empty(n)
        kernel_helpers._sorted_into(values, out)
        assert np.array_equal(out, np.sort(values), equal_nan=True)
        # Bit for bit but for the sign of zeros (-0.0 + 0.0 is 0.0): ±0 may swap places.
        assert same_bits(out + 0.0, np.sort(values) + 0.0)
        keys = rng.integers(0, 4, size=n + 3)  # only the first n are sorted
        order = np.full(n + 3, -1, dtype=np.int64)
        kernel_helpers._stable_order_into(keys, n, order)
        assert order[:n].tolist() == np.argsort(keys[:n], kind="mergesort").tolist()


def test_numpy_calls_the_c_librarys_elementary_functions() -> None:
    """The kernel tests' premise (``tests/numpy_env.py``): numpy's arctan2, arccos and exp give
    the C library's bits, as the compiled kernels do. Fails if numpy loaded before the plugin
    could turn its own AVX-512 functions off."""
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-10.0, 10.0, (2, 2000))
    assert np.array_equal(np.arctan2(y, x), [math.atan2(b, a) for a, b in zip(x, y, strict=True)])
    assert np.array_equal(np.arccos(x / 10.0), [math.acos(a / 10.0) for a in x])
    assert np.array_equal(np.exp(x), [math.exp(a) for a in x])
