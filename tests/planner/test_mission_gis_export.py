"""Every new export of the paper field and three real fields, read back by readers we didn't write.

- ``.waypoints`` (QGC WPL 110): pymavlink's ``mavwp.MAVWPLoader``;
- ``.plan``: json, checked against QGroundControl's documented plan-file layout;
- ``kml`` and ``gpkg``: GDAL through pyogrio (layers, feature counts, CRS, geometry);
- ``gpkg`` to a Shapefile: the ``ogr2ogr`` command (gdal-bin).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pyogrio
import pyogrio.raw
import pytest
import shapely
from pymavlink import mavwp
from shapely import Polygon

from planner import CoveragePlan, plan_coverage
from planner.export import plan_to_gpkg, plan_to_kml, plan_to_qgc_plan, plan_to_qgc_wpl
from planner.io import read_fields
from tests.planner.field_files import REAL_FIELDS, shared_feature, shared_polygon

SPEED_MPS = 0.8


@pytest.fixture(scope="module", params=list(REAL_FIELDS))
def plan(request: pytest.FixtureRequest) -> CoveragePlan:
    path, feature_id = REAL_FIELDS[request.param]
    feature = shared_feature(path, feature_id) if feature_id else json.loads(path.read_text())
    (spec,) = read_fields(json.dumps(feature).encode(), filename=path.name)
    return plan_coverage(
        spec.field_lonlat,
        interval_m=4.0,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
        speed_mps=SPEED_MPS,
    )


def test_the_real_fields_include_one_with_holes() -> None:
    assert max(len(shared_polygon(name).interiors) for name in REAL_FIELDS) >= 1


def test_qgc_wpl_loads_in_pymavlink_with_every_waypoint_in_order(
    plan: CoveragePlan, tmp_path: Path
) -> None:
    path = tmp_path / "mission.waypoints"
    path.write_text(plan_to_qgc_wpl(plan, speed_mps=SPEED_MPS))
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(path)) == len(plan.waypoints) + 2
    home = loader.wp(0)
    starts = [w for w in plan.waypoints if w.role == "start"]
    start = starts[0] if starts else plan.waypoints[0]
    assert (home.command, home.x, home.y, home.z) == (16, start.lat, start.lon, 0)
    speed = loader.wp(1)
    assert (speed.command, speed.param1, speed.param2) == (178, 1, SPEED_MPS)
    for i, waypoint in enumerate(plan.waypoints):
        item = loader.wp(i + 2)
        assert item.seq == i + 2
        assert (item.command, item.frame, item.z, item.autocontinue) == (16, 3, 0, 1)
        assert abs(item.x - waypoint.lat) <= 1e-7 and abs(item.y - waypoint.lon) <= 1e-7
    lines = path.read_text().splitlines()
    assert lines[0] == "QGC WPL 110" and all(len(line.split("\t")) == 12 for line in lines[1:])


def _check_documented_plan_layout(document: dict) -> None:
    """QGroundControl's plan file (dev guide, *Plan File Format*): the keys and their types."""
    assert document["fileType"] == "Plan" and document["version"] == 1
    assert isinstance(document["groundStation"], str)
    mission = document["mission"]
    assert mission["version"] == 2
    assert (mission["firmwareType"], mission["vehicleType"]) == (3, 10)
    for key in ("cruiseSpeed", "hoverSpeed", "globalPlanAltitudeMode"):
        assert isinstance(mission[key], (int, float))
    assert len(mission["plannedHomePosition"]) == 3
    assert mission["items"], "a plan must contain at least one mission item"
    for number, item in enumerate(mission["items"], start=1):
        assert item["type"] == "SimpleItem"
        assert item["doJumpId"] == number
        assert isinstance(item["autoContinue"], bool)
        assert len(item["params"]) == 7
        assert isinstance(item["command"], int) and isinstance(item["frame"], int)
    fence = document["geoFence"]
    assert fence["version"] == 2 and fence["circles"] == []
    for polygon in fence["polygons"]:
        assert isinstance(polygon["inclusion"], bool) and polygon["version"] == 1
        assert all(len(vertex) == 2 for vertex in polygon["polygon"])
    assert document["rallyPoints"] == {"points": [], "version": 2}


def test_qgc_plan_follows_the_documented_layout_with_field_and_holes_as_geofences(
    plan: CoveragePlan,
) -> None:
    document = json.loads(json.dumps(plan_to_qgc_plan(plan, speed_mps=SPEED_MPS)))
    _check_documented_plan_layout(document)
    items = document["mission"]["items"]
    assert [i["command"] for i in items] == [178] + [16] * len(plan.waypoints)
    for item, waypoint in zip(items[1:], plan.waypoints, strict=True):
        assert item["params"][4:] == [waypoint.lat, waypoint.lon, 0]
    home = document["mission"]["plannedHomePosition"]
    assert home[:2] == [plan.waypoints[0].lat, plan.waypoints[0].lon]

    fences = document["geoFence"]["polygons"]
    inclusion = [f for f in fences if f["inclusion"]]
    exclusion = [f for f in fences if not f["inclusion"]]
    assert len(inclusion) == 1 and len(exclusion) == len(plan.field_lonlat.interiors)

    def ring(vertices: list[list[float]]) -> Polygon:
        return Polygon([(lon, lat) for lat, lon in vertices])

    assert ring(inclusion[0]["polygon"]).equals(Polygon(plan.field_lonlat.exterior))
    for fence, hole in zip(exclusion, plan.field_lonlat.interiors, strict=True):
        assert ring(fence["polygon"]).equals(Polygon(hole))


def test_kml_reads_back_in_gdal_with_every_kind(plan: CoveragePlan, tmp_path: Path) -> None:
    path = tmp_path / "plan.kml"
    path.write_text(plan_to_kml(plan, name="plan"))
    layers = {str(name): kind for name, kind in pyogrio.list_layers(path)}
    counts = {name: pyogrio.read_info(path, layer=name)["features"] for name in layers}
    lines = sum(1 for s in plan.segments if s.kind == "line")
    assert counts["Field"] == 1 and counts["Tillage lines"] == lines
    assert counts["Waypoints"] == len(plan.waypoints) and counts["Path"] == 1
    assert counts["Turns"] == sum(1 for s in plan.segments if s.kind == "turn")
    info = pyogrio.read_info(path, layer="Field")
    assert info["crs"] == "EPSG:4326"
    _, _, geometry, _ = pyogrio.raw.read(path, layer="Field", force_2d=True)
    assert shapely.from_wkb(geometry[0]).equals_exact(plan.field_lonlat, tolerance=1e-9)
    _, _, points, _ = pyogrio.raw.read(path, layer="Waypoints")
    coords = shapely.get_coordinates(shapely.from_wkb(points))
    expected = np.array([(w.lon, w.lat) for w in plan.waypoints])
    assert np.abs(coords - expected).max() <= 1e-9


def test_gpkg_has_a_layer_per_kind_and_becomes_a_shapefile_with_ogr2ogr(
    plan: CoveragePlan, tmp_path: Path
) -> None:
    path = tmp_path / "plan.gpkg"
    path.write_bytes(plan_to_gpkg(plan, name="plan"))
    layers = dict(pyogrio.list_layers(path))
    assert layers == {
        "field": "Polygon",
        "lines": "LineString",
        "headland": "LineString",
        "turns": "LineString",
        "transit": "LineString",
        "path": "LineString",
        "waypoints": "Point",
    }
    expected = {
        "field": 1,
        "lines": sum(1 for s in plan.segments if s.kind == "line"),
        "turns": sum(1 for s in plan.segments if s.kind == "turn"),
        "headland": sum(1 for s in plan.segments if s.kind == "headland"),
        "transit": sum(1 for s in plan.segments if s.kind == "transit"),
        "path": 1,
        "waypoints": len(plan.waypoints),
    }
    for layer, count in expected.items():
        info = pyogrio.read_info(path, layer=layer)
        assert (info["features"], info["crs"]) == (count, "EPSG:4326"), layer
    meta, _, geometry, columns = pyogrio.raw.read(path, layer="field")
    assert shapely.from_wkb(geometry[0]).equals(plan.field_lonlat)
    figures = dict(zip(meta["fields"], (c[0] for c in columns), strict=True))
    assert figures["line_count"] == plan.stats.line_count
    assert figures["path_length_m"] == pytest.approx(plan.stats.path_length_m)

    ogr2ogr = shutil.which("ogr2ogr")
    assert ogr2ogr, "ogr2ogr (Debian gdal-bin) is needed; .ci/run installs it"
    out = tmp_path / "shp"
    subprocess.run([ogr2ogr, "-f", "ESRI Shapefile", str(out), str(path)], check=True)
    for layer, count in expected.items():
        shp = out / f"{layer}.shp"
        if count == 0:
            continue
        info = pyogrio.read_info(shp)
        assert info["features"] == count and info["crs"] == "EPSG:4326", layer
    _, _, points, columns = pyogrio.raw.read(out / "waypoints.shp")
    assert list(columns[0]) == [w.seq for w in plan.waypoints]
