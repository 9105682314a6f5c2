"""score_track: any track against a plan, with figures known in advance."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from navigation import NavigationError, score_track
from navigation import coverage as coverage_module
from navigation import metrics as metrics_module
from navigation import route as route_module
from navigation.metrics import _polygon_mask
from planner import local_frame

#: The frame the hand-built plans are drawn in (tests/navigation/conftest.py).
HAND_FRAME = local_frame(115.298, -8.6265)


def track_lonlat(plan, x, y):  # type: ignore[no-untyped-def]
    return HAND_FRAME.to_lonlat_xy(np.asarray(x, float), np.asarray(y, float))


def local_waypoints(plan):  # type: ignore[no-untyped-def]
    return HAND_FRAME.to_local_xy([w.lon for w in plan.waypoints], [w.lat for w in plan.waypoints])


def drive(xs, ys, spacing=0.05):  # type: ignore[no-untyped-def]
    """A dense polyline through the given vertices."""
    out_x, out_y = [xs[0]], [ys[0]]
    for x0, y0, x1, y1 in zip(xs[:-1], ys[:-1], xs[1:], ys[1:], strict=True):
        n = max(int(math.hypot(x1 - x0, y1 - y0) / spacing), 1)
        s = np.arange(1, n + 1) / n
        out_x.extend(x0 + s * (x1 - x0))
        out_y.extend(y0 + s * (y1 - y0))
    return np.array(out_x), np.array(out_y)


def test_a_track_on_the_plan_scores_zero_error_and_full_completion(two_line_plan) -> None:  # type: ignore[no-untyped-def]
    wx, wy = local_waypoints(two_line_plan)
    x, y = drive(wx, wy)
    lon, lat = track_lonlat(two_line_plan, x, y)
    t = np.arange(len(x)) * 0.1
    m = score_track(two_line_plan, t, lon, lat)
    assert m.completed
    assert m.time_s == pytest.approx(t[-1])
    assert m.distance_m == pytest.approx(4 + 30 + 4 + 30 + 4, rel=1e-6)
    assert m.cross_track_max_m == pytest.approx(0.0, abs=1e-6)
    assert m.waypoint_error_max_m == pytest.approx(0.0, abs=1e-6)
    assert m.stretches == ()
    # Two 4 m wide passes over an 8 m × 30 m field cover it all.
    assert m.coverage_ratio == pytest.approx(1.0, abs=0.01)
    assert m.fix_count == len(x)
    assert m.filter_rms_m is None and m.gps_rms_m is None


def test_an_offset_track_has_that_cross_track_error_and_loses_that_coverage(two_line_plan) -> None:  # type: ignore[no-untyped-def]
    wx, wy = local_waypoints(two_line_plan)
    # Drive both lines 0.8 m east of the plan.
    x, y = drive(wx + 0.8, wy)
    lon, lat = track_lonlat(two_line_plan, x, y)
    m = score_track(two_line_plan, np.arange(len(x)) * 0.1, lon, lat, threshold_m=0.5)
    assert m.cross_track_max_m == pytest.approx(0.8, abs=1e-3)
    assert m.cross_track_rms_m == pytest.approx(0.8, abs=1e-3)
    assert m.cross_track_p95_m == pytest.approx(0.8, abs=1e-3)
    assert m.waypoint_error_max_m == pytest.approx(0.8, abs=1e-3)
    # The footprint misses a 0.8 m strip along the west edge: 0.8 / 8 of the field.
    assert m.coverage_ratio == pytest.approx(1.0 - 0.8 / 8.0, abs=0.01)
    # One stretch per line, nearly as long as the line takes to drive (60 s): within 0.8 m
    # of each end, the fixes are nearer the turn or transit leg than the line.
    assert [s.line for s in m.stretches] == [0, 1]
    for s in m.stretches:
        assert s.max_error_m == pytest.approx(0.8, abs=1e-3)
        assert (30.0 - 2 * 0.8) / 0.05 * 0.1 - 0.2 <= s.duration_s <= 60.0


def test_a_track_that_stops_halfway_is_not_complete(two_line_plan) -> None:  # type: ignore[no-untyped-def]
    wx, wy = local_waypoints(two_line_plan)
    x, y = drive(wx[:3], wy[:3])
    lon, lat = track_lonlat(two_line_plan, x, y)
    m = score_track(two_line_plan, np.arange(len(x)), lon, lat)
    assert not m.completed
    assert m.waypoint_errors_m[:3] == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    assert m.waypoint_errors_m[3] == pytest.approx(4.0, abs=1e-6)
    assert m.coverage_ratio == pytest.approx(0.5, abs=0.01)


def test_closest_approach_is_measured_to_the_polyline_not_just_its_vertices(straight_plan) -> None:  # type: ignore[no-untyped-def]
    # Two fixes 100 m apart that pass 0.3 m beside both ends of the line.
    lon, lat = track_lonlat(straight_plan, [0.3, 0.3], [-50.0, 150.0])
    m = score_track(straight_plan, [0.0, 60.0], lon, lat)
    assert m.waypoint_errors_m == pytest.approx((0.3, 0.3), abs=1e-6)


def test_fixes_beyond_the_line_ends_are_not_on_the_line(straight_plan) -> None:  # type: ignore[no-untyped-def]
    lon, lat = track_lonlat(straight_plan, [0.5, 0.5, 0.5, 3.0], [-10.0, 50.0, 110.0, 120.0])
    m = score_track(straight_plan, [0, 1, 2, 3], lon, lat)
    assert m.on_line_share == pytest.approx(0.25)
    assert m.cross_track_max_m == pytest.approx(0.5, abs=1e-6)


def test_no_fix_on_a_line_gives_no_cross_track_figures(straight_plan) -> None:  # type: ignore[no-untyped-def]
    lon, lat = track_lonlat(straight_plan, [0.0], [-30.0])
    m = score_track(straight_plan, [0.0], lon, lat)
    assert m.cross_track_rms_m is None and m.cross_track_max_m is None
    assert m.time_s == 0.0 and m.distance_m == 0.0
    assert m.as_dict()["cross_track_rms_m"] is None


def test_a_real_plan_scored_on_a_noisy_track(paper_plan) -> None:  # type: ignore[no-untyped-def]
    # Every vertex of the planned path, jittered by 0.3 m: errors are about that size.
    rng = np.random.default_rng(9)
    wx, wy = local_waypoints(paper_plan)
    x, y = drive(wx, wy, spacing=0.5)
    x = x + rng.normal(0, 0.3, len(x))
    y = y + rng.normal(0, 0.3, len(y))
    lon, lat = track_lonlat(paper_plan, x, y)
    m = score_track(paper_plan, np.arange(len(x)), lon, lat)
    assert m.completed
    assert 0.2 < m.cross_track_rms_m < 0.4  # |N(0, 0.3)| across the line: RMS 0.3
    assert m.coverage_ratio > 0.95


@pytest.mark.parametrize(
    ("time", "lon", "lat", "match"),
    [
        ([], [], [], "track: has no fixes"),
        ([0.0, 1.0], [115.298], [-8.6265, -8.6265], "differ in length"),
        ([1.0, 0.0], [115.298, 115.298], [-8.6265, -8.6265], "backwards"),
        ([0.0, 1.0], [115.298, float("nan")], [-8.6265, -8.6265], "finite"),
    ],
)
def test_bad_tracks_are_refused(straight_plan, time, lon, lat, match) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(NavigationError, match=match):
        score_track(straight_plan, time, lon, lat)


def test_polygon_mask_matches_shapely_on_a_field_with_a_hole() -> None:
    poly = shapely.Polygon(
        [(0, 0), (50, 3), (47, 40), (20, 25), (5, 45)], [[(10, 10), (20, 10), (15, 18)]]
    )
    cell = 0.37
    nx, ny = int(60 / cell), int(50 / cell)
    mask = _polygon_mask(poly, -2.0, -2.0, cell, nx, ny)
    gx, gy = np.meshgrid(-2 + (np.arange(nx) + 0.5) * cell, -2 + (np.arange(ny) + 0.5) * cell)
    assert np.array_equal(mask, shapely.contains_xy(poly, gx, gy))


def _drift_track(two_line_plan):  # type: ignore[no-untyped-def]
    """Line 0 driven north, but from 8 m to 20 m the tractor sits on line 1 (4 m east)."""
    xs = [-2, -2, -2, 2, 2, -2, -2, 2, 2, 2]
    ys = [-4, 0, 8, 10, 18, 20, 30, 30, 0, -4]
    return drive(xs, ys)


def test_drifting_onto_the_neighbour_line_is_measured_to_the_line_being_driven(
    two_line_plan,
) -> None:  # type: ignore[no-untyped-def]
    # Measured to the nearest line the error could never exceed half the interval (2 m): the
    # drift sits exactly on line 1. Measured to line 0, which the tractor was driving, it is
    # the full 4 m, whether the intent is inferred from the track or known (simulator).
    x, y = _drift_track(two_line_plan)
    lon, lat = track_lonlat(two_line_plan, x, y)
    t = np.arange(len(x)) * 0.1
    inferred = score_track(two_line_plan, t, lon, lat)
    assert inferred.cross_track_max_m > two_line_plan.interval_m / 2
    assert inferred.cross_track_max_m == pytest.approx(4.0, abs=1e-3)
    assert [s.line for s in inferred.stretches] == [0]
    # The simulator's own knowledge: waypoint 2 (line 0's end) is steered to until y = 30.
    leg = np.where(np.arange(len(x)) < np.argmax(y >= 30.0), 2, 4)
    leg[: np.argmax(y >= 0.0)] = 1
    known = score_track(two_line_plan, t, lon, lat, leg=leg)
    assert known.cross_track_max_m == pytest.approx(4.0, abs=1e-3)


def test_turns_are_scored_apart_from_lines(two_line_plan) -> None:  # type: ignore[no-untyped-def]
    wx, wy = local_waypoints(two_line_plan)
    # The turn at the far end bulges 1.5 m beyond the plan's straight turn.
    xs = [wx[0], wx[1], wx[2], wx[2], wx[3], wx[3], wx[4], wx[5]]
    ys = [wy[0], wy[1], wy[2], wy[2] + 1.5, wy[3] + 1.5, wy[3], wy[4], wy[5]]
    x, y = drive(xs, ys)
    lon, lat = track_lonlat(two_line_plan, x, y)
    m = score_track(two_line_plan, np.arange(len(x)) * 0.1, lon, lat)
    assert m.cross_track_max_m == pytest.approx(0.0, abs=1e-6)
    assert m.turn_cross_track_max_m == pytest.approx(1.5, abs=1e-3)


def test_a_live_track_has_no_error_for_waypoints_not_reached(two_line_plan) -> None:  # type: ignore[no-untyped-def]
    wx, wy = local_waypoints(two_line_plan)
    # Six fixes along the start leg and the first metres of line 0.
    x = np.full(6, wx[0])
    y = np.linspace(wy[0], wy[0] + 10.0, 6)
    lon, lat = track_lonlat(two_line_plan, x, y)
    m = score_track(two_line_plan, np.arange(6.0), lon, lat, live=True)
    assert m.waypoint_errors_m[0] == pytest.approx(0.0, abs=1e-6)
    assert m.waypoint_errors_m[2:] == (None, None, None, None)
    assert m.waypoints_reached == 2
    assert m.waypoint_error_max_m == pytest.approx(0.0, abs=1e-6)
    assert 0.0 < m.plan_progress < 0.5
    # What the driven part of the plan would till, the track tilled.
    assert m.coverage_of_driven_ratio == pytest.approx(1.0, abs=0.05)
    assert m.coverage_ratio < 0.3
    # Scored as a finished upload instead, the far waypoints count as misses.
    done = score_track(two_line_plan, np.arange(6.0), lon, lat)
    assert done.waypoint_error_max_m > 20.0


def test_coverage_uses_the_implement_width(two_line_plan) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    wx, wy = local_waypoints(two_line_plan)
    x, y = drive(wx, wy)
    lon, lat = track_lonlat(two_line_plan, x, y)
    # A 1 m implement on lines 4 m apart tills a quarter of the field (the plan object of
    # branch i9a carries implement_width_m; a stand-in with the attribute does too).
    narrow = type(
        "NarrowPlan",
        (),
        {k: getattr(two_line_plan, k) for k in ("field_lonlat", "waypoints", "segments", "stats")},
    )()
    narrow.interval_m = 4.0
    narrow.implement_width_m = 1.0
    m = score_track(narrow, np.arange(len(x)) * 0.1, lon, lat)  # type: ignore[arg-type]
    assert m.implement_width_m == 1.0
    assert m.coverage_ratio == pytest.approx(0.25, abs=0.02)
    full = score_track(dataclasses.replace(two_line_plan), np.arange(len(x)) * 0.1, lon, lat)
    assert full.coverage_ratio == pytest.approx(1.0, abs=0.01)


@settings(max_examples=15, deadline=None)
@given(offset=st.floats(min_value=0.0, max_value=3.6), side=st.sampled_from([-1.0, 1.0]))
def test_a_track_offset_by_up_to_nearly_an_interval_is_measured_by_its_offset(
    two_line_plan, offset: float, side: float
) -> None:  # type: ignore[no-untyped-def]
    # Both lines driven ``offset`` to one side (up to 0.9 of the 4 m interval, so past the
    # neighbour's half): the error is the offset, not its distance to the nearest line.
    wx, wy = local_waypoints(two_line_plan)
    x, y = drive(wx + side * offset, wy, spacing=0.2)
    lon, lat = track_lonlat(two_line_plan, x, y)
    m = score_track(two_line_plan, np.arange(len(x)) * 0.1, lon, lat)
    assert m.cross_track_max_m == pytest.approx(offset, abs=1e-3)


@settings(max_examples=30, deadline=None)
@given(
    steps=st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=1, max_size=60),
    chunk=st.integers(min_value=1, max_value=8),
)
def test_distance_along_in_blocks_is_the_running_sum_of_the_steps(steps, chunk) -> None:  # type: ignore[no-untyped-def]
    xy = np.cumsum(np.array(steps, dtype=float), axis=0)
    x, y = xy[:, 0], xy[:, 1]
    expected = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(route_module, "CHUNK_FIXES", chunk)
        got = route_module.distance_along(x, y)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-9)


def test_a_track_scored_in_small_blocks_scores_as_in_one(paper_plan) -> None:  # type: ignore[no-untyped-def]
    """The blocks bounding a day's log's memory change no figure (blocks of 7 vs one)."""
    rng = np.random.default_rng(3)
    wps = paper_plan.waypoints
    lon = np.repeat([w.lon for w in wps], 40) + rng.normal(0, 5e-6, 40 * len(wps))
    lat = np.repeat([w.lat for w in wps], 40) + rng.normal(0, 5e-6, 40 * len(wps))
    t = np.arange(len(lon)) * 0.1
    whole = score_track(paper_plan, t, lon, lat, live=True)
    with pytest.MonkeyPatch.context() as patch:
        for module in (route_module, metrics_module):
            patch.setattr(module, "CHUNK_FIXES", 7)
        patch.setattr(coverage_module, "CHUNK_SAMPLES", 5)
        blocks = score_track(paper_plan, t, lon, lat, live=True)
    # The same figures; sums over blocks may differ from one pass in the last bit.
    for name in (f.name for f in dataclasses.fields(whole)):
        value, got = getattr(whole, name), getattr(blocks, name)
        if isinstance(value, float):
            assert got == pytest.approx(value, rel=1e-12, abs=1e-12), name
        else:
            assert got == value, name
    assert whole.fix_count == len(lon) > 7 and whole.coverage_ratio > 0
