"""``tillpath plan`` on files of many fields and in every import format, and its new outputs."""

from __future__ import annotations

import json
from pathlib import Path

import pyogrio
from pymavlink import mavwp

from planner.io import read_fields
from tests.cli.test_plan_cli import run
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import kmz_bytes, shared_polygon, zipped_utm_shapefile_bytes

RWANDA = FIELDS_DIR / "rwanda_2021.geojson"


def test_feature_3_as_waypoints_loads_in_pymavlink_with_every_waypoint_in_order(
    tmp_path: Path,
) -> None:
    out = tmp_path / "m.waypoints"
    result = run(
        "plan",
        str(RWANDA),
        "--feature",
        "3",
        "--interval",
        "4",
        "--format",
        "waypoints",
        "-o",
        str(out),
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr.startswith("rwanda_2021-3: ")
    plan = json.loads(run("plan", str(RWANDA), "--feature", "3", "--interval", "4").stdout)
    waypoints = sorted(
        (f for f in plan["features"] if f["properties"]["kind"] == "waypoint"),
        key=lambda f: f["properties"]["seq"],
    )
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(out)) == len(waypoints) + 2
    for i, feature in enumerate(waypoints):
        item = loader.wp(i + 2)
        lon, lat = feature["geometry"]["coordinates"]
        assert item.command == 16 and abs(item.x - lat) <= 1e-7 and abs(item.y - lon) <= 1e-7


def test_a_file_of_many_fields_without_feature_lists_them_and_exits_2() -> None:
    result = run("plan", str(RWANDA), "--interval", "4")
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.startswith("error: FIELD: ") and "holds 30 fields" in result.stderr
    assert "--feature ID|NAME|INDEX" in result.stderr
    for i in range(30):
        assert f"rwanda_2021-{i} " in result.stderr
    assert "Traceback" not in result.stderr


def test_unknown_feature_lists_the_choices() -> None:
    result = run("plan", str(RWANDA), "--interval", "4", "--feature", "north field")
    assert result.returncode == 2
    assert "has no field with id or name 'north field'" in result.stderr
    assert "rwanda_2021-29" in result.stderr


def test_binary_file_is_a_clear_error_not_a_traceback(tmp_path: Path) -> None:
    photo = tmp_path / "field.geojson"
    photo.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    result = run("plan", str(photo), "--interval", "4")
    assert result.returncode == 2
    assert result.stderr.startswith(f"error: FIELD: {photo}: is binary data")
    assert "Traceback" not in result.stderr and "UnicodeDecodeError" not in result.stderr


def test_kmz_and_zipped_utm_shapefile_plan_like_the_geojson(tmp_path: Path) -> None:
    polygon = shared_polygon("rwanda-3")
    expected = run(
        "plan", str(RWANDA), "--feature", "rwanda_2021-3", "--interval", "6", "--format", "csv"
    )
    for name, data in [
        ("field.kmz", kmz_bytes(tmp_path, polygon)),
        ("field.zip", zipped_utm_shapefile_bytes(tmp_path, polygon)),
    ]:
        path = tmp_path / name
        path.write_bytes(data)
        result = run("plan", str(path), "--interval", "6", "--format", "csv")
        assert result.returncode == 0, result.stderr
        assert len(result.stdout.splitlines()) == len(expected.stdout.splitlines())


def test_gpkg_output_needs_a_file_and_has_every_layer(tmp_path: Path) -> None:
    refused = run("plan", str(RWANDA), "--feature", "0", "--interval", "4", "--format", "gpkg")
    assert refused.returncode == 2 and "give -o FILE.gpkg" in refused.stderr
    out = tmp_path / "plan.gpkg"
    result = run(
        "plan", str(RWANDA), "--feature", "0", "--interval", "4", "--format", "gpkg", "-o", str(out)
    )
    assert result.returncode == 0, result.stderr
    assert [str(n) for n, _ in pyogrio.list_layers(out)] == [
        "field",
        "lines",
        "headland",
        "turns",
        "transit",
        "path",
        "waypoints",
    ]
    (imported,) = read_fields(out.read_bytes(), filename="plan.gpkg")  # reads back as a field
    assert imported.name == "rwanda_2021-0"


def test_plan_and_kml_outputs(tmp_path: Path) -> None:
    plan = run("plan", str(RWANDA), "--feature", "0", "--interval", "4", "--format", "plan")
    document = json.loads(plan.stdout)
    assert document["fileType"] == "Plan" and document["mission"]["vehicleType"] == 10
    kml = run("plan", str(RWANDA), "--feature", "0", "--interval", "4", "--format", "kml")
    assert kml.returncode == 0 and "<kml" in kml.stdout


def test_simulate_takes_a_kmz_field(tmp_path: Path) -> None:
    path = tmp_path / "sawah.kmz"
    path.write_bytes(kmz_bytes(tmp_path, shared_polygon("paper")))
    result = run("simulate", str(path), "--interval", "4")
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["scenario"]["interval_m"] == 4.0 and report["metrics"]["completed"] is True
