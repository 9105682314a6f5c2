"""``tillpath plan`` run as a user runs it: a real process, real files."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys
from pathlib import Path

import gpxpy
import pytest

from tests.conftest import PAPER_FIELD

TILLPATH = [sys.executable, "-c", "from app.cli import main; main()"]


def run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*TILLPATH, *args], capture_output=True, text=True, cwd=cwd, timeout=120)


def test_plan_paper_field_as_gpx(tmp_path: Path) -> None:
    out = tmp_path / "plan.gpx"
    # Along the paper's rows (1°): the paper's 4 lines.
    result = run("plan", str(PAPER_FIELD), "--angle", "1", "--format", "gpx", "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""
    assert "4 lines" in result.stderr and "vehicle hand_tractor" in result.stderr
    route = gpxpy.parse(out.read_text()).routes[0]
    # The pivots between the lines are waypoints too (the driven curve, ≤ 0.5 m apart).
    roles = [p.type for p in route.points if p.type != "turn"]
    assert roles == ["start"] + ["line_start", "line_end"] * 4 + ["finish"]
    field = json.loads(PAPER_FIELD.read_text())
    start, finish = (f["geometry"]["coordinates"] for f in field["features"][1:])
    assert [route.points[0].longitude, route.points[0].latitude] == start
    assert [route.points[-1].longitude, route.points[-1].latitude] == finish


@pytest.mark.parametrize("fmt", ["geojson", "csv", "json"])
def test_plan_to_stdout_in_each_format(fmt: str) -> None:
    result = run("plan", str(PAPER_FIELD), "--format", fmt, "--interval", "2", "--headland", "1")
    assert result.returncode == 0, result.stderr
    if fmt == "csv":
        rows = list(csv.DictReader(io.StringIO(result.stdout)))
        assert rows[0]["role"] == "start" and rows[-1]["role"] == "finish"
    else:
        data = json.loads(result.stdout)
        assert data["features" if fmt == "geojson" else "waypoints"]


def test_flags_override_the_file(tmp_path: Path) -> None:
    result = run(
        "plan",
        str(PAPER_FIELD),
        "--format",
        "json",
        "--angle",
        "90",
        "--start",
        "115.2981,-8.6266",
        "--objective",
        "fewest_lines",
    )
    assert result.returncode == 0, result.stderr
    first = json.loads(result.stdout)["waypoints"][0]
    assert (first["lon"], first["lat"], first["role"]) == (115.2981, -8.6266, "start")
    assert "heading 90.0°" in result.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--interval", "0"], "error: interval_m: must be between 0.2 and 50 m, got 0"),
        (["--interval", "abc"], "error: Invalid value for '--interval'"),
        (["--start", "115.3"], "error: --start: expected LON,LAT"),
        (["--start", "116.3,-8.6"], "error: start: "),
        (["--angle", "200"], "error: angle_deg: must be at least 0 and less than 180"),
        (["--format", "shp"], "error: Invalid value for '--format'"),
        (["--headland", "9"], "error: headland_passes: must be from 0 to 5"),
    ],
)
def test_bad_flags_exit_2_with_a_clear_error(args: list[str], message: str) -> None:
    result = run("plan", str(PAPER_FIELD), *args)
    assert result.returncode == 2
    assert result.stderr.startswith(message), result.stderr
    assert result.stdout == ""


def test_bad_files_exit_2(tmp_path: Path) -> None:
    missing = run("plan", str(tmp_path / "nope.geojson"))
    assert missing.returncode == 2 and missing.stderr.startswith("error: FIELD: cannot read")
    broken = tmp_path / "broken.geojson"
    broken.write_text('{"type": "Polygon", ')
    result = run("plan", str(broken))
    assert (
        result.returncode == 2
        and "error: FIELD: " in result.stderr
        and "not valid JSON" in result.stderr
    )
    no_interval = tmp_path / "bare.geojson"
    field = json.loads(PAPER_FIELD.read_text())["features"][0]["geometry"]
    no_interval.write_text(json.dumps(field))
    result = run("plan", str(no_interval))
    assert result.returncode == 2 and result.stderr.startswith("error: interval_m: give --interval")
    point = tmp_path / "point.geojson"
    point.write_text('{"type": "Point", "coordinates": [115, -8]}')
    result = run("plan", str(point), "--interval", "4")
    assert result.returncode == 2 and result.stderr.startswith("error: FIELD: ")
    assert "point.geojson: holds no field boundary" in result.stderr


def test_plan_takes_a_vehicle_preset_implement_width_pattern_and_speed(tmp_path: Path) -> None:
    out = tmp_path / "plan.geojson"
    result = run(
        "plan",
        str(PAPER_FIELD),
        "--interval",
        "4",
        "--vehicle",
        "small_tractor",
        "--implement-width",
        "5",
        "--pattern",
        "snake",
        "--speed",
        "1.2",
        "-o",
        str(out),
    )
    assert result.returncode == 0, result.stderr
    properties = json.loads(out.read_text())["properties"]
    assert properties["vehicle"]["preset"] == "small_tractor"
    assert properties["implement_width_m"] == 5.0
    assert properties["overlap_m"] == 1.0
    assert "vehicle small_tractor" in result.stderr


def test_plan_reads_a_vehicle_file_and_names_a_bad_field(tmp_path: Path) -> None:
    vehicle = tmp_path / "tractor.json"
    vehicle.write_text(json.dumps({"preset": "small_tractor", "min_turn_radius_m": 2.5}))
    out = tmp_path / "plan.geojson"
    result = run("plan", str(PAPER_FIELD), "--vehicle", str(vehicle), "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert json.loads(out.read_text())["properties"]["vehicle"]["min_turn_radius_m"] == 2.5
    vehicle.write_text(json.dumps({"preset": "small_tractor", "wheels": 4}))
    result = run("plan", str(PAPER_FIELD), "--vehicle", str(vehicle))
    assert result.returncode == 2
    assert result.stderr.startswith("error: vehicle.wheels: is not a vehicle field")
    assert "Traceback" not in result.stderr


def test_plan_refuses_an_unknown_preset() -> None:
    result = run("plan", str(PAPER_FIELD), "--vehicle", "tank")
    assert result.returncode == 2
    assert "error: vehicle: unknown preset 'tank'" in result.stderr


def test_plan_spiral_writes_rounds_as_one_path(tmp_path: Path) -> None:
    out = tmp_path / "spiral.geojson"
    result = run(
        "plan",
        str(PAPER_FIELD),
        "--pattern",
        "spiral",
        "--vehicle",
        "small_tractor",
        "--interval",
        "1",  # at 4 m a 3 m radius fits one round in this 16 m-wide field
        "-o",
        str(out),
    )
    assert result.returncode == 0, result.stderr
    document = json.loads(out.read_text())
    assert document["properties"]["vehicle"]["preset"] == "small_tractor"
    features = document["features"]
    kinds = [f["properties"]["kind"] for f in features]
    assert kinds.count("round") >= 2
    driven = ("round", "turn", "line", "transit")
    segments = [f for f in features if f["properties"]["kind"] in driven]
    for before, after in zip(segments[:-1], segments[1:], strict=True):
        assert before["geometry"]["coordinates"][-1] == after["geometry"]["coordinates"][0]


def test_plan_unknown_pattern_fails_with_status_2() -> None:
    result = run("plan", str(PAPER_FIELD), "--pattern", "zigzag")
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
