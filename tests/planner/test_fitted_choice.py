"""A convex field's heading and way round (planner.fitted_choice): R5 within the heading."""

from __future__ import annotations

import json

import pytest
import shapely

from planner import plan_coverage, validation
from planner.convex_fits import fit_headings
from planner.parity_kernels import PARITY_SLACK_SHARE
from planner.projection import field_frame
from planner.vehicles import resolve_vehicle
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import shared_feature


@pytest.mark.parametrize("feature_id", ["rwanda_2021-25", "rwanda_2021-27", "rwanda_2021-14"])
def test_a_convex_plan_is_driven_the_way_round_that_covers_most(feature_id: str) -> None:
    """No other variant at the plan's heading covers more than the parity slack beyond it.

    On the first two the way round that saved length covered 0.38 and 0.23 pp less; on the
    third the choice covered most already.
    """
    feature = shared_feature(FIELDS_DIR / "rwanda_2021.geojson", feature_id)
    field, _ = validation.validate_field(shapely.from_geojson(json.dumps(feature["geometry"])))
    local = shapely.orient_polygons(field_frame(field).to_local(field))
    assert local.equals(local.convex_hull), "the premise: a convex field"
    plan = plan_coverage(field, interval_m=4.0, vehicle="small_tractor")
    ways = fit_headings(
        local, [plan.stats.angle_deg] * 4, [0, 1, 2, 3], interval_m=4.0, implement_width_m=4.0,
        vehicle=resolve_vehicle("small_tractor"), pattern="boustrophedon",
    )  # fmt: skip
    best_ratio = max(way[1] for way in ways if not isinstance(way, Exception)) / local.area
    assert plan.stats.coverage_ratio >= best_ratio - PARITY_SLACK_SHARE - 1e-9
