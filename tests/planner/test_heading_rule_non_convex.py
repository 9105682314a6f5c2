"""Issue 9 item 5 on non-convex fields: the search keeps R5 and never loses to a fixed heading.

Every fixed heading (every 1°, 0–179) is planned with ``angle_deg`` as a user would; the rule
(R5) compares only those whose coverage is within 0.2 pp of the best fixed heading's: the
searched plan must cover no less than the best one's coverage minus that slack, and be no more
than 1 % longer than the shortest of them (the measure is :mod:`bench.heading_rule`'s, the
same sum the brute-force benches count). The fields are star fields of the property tests
(:func:`bench.shapes.star_field`), with holes, at intervals a tenth to a
fortieth of their size, with the default vehicle (the hand tractor); and real fields at 4 m
on which the search covered over 0.2 pp less than a fixed heading (its few headings
decomposed all missed the best-covering one).

Each case plans 181 fields' worth (the 15 cases: 16 s with two workers on a 2-core AMD
EPYC). The star fields are the first few of a seeded draw that plan quickly, and two that a
25-field check of the search found 1.4 % and 4.3 % longer than a fixed heading (the search
fitted too few headings and compared them in a greedy cell order).
"""

from __future__ import annotations

import json

import pytest
import shapely
from shapely import Polygon

from bench.heading_rule import LOSS_PCT, compare
from bench.shapes import NON_CONVEX_CASES, field_from_local, star_field
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import shared_feature

#: (vertices, seed, size [m], holes asked for, interval [m]), shared with
#: ``bench.heading_brute_force_non_convex --cases``.
CASES = [pytest.param(*case, id=name) for name, case in NON_CONVEX_CASES.items()]
#: Real fields: (dataset, feature id, vehicle); the search covered 0.284 pp and 2.086 pp less
#: than the best fixed heading before the misjudged headings were decomposed.
REAL_CASES = [
    pytest.param("germany_2018_2019", "germany_2018_2019-65", "hand_tractor", id="germany-65"),
    pytest.param(
        "germany_2018_2019", "germany_2018_2019-37", "small_tractor", id="germany-37-small"
    ),
    # 1.64 and 0.27 pp beyond the slack before every heading's decomposed estimate was
    # screened (the search's few headings were close to the best-covering one, but fitted
    # coverage drops by 2 pp within 0.6° there).
    pytest.param("germany_2018_2019", "germany_2018_2019-4", "hand_tractor", id="germany-4"),
    pytest.param("germany_2018_2019", "germany_2018_2019-9", "hand_tractor", id="germany-9"),
    # 5.71 and 1.88 pp beyond the slack while headings were ranked on the decomposed
    # estimate alone: with a radius it misjudges fitted coverage by a few pp; the best by it
    # are now screened with every cell fitted from a table of the vehicle's turns
    # (planner.fit_screen).
    pytest.param("germany_2018_2019", "germany_2018_2019-9", "small_tractor", id="germany-9-small"),
    # 0.10 pp beyond the slack while a move's drop that clashed with another's was not
    # tried again (planner.cell_moves._LineDrops): 174.19° against 169°.
    pytest.param(
        "germany_2018_2019", "germany_2018_2019-77", "small_tractor", id="germany-77-small"
    ),
    pytest.param("germany_2018_2019", "germany_2018_2019-1", "small_tractor", id="germany-1-small"),
    # 4.69 % longer than the shortest 1° heading that keeps the rule (53.46° against 64°):
    # fitted at the edge direction 63.637° the search lost a pp of cover that 63.640° keeps;
    # now the neighbours of such a heading are fitted too (planner.fitted_cells._probed).
    pytest.param("germany_2018_2019", "germany_2018_2019-21", "hand_tractor", id="germany-21"),
    # Known gap (issue 9): a move between cells with no curve drops the lines that block it
    # (planner.cell_moves._LineDrops), and driven cover jumps between headings the fitted
    # screen ranks alike: the search drives 89° (79.79 %), 0.16 pp beyond the slack of 80°
    # (80.16 %; ``python -m bench.heading_brute_force_real small_tractor``: 7 of 223 short).
    pytest.param(
        "germany_2018_2019",
        "germany_2018_2019-5",
        "small_tractor",
        id="germany-5-small",
        marks=pytest.mark.xfail(
            strict=True,
            raises=AssertionError,
            reason="lines dropped for moves make driven cover jump between headings",
        ),
    ),
]
#: The interval of the real fields [m] (their benchmarks').
REAL_INTERVAL_M = 4.0


def assert_rule(field: Polygon, interval_m: float, vehicle: str) -> None:
    """The searched plan keeps R5 against every 1° fixed heading and is within 1 % of them."""
    outcome = compare(field, interval_m, vehicle)
    assert outcome.shortfall_pp == 0.0, outcome.describe()
    assert outcome.excess_pct <= LOSS_PCT, outcome.describe()


@pytest.mark.slow
@pytest.mark.parametrize(("n", "seed", "size_m", "holes", "interval_m"), CASES)
def test_search_keeps_the_rule_and_is_within_one_percent_of_every_fixed_heading(
    n: int, seed: int, size_m: float, holes: int, interval_m: float
) -> None:
    local = star_field(n, seed, size_m, holes)
    field = field_from_local(list(local.exterior.coords), [list(h.coords) for h in local.interiors])
    assert_rule(field, interval_m, "hand_tractor")


@pytest.mark.slow
@pytest.mark.parametrize(("dataset", "feature_id", "vehicle"), REAL_CASES)
def test_search_keeps_the_rule_on_real_fields(dataset: str, feature_id: str, vehicle: str) -> None:
    feature = shared_feature(FIELDS_DIR / f"{dataset}.geojson", feature_id)
    field = shapely.from_geojson(json.dumps(feature["geometry"]))
    assert isinstance(field, Polygon)
    assert_rule(field, REAL_INTERVAL_M, vehicle)
