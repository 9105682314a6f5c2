"""The heading search (R5): coverage first, then the objective; refined locally at 0.1°.

Every figure here is measured from plans made with a fixed ``angle_deg``, independently of
the search's own scores.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner import angles, parse_field_geojson, plan_coverage
from planner.coverage import convex_chains, covered_area
from planner.heading_coverage import convex_coverage
from planner.lines import line_positions, to_sweep
from planner.ordering import score_headings
from planner.projection import field_frame
from planner.types import CoveragePlan
from tests.planner.plan_checks import TINY_VEHICLE
from tests.planner.test_pipeline import ESTIMATE_ERROR, convex_fields, plan_or_too_small

SETTINGS = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
#: Rounding of the reported figures (coverage to 1e-6, given up to 1e-4 pp).
ROUNDING = 2e-6
#: A vehicle whose body hardly matters: the search scores unfitted lines (it does not see the
#: pull-back of line ends that a long body needs; see fitting_slack), so its rule is tested
#: where the fitting changes little.
POINT_VEHICLE = {**TINY_VEHICLE, "length_m": 0.1}


def fitting_slack(field: shapely.Polygon, interval: float) -> float:
    """Coverage the search cannot see: it scores unfitted lines, plans pull their ends back.

    The 0.1 m × 0.1 m vehicle's driven turns pull each line end back a little, and a line whose turn
    cannot reach a sharp corner is left out; two intervals squared of the field bound both.
    """
    return 2.0 * interval * interval / float(field_frame(field).to_local(field).area)


def best_coverage(plan: CoveragePlan) -> float:
    """The best candidate's coverage, as the plan reports it."""
    return plan.stats.coverage_ratio + plan.stats.coverage_given_up_pp / 100.0


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(3, 14),
    aspect=st.floats(0.05, 1.0),
    frac=st.floats(0.01, 0.6),
)
def test_convex_coverage_equals_covered_area_at_every_heading(
    seed: int, n: int, aspect: float, frac: float
) -> None:
    rng = np.random.default_rng(seed)
    hull = shapely.MultiPoint(rng.uniform(-1, 1, (n, 2)) * [50.0, 50.0 * aspect]).convex_hull
    if hull.geom_type != "Polygon" or hull.area < 1.0:
        hull = shapely.box(0, 0, 40, 10)
    ring = np.asarray(shapely.orient_polygons(hull).exterior.coords)[:-1]
    d = frac * np.sqrt(hull.area)
    headings = rng.uniform(0.0, 180.0, 12)
    fast = convex_coverage(ring, headings, d)
    for heading, got in zip(headings, fast, strict=True):
        u, v = to_sweep(ring[:, 0], ring[:, 1], heading)
        chains = convex_chains(u, v)
        at = line_positions(chains.u_min, chains.u_max, d)
        lo = np.interp(at, chains.lo_u, chains.lo_v)
        hi = np.interp(at, chains.hi_u, chains.hi_v)
        assert got == pytest.approx(covered_area(chains, at, lo, hi, d) / hull.area, abs=1e-9)


@SETTINGS
@given(job=convex_fields())
def test_chosen_heading_covers_within_slack_of_every_candidate(job: tuple) -> None:
    """R5: against every candidate (edge directions, the 1° sweep), as fixed-angle plans."""
    field, interval, start, finish = job
    kwargs = {
        "interval_m": interval,
        "start_lonlat": start,
        "finish_lonlat": finish,
        "vehicle": POINT_VEHICLE,
    }
    plan = plan_or_too_small(field, **kwargs)
    if plan is None:
        return
    slack = fitting_slack(field, interval)
    ring = np.asarray(field_frame(field).to_local(field).exterior.coords)[:-1]
    covers = [
        plan_coverage(field, angle_deg=float(h), **kwargs).stats.coverage_ratio
        for h in angles.candidate_headings(ring)
    ]
    assert max(covers) <= best_coverage(plan) + slack + ESTIMATE_ERROR + ROUNDING
    assert plan.stats.coverage_ratio >= max(covers) - angles.COVERAGE_SLACK - slack - ROUNDING
    assert 0.0 <= plan.stats.coverage_given_up_pp <= 100 * angles.COVERAGE_SLACK + 1e-6


@SETTINGS
@given(job=convex_fields())
def test_no_nearby_tenth_of_a_degree_keeping_the_rule_is_shorter(job: tuple) -> None:
    """The local refinement: within 0.9° on the 0.1° grid, nothing is 0.05 % shorter."""
    field, interval, start, finish = job
    kwargs = {
        "interval_m": interval,
        "start_lonlat": start,
        "finish_lonlat": finish,
        "vehicle": POINT_VEHICLE,
    }
    plan = plan_or_too_small(field, **kwargs)
    if plan is None:
        return
    slack = fitting_slack(field, interval)
    grid = round(plan.stats.angle_deg, 1)
    for step in range(-9, 10):
        near = plan_coverage(field, angle_deg=(grid + step / 10) % 180.0, **kwargs)
        if near.stats.coverage_ratio >= best_coverage(plan) - angles.COVERAGE_SLACK + slack:
            # Driven turns and pulled-back ends: up to ~0.5 m per line (test_pipeline).
            lines = max(plan.stats.line_count, near.stats.line_count)
            assert plan.stats.path_length_m <= near.stats.path_length_m * 1.0005 + 0.5 * lines


@pytest.mark.parametrize("interval_m", [1.0, 1.5, 2.0, 2.5, 4.0])
def test_paper_field_never_buys_length_with_coverage(
    paper_geojson: dict, interval_m: float
) -> None:
    """Issue 9: at 2.5 m the search took 8° (95.5 %) over 1° (99.8 %) to save 11.6 m."""
    spec = parse_field_geojson(paper_geojson)
    plan = plan_coverage(spec.field_lonlat, interval_m=interval_m)
    for heading in (1.0, 8.0, 90.0):
        fixed = plan_coverage(spec.field_lonlat, interval_m=interval_m, angle_deg=heading)
        assert plan.stats.coverage_ratio >= fixed.stats.coverage_ratio - 0.002 - ROUNDING


def test_fixed_heading_gives_nothing_up(paper_geojson: dict) -> None:
    spec = parse_field_geojson(paper_geojson)
    plan = plan_coverage(spec.field_lonlat, interval_m=2.5, angle_deg=8.0)
    assert plan.stats.angle_deg == 8.0
    assert plan.stats.coverage_given_up_pp == 0.0


def test_coverage_rule_keeps_headings_within_two_tenths_of_a_point() -> None:
    coverage = np.array([0.998, 0.955, 0.9960001, 0.9959])
    assert angles.coverage_eligible(coverage).tolist() == [True, False, True, False]


#: Fixed random convex fields for the global brute force: (seed, vertices, aspect, lines
#: across, start and finish given).
BRUTE_FORCE_FIELDS = [
    (
        int(rng.integers(0, 2**32)),
        int(rng.integers(3, 17)),
        float(rng.uniform(0.1, 1.0)),
        float(10 ** rng.uniform(np.log10(3.0), 2.0)),
        bool(rng.random() < 0.5),
    )
    for rng in [np.random.default_rng(0)]
    for _ in range(60)
]


def searched_and_brute_force(
    seed: int, n: int, aspect: float, lines: float, with_ends: bool
) -> tuple[float, float, float]:
    """Search one field on the closed-form scores and score every 0.1° of [0, 180) too.

    Returns the searched plan's excess length over the best heading of the brute force that
    keeps the rule [%], its coverage and the brute force's best coverage.
    """
    rng = np.random.default_rng(seed)
    hull = shapely.MultiPoint(rng.uniform(-1, 1, (n, 2)) * [100.0, 100.0 * aspect]).convex_hull
    if hull.geom_type != "Polygon" or hull.area < 1.0:
        hull = shapely.box(0, 0, 160, 40)
    ring = np.asarray(shapely.orient_polygons(hull).exterior.coords)[:-1]
    d = float(np.sqrt(hull.area)) / lines
    start = tuple(rng.uniform(-150, 150, 2)) if with_ends else None
    finish = tuple(rng.uniform(-150, 150, 2)) if with_ends else None

    def lengths_of(h: np.ndarray) -> tuple:
        return score_headings(ring, h, d, start, finish)

    def coverage_of(h: np.ndarray) -> np.ndarray:
        return convex_coverage(ring, h, d)

    choice = angles.search_headings(
        lengths_of, coverage_of, angles.candidate_headings(ring), "shortest_path", interval_m=d
    )
    grid = np.round(np.arange(0.0, 180.0, 0.1), 1)
    grid_lengths, _ = lengths_of(grid)
    grid_coverage = coverage_of(grid)
    best_coverage = max(float(grid_coverage.max()), choice.coverage_ratio)
    eligible = grid_coverage >= best_coverage - angles.COVERAGE_SLACK
    brute = float(grid_lengths.total[eligible].min())
    found = float(lengths_of(np.array([choice.heading_deg]))[0].total[0, choice.variant])
    return (found / brute - 1.0) * 100.0, choice.coverage_ratio, float(grid_coverage.max())


def test_search_is_within_five_hundredths_of_a_percent_of_a_tenth_degree_brute_force() -> None:
    """Issue 9 item 5, globally, on the search's own scores (60 fixed fields, 0.1° steps).

    The plans' figures also carry the fitting for the vehicle, which the search does not see
    (``python -m bench.heading_brute_force`` measures whole plans); here coverage and length
    are the closed forms the search ranks by, so the search alone is judged. The rule's
    bound is the best coverage anywhere on the grid, located to 0.02 pp. Before the
    refinement swept the best-covering headings and gave length-only headings their
    coverage, 3 of these fields were beyond 0.05 % (up to 0.38 %) and one chose 0.09 pp
    beyond the rule. A grid heading far from every seed can still be missed (1 in 60 here
    at 0.058 %; on other draws up to 0.45 %, 1 field in 60).
    """
    excess, covered, best = np.array(
        [searched_and_brute_force(*field) for field in BRUTE_FORCE_FIELDS]
    ).T
    assert (covered >= best - angles.COVERAGE_SLACK - 2e-4).all(), (best - covered).max()
    assert np.median(excess) <= 1e-9
    assert (excess > 0.05).sum() <= 1, np.sort(excess)[-3:]
    assert excess.max() <= 0.1, excess.max()


def test_least_equals_numpy_reduction() -> None:
    """The four variants' least rounded length per heading, the same to the bit."""
    rng = np.random.default_rng(3)
    tied = np.round(rng.uniform(0.0, 500.0, size=(300, 4)), 1)  # ties between variants
    tied[5] = np.inf
    tied[6, 2] = np.nan
    least = angles._least(tied)
    expected = tied.min(axis=1)
    assert np.array_equal(least, expected, equal_nan=True)
    number = ~np.isnan(expected)
    assert np.array_equal(least[number].view(np.int64), expected[number].view(np.int64))
