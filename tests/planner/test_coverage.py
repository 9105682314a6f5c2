from dataclasses import replace

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.cell_plans import plan_heading
from planner.cell_route import fit_cells
from planner.coverage import cell_area, convex_chains, covered_area, covered_cells
from planner.decomposition import decompose_sweep
from planner.footprints import cells_and_band_m2
from planner.line_ends import machine_area
from planner.lines import scan_cell, scan_cells, to_sweep
from planner.vehicles import resolve_vehicle
from tests.conftest import convex_polygon
from tests.planner.random_fields import fields_with_holes, star_field


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(3, 12),
    stretch=st.floats(0.05, 1.0),
    heading=st.floats(0, 179.999),
    interval=st.floats(0.3, 30.0),
)
def test_covered_area_equals_shapely_union_of_footprints(
    seed: int, n: int, stretch: float, heading: float, interval: float
) -> None:
    points = np.random.default_rng(seed).uniform(-50, 50, (n, 2)) * [1.0, stretch]
    hull = convex_polygon(points)
    if hull.geom_type != "Polygon" or hull.area < 1.0:
        return
    ring = np.asarray(hull.exterior.coords)[:-1]
    scan = scan_cell(ring, np.array([heading]), interval)
    u_ring, v_ring = to_sweep(ring[:, 0], ring[:, 1], heading)
    chains = convex_chains(u_ring, v_ring)
    ours = covered_area(chains, scan.u, scan.v_lo, scan.v_hi, interval)
    cell = shapely.Polygon(np.stack([u_ring, v_ring], axis=1))
    footprints = shapely.box(scan.u - interval / 2, scan.v_lo, scan.u + interval / 2, scan.v_hi)
    reference = shapely.intersection(cell, shapely.union_all(footprints)).area
    assert ours == pytest.approx(reference, rel=1e-9, abs=1e-9)
    assert cell_area(chains) == pytest.approx(cell.area, rel=1e-9)


def test_a_slanted_end_leaves_a_triangle_untilled() -> None:
    # A right trapezoid: lines at heading 0 end on the slanted top edge.
    u_ring = np.array([0.0, 4.0, 4.0, 0.0])
    v_ring = np.array([0.0, 0.0, 12.0, 10.0])
    chains = convex_chains(u_ring, v_ring)
    covered = covered_area(chains, np.array([2.0]), np.array([0.0]), np.array([11.0]), 4.0)
    # The footprint misses the triangle above v = 11 on the right, 2 m × 1 m / 2.
    assert covered == pytest.approx(cell_area(chains) - 1.0)


@settings(max_examples=40, deadline=None)
@given(
    field=fields_with_holes(),
    heading=st.floats(0, 179.999),
    frac=st.floats(0.005, 0.2),
    inset=st.sampled_from([0.25, 0.5]),
)
def test_covered_cells_equals_each_cell_measured_on_its_own(
    field: shapely.Polygon, heading: float, frac: float, inset: float
) -> None:
    """All cells of a heading in one pass: the sum of :func:`covered_area` per cell."""
    d = frac * float(np.sqrt(field.area))
    rings = decompose_sweep(shapely.orient_polygons(field), heading)
    scan = scan_cells(rings, d, edge_m=inset * d)
    chains = [convex_chains(u, v) for u, v in rings]
    one_by_one = sum(
        covered_area(c, scan.u[a:b], scan.v_lo[a:b], scan.v_hi[a:b], d)
        for c, a, b in zip(chains, scan.offsets[:-1], scan.offsets[1:], strict=True)
    )
    together = covered_cells(chains, scan.offsets, scan.u, scan.v_lo, scan.v_hi, d)
    assert together == pytest.approx(one_by_one, rel=1e-9, abs=1e-6)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    holes=st.integers(0, 3),
    heading=st.floats(0, 179.999),
    width_share=st.sampled_from([0.5, 1.0, 1.5]),
)
def test_fitted_cover_is_each_cell_measured_on_its_own_and_kept_only_for_the_same_lines(
    seed: int, holes: int, heading: float, width_share: float
) -> None:
    """The fitted lines' cover in one pass is covered_area cell by cell; measured again on
    the same lines it is the same, and on other lines it is measured anew."""
    field = shapely.orient_polygons(star_field(9, seed, 60.0, holes))
    vehicle = resolve_vehicle("small_tractor")
    d = 4.0
    area = machine_area(field, vehicle)
    parts = [p for p in shapely.get_parts(area) if p.area > 1e-6]
    plan = plan_heading(parts, heading, d, None, None, d / 4.0)
    fitted = fit_cells(plan, vehicle=vehicle, pattern="boustrophedon", interval_m=d)
    width = width_share * d
    one_by_one = 0.0
    for (cell, _), fit in zip(plan.order, fitted, strict=True):
        if len(fit.u):
            k = np.argsort(fit.u, kind="stable")
            a, b = fit.v_start[k], fit.v_end[k]
            chains = plan.cells[cell].chains
            one_by_one += covered_area(chains, fit.u[k], np.minimum(a, b), np.maximum(a, b), width)
    inside, band = cells_and_band_m2(plan, fitted, field, area, heading, width)
    assert inside == pytest.approx(one_by_one, rel=1e-9, abs=1e-6)
    assert band >= -1e-6
    renumbered = [replace(f, index=f.index + 1) for f in fitted]
    assert cells_and_band_m2(plan, renumbered, field, area, heading, width) == (inside, band)
    # Every line shortened by a metre at its start: less is covered, not the kept figure.
    shorter = [
        replace(f, v_start=f.v_start + np.where(f.v_end >= f.v_start, 1.0, -1.0)) for f in fitted
    ]
    if any(len(f.u) for f in fitted):
        less, _ = cells_and_band_m2(plan, shorter, field, area, heading, width)
        assert less < inside
