"""Issue 9 item 5 on non-convex fields: the search never loses to a fixed heading by over 1 %.

Every fixed heading (every 1°, 0–179) is planned with ``angle_deg`` as a user would; the rule
(R5) compares only those whose coverage is within 0.2 pp of the best fixed heading's, and the
searched plan must be no more than 1 % longer than the shortest of them. The fields are star
fields of the property tests (:func:`tests.planner.random_fields.star_field`), with holes,
at intervals a tenth to a fortieth of their size; the default vehicle (the hand tractor).

Each case plans 181 fields' worth (about 5 s a case on a quiet machine): the first few of a
seeded draw that plan quickly, and two that a 25-field check of the search found 1.4 % and
4.3 % longer than a fixed heading (the search fitted too few headings and compared them in a
greedy cell order).
"""

from __future__ import annotations

import numpy as np
import pytest

from planner import angles, plan_coverage
from tests.conftest import field_from_local
from tests.planner.random_fields import star_field

#: (vertices, seed, size [m], holes asked for, interval [m]).
CASES = [
    pytest.param(10, 2212568278, 334.8615342348589, 2, 18.13, id="10-gon-2-holes"),
    pytest.param(9, 1850753208, 230.22401567130785, 3, 12.41, id="9-gon-3-holes"),
    pytest.param(6, 4255028923, 78.40930496557849, 1, 2.81, id="6-gon-1-hole"),
    pytest.param(8, 1123361780, 251.0792911278842, 1, 8.62, id="8-gon-1-hole"),
    pytest.param(13, 4110225764, 202.1527627324664, 3, 11.82, id="13-gon-was-1.4pct"),
    pytest.param(16, 401347228, 401.4893937441768, 1, 40.07, id="16-gon-was-4.3pct"),
]
#: The searched plan may be this much longer than the best fixed heading that keeps the rule.
LOSS_SHARE = 0.01


@pytest.mark.slow
@pytest.mark.parametrize(("n", "seed", "size_m", "holes", "interval_m"), CASES)
def test_search_is_within_one_percent_of_every_fixed_heading_keeping_the_rule(
    n: int, seed: int, size_m: float, holes: int, interval_m: float
) -> None:
    local = star_field(n, seed, size_m, holes)
    field = field_from_local(list(local.exterior.coords), [list(h.coords) for h in local.interiors])
    searched = plan_coverage(field, interval_m=interval_m)
    fixed = [
        plan_coverage(field, interval_m=interval_m, angle_deg=float(h)).stats
        for h in np.arange(0.0, 180.0, 1.0)
    ]
    best_coverage = max(s.coverage_ratio for s in fixed)
    keeping = [s for s in fixed if s.coverage_ratio >= best_coverage - angles.COVERAGE_SLACK]
    shortest = min(keeping, key=lambda s: s.path_length_m)
    assert searched.stats.path_length_m <= shortest.path_length_m * (1.0 + LOSS_SHARE), (
        f"{searched.stats.angle_deg:.1f}° is {searched.stats.path_length_m:.1f} m, "
        f"{shortest.angle_deg:.1f}° {shortest.path_length_m:.1f} m"
    )
