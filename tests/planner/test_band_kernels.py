import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely import MultiPolygon, Polygon

from planner import footprints
from planner.cell_plans import plan_heading
from planner.cell_route import fit_cells
from planner.footprints import FloatArray, band_m2, cell_lines, footprint_boxes
from planner.line_ends import machine_area
from planner.lines import to_sweep
from planner.projection import field_frame
from planner.vehicles import resolve_vehicle
from tests.planner.field_files import shared_polygon
from tests.planner.random_fields import fields_with_holes


def shapely_band_m2(
    u: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    field: Polygon,
    area: Polygon | MultiPolygon,
    heading: float,
    width: float,
) -> float:
    """The band as it was measured before planner.band_kernels: three shapely overlays.

    On a fine grid: unsnapped, GEOS can lose area where rotated boxes share sides.
    """
    boxes = footprint_boxes(u, lo, hi, heading, width)
    if not len(boxes):
        return 0.0
    reach = shapely.union_all(boxes, grid_size=1e-9)
    return float(shapely.intersection(field, reach).area - shapely.intersection(area, reach).area)


@settings(max_examples=60, deadline=None)
@given(
    field=fields_with_holes(max_vertices=25),
    heading=st.floats(0.0, 179.999),
    width=st.floats(0.5, 12.0),
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 30),
    clockwise=st.booleans(),
)
def test_band_equals_shapely_overlays(
    field: Polygon, heading: float, width: float, seed: int, n: int, clockwise: bool
) -> None:
    """Boxes anywhere over a field with holes and its eroded area (often in pieces): some
    share sides exactly (whole widths apart), some overlap, some repeat, some are empty."""
    if clockwise:
        field = shapely.orient_polygons(field, exterior_cw=True)
    area = field.buffer(-width / 2.0, join_style="mitre")
    rng = np.random.default_rng(seed)
    xy = shapely.get_coordinates(field)
    fu, fv = to_sweep(xy[:, 0], xy[:, 1], heading)
    steps = np.floor((fu.max() - fu.min()) / width) + 1
    u = fu.min() + width * rng.integers(0, steps + 1, n) + rng.choice([0.0, 0.3 * width], n)
    ends = rng.uniform(fv.min() - width, fv.max() + width, (n, 2))
    lo, hi = ends.min(axis=1), ends.max(axis=1)
    empty = rng.random(n) < 0.1
    hi[empty] = lo[empty]
    repeat = rng.random(n) < 0.2
    u, lo, hi = np.r_[u, u[repeat]], np.r_[lo, lo[repeat]], np.r_[hi, hi[repeat]]
    ours = band_m2(u, lo, hi, field, area, heading, width)
    theirs = shapely_band_m2(u, lo, hi, field, area, heading, width)
    assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-9 * field.area)


@pytest.mark.parametrize("name", ["rwanda-3", "netherlands-0", "germany-22-hole"])
@pytest.mark.parametrize("heading", [0.0, 37.0, 90.0, 151.5])
def test_band_of_fitted_lines_on_real_fields(name: str, heading: float) -> None:
    """The outermost fitted lines of real fields' cells, as cells_and_band_m2 measures them."""
    lonlat = shared_polygon(name)
    field = field_frame(lonlat).to_local(lonlat)
    vehicle = resolve_vehicle("small_tractor")
    d = 4.0
    area = machine_area(field, vehicle)
    parts = [p for p in shapely.get_parts(area) if p.area > 1e-6]
    plan = plan_heading(parts, heading, d, None, None, d / 4.0)
    fitted = fit_cells(plan, vehicle=vehicle, pattern="boustrophedon", interval_m=d)
    lines = cell_lines(plan, fitted)
    ends = np.stack([lines.offsets[:-1], lines.offsets[1:] - 1], axis=1).ravel()
    u, lo, hi = lines.u[ends], lines.v_lo[ends], lines.v_hi[ends]
    ours = band_m2(u, lo, hi, field, area, heading, d)
    theirs = shapely_band_m2(u, lo, hi, field, area, heading, d)
    assert theirs > 1.0
    assert ours == pytest.approx(theirs, rel=1e-9)


def test_a_band_too_large_for_the_kernel_is_measured_by_the_overlay(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Above BAND_KERNEL_MAX_WORK the overlay measures the band; both agree."""
    field = Polygon(
        [(0, 0), (40, 0), (40, 30), (0, 30)], [[(15, 10), (25, 10), (25, 20), (15, 20)]]
    )
    area = field.buffer(-0.6, join_style="mitre")
    u, lo, hi = np.array([1.0, 39.0]), np.array([0.5, 0.5]), np.array([29.5, 29.5])
    by_kernel = footprints.band_m2(u, lo, hi, field, area, 0.0, 4.0)
    monkeypatch.setattr(footprints, "BAND_KERNEL_MAX_WORK", 0)
    by_overlay = footprints.band_m2(u, lo, hi, field, area, 0.0, 4.0)
    assert by_kernel > 0.0
    assert by_overlay == pytest.approx(by_kernel, rel=1e-9)
