"""Every real field of ``../shared/fields`` plans, inside (R1), at 2 m and 4 m (issue 5)."""

from __future__ import annotations

import json
import statistics
from functools import cache

import pytest
import shapely
from shapely import Polygon

from planner import plan_coverage
from planner.general import inner_parts
from planner.projection import field_frame
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import shared_feature
from tests.planner.plan_checks import (
    TINY_VEHICLE,
    assert_body_inside,
    assert_figures_add_up,
    assert_inside,
)

DATASETS = ("rwanda_2021", "south_africa_2017", "germany_2018_2019", "netherlands_f2c")
#: Issue 5: coverage with one headland pass at 4 m.
COVERAGE_TARGET = 0.97


@cache
def real_fields() -> tuple[tuple[str, Polygon], ...]:
    fields = []
    for name in DATASETS:
        collection = json.loads((FIELDS_DIR / f"{name}.geojson").read_text(encoding="utf-8"))
        for feature in collection["features"]:
            fields.append(
                (feature["properties"]["id"], shapely.geometry.shape(feature["geometry"]))
            )
    return tuple(fields)


def test_all_223_real_fields_are_there() -> None:
    assert len(real_fields()) == 223
    assert sum(1 for _, f in real_fields() if f.interiors) >= 17


@pytest.mark.slow
@pytest.mark.parametrize("interval_m", [2.0, 4.0])
def test_every_real_field_plans_inside_r1(interval_m: float) -> None:
    failures = []
    for field_id, field in real_fields():
        try:
            plan = plan_coverage(field, interval_m=interval_m)
            assert_inside(plan)
            assert_figures_add_up(plan)
        except (AssertionError, ValueError) as error:
            failures.append(f"{field_id}: {error}")
    assert not failures, "\n".join(failures)


@pytest.mark.slow
def test_one_headland_pass_covers_97_percent_of_every_real_field_at_4_m() -> None:
    """Coverage with one headland pass at 4 m, over every real field.

    A field that is nowhere wider than two passes (8 m) has no inner area left for lines
    once the pass is driven: its single round, with mitred corners clipped at sharp tips,
    is all the plan can be, and such a field is held to 90 % instead.

    This is issue 5's figure for the lines and passes themselves, so it is measured with a
    vehicle of 0.1 m (the size of the old point model); the hand tractor's own figures (its
    pivots round the corners, its turning room) are in docs/benchmarks.md.
    """
    low, ratios = [], []
    for field_id, field in real_fields():
        plan = plan_coverage(field, interval_m=4.0, headland_passes=1, vehicle=TINY_VEHICLE)
        assert_inside(plan)
        ratio = plan.stats.coverage_ratio
        ratios.append(ratio)
        field_local = field_frame(field).to_local(field)
        too_narrow = not inner_parts(field_local, passes=1, interval_m=4.0)
        if ratio < (0.90 if too_narrow else COVERAGE_TARGET):
            low.append(f"{field_id}: {ratio:.4f}")
    assert not low, "\n".join(low)
    assert statistics.median(ratios) >= 0.99


def real_field(dataset: str, feature_id: str) -> Polygon:
    feature = shared_feature(FIELDS_DIR / f"{dataset}.geojson", feature_id)
    polygon = shapely.geometry.shape(feature["geometry"])
    assert isinstance(polygon, Polygon)
    return polygon


@pytest.mark.parametrize(
    ("feature_id", "target"),
    [
        # 43 m long, 3.6-5 m wide: no inner area, and the one pass at 2 m (rounded for the
        # pivots) ran only along its widest 8 m: 0.28 with the hand tractor (issue 9).
        ("germany_2018_2019-25", 0.90),
        # A 3 m-wide strip 190 m long off a wide field: no pass ran along it (0.967).
        ("germany_2018_2019-53", COVERAGE_TARGET),
    ],
)
def test_one_headland_pass_tills_the_narrow_parts_with_the_hand_tractor(
    feature_id: str, target: float
) -> None:
    """The parts of the band too narrow for the pass get a round of their own, inside."""
    field = real_field("germany_2018_2019", feature_id)
    plan = plan_coverage(field, interval_m=4.0, headland_passes=1)
    assert plan.vehicle is not None and plan.vehicle.preset == "hand_tractor"
    assert plan.stats.coverage_ratio >= target
    assert_inside(plan)
    assert_body_inside(plan)
    assert_figures_add_up(plan)
