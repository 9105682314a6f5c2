"""Every export parses back, with real readers, to the plan's waypoints."""

from __future__ import annotations

import csv
import datetime as dt
import io
import json

import gpxpy
import pytest
from lxml import etree
from shapely import Polygon

from planner import CoveragePlan, parse_field_geojson, plan_coverage
from planner.export import (
    GpxTrack,
    plan_from_geojson,
    plan_to_csv,
    plan_to_geojson,
    plan_to_gpx,
    plan_to_waypoints_json,
)
from tests.conftest import GPX_XSD, field_from_local


@pytest.fixture(scope="module")
def gpx_schema() -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(GPX_XSD)))


@pytest.fixture
def paper_plan(paper_geojson: dict) -> CoveragePlan:
    spec = parse_field_geojson(paper_geojson)
    return plan_coverage(
        spec.field_lonlat,
        interval_m=4.0,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
    )


@pytest.fixture
def headland_plan() -> CoveragePlan:
    field = field_from_local([(0, 0), (60, 0), (55, 40), (0, 45)])
    return plan_coverage(field, interval_m=3.0, headland_passes=2, start_lonlat=None)


def waypoint_rows(plan: CoveragePlan) -> list[tuple]:
    return [(w.seq, w.lat, w.lon, w.role, w.line) for w in plan.waypoints]


@pytest.mark.parametrize("plan_name", ["paper_plan", "headland_plan"])
def test_gpx_validates_and_reads_back(
    plan_name: str, request: pytest.FixtureRequest, gpx_schema: etree.XMLSchema
) -> None:
    plan = request.getfixturevalue(plan_name)
    text = plan_to_gpx(plan, name="Ketewel <paddy> & co")
    gpx_schema.assertValid(etree.fromstring(text.encode()))
    parsed = gpxpy.parse(text)
    (route,) = parsed.routes
    assert route.name == "Ketewel <paddy> & co"
    assert [p.name for p in route.points] == [f"WP{w.seq:03d}" for w in plan.waypoints]
    assert [(p.latitude, p.longitude, p.type) for p in route.points] == [
        (w.lat, w.lon, w.role) for w in plan.waypoints
    ]
    ends = [w for w in plan.waypoints if w.role in ("start", "finish")]
    assert [(p.name, p.latitude, p.longitude) for p in parsed.waypoints] == [
        (w.role, w.lat, w.lon) for w in ends
    ]


def test_gpx_tracks_carry_times(paper_plan: CoveragePlan, gpx_schema: etree.XMLSchema) -> None:
    t0 = dt.datetime(2022, 3, 1, 8, 0, tzinfo=dt.UTC)
    times = [t0 + dt.timedelta(seconds=s) for s in range(3)]
    track = GpxTrack("tractor", [115.298, 115.2981, 115.2982], [-8.6265, -8.6264, -8.6263], times)
    text = plan_to_gpx(paper_plan, name="run", tracks=[track])
    gpx_schema.assertValid(etree.fromstring(text.encode()))
    (parsed,) = gpxpy.parse(text).tracks
    points = parsed.segments[0].points
    assert [p.time for p in points] == times
    assert [p.longitude for p in points] == [115.298, 115.2981, 115.2982]


@pytest.mark.parametrize("plan_name", ["paper_plan", "headland_plan"])
def test_csv_reads_back(plan_name: str, request: pytest.FixtureRequest) -> None:
    plan = request.getfixturevalue(plan_name)
    rows = list(csv.DictReader(io.StringIO(plan_to_csv(plan))))
    assert list(rows[0]) == ["seq", "lat", "lon", "role", "line"]
    parsed = [
        (
            int(r["seq"]),
            float(r["lat"]),
            float(r["lon"]),
            r["role"],
            int(r["line"]) if r["line"] else None,
        )
        for r in rows
    ]
    assert parsed == waypoint_rows(plan)


@pytest.mark.parametrize("plan_name", ["paper_plan", "headland_plan"])
def test_waypoints_json_reads_back(plan_name: str, request: pytest.FixtureRequest) -> None:
    plan = request.getfixturevalue(plan_name)
    data = json.loads(json.dumps(plan_to_waypoints_json(plan)))
    assert [(w["seq"], w["lat"], w["lon"], w["role"], w["line"]) for w in data["waypoints"]] == (
        waypoint_rows(plan)
    )


@pytest.mark.parametrize("plan_name", ["paper_plan", "headland_plan"])
def test_geojson_round_trips(plan_name: str, request: pytest.FixtureRequest) -> None:
    plan = request.getfixturevalue(plan_name)
    data = json.loads(json.dumps(plan_to_geojson(plan, name="p")))
    kinds = [f["properties"]["kind"] for f in data["features"]]
    assert kinds.count("field") == 1 and kinds.count("path") == 1
    assert kinds.count("line") == plan.stats.line_count
    assert kinds.count("waypoint") == len(plan.waypoints)
    assert data["properties"]["line_count"] == plan.stats.line_count
    assert "planning_ms" not in data["properties"]
    back = plan_from_geojson(data)
    assert back.waypoints == plan.waypoints
    assert back.segments == plan.segments
    assert back.field_lonlat.equals(plan.field_lonlat)
    assert back.interval_m == plan.interval_m


def test_geojson_path_is_the_waypoints_in_order(paper_plan: CoveragePlan) -> None:
    data = plan_to_geojson(paper_plan)
    (path,) = [f for f in data["features"] if f["properties"]["kind"] == "path"]
    assert path["geometry"]["coordinates"] == [[w.lon, w.lat] for w in paper_plan.waypoints]


def test_exports_are_identical_byte_for_byte_for_the_same_request(paper_geojson: dict) -> None:
    spec = parse_field_geojson(paper_geojson)

    def exports() -> tuple[str, ...]:
        plan = plan_coverage(spec.field_lonlat, interval_m=4.0, start_lonlat=spec.start_lonlat)
        return (
            json.dumps(plan_to_geojson(plan)),
            plan_to_gpx(plan, name="x"),
            plan_to_csv(plan),
            json.dumps(plan_to_waypoints_json(plan)),
        )

    assert exports() == exports()


def test_plan_from_geojson_refuses_a_plain_field(paper_geojson: dict) -> None:
    with pytest.raises(ValueError, match="^plan: holds no tillpath plan"):
        plan_from_geojson(paper_geojson)


def test_field_parsing_accepts_the_shapes_people_send(square_field: Polygon) -> None:
    ring = [list(c) for c in square_field.exterior.coords]
    polygon = {"type": "Polygon", "coordinates": [ring]}
    for obj in (
        polygon,
        {"type": "Feature", "properties": {"interval_m": 3}, "geometry": polygon},
        {"type": "MultiPolygon", "coordinates": [[ring]]},
        {
            "type": "FeatureCollection",
            "features": [{"type": "Feature", "properties": {}, "geometry": polygon}],
        },
    ):
        assert parse_field_geojson(obj).field_lonlat.equals(square_field)


@pytest.mark.parametrize(
    ("obj", "message"),
    [
        ([], "must be a GeoJSON object"),
        ({"type": "Point", "coordinates": [1, 2]}, "must be a Polygon, not 'Point'"),
        ({"type": "Polygon", "coordinates": []}, "polygon has no coordinates"),
        ({"type": "Polygon", "coordinates": [[[1, 2], [3, 4]]]}, "at least 3 distinct vertices"),
        (
            {"type": "Polygon", "coordinates": [[[1, 2], ["a", 4], [3, 4], [1, 2]]]},
            "not \\[lon, lat\\]",
        ),
        ({"type": "FeatureCollection", "features": []}, "holds no Polygon"),
        ({"type": "MultiPolygon", "coordinates": [[], []]}, "exactly one polygon"),
    ],
)
def test_field_parsing_errors_name_the_problem(obj: object, message: str) -> None:
    with pytest.raises(ValueError, match=f"^field: .*{message}"):
        parse_field_geojson(obj)
