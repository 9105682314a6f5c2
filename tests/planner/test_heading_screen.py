"""planner.heading_screen: each heading measured as cover_heading does, bit for bit; kept cells."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import Polygon, affinity

from bench.screen_speed import prepared_field
from planner.cell_kernels import sweep_cells
from planner.cell_plans import cover_heading, cover_screened
from planner.cover_picks import SCREENED_FITS
from planner.coverage import _laid_out
from planner.decomposition import SweepRings, _cuts, sweep_rings
from planner.fit_screen import turn_table
from planner.fitted_cells import _turn_count, turn_change_m
from planner.heading_screen import (
    fit_screened,
    fit_screened_cells,
    screen_cells,
    screen_covers,
    screen_fitted,
    screened_cells,
)
from planner.lines import to_sweep
from planner.parity_kernels import parity_losses_m2
from planner.vehicles import resolve_vehicle
from tests.planner.random_fields import fields_with_holes
from tests.planner.test_real_fields import real_fields

FloatArray = np.ndarray
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
#: Real fields with holes, many cells, or cells measured on their own (``covered_area``).
REAL_FIELDS = (
    "germany_2018_2019-42",  # a hole; 171 headings with a cell measured on its own
    "germany_2018_2019-75",  # 7 holes, up to 46 cells
    "south_africa_2017-52",  # 2 holes, up to 480 lines
    "germany_2018_2019-77",
)


def same_bits(a: FloatArray, b: FloatArray) -> bool:
    """Equal to the last bit, signed zeros and NaN included."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


def looped(
    prepared: list[SweepRings], headings: FloatArray, d: float, edge_m: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The reference: ``cover_heading`` at each heading, NaN and -1 where it raises."""
    covered, lines, turns = [], [], []
    for heading in headings.tolist():
        try:
            cover = cover_heading(prepared, heading, d, edge_m)
        except ValueError:
            covered.append(np.nan)
            lines.append(-1)
            turns.append(-1)
            continue
        covered.append(cover.covered_m2)
        lines.append(cover.line_count)
        turns.append(_turn_count(cover))
    return np.array(covered), np.array(lines), np.array(turns)


def assert_screen_equals_loop(
    prepared: list[SweepRings], headings: FloatArray, d: float, edge_m: float
) -> None:
    covered, lines, turns = screen_covers(prepared, headings, d, edge_m)
    ref_covered, ref_lines, ref_turns = looped(prepared, headings, d, edge_m)
    assert lines.dtype == turns.dtype == np.int64 and covered.dtype == np.float64
    assert lines.tolist() == ref_lines.tolist()
    assert turns.tolist() == ref_turns.tolist()
    assert same_bits(covered, ref_covered), np.flatnonzero(covered != ref_covered)


@cache
def prepared_real(field_id: str) -> tuple[list[SweepRings], float]:
    """``plan_general``'s parts (hand_tractor, 4 m, no headland) of a real field, and its edge."""
    return prepared_field(dict(real_fields())[field_id])


@pytest.mark.parametrize("field_id", REAL_FIELDS)
def test_real_fields_every_degree_equal_cover_heading(field_id: str) -> None:
    prepared, edge_m = prepared_real(field_id)
    assert_screen_equals_loop(prepared, np.arange(0.0, 180.0, 1.0), 4.0, edge_m)


def test_real_fields_hold_holes_and_cells_measured_alone() -> None:
    """The fields above test what they are picked for: holes, many cells, odd cells."""
    prepared, _ = prepared_real("germany_2018_2019-75")
    assert len(prepared[0].sizes) == 8
    prepared, edge_m = prepared_real("germany_2018_2019-42")
    odd = 0
    for heading in range(0, 180, 5):
        cover = cover_heading(prepared, float(heading), 4.0, edge_m)
        s = cover.scan
        alone, _, _ = _laid_out(
            [c.chains for c in cover.cells], s.offsets, s.u, s.v_lo, s.v_hi, 4.0
        )
        odd += len(alone)
    assert odd > 0


@st.composite
def parts_and_headings(draw: st.DrawFn) -> tuple[list[Polygon], FloatArray, float, float]:
    """One or two star fields with holes (the second beside the first), headings, d, edge."""
    parts = [draw(fields_with_holes(max_vertices=30))]
    if draw(st.booleans()):
        other = draw(fields_with_holes(max_vertices=20))
        parts.append(affinity.translate(other, xoff=parts[0].bounds[2] - other.bounds[0] + 5.0))
    headings = draw(
        st.lists(
            st.one_of(st.floats(0.0, 180.0), st.sampled_from([0.0, 45.0, 90.0, 135.0])),
            min_size=1,
            max_size=8,
        )
    )
    d = draw(st.floats(1.0, 12.0))
    edge_m = d * draw(st.floats(0.25, 0.5))
    return parts, np.array(headings), d, edge_m


@SETTINGS
@given(case=parts_and_headings())
def test_random_fields_with_holes_equal_cover_heading(
    case: tuple[list[Polygon], FloatArray, float, float],
) -> None:
    parts, headings, d, edge_m = case
    assert_screen_equals_loop([sweep_rings(p) for p in parts], headings, d, edge_m)


def test_a_heading_cover_heading_cannot_do_is_nan() -> None:
    """No parts: cover_heading raises; the screen says NaN, -1, -1."""
    covered, lines, turns = screen_covers([], np.array([0.0, 30.0]), 4.0, 1.0)
    assert np.isnan(covered).all() and lines.tolist() == turns.tolist() == [-1, -1]


def test_a_boundary_the_sweep_cannot_take_is_measured_by_cover_heading() -> None:
    """At 45° this field's ring has a vertex too far off a cut (``_pieces`` gives up): shapely."""
    field = shapely.from_wkt(
        "POLYGON ((85 -25, 45 -15, 55 -55, -70 -50, -40 -15, -75 -5, -75 0, -40 90, -20 50,"
        " -10 35, 40 85, 45 85, 85 -25), (-35 20, -30 5, -25 30, -35 20))"
    )
    prepared = sweep_rings(field)
    u, v = to_sweep(prepared.x, prepared.y, 45.0)
    turn = (u - u[prepared.prv]) * (u[prepared.nxt] - u) <= 0.0
    r = prepared
    status, *_ = sweep_cells(
        u, v, turn, _cuts(u[turn]), r.sizes, r.first, r.ring_of, r.local, r.nxt, r.prv
    )
    assert status == 0
    assert_screen_equals_loop([prepared], np.array([0.0, 45.0, 90.0]), 4.0, 1.0)


def test_l_field_by_hand() -> None:
    """An L at 0°: one cell, 15 lines; at 135°: three cells, 23 lines."""
    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    covered, lines, turns = screen_covers([sweep_rings(ell)], [0.0, 135.0], 4.0, 2.0)
    assert lines.tolist() == [15, 23] and turns.tolist() == [14, 20]
    assert covered[0] == 2640.0  # 15 footprints inside the L's 2700 m², 4 m wide, 2 m in


# The cells kept while screening, fitted: as screen_fitted decomposes them again.

SMALL = resolve_vehicle("small_tractor")


@cache
def prepared_small(field_id: str) -> tuple[list[SweepRings], float]:
    """``plan_general``'s parts of a real field with ``small_tractor`` at 4 m, and its edge."""
    return prepared_field(dict(real_fields())[field_id], vehicle="small_tractor")


def small_at_4m(field_id: str) -> tuple[list[SweepRings], float, FloatArray, float, float]:
    """A real field's parts and edge with ``small_tractor``, every 1°, 4 m, and the reach."""
    prepared, edge_m = prepared_small(field_id)
    _, reach_m = turn_change_m(SMALL, 4.0)
    return prepared, edge_m, np.arange(0.0, 180.0, 1.0), 4.0, reach_m


def best_by_estimate(
    covered: FloatArray,
    lines: FloatArray,
    turns: FloatArray,
    headings: FloatArray,
    reach_m: float,
    d: float,
    count: int,
) -> FloatArray:
    """``cover_picks``'s first ``count`` headings by the estimate, the refused left out."""
    estimate = np.round(np.where(lines >= 0, covered - 2.0 * turns * reach_m * d, -np.inf), 6)
    order = np.lexsort((headings, -estimate))[:count]
    return order[np.isfinite(estimate[order])]


@pytest.mark.parametrize("keep", [1, 3, SCREENED_FITS])
@pytest.mark.parametrize("field_id", ["germany_2018_2019-42", "germany_2018_2019-75"])
def test_the_best_estimated_headings_are_kept_and_fit_as_screen_fitted(
    field_id: str, keep: int
) -> None:
    prepared, edge_m, headings, d, reach_m = small_at_4m(field_id)
    table = turn_table(SMALL, d)
    screened = screen_cells(prepared, headings, d, edge_m, reach_m=reach_m, keep=keep)
    assert screened.kept is not None
    assert (screened.kept.kept_of < 0).any()  # some headings are not kept: the test's premise
    best = best_by_estimate(*screened[:3], headings, reach_m, d, keep)
    assert len(best) == keep
    again = screen_fitted(prepared, headings[best], d, edge_m, table)
    assert np.isfinite(again).all()
    assert same_bits(fit_screened(screened, best, table), again)
    assert same_bits(
        np.asarray(screened[:3]), np.asarray(screen_covers(prepared, headings, d, edge_m))
    )


def test_headings_not_kept_fit_to_nan() -> None:
    prepared, edge_m = prepared_small("germany_2018_2019-42")
    headings = np.arange(0.0, 180.0, 15.0)
    screened = screen_cells(prepared, headings, 4.0, edge_m)  # keep nothing
    fitted = fit_screened(screened, np.arange(len(headings)), turn_table(SMALL, 4.0))
    assert screened.kept is None and np.isnan(fitted).all()


@pytest.mark.parametrize(
    ("field_id", "rank"), [("germany_2018_2019-42", 3), ("germany_2018_2019-75", SCREENED_FITS)]
)
def test_a_ranked_screen_measures_the_best_as_in_full_and_leaves_only_what_cannot_rank(
    field_id: str, rank: int
) -> None:
    prepared, edge_m, headings, d, reach_m = small_at_4m(field_id)
    table = turn_table(SMALL, d)
    full = screen_cells(prepared, headings, d, edge_m, reach_m=reach_m, keep=rank)
    ranked = screen_cells(prepared, headings, d, edge_m, reach_m=reach_m, keep=rank, rank=rank)

    left = np.isnan(ranked.covered_m2) & np.isfinite(full.covered_m2)
    assert left.sum() > len(headings) // 2  # with a radius most headings cannot rank
    # Each heading left unmeasured: even covering the whole field it ranks below the best.
    best = best_by_estimate(*full[:3], headings, reach_m, d, rank)
    assert len(best) == rank
    area_m2 = sum(p.field.area for p in prepared)
    kth_m2 = (full.covered_m2 - 2.0 * full.turn_count * reach_m * d)[best[-1]]
    assert (area_m2 - 2.0 * ranked.turn_count[left] * reach_m * d < kth_m2).all()
    # The rest measured bit for bit; lines and turns counted at every heading.
    assert same_bits(ranked.covered_m2[~left], full.covered_m2[~left])
    assert (ranked.line_count == full.line_count).all()
    assert (ranked.turn_count == full.turn_count).all()
    # So the best are the same, kept, and fit the same.
    assert (best_by_estimate(*ranked[:3], headings, reach_m, d, rank) == best).all()
    assert same_bits(fit_screened(ranked, best, table), fit_screened(full, best, table))


@pytest.mark.parametrize("field_id", REAL_FIELDS)
def test_the_screened_cells_are_cover_headings_bit_for_bit(field_id: str) -> None:
    prepared, edge_m = prepared_small(field_id)
    headings, d = np.arange(0.0, 180.0, 7.0), 4.0
    _, reach_m = turn_change_m(SMALL, d)
    screened = screen_cells(prepared, headings, d, edge_m, reach_m=reach_m, rank=3)
    assert np.isnan(screened.covered_m2).any()  # some covers left unmeasured: measured again
    compared = 0
    for a, heading in enumerate(headings.tolist()):
        cells = screened_cells(screened, a)
        if cells is None:
            continue
        expected = cover_heading(prepared, heading, d, edge_m)
        got = cover_screened(*cells, heading, d)
        assert len(got.cells) == len(expected.cells)
        for mine, theirs in zip(got.cells, expected.cells, strict=True):
            assert same_bits(mine.u_ring, theirs.u_ring) and same_bits(mine.v_ring, theirs.v_ring)
            assert mine.lines == theirs.lines
        for name in ("offsets", "u", "v_lo", "v_hi"):
            assert np.array_equal(getattr(got.scan, name), getattr(expected.scan, name))
            assert same_bits(getattr(got.scan, name), getattr(expected.scan, name))
        assert same_bits(got.covered_m2, expected.covered_m2)
        assert got.line_count == expected.line_count
        compared += 1
    assert compared > len(headings) // 2


@pytest.mark.parametrize("field_id", ["germany_2018_2019-42", "germany_2018_2019-75"])
def test_the_kept_cells_losses_are_parity_losses_of_cover_heading_bit_for_bit(
    field_id: str,
) -> None:
    prepared, edge_m = prepared_small(field_id)
    headings, d = np.arange(0.0, 180.0, 3.0), 4.0
    _, reach_m = turn_change_m(SMALL, d)
    table = turn_table(SMALL, d)
    screened = screen_cells(prepared, headings, d, edge_m, reach_m=reach_m, keep=SCREENED_FITS)
    which = np.arange(len(headings))
    fits = fit_screened_cells(screened, which, table)
    assert same_bits(fits.fitted_m2, fit_screened(screened, which, table))
    compared = 0
    for a, losses in enumerate(fits.cell_losses_m2):
        if losses is None:
            assert np.isnan(fits.fitted_m2[a])  # not kept
            continue
        cover = cover_heading(prepared, float(headings[a]), d, edge_m)
        s = cover.scan
        expected = parity_losses_m2(
            [c.chains for c in cover.cells], s.offsets, s.u, s.v_lo, s.v_hi, d, table
        )
        assert same_bits(losses, expected)
        compared += 1
    assert 0 < compared < len(headings)  # some kept, some not: both ways are tested


def test_a_ranked_screen_measures_every_heading_it_is_asked_to_keep() -> None:
    """Asked to keep more than it ranks, the screen ranks as many: none to fit is left out."""
    # An L: covered nearly whole at most headings, so the bound prunes close to the best.
    ell = Polygon([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    prepared, edge_m = [sweep_rings(ell)], 1.35
    headings, d = np.arange(0.0, 180.0, 1.0), 4.0
    _, reach_m = turn_change_m(SMALL, d)
    screened = screen_cells(
        prepared, headings, d, edge_m, reach_m=reach_m, keep=SCREENED_FITS, rank=3
    )
    full = screen_cells(prepared, headings, d, edge_m, reach_m=reach_m)
    best = best_by_estimate(*full[:3], headings, reach_m, d, SCREENED_FITS)
    assert len(best) == SCREENED_FITS
    assert np.isfinite(fit_screened(screened, best, turn_table(SMALL, d))).all()
