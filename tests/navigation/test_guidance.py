"""Guidance: haversine and bearing against pyproj's geodesic, wrapping, the clutch laws."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pyproj import Geod

from navigation.guidance import (
    bearing_deg,
    clutch_for,
    haversine_m,
    heading_error_deg,
    pure_pursuit_command,
    pursuit_law,
    segment_axes,
    segment_progress,
    waypoint_command,
    waypoint_law,
)
from navigation.types import LEFT, RIGHT, STRAIGHT

GEOD = Geod(ellps="WGS84")


def random_pairs(rng: np.random.Generator, n: int, max_deg: float):  # type: ignore[no-untyped-def]
    lon1 = rng.uniform(-180, 180, n)
    lat1 = rng.uniform(-70, 70, n)
    lon2 = lon1 + rng.uniform(-max_deg, max_deg, n)
    lat2 = np.clip(lat1 + rng.uniform(-max_deg, max_deg, n), -80, 80)
    return lon1, lat1, lon2, lat2


def test_haversine_agrees_with_the_ellipsoid_within_the_spheres_error() -> None:
    # A sphere differs from WGS84 by at most ~0.56 % in distance.
    rng = np.random.default_rng(1)
    lon1, lat1, lon2, lat2 = random_pairs(rng, 300, 5.0)
    _, _, geod = GEOD.inv(lon1, lat1, lon2, lat2)
    ours = np.array([haversine_m(*p) for p in zip(lon1, lat1, lon2, lat2, strict=True)])
    assert np.all(np.abs(ours / geod - 1.0) < 0.006)


def test_haversine_over_field_distances_is_within_the_spheres_error() -> None:
    # Near the equator the meridian's radius is 0.56 % shorter than the mean radius.
    rng = np.random.default_rng(2)
    lon1 = 115.298 + rng.uniform(-0.001, 0.001, 100)
    lat1 = -8.6265 + rng.uniform(-0.001, 0.001, 100)
    az = rng.uniform(0, 360, 100)
    dist = rng.uniform(1, 200, 100)
    lon2, lat2, _ = GEOD.fwd(lon1, lat1, az, dist)
    ours = np.array([haversine_m(*p) for p in zip(lon1, lat1, lon2, lat2, strict=True)])
    assert np.all(np.abs(ours - dist) < dist * 0.006)


def test_bearing_agrees_with_the_geodesic_azimuth() -> None:
    rng = np.random.default_rng(3)
    lon1, lat1, lon2, lat2 = random_pairs(rng, 300, 0.05)  # field-sized to ~5 km
    az, _, _ = GEOD.inv(lon1, lat1, lon2, lat2)
    ours = np.array([bearing_deg(*p) for p in zip(lon1, lat1, lon2, lat2, strict=True)])
    diff = (ours - az + 180.0) % 360.0 - 180.0
    assert np.all(np.abs(diff) < 0.2)
    assert np.all((ours >= 0.0) & (ours < 360.0))


@pytest.mark.parametrize(
    ("target", "heading", "error"),
    [
        (10.0, 350.0, 20.0),
        (350.0, 10.0, -20.0),
        (179.0, -179.0, -2.0),
        (-179.0, 179.0, 2.0),
        (0.0, 180.0, -180.0),
        (360.0, 0.0, 0.0),
        (90.0, 45.0, 45.0),
        (720.5, 0.0, 0.5),
    ],
)
def test_heading_error_is_wrapped_to_plus_minus_180(
    target: float, heading: float, error: float
) -> None:
    assert heading_error_deg(target, heading) == pytest.approx(error)


def test_heading_error_never_leaves_the_half_open_interval() -> None:
    rng = np.random.default_rng(4)
    for t, h in rng.uniform(-1000, 1000, (500, 2)):
        e = heading_error_deg(t, h)
        assert -180.0 <= e < 180.0
        assert math.isclose(math.cos(math.radians(e)), math.cos(math.radians(t - h)), abs_tol=1e-9)


def test_clutch_tolerance_band() -> None:
    assert clutch_for(5.0, tolerance_deg=5.0) == STRAIGHT
    assert clutch_for(-5.0, tolerance_deg=5.0) == STRAIGHT
    assert clutch_for(5.01, tolerance_deg=5.0) == RIGHT
    assert clutch_for(-5.01, tolerance_deg=5.0) == LEFT


def test_waypoint_command_turns_toward_the_waypoint() -> None:
    lon, lat = 115.298, -8.6265
    east_lon, east_lat, _ = GEOD.fwd(lon, lat, 90.0, 20.0)
    cmd = waypoint_command(lon, lat, 0.0, east_lon, east_lat, tolerance_deg=5.0)
    assert cmd.clutch == RIGHT
    assert cmd.heading_error_deg == pytest.approx(90.0, abs=0.1)
    assert cmd.distance_m == pytest.approx(20.0, rel=0.005)
    cmd = waypoint_command(lon, lat, 92.0, east_lon, east_lat, tolerance_deg=5.0)
    assert cmd.clutch == STRAIGHT


def test_pure_pursuit_pulls_back_onto_the_line_from_either_side() -> None:
    kwargs = {"lookahead_m": 2.0, "tolerance_deg": 3.0}
    left_of_line = pure_pursuit_command(-1.0, 5.0, 0.0, 0.0, 0.0, 0.0, 20.0, **kwargs)
    right_of_line = pure_pursuit_command(1.0, 5.0, 0.0, 0.0, 0.0, 0.0, 20.0, **kwargs)
    on_line = pure_pursuit_command(0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 20.0, **kwargs)
    assert (left_of_line.clutch, right_of_line.clutch, on_line.clutch) == (RIGHT, LEFT, STRAIGHT)
    assert left_of_line.heading_error_deg == pytest.approx(-right_of_line.heading_error_deg)
    assert on_line.distance_m == pytest.approx(15.0)


def test_segment_progress_signs() -> None:
    along, cross, length = segment_progress(3.0, 1.0, 0.0, 0.0, 10.0, 0.0)  # segment due east
    assert (along, cross, length) == pytest.approx((3.0, -1.0, 10.0))  # north of it = left


def test_the_loops_waypoint_law_is_haversine_and_bearing_bit_for_bit() -> None:
    rng = np.random.default_rng(5)
    lon1, lat1, lon2, lat2 = random_pairs(rng, 500, 0.01)
    heading = rng.uniform(0.0, 360.0, 500)
    for p in zip(lon1, lat1, lon2, lat2, heading, strict=True):
        a, b, c, d, h = (float(v) for v in p)
        error = heading_error_deg(bearing_deg(a, b, c, d), h)
        expected = (clutch_for(error, tolerance_deg=8.0), error, haversine_m(a, b, c, d))
        assert waypoint_law(a, b, h, c, d, tolerance_deg=8.0) == expected


def test_the_loops_pursuit_law_is_pure_pursuit_given_the_progress() -> None:
    rng = np.random.default_rng(6)
    for _ in range(300):
        x, y, ax, ay, bx, by = (float(v) for v in rng.uniform(-50.0, 50.0, 6))
        h = float(rng.uniform(0.0, 2.0 * math.pi))
        along, _, length = segment_progress(x, y, ax, ay, bx, by)
        ux, uy, axes_length = segment_axes(ax, ay, bx, by)
        # The loop's along-track distance from the leg's axes: segment_progress's, exactly.
        assert (axes_length, (x - ax) * ux + (y - ay) * uy) == (length, along)
        cmd = pure_pursuit_command(x, y, h, ax, ay, bx, by, lookahead_m=2.5, tolerance_deg=3.0)
        law = pursuit_law(
            x, y, h, ax, ay, bx, by, along, length, lookahead_m=2.5, tolerance_deg=3.0
        )
        assert law == (cmd.clutch, cmd.heading_error_deg, cmd.distance_m)
    assert segment_axes(1.0, 2.0, 1.0, 2.0) == (0.0, 0.0, 0.0)
