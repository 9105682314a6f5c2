"""The machine in the plan (issue 9): every preset keeps its body inside, drives its turns,
keeps the spacing and plans the same twice; coverage is measured with the implement."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely import Polygon

from planner import PRESETS, parse_field_geojson, plan_coverage
from planner.errors import InvalidParameterError
from planner.projection import field_frame
from planner.turns import turning_radius_m
from tests.conftest import field_from_local
from tests.planner.plan_checks import (
    TOLERANCE_M,
    assert_body_inside,
    assert_figures_add_up,
    assert_inside,
    assert_turns_drivable,
    line_offsets,
    local_segments,
    reference_coverage,
)
from tests.planner.random_fields import fields_with_holes
from tests.planner.test_non_convex import assert_spacing_per_cell
from tests.planner.test_real_fields import real_fields

SETTINGS = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@st.composite
def jobs(draw: st.DrawFn) -> tuple[Polygon, float, str, int]:
    """A random field with holes, convex or not, an interval, a preset and headland passes."""
    local = draw(fields_with_holes(max_vertices=24, max_holes=2))
    field = field_from_local(
        list(local.exterior.coords), [list(h.coords) for h in local.interiors], at=(110.4, -7.8)
    )
    size = math.sqrt(local.area)
    low = max(0.5, size / 40)
    interval = draw(st.floats(low, max(low, min(12.0, size / 6))))
    return field, interval, draw(st.sampled_from(sorted(PRESETS))), draw(st.integers(0, 1))


def plan_or_refused(job: tuple) -> object:
    field, interval, vehicle, passes = job
    try:
        return plan_coverage(field, interval_m=interval, vehicle=vehicle, headland_passes=passes)
    except InvalidParameterError as error:
        # Refused only when there is no room: for the headland passes, or anywhere to turn.
        if error.input_name == "vehicle":
            preset = PRESETS[vehicle]
            radius = turning_radius_m(preset)
            local = field_frame(field).to_local(field)
            assert local.buffer(-(preset.width_m / 2 + 2 * radius + interval)).is_empty, error
        else:
            assert error.input_name == "headland_passes", error
        return None


@SETTINGS
@given(job=jobs())
def test_every_preset_keeps_its_body_inside_and_drives_its_turns(job: tuple) -> None:
    plan = plan_or_refused(job)
    if plan is None:
        return
    assert_inside(plan)  # type: ignore[arg-type]
    assert_body_inside(plan)  # type: ignore[arg-type]
    assert_turns_drivable(plan)  # type: ignore[arg-type]
    assert_spacing_per_cell(plan)  # type: ignore[arg-type]
    assert_figures_add_up(plan)  # type: ignore[arg-type]
    assert plan.vehicle == PRESETS[job[2]]  # type: ignore[attr-defined]


@SETTINGS
@given(job=jobs())
def test_every_preset_plans_the_same_twice_r7(job: tuple) -> None:
    first, again = plan_or_refused(job), plan_or_refused(job)
    if first is None:
        assert again is None
        return
    assert first.waypoints == again.waypoints  # type: ignore[attr-defined]
    assert first.segments == again.segments  # type: ignore[attr-defined]


@pytest.mark.parametrize("interval_m", [1.0, 1.5, 2.0, 2.5, 4.0])
def test_paper_field_hand_tractor_turns_stay_inside(paper_geojson: dict, interval_m: float) -> None:
    """The paper's own intervals: every pivot, buffered by half the tractor, is in the field."""
    spec = parse_field_geojson(paper_geojson)
    plan = plan_coverage(
        spec.field_lonlat,
        interval_m=interval_m,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
        vehicle="hand_tractor",
    )
    assert_body_inside(plan)
    assert_turns_drivable(plan)
    assert plan.stats.line_count >= 3
    turns = [s for s in plan.segments if s.kind == "turn"]
    assert len(turns) == plan.stats.line_count - 1
    assert all(len(t.lonlat) > 2 for t in turns), "turns are driven curves, not straight moves"


@pytest.mark.parametrize("ratio", [0.5, 1.0, 1.5])
def test_coverage_is_measured_with_the_implement_width(ratio: float) -> None:
    field = field_from_local([(0, 0), (83, 0), (91, 47), (-6, 52)])
    plan = plan_coverage(field, interval_m=4.0, implement_width_m=4.0 * ratio)
    assert plan.implement_width_m == 4.0 * ratio
    assert plan.stats.implement_width_m == 4.0 * ratio
    assert plan.stats.overlap_m == pytest.approx(4.0 * ratio - 4.0)
    assert plan.stats.coverage_ratio == pytest.approx(reference_coverage(plan), abs=2e-4)
    if ratio < 1:  # strips left between the passes: about half the field
        assert 0.4 < plan.stats.coverage_ratio < 0.55


def test_a_wider_implement_covers_more_a_narrower_less() -> None:
    field = field_from_local([(0, 0), (60, 0), (60, 30), (30, 30), (30, 60), (0, 60)])
    cover = [
        plan_coverage(field, interval_m=3.0, implement_width_m=w).stats.coverage_ratio
        for w in (2.0, 3.0, 4.0)
    ]
    assert cover[0] < cover[1] < cover[2]


def test_small_tractor_snake_skips_lines_so_turns_need_no_loop() -> None:
    field = field_from_local([(0, 0), (120, 0), (120, 80), (0, 80)])
    snake = plan_coverage(
        field, interval_m=2.0, angle_deg=0.0, vehicle="small_tractor", pattern="snake"
    )
    back_and_forth = plan_coverage(field, interval_m=2.0, angle_deg=0.0, vehicle="small_tractor")
    assert_body_inside(snake)
    assert_turns_drivable(snake)
    # Driven one after the other, lines are three apart (6 m: two turning radii) except
    # where one pass across the field hands over to the next.
    frame = field_frame(snake.field_lonlat)
    lines = [s for s in snake.segments if s.kind == "line"]
    x = np.array([frame.to_local_xy(*s.lonlat[0])[0] for s in lines])
    steps = np.abs(np.diff(x))
    assert np.sum(np.isclose(steps, 6.0, atol=1e-3)) >= len(steps) - 3
    # U-turns of two arcs are shorter than the Ω every back-and-forth turn needs at 2 m.
    assert snake.stats.turn_length_m < back_and_forth.stats.turn_length_m
    offsets, _, _ = line_offsets(snake)
    # R2: the same lines, in another order; the last may sit nearer its neighbour.
    steps = np.diff(offsets)
    assert np.allclose(steps[:-1], 2.0, atol=1e-3)
    assert 0.0 < steps[-1] <= 2.0 + 1e-3


def test_a_field_too_narrow_for_the_turning_radius_is_refused_naming_both() -> None:
    strip = field_from_local([(0, 0), (7, 0), (7, 200), (0, 200)])
    with pytest.raises(InvalidParameterError) as refused:
        plan_coverage(
            strip,
            interval_m=3.0,
            angle_deg=0.0,
            vehicle={"preset": "small_tractor", "min_turn_radius_m": 6.0},
        )
    assert str(refused.value) == "vehicle: a 6 m turning radius does not fit this 7.0 m-wide field"


def test_a_vehicle_wider_than_the_field_is_refused() -> None:
    with pytest.raises(InvalidParameterError, match="^vehicle: a 5 m-wide vehicle"):
        plan_coverage(
            field_from_local([(0, 0), (4, 0), (4, 30), (0, 30)]),
            interval_m=2.0,
            vehicle={"preset": "small_tractor", "width_m": 5.0},
        )


def test_spiral_keeps_a_wide_body_inside_the_field() -> None:
    """The spiral's rounds move inward when half the body is wider than half an interval."""
    field = field_from_local([(0, 0), (40, 0), (40, 30), (0, 30)])
    plan = plan_coverage(field, interval_m=1.0, pattern="spiral", vehicle="small_tractor")
    assert plan.vehicle is not None and plan.vehicle.preset == "small_tractor"
    frame = field_frame(plan.field_lonlat)
    inside = frame.to_local(plan.field_lonlat).buffer(-plan.vehicle.width_m / 2.0 + TOLERANCE_M)
    rounds = local_segments(plan, "round")
    assert rounds
    assert all(inside.covers(r) for r in rounds)


@pytest.mark.slow
def test_small_tractor_plans_every_real_field_with_no_path_outside() -> None:
    """§11: all 223 real fields at 4 m with small_tractor, none fails, 0 m outside."""
    failures = []
    for field_id, field in real_fields():
        try:
            plan = plan_coverage(field, interval_m=4.0, vehicle="small_tractor")
        except InvalidParameterError as error:
            failures.append(f"{field_id}: {error}")
            continue
        assert_body_inside(plan)
        assert_turns_drivable(plan)
    assert failures == []
