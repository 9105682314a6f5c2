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


def test_no_heading_is_fitted_twice(monkeypatch: pytest.MonkeyPatch) -> None:
    """The way round reuses the chosen heading's fit, and a check fits at most 32 at once.

    germany_2018_2019-25 comes to the way round after fitting its scored headings; before, the
    chosen heading and variant were fitted again there.
    """
    from planner import fitted_choice

    calls: list[list[tuple[float, int]]] = []

    def counted(field, headings, variants, **kwargs):  # type: ignore[no-untyped-def]
        calls.append(list(zip(map(float, headings), map(int, variants), strict=True)))
        return fit_headings(field, headings, variants, **kwargs)

    monkeypatch.setattr(fitted_choice, "fit_headings", counted)
    feature = shared_feature(FIELDS_DIR / "germany_2018_2019.geojson", "germany_2018_2019-25")
    field, _ = validation.validate_field(shapely.from_geojson(json.dumps(feature["geometry"])))
    plan_coverage(field, interval_m=4.0, vehicle="small_tractor")
    fitted = [pair for call in calls for pair in call]
    assert len(calls) > 2, "the premise: the plan was checked on fitted headings"
    assert len(fitted) == len(set(fitted))
    assert max(len(call) for call in calls) <= fitted_choice._BLOCK_MAX
