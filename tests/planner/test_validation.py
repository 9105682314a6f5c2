"""Every bad input gets its own error, naming the input and the problem."""

import math

import numpy as np
import pytest
from shapely import LineString, Point, Polygon

from planner import (
    InvalidFieldError,
    InvalidParameterError,
    PlannerError,
    PlanTooLargeError,
    plan_coverage,
)
from tests.conftest import BALI, field_from_local


def plan(field: object, **kwargs: object):  # type: ignore[no-untyped-def]
    kwargs.setdefault("interval_m", 4.0)
    return plan_coverage(field, **kwargs)  # type: ignore[arg-type]


def test_fewer_than_three_distinct_vertices(square_field: Polygon) -> None:
    lon, lat = BALI
    flat = Polygon([(lon, lat), (lon + 0.001, lat), (lon, lat), (lon + 0.001, lat)])
    with pytest.raises(InvalidFieldError, match="^field: polygon needs at least 3 distinct"):
        plan(flat)


def test_collinear_vertices_have_no_area() -> None:
    lon, lat = BALI
    line = Polygon([(lon, lat), (lon + 0.001, lat), (lon + 0.002, lat)])
    with pytest.raises(InvalidFieldError, match="^field: polygon has no area"):
        plan(line)


def test_symmetric_bow_tie_is_self_intersecting_not_flat() -> None:
    bowtie = Polygon([(115.25, -8.5), (115.375, -8.375), (115.375, -8.5), (115.25, -8.375)])
    assert bowtie.area == 0.0  # its two halves cancel exactly
    with pytest.raises(InvalidFieldError, match="^field: polygon is self-intersecting near"):
        plan(bowtie)


def test_self_intersection_says_where() -> None:
    bowtie = field_from_local([(0, 0), (40, 40), (40, 0), (0, 40)])
    with pytest.raises(InvalidFieldError) as caught:
        plan(bowtie)
    message = str(caught.value)
    assert message.startswith("field: polygon is self-intersecting near (")
    lon, lat = (float(v) for v in message.split("(")[1].rstrip(")").split(","))
    crossing = field_from_local([(20, 20), (20, 21), (21, 20)]).exterior.coords[0]
    assert math.hypot(lon - crossing[0], lat - crossing[1]) < 2e-6  # within 0.2 m


def test_hole_outside_the_boundary() -> None:
    field = field_from_local(
        [(0, 0), (40, 0), (40, 40), (0, 40)], [[(50, 50), (60, 50), (60, 60), (50, 60)]]
    )
    with pytest.raises(InvalidFieldError, match="hole lies outside the field boundary"):
        plan(field)


def test_tiny_area_is_refused() -> None:
    with pytest.raises(InvalidFieldError, match=r"area is .* too small"):
        plan(field_from_local([(0, 0), (0.9, 0), (0.9, 0.9), (0, 0.9)]), interval_m=0.2)


def test_huge_area_is_refused() -> None:
    huge = field_from_local([(0, 0), (5000, 0), (5000, 5000), (0, 5000)])
    with pytest.raises(InvalidFieldError, match="2,000 ha"):
        plan(huge)


def test_a_sliver_hundreds_of_km_long_is_refused_fast() -> None:
    # The paper field with one latitude typed as 4 for -8.6265: 1,816 ha, so under the area
    # limit, but its lines would run 640 km (answered with 1.1 million waypoints in 30 s).
    sliver = Polygon(
        [(115.2979, 4.0), (115.29813989, -8.626492), (115.29790448, -8.626244), (115.2979, 4.0)]
    )
    with pytest.raises(InvalidFieldError, match=r"^field: spans 1,39\d km corner to corner"):
        plan(sliver, interval_m=5.0)


def test_a_long_narrow_field_within_the_span_is_planned() -> None:
    strip = field_from_local([(0, 0), (20_000, 0), (20_000, 30), (0, 30)])  # 20 km, 60 ha
    assert plan(strip, interval_m=5.0).stats.line_count >= 1


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_coordinates(bad: float) -> None:
    lon, lat = BALI
    with np.errstate(invalid="ignore"):
        field = Polygon([(lon, lat), (lon + 0.001, lat), (bad, lat + 0.001)])
    with pytest.raises(InvalidFieldError, match="not a finite number"):
        plan(field)


def test_latitude_out_of_range_reminds_of_lon_lat_order() -> None:
    swapped = Polygon([(-8.6265, 115.298), (-8.6264, 115.298), (-8.6264, 115.299)])
    with pytest.raises(InvalidFieldError, match="longitude first"):
        plan(swapped)


def test_polar_field_is_refused() -> None:
    polar = Polygon([(10.0, 85.0), (10.01, 85.0), (10.01, 85.01)])
    with pytest.raises(InvalidFieldError, match="80°S to 84°N"):
        plan(polar)


@pytest.mark.parametrize("geometry", [Point(BALI), LineString([BALI, (115.3, -8.6)]), "field"])
def test_not_a_polygon(geometry: object) -> None:
    with pytest.raises(InvalidFieldError, match="^field: must be a Polygon"):
        plan(geometry)


@pytest.mark.parametrize("interval", [0, 0.1, 50.5, -4, math.nan, math.inf])
def test_interval_out_of_range(square_field: Polygon, interval: float) -> None:
    with pytest.raises(InvalidParameterError, match="^interval_m: must be"):
        plan(square_field, interval_m=interval)


@pytest.mark.parametrize("interval", ["4", None, True])
def test_interval_must_be_a_number(square_field: Polygon, interval: object) -> None:
    with pytest.raises(InvalidParameterError, match="^interval_m: must be a number"):
        plan(square_field, interval_m=interval)


@pytest.mark.parametrize("name", ["start", "finish"])
def test_point_too_far_from_the_field(square_field: Polygon, name: str) -> None:
    far = (BALI[0] + 0.1, BALI[1])  # about 11 km east
    with pytest.raises(InvalidParameterError, match=rf"^{name}: .* km from the field; it must"):
        plan(square_field, **{f"{name}_lonlat": far})


@pytest.mark.parametrize("name", ["start", "finish"])
@pytest.mark.parametrize("value", [(math.nan, 1.0), (1.0,), "115,-8", (200.0, 0.0)])
def test_malformed_point(square_field: Polygon, name: str, value: object) -> None:
    with pytest.raises(InvalidParameterError, match=rf"^{name}: "):
        plan(square_field, **{f"{name}_lonlat": value})


def test_points_are_checked_in_turn(square_field: Polygon) -> None:
    """The start's form and distance first, then the finish's (both projected in one call)."""
    far, near, malformed = (BALI[0] + 0.1, BALI[1]), BALI, (1.0,)
    with pytest.raises(InvalidParameterError, match=r"^start: .* km from the field"):
        plan(square_field, start_lonlat=far, finish_lonlat=malformed)
    with pytest.raises(InvalidParameterError, match=r"^start: must be a \[lon, lat\] pair"):
        plan(square_field, start_lonlat=malformed, finish_lonlat=far)
    with pytest.raises(InvalidParameterError, match=r"^finish: must be a \[lon, lat\] pair"):
        plan(square_field, start_lonlat=near, finish_lonlat=malformed)
    with pytest.raises(InvalidParameterError, match=r"^finish: .* km from the field"):
        plan(square_field, start_lonlat=near, finish_lonlat=far)
    both = plan(square_field, start_lonlat=near, finish_lonlat=near)
    assert [w.role for w in both.waypoints][:: len(both.waypoints) - 1] == ["start", "finish"]


@pytest.mark.parametrize("angle", [-1, 180, 360, math.nan])
def test_angle_out_of_range(square_field: Polygon, angle: float) -> None:
    with pytest.raises(InvalidParameterError, match="^angle_deg: must be"):
        plan(square_field, angle_deg=angle)


def test_unknown_objective(square_field: Polygon) -> None:
    with pytest.raises(InvalidParameterError, match="^objective: must be one of shortest_path"):
        plan(square_field, objective="fastest")


@pytest.mark.parametrize("passes", [-1, 6, 1.5, "2"])
def test_headland_passes_out_of_range(square_field: Polygon, passes: object) -> None:
    with pytest.raises(InvalidParameterError, match="^headland_passes: "):
        plan(square_field, headland_passes=passes)


def test_too_many_headland_passes_for_a_narrow_field() -> None:
    narrow = field_from_local([(0, 0), (100, 0), (100, 10), (0, 10)])
    with pytest.raises(InvalidParameterError, match="too narrow for 2 headland"):
        plan(narrow, headland_passes=2)


@pytest.mark.parametrize("speed", [0, 0.01, 11, math.nan])
def test_speed_out_of_range(square_field: Polygon, speed: float) -> None:
    with pytest.raises(InvalidParameterError, match="^speed_mps: must be"):
        plan(square_field, speed_mps=speed)


def test_more_than_20000_lines_is_refused_before_planning() -> None:
    # 4.4 km square at 0.2 m needs 22,000 lines in every direction.
    big = field_from_local([(0, 0), (4400, 0), (4400, 4400), (0, 4400)])
    with pytest.raises(PlanTooLargeError, match="^interval_m: at 0.2 m the field needs at least"):
        plan(big, interval_m=0.2)


def test_every_error_is_a_value_error_naming_its_input(square_field: Polygon) -> None:
    with pytest.raises(ValueError) as caught:
        plan(square_field, interval_m=0)
    assert isinstance(caught.value, PlannerError)
    assert caught.value.input_name == "interval_m"


def test_field_with_too_many_vertices_is_refused_before_any_work() -> None:
    import numpy as np

    angle = np.linspace(0, 2 * np.pi, 2_500, endpoint=False)
    circle = field_from_local(list(zip(100 * np.cos(angle), 100 * np.sin(angle), strict=True)))
    with pytest.raises(InvalidFieldError, match="^field: boundary has 2,501 vertices; simplify"):
        plan(circle)


@pytest.mark.parametrize("properties", [[], "x", 3])
def test_feature_properties_must_be_an_object(properties: object) -> None:
    from planner import parse_field_geojson

    feature = {
        "type": "Feature",
        "properties": properties,
        "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0]]]},
    }
    with pytest.raises(InvalidFieldError, match="properties must be a JSON object"):
        parse_field_geojson(feature)
    with pytest.raises(InvalidFieldError, match="properties must be a JSON object"):
        parse_field_geojson({"type": "FeatureCollection", "features": [feature]})
