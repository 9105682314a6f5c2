"""The headings R5 fits first (``planner.cover_picks``)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely

from bench.screen_speed import prepared_field
from planner.cell_plans import cover_heading
from planner.cover_picks import COVER_FITS, cover_picks
from planner.fitted_cells import estimate_m2
from planner.vehicles import resolve_vehicle
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import shared_feature

#: Real fields whose searched heading covered less than R5 allows before every heading was
#: screened (``bench.heading_brute_force_real``), and one with holes.
FIELDS = ["germany_2018_2019-4", "germany_2018_2019-21", "germany_2018_2019-42"]


@pytest.mark.parametrize("vehicle", ["hand_tractor", "small_tractor"])
@pytest.mark.parametrize("feature_id", FIELDS)
def test_cover_picks_are_the_best_headings_by_the_decomposed_estimate(
    feature_id: str, vehicle: str
) -> None:
    feature = shared_feature(FIELDS_DIR / "germany_2018_2019.geojson", feature_id)
    field = shapely.from_geojson(json.dumps(feature["geometry"]))
    prepared, edge_m = prepared_field(field, 4.0, vehicle)
    machine = resolve_vehicle(vehicle)
    headings = np.arange(0.0, 180.0, 1.0)

    picks = cover_picks(prepared, headings, 4.0, edge_m, machine).picks

    # Measured the slow way: every heading decomposed on its own.
    estimate = np.array(
        [estimate_m2(cover_heading(prepared, h, 4.0, edge_m), machine, 4.0) for h in headings]
    )
    best_first = np.lexsort((headings, -estimate))
    assert picks == best_first[:COVER_FITS].tolist()
