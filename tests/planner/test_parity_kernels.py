"""Which way round each cell is driven (planner.parity_kernels): classes, screen, plans."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
from shapely import Polygon

import planner.general
from planner import angles, plan_coverage, validation
from planner.cell_plans import cover_heading
from planner.coverage import covered_area
from planner.decomposition import sweep_rings
from planner.fit_screen import turn_table
from planner.line_ends import fit_lines, machine_area
from planner.ordering import order_boustrophedon
from planner.parity_kernels import parity_choice, parity_losses_m2
from planner.projection import field_frame
from planner.vehicles import resolve_vehicle
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import shared_feature

SMALL = resolve_vehicle("small_tractor")
INTERVAL_M = 4.0
EDGE_M = max((INTERVAL_M - SMALL.width_m) / 2.0, INTERVAL_M / 4.0)
#: A real field whose cells lose far more cover one way round than the other (issue 9).
WAYS_FIELD = ("south_africa_2017", "south_africa_2017-82")
#: ... at this heading [deg].
WAYS_HEADING = 54.0


@pytest.mark.parametrize("lines", [2, 3, 4, 5, 8])
@pytest.mark.parametrize("variant", [0, 1, 2, 3])
def test_a_variant_is_excluded_with_the_ends_its_turns_use(lines: int, variant: int) -> None:
    """The way whose first turn (between the cell's first two lines) is at the bottom loses."""
    index, up = order_boustrophedon(lines, variant)
    # The turn between lines 0 and 1 leaves whichever of them is driven first, at its end.
    first = index.tolist().index(0) < index.tolist().index(1)
    leaving = up[index.tolist().index(0 if first else 1)]
    turns_at_top = bool(leaving)
    excluded = parity_choice(np.array([[0.0, 100.0]]), np.array([lines]), 1.0)
    assert bool(excluded[0, variant]) == (not turns_at_top)


def _local(dataset: str, feature_id: str) -> Polygon:
    feature = shared_feature(FIELDS_DIR / f"{dataset}.geojson", feature_id)
    field, _ = validation.validate_field(shapely.from_geojson(json.dumps(feature["geometry"])))
    return shapely.orient_polygons(field_frame(field).to_local(field))


def _fitted_loss_m2(cell_chains, u, lo, hi, variant: int) -> float:  # type: ignore[no-untyped-def]
    """What fitting a cell's lines for real, driven as ``variant``, takes off its cover."""
    index, up = order_boustrophedon(len(u), variant)
    start, end = np.where(up, lo[index], hi[index]), np.where(up, hi[index], lo[index])
    fit = fit_lines(u[index], start, end, index, machine=cell_chains, vehicle=SMALL)
    order = np.argsort(fit.u)
    a, b = fit.v_start[order], fit.v_end[order]
    fitted = covered_area(cell_chains, fit.u[order], np.minimum(a, b), np.maximum(a, b), 4.0)
    return covered_area(cell_chains, u, lo, hi, INTERVAL_M) - fitted


@pytest.mark.parametrize("heading", [WAYS_HEADING, 10.0, 100.0, 150.0])
def test_the_screen_tells_which_way_round_loses_more(heading: float) -> None:
    """Where the screen puts one way 1 % of the field's area worse, so does the real fit."""
    area = machine_area(_local(*WAYS_FIELD), SMALL)
    prepared = [sweep_rings(p) for p in sorted(shapely.get_parts(area), key=lambda p: -p.area)]
    cover = cover_heading(prepared, heading, INTERVAL_M, EDGE_M)
    scan = cover.scan
    losses = parity_losses_m2(
        [c.chains for c in cover.cells], scan.offsets, scan.u, scan.v_lo, scan.v_hi,
        INTERVAL_M, turn_table(SMALL, INTERVAL_M),
    )  # fmt: skip
    clear = 0
    for c, cell in enumerate(cover.cells):
        k = cell.lines
        if k.stop - k.start < 2 or abs(losses[c, 0] - losses[c, 1]) < 0.01 * area.area:
            continue
        clear += 1
        u, lo, hi = scan.u[k], scan.v_lo[k], scan.v_hi[k]
        up_m2, down_m2 = (_fitted_loss_m2(cell.chains, u, lo, hi, v) for v in (0, 1))
        assert (up_m2 < down_m2) == (losses[c, 0] < losses[c, 1]), (c, losses[c], up_m2, down_m2)
    if heading == WAYS_HEADING:
        assert clear, "the premise: a cell loses far more one way round"


def test_a_plan_does_not_buy_length_with_a_cells_cover() -> None:
    """Driven the way round that saves length, the field's cells would cover 0.2 pp less."""
    feature = shared_feature(FIELDS_DIR / f"{WAYS_FIELD[0]}.geojson", WAYS_FIELD[1])
    field = shapely.from_geojson(json.dumps(feature["geometry"]))
    kwargs = {"interval_m": INTERVAL_M, "vehicle": "small_tractor", "angle_deg": WAYS_HEADING}
    chosen = plan_coverage(field, **kwargs)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(planner.general, "PARITY_SLACK_SHARE", math.inf)
        for_length = plan_coverage(field, **kwargs)
    gained = chosen.stats.coverage_ratio - for_length.stats.coverage_ratio
    assert gained > angles.COVERAGE_SLACK, (chosen.stats, for_length.stats)
    assert chosen.stats.path_length_m >= for_length.stats.path_length_m  # what it costs
