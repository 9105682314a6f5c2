"""R5 on the plan's own lines (issue 9 item 5): no searched heading more than 0.2 pp below a
heading the search looked at, planned at that fixed heading, on real convex fields."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from planner import plan_coverage
from planner.angles import COVERAGE_SLACK, candidate_headings
from planner.errors import PlannerError
from planner.projection import field_frame
from tests.planner.plan_checks import fixed_heading_figures
from tests.planner.random_fields import random_convex_jobs
from tests.planner.test_real_fields import real_fields

#: The plan reports its coverage ratio to 1e-6.
_ROUNDING = 1e-6


@pytest.mark.parametrize(
    ("field_id", "vehicle"),
    [
        # Fitted coverage peaks at 52.0° (96.55 %) and falls 0.8 pp within 0.6°; the search's
        # three alternatives, a seed gap apart, all missed it (96.19 % was chosen).
        ("rwanda_2021-27", "hand_tractor"),
        # 75.0° covers 83.66 %; the alternatives' best was 75.6° (82.83 %).
        ("rwanda_2021-12", "small_tractor"),
    ],
)
def test_searched_heading_keeps_the_rule_over_fixed_candidate_headings(
    field_id: str, vehicle: str
) -> None:
    field = dict(real_fields())[field_id]
    local = field_frame(field).to_local(field)
    ring = np.asarray(shapely.orient_polygons(local).exterior.coords)[:-1]
    searched = plan_coverage(field, interval_m=4.0, vehicle=vehicle).stats
    fixed = []
    for heading in candidate_headings(ring).tolist():  # the 1° sweep and every edge direction
        try:
            stats = plan_coverage(field, interval_m=4.0, vehicle=vehicle, angle_deg=heading).stats
        except PlannerError:
            continue
        fixed.append((stats.coverage_ratio, heading))
    best, at = max(fixed)
    assert searched.coverage_ratio >= best - COVERAGE_SLACK - _ROUNDING, (
        f"searched {searched.angle_deg}° covers {searched.coverage_ratio:.6f}, "
        f"fixed {at}° {best:.6f}"
    )


#: Fields of ``bench.heading_brute_force`` (``random_convex_jobs``, seed 9) that the search
#: planned more than 0.05 % longer than the 0.1° brute force: on field 9 (7 lines) the
#: estimate ruled out 32.4°, which covers 98.15 % fitted against the best 98.32 % (1.0 %
#: shorter); field 20 (11 lines, estimate failed) was fitted at the scored headings only and
#: missed 118.6° between them (0.3 %).
BRUTE_FORCE_FIELDS = (9, 20)


@pytest.mark.slow
@pytest.mark.parametrize("field_k", BRUTE_FORCE_FIELDS)
def test_searched_plan_within_five_hundredths_of_a_percent_of_a_tenth_degree_brute_force(
    field_k: int,
) -> None:
    field, interval, start, finish = random_convex_jobs(field_k + 1)[field_k]
    kwargs = {"interval_m": interval, "start_lonlat": start, "finish_lonlat": finish}
    searched = plan_coverage(field, **kwargs).stats
    _, lengths, cover = fixed_heading_figures(
        field, np.round(np.arange(0.0, 180.0, 0.1), 1).tolist(), **kwargs
    )
    keeps_rule = cover >= cover.max() - COVERAGE_SLACK - _ROUNDING
    shortest = float(lengths[keeps_rule].min())
    assert searched.coverage_ratio >= cover.max() - COVERAGE_SLACK - _ROUNDING
    assert searched.path_length_m <= shortest * 1.0005, (
        f"searched {searched.angle_deg}° {searched.path_length_m:.1f} m, "
        f"brute force {shortest:.1f} m"
    )
