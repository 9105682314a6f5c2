"""Many headings fitted at once give what one heading at a time gives."""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.convex_fits import convex_lines, convex_machine_area, fit_headings
from planner.coverage import convex_chains, covered_area, covered_each_cell
from planner.errors import InvalidParameterError
from planner.lines import scan_cell, to_sweep
from planner.vehicles import resolve_vehicle
from tests.conftest import convex_polygon

PRESETS = ("hand_tractor", "paper_g1000", "small_tractor", "rover")


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(3, 10),
    stretch=st.floats(0.1, 1.0),
    size_m=st.floats(15.0, 150.0),
    interval=st.floats(0.5, 12.0),
    implement=st.floats(0.5, 1.5),
    preset=st.sampled_from(PRESETS),
    pattern=st.sampled_from(["boustrophedon", "snake"]),
    headings=st.lists(st.floats(0.0, 179.99), min_size=1, max_size=12),
)
def test_fit_headings_matches_one_heading_at_a_time(
    seed: int,
    n: int,
    stretch: float,
    size_m: float,
    interval: float,
    implement: float,
    preset: str,
    pattern: str,
    headings: list[float],
) -> None:
    points = np.random.default_rng(seed).uniform(-1, 1, (n, 2)) * [size_m, size_m * stretch]
    field = convex_polygon(points)
    if field.geom_type != "Polygon" or field.area < 50.0:
        return
    vehicle = resolve_vehicle(preset)
    try:
        area = convex_machine_area(field, vehicle)
    except InvalidParameterError:
        return
    variants = [i % 4 for i in range(len(headings))]
    width = interval * implement
    together = fit_headings(
        field, headings, variants, interval_m=interval, implement_width_m=width,
        vehicle=vehicle, pattern=pattern, area=area,
    )  # fmt: skip
    ring = np.asarray(field.exterior.coords)[:-1]
    for heading, variant, got in zip(headings, variants, together, strict=True):
        try:
            alone = convex_lines(
                field, heading, interval_m=interval, vehicle=vehicle, pattern=pattern,
                variant=variant, area=area,
            )  # fmt: skip
        except InvalidParameterError as refused:
            assert isinstance(got, InvalidParameterError)
            assert str(got) == str(refused)
            continue
        assert not isinstance(got, InvalidParameterError)
        fit, covered_m2 = got
        np.testing.assert_array_equal(fit.index, alone.index)
        for ours, reference in (
            (fit.u, alone.u),
            (fit.v_start, alone.v_start),
            (fit.v_end, alone.v_end),
            (fit.turns.xy, alone.turns.xy),
        ):
            np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-9)
        u_ring, v_ring = to_sweep(ring[:, 0], ring[:, 1], heading)
        order = np.argsort(alone.index, kind="stable")
        a, b = alone.v_start[order], alone.v_end[order]
        reference_m2 = covered_area(
            convex_chains(u_ring, v_ring), alone.u[order], np.minimum(a, b), np.maximum(a, b),
            width,
        )  # fmt: skip
        assert covered_m2 == pytest.approx(reference_m2, rel=1e-9, abs=1e-6)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    cells=st.integers(1, 6),
    interval=st.floats(0.5, 20.0),
    width_ratio=st.floats(0.3, 2.0),
)
def test_covered_each_cell_is_covered_area_cell_by_cell(
    seed: int, cells: int, interval: float, width_ratio: float
) -> None:
    rng = np.random.default_rng(seed)
    chains, us, los, his, sizes, reference = [], [], [], [], [0], []
    width = interval * width_ratio
    for _ in range(cells):
        hull = convex_polygon(rng.uniform(-40, 40, (rng.integers(3, 9), 2)))
        if hull.geom_type != "Polygon" or hull.area < 1.0:
            continue
        ring = np.asarray(shapely.orient_polygons(hull).exterior.coords)[:-1]
        heading = float(rng.uniform(0, 180))
        scan = scan_cell(ring, np.array([heading]), interval)
        u_ring, v_ring = to_sweep(ring[:, 0], ring[:, 1], heading)
        chain = convex_chains(u_ring, v_ring)
        # Shorten some lines at random, as fitting does.
        lo = scan.v_lo + rng.uniform(0, 1, len(scan.u)) * (scan.v_hi - scan.v_lo) / 3
        hi = scan.v_hi - rng.uniform(0, 1, len(scan.u)) * (scan.v_hi - scan.v_lo) / 3
        chains.append(chain)
        us.append(scan.u)
        los.append(lo)
        his.append(hi)
        sizes.append(len(scan.u))
        reference.append(covered_area(chain, scan.u, lo, hi, width))
    if not chains:
        return
    each = covered_each_cell(
        chains, np.cumsum(sizes), np.concatenate(us), np.concatenate(los),
        np.concatenate(his), width,
    )  # fmt: skip
    np.testing.assert_allclose(each, reference, rtol=1e-9, atol=1e-6)
