import math

import numpy as np
import pytest
from shapely import Polygon

from planner.errors import InvalidFieldError
from planner.projection import WGS84, field_frame, geodesic_area_m2, local_frame, utm_epsg
from tests.conftest import field_from_local


@pytest.mark.parametrize(
    ("lon", "lat", "epsg"),
    [
        (115.298, -8.6265, 32750),  # Bali
        (-0.1, 51.5, 32630),  # London
        (3.5, 60.0, 32632),  # western Norway: zone 32V is widened
        (2.9, 60.0, 32631),
        (15.0, 78.0, 32633),  # Svalbard 33X
        (8.0, 78.0, 32631),  # Svalbard 31X
        (179.9, 10.0, 32660),
        (-180.0, -10.0, 32701),
    ],
)
def test_utm_epsg_follows_the_zone_layout(lon: float, lat: float, epsg: int) -> None:
    assert utm_epsg(lon, lat) == epsg


def test_utm_epsg_refuses_polar_latitudes() -> None:
    with pytest.raises(InvalidFieldError, match="latitude"):
        utm_epsg(10.0, 85.0)


@pytest.mark.parametrize(
    ("lon", "lat"),
    [(115.298, -8.6265), (14.999, 52.4), (-62.9, -35.0), (6.06, 51.51), (29.99, 0.01)],
)
@pytest.mark.parametrize("azimuth_deg", [0.0, 37.0, 90.0, 200.0])
def test_local_frame_is_true_north_and_true_scale(
    lon: float, lat: float, azimuth_deg: float
) -> None:
    frame = local_frame(lon, lat)
    distance_m = 500.0
    lon2, lat2, _ = WGS84.fwd(lon, lat, azimuth_deg, distance_m)
    x, y = frame.to_local_xy(lon2, lat2)
    assert math.hypot(x, y) == pytest.approx(distance_m, rel=2e-5)
    heading = math.degrees(math.atan2(x, y)) % 360.0
    assert abs((heading - azimuth_deg + 180.0) % 360.0 - 180.0) < 1e-3


def test_local_frame_round_trips_to_a_tenth_of_a_millimetre() -> None:
    frame = local_frame(115.298, -8.6265)
    x = np.array([-1500.0, 0.0, 2500.5])
    y = np.array([3000.0, 0.0, -10.25])
    lon, lat = frame.to_lonlat_xy(x, y)
    x2, y2 = frame.to_local_xy(lon, lat)
    assert np.allclose(x2, x, atol=1e-4) and np.allclose(y2, y, atol=1e-4)


@pytest.mark.parametrize("at", [(115.298, -8.6265), (17.9, 52.0), (12.01, 52.0), (-47.0, -15.0)])
def test_projected_area_agrees_with_geodesic_area_within_a_tenth_of_a_percent(
    at: tuple[float, float],
) -> None:
    field = field_from_local([(0, 0), (1500, 100), (1300, 1400), (-200, 1200)], at=at)
    local = field_frame(field).to_local(field)
    assert local.area == pytest.approx(geodesic_area_m2(field), rel=1e-3)


def test_geodesic_area_subtracts_holes() -> None:
    outer = [(0, 0), (100, 0), (100, 100), (0, 100)]
    hole = [(40, 40), (60, 40), (60, 60), (40, 60)]
    with_hole = field_from_local(outer, [hole])
    without = Polygon(with_hole.exterior)
    assert geodesic_area_m2(without) - geodesic_area_m2(with_hole) == pytest.approx(400, rel=1e-3)
