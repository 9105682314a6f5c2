"""Corner loops (planner.round_corners): a pivoting vehicle's round tills its corners, keeps
to where the body may go, bends no tighter than the pivot and loses nothing it covered."""

from __future__ import annotations

import numpy as np
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from shapely import LineString, Polygon

from planner.round_corners import corner_loops
from planner.round_shapes import RADIUS_SLACK, regular_region, resample_ring, round_step_m
from tests.planner.plan_checks import turn_curvatures

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
#: The hand tractor's pivot (half its 0.7 m track), as the spiral plans it.
PIVOT_M = 0.35 * RADIUS_SLACK


def band_footprint(points: np.ndarray, width_m: float) -> shapely.Geometry:
    """What a round covers: the closed path buffered by half the width, mitre joins."""
    closed = np.vstack([points, points[:2]])
    return LineString(closed).buffer(width_m / 2.0, cap_style="flat", join_style="mitre")


def round_of(field: Polygon, offset_m: float) -> np.ndarray | None:
    """The spiral's round ``offset_m`` inside ``field``: corners arcs of the pivot (None if
    no single round fits there)."""
    region = shapely.orient_polygons(regular_region(field.buffer(-offset_m), PIVOT_M))
    if not isinstance(region, Polygon) or region.is_empty:
        return None
    return resample_ring(region.exterior, round_step_m(PIVOT_M))


@st.composite
def convex_fields(draw: st.DrawFn) -> Polygon:
    """Convex hulls of 3–9 random points in a 20–80 m square (thin ones left out)."""
    seed = draw(st.integers(0, 2**32 - 1))
    size = draw(st.floats(20.0, 80.0))
    rng = np.random.default_rng(seed)
    hull = shapely.MultiPoint(rng.uniform(0.0, size, (draw(st.integers(3, 9)), 2))).convex_hull
    if not isinstance(hull, Polygon) or hull.buffer(-6.0).area < 0.1 * hull.area:
        # Thin ones as strips: a round's region a finger about 2 r wide turns some 180° at
        # each end (the loops' legs would reach without bound).
        hull = shapely.box(0.0, 0.0, size, draw(st.floats(4.0, 14.0)))
    return shapely.orient_polygons(hull)  # type: ignore[no-any-return]


def test_a_square_round_tills_its_corners() -> None:
    # A 4 m implement on a 20 m square, the round 2 m inside: the inner-wheel pivots leave
    # about 1.2 m² at each corner; the loops leave nothing.
    field = shapely.box(0.0, 0.0, 20.0, 20.0)
    ring = round_of(field, 2.0)
    assert ring is not None
    allowed = field.buffer(-0.425)
    looped = corner_loops(ring, radius_m=PIVOT_M, allowed=allowed, step_m=round_step_m(PIVOT_M))
    band = field.difference(field.buffer(-4.0, join_style="mitre"))
    before = band.difference(band_footprint(ring, 4.0)).area
    after = band.difference(band_footprint(looped, 4.0)).area
    assert 4 * 1.0 < before < 4 * 1.4
    assert after < 1e-3, after
    assert shapely.covers(allowed, LineString(np.vstack([looped, looped[:1]])))


def test_no_loop_where_the_body_would_leave() -> None:
    # The round 0.5 m inside (a 1 m interval): a loop would swing 0.7 m towards the bund.
    field = shapely.box(0.0, 0.0, 20.0, 20.0)
    ring = round_of(field, 0.5)
    assert ring is not None
    looped = corner_loops(
        ring, radius_m=PIVOT_M, allowed=field.buffer(-0.425), step_m=round_step_m(PIVOT_M)
    )
    assert looped is ring


def test_a_strip_whose_round_is_a_finger_is_planned() -> None:
    # 40 m × 5 m at 4 m: the round's region is 1 m wide, its ends turn 180° each (a
    # loop's legs once reached 74,355 km there and the plan ran out of memory).
    from planner.spiral import order_spiral

    for width in (4.75, 5.0, 12.75):
        plan = order_spiral(shapely.box(0.0, 0.0, 40.0, width), interval_m=4.0)
        assert 0.97 < plan.coverage_ratio <= 1.0


@SETTINGS
@given(field=convex_fields(), offset=st.floats(1.0, 4.0))
def test_loops_keep_inside_bend_no_tighter_and_lose_nothing(field: Polygon, offset: float) -> None:
    ring = round_of(field, offset)
    assume(ring is not None and len(ring) >= 6)
    assert ring is not None
    allowed = field.buffer(-0.425)
    step = round_step_m(PIVOT_M)
    looped = corner_loops(ring, radius_m=PIVOT_M, allowed=allowed, step_m=step)
    path = np.vstack([looped, looped[:1]])
    assert shapely.covers(allowed.buffer(1e-9), LineString(path))
    assert (np.hypot(*np.diff(path, axis=0).T) <= step + 1e-9).all()
    assert (turn_curvatures(path) <= 1.0 / PIVOT_M * 1.02 + 0.02).all()
    width = 2.0 * offset
    before = shapely.intersection(field, band_footprint(ring, width)).area
    after = shapely.intersection(field, band_footprint(looped, width)).area
    assert after >= before - 1e-6 * field.area


@SETTINGS
@given(convex_fields(), st.floats(0.01, 3.0), st.floats(0.1, 3.0))
def test_resampled_ring_is_geos_interpolation(field: Polygon, grow_m: float, step_m: float) -> None:
    """``resample_ring`` gives the points GEOS's ``line_interpolate_point`` gives, evenly spaced.

    The reference walks the ring from its start for every point (the resampling once took a
    second on a large field's rounds), so it is kept here, not in the planner.
    """
    ring = field.buffer(grow_m).exterior
    points = resample_ring(ring, step_m)
    n = len(points)
    along = np.arange(n) * (ring.length / n)
    expected = shapely.get_coordinates(shapely.line_interpolate_point(ring, along))
    assert n >= max(3, int(ring.length / step_m))
    assert np.allclose(points, expected, rtol=0.0, atol=1e-9)
