"""The fitted-coverage screen (planner.fit_screen): its table, its integrals, its estimate."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely import Polygon

from planner import validation
from planner.cell_plans import cover_heading
from planner.coverage import covered_area
from planner.decomposition import sweep_rings
from planner.fit_screen import (
    SPACING_CLASSES,
    SUBSAMPLE,
    TABLE_REACH_M,
    TABLE_STEP_M,
    _under_chain_m2,
    turn_table,
)
from planner.heading_screen import screen_fitted
from planner.line_ends import fit_lines, machine_area
from planner.ordering import order_boustrophedon
from planner.projection import field_frame
from planner.turns import TurnEnds, vehicle_turns
from planner.vehicles import resolve_vehicle
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import shared_feature

SMALL = resolve_vehicle("small_tractor")
INTERVAL_M = 4.0


@pytest.mark.parametrize(("spacing_class", "offset_m"), [(8, 0.0), (8, 3.4), (8, -17.2), (3, 1.0)])
def test_a_tabled_turn_is_the_vehicles_own_turn(spacing_class: int, offset_m: float) -> None:
    table = turn_table(SMALL, INTERVAL_M)
    per_class = 2 * round(TABLE_REACH_M / TABLE_STEP_M) + 1
    shape = (spacing_class - 1) * per_class + round((offset_m + TABLE_REACH_M) / TABLE_STEP_M)
    spacing_m = INTERVAL_M * spacing_class / SPACING_CLASSES
    one = np.zeros(1)
    direct = vehicle_turns(
        TurnEnds(one, one, one + math.pi / 2, one + spacing_m, one + offset_m, one - math.pi / 2),
        SMALL,
    ).xy
    kept = (
        np.r_[direct[::SUBSAMPLE], direct[-1:]]
        if (len(direct) - 1) % SUBSAMPLE
        else direct[::SUBSAMPLE]
    )
    points = np.stack([table.u, table.v], axis=1)[table.offsets[shape] : table.offsets[shape + 1]]
    np.testing.assert_allclose(points, kept, atol=1e-9)
    assert table.beyond_m[shape] == pytest.approx(direct[:, 1].max() - max(offset_m, 0.0))


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-20, 20), min_size=2, max_size=6),
    st.lists(st.floats(0.1, 10), min_size=1, max_size=5),
    st.floats(-25, 25),
    st.floats(0.1, 30),
    st.floats(-15, 15),
    st.floats(0.0, 20),
    st.sampled_from([1.0, -1.0]),
)
def test_the_clipped_integral_under_a_chain_is_exact(
    v: list[float],
    steps: list[float],
    x0: float,
    width: float,
    base: float,
    cap: float,
    sign: float,
) -> None:
    chain_v = np.asarray(v)
    chain_u = np.concatenate([[-10.0], -10.0 + np.cumsum(steps)])[: len(chain_v)]
    chain_v = chain_v[: len(chain_u)]
    x = np.linspace(x0, x0 + width, 200_001)
    integrand = np.clip(sign * (np.interp(x, chain_u, chain_v) - base), 0.0, cap)
    numeric = float(np.sum((integrand[1:] + integrand[:-1]) / 2.0 * np.diff(x)))
    exact = _under_chain_m2(chain_u, chain_v, x0, x0 + width, base, cap, sign)
    assert exact == pytest.approx(numeric, rel=1e-6, abs=1e-6 * width * max(cap, 1.0))


def _local(dataset: str, feature_id: str) -> Polygon:
    feature = shared_feature(FIELDS_DIR / f"{dataset}.geojson", feature_id)
    field, _ = validation.validate_field(shapely.from_geojson(json.dumps(feature["geometry"])))
    return shapely.orient_polygons(field_frame(field).to_local(field))


def _fitted_both_ways_m2(area: Polygon, heading: float, edge_m: float) -> tuple[float, float]:
    """The cells' cover at ``heading``, and with each cell fitted for real, both ways, averaged."""
    prepared = [sweep_rings(p) for p in sorted(shapely.get_parts(area), key=lambda p: -p.area)]
    cover = cover_heading(prepared, heading, INTERVAL_M, edge_m)
    fitted = 0.0
    for cell in cover.cells:
        k = cell.lines
        u, lo, hi = cover.scan.u[k], cover.scan.v_lo[k], cover.scan.v_hi[k]
        for variant in (0, 1):
            index, up = order_boustrophedon(len(u), variant)
            start, end = np.where(up, lo[index], hi[index]), np.where(up, hi[index], lo[index])
            fit = fit_lines(u[index], start, end, index, machine=cell.chains, vehicle=SMALL)
            order = np.argsort(fit.u)
            a, b = fit.v_start[order], fit.v_end[order]
            covered = covered_area(
                cell.chains, fit.u[order], np.minimum(a, b), np.maximum(a, b), INTERVAL_M
            )
            fitted += covered / 2.0
    return cover.covered_m2, fitted


@pytest.mark.parametrize(
    ("dataset", "feature_id"),
    [
        ("germany_2018_2019", "germany_2018_2019-9"),
        ("germany_2018_2019", "germany_2018_2019-97"),
        ("rwanda_2021", "rwanda_2021-0"),
    ],
)
def test_the_screen_estimates_what_the_fit_covers(dataset: str, feature_id: str) -> None:
    """Within a quarter of what fitting takes off, at most 1 pp, at headings every 15°."""
    area = machine_area(_local(dataset, feature_id), SMALL)
    edge_m = max((INTERVAL_M - SMALL.width_m) / 2.0, INTERVAL_M / 4.0)
    headings = np.arange(0.0, 180.0, 15.0)
    prepared = [sweep_rings(p) for p in sorted(shapely.get_parts(area), key=lambda p: -p.area)]
    screened = screen_fitted(prepared, headings, INTERVAL_M, edge_m, turn_table(SMALL, INTERVAL_M))
    for heading, estimate_m2 in zip(headings, screened, strict=True):
        cover_m2, fitted_m2 = _fitted_both_ways_m2(area, float(heading), edge_m)
        taken_off_m2 = cover_m2 - fitted_m2
        assert abs(estimate_m2 - fitted_m2) <= min(0.25 * taken_off_m2, 0.01 * area.area), (
            f"{heading}°: screened {estimate_m2:.0f} m², fitted {fitted_m2:.0f} m², "
            f"cover {cover_m2:.0f} m²"
        )


def test_a_turn_beyond_the_table_is_its_last_turn_moved_along_the_lines() -> None:
    """A cell whose top rises 40 m per line: every turn's end lies beyond the table."""
    rise = 10.0
    cell = Polygon([(0, 0), (40, 0), (40, 40 * rise + 30), (0, 30)])
    edge_m = 1.35
    covers, fitted = _fitted_both_ways_m2(cell, 0.0, edge_m)
    screened = screen_fitted([sweep_rings(cell)], [0.0], INTERVAL_M, edge_m, turn_table(SMALL, 4.0))
    assert INTERVAL_M * rise > TABLE_REACH_M  # the premise: offsets beyond the table
    assert screened[0] == pytest.approx(fitted, rel=0.02), (covers, fitted, screened[0])
