"""``tillpath simulate``: metrics on stdout, Monte Carlo, plot, GPX, clear errors."""

from __future__ import annotations

import json
from pathlib import Path

import gpxpy
import pytest
from typer.testing import CliRunner

from app.cli import cli
from planner import parse_field_geojson, plan_coverage
from planner.export.geojson import plan_to_geojson

PAPER = str(Path(__file__).resolve().parents[1] / "data" / "paper_ketewel.geojson")


def invoke(*args: str):  # type: ignore[no-untyped-def]
    return CliRunner().invoke(cli, ["simulate", *args])


def test_simulate_a_field_prints_metrics_as_json() -> None:
    result = invoke(PAPER, "--seed", "3")
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["scenario"]["gps"] == "m8n" and out["scenario"]["guidance"] == "waypoint"
    assert out["scenario"]["interval_m"] == 4.0
    assert out["seed"] == 3
    m = out["metrics"]
    assert m["completed"] is True
    assert m["time_s"] > 150
    assert len(m["waypoint_errors_m"]) == out["scenario"]["waypoints"]
    assert invoke(PAPER, "--seed", "3").stdout == result.stdout  # reproducible


def test_simulate_a_plan_file_gives_the_same_run_as_its_field(tmp_path: Path) -> None:
    # The plan the CLI makes of the field (heading searched), written to a file.
    spec = parse_field_geojson(json.loads(Path(PAPER).read_text(encoding="utf-8")))
    searched = plan_coverage(
        spec.field_lonlat,
        interval_m=spec.interval_m,
        start_lonlat=spec.start_lonlat,
        finish_lonlat=spec.finish_lonlat,
    )
    plan_file = tmp_path / "plan.geojson"
    plan_file.write_text(json.dumps(plan_to_geojson(searched, name="paper")))
    from_plan = invoke(str(plan_file), "--guidance", "line", "--gps", "rtk")
    from_field = invoke(PAPER, "--guidance", "line", "--gps", "rtk")
    assert from_plan.exit_code == 0, from_plan.stderr
    a = json.loads(from_plan.stdout)["metrics"]
    b = json.loads(from_field.stdout)["metrics"]
    assert a["time_s"] == pytest.approx(b["time_s"], abs=1.0)
    assert a["cross_track_rms_m"] == pytest.approx(b["cross_track_rms_m"], abs=0.02)


def test_monte_carlo_reports_median_and_spread(tmp_path: Path) -> None:
    plot = tmp_path / "sim.png"
    gpx = tmp_path / "sim.gpx"
    result = invoke(PAPER, "--runs", "4", "--seed", "10", "--plot", str(plot), "--gpx", str(gpx))
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["runs"] == 4 and out["seeds"] == [10, 13]
    s = out["summary"]
    assert s["completed_share"] == 1.0
    rms = s["cross_track_rms_m"]
    assert rms["min"] <= rms["p5"] <= rms["median"] <= rms["p95"] <= rms["max"]
    assert rms["n"] == 4
    assert 10 <= out["shown_seed"] <= 13
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    doc = gpxpy.parse(gpx.read_text())
    assert [t.name for t in doc.tracks] == ["true", "estimated", "gps"]
    assert len(doc.routes) == 1 and len(doc.routes[0].points) == out["scenario"]["waypoints"]
    assert all(p.time is not None for p in doc.tracks[0].segments[0].points)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--gps", "zed"], "error: --gps: unknown preset 'zed'; choose one of m8n, rtk"),
        (["--guidance", "fly"], "error: --guidance: unknown mode 'fly'"),
        (["--runs", "0"], "error: --runs: must be between 1 and"),
        (["--seed", "-1"], "error: --seed: must be ≥ 0"),
        (["--plot", "out.jpg"], "error: --plot: the plot is a PNG"),
    ],
)
def test_bad_options_fail_with_status_2(args: list[str], message: str) -> None:
    result = invoke(PAPER, *args)
    assert result.exit_code == 2
    assert result.stderr.startswith(message)
    assert result.stdout == ""


def test_bad_files_fail_with_status_2(tmp_path: Path) -> None:
    missing = invoke(str(tmp_path / "nope.geojson"))
    assert missing.exit_code == 2 and missing.stderr.startswith("error: FIELD|PLAN: cannot read")
    no_interval = tmp_path / "field.geojson"
    doc = json.loads(Path(PAPER).read_text())
    del doc["features"][0]["properties"]["interval_m"]
    no_interval.write_text(json.dumps(doc))
    result = invoke(str(no_interval))
    assert result.exit_code == 2 and result.stderr.startswith("error: interval_m: give --interval")
    assert invoke(str(no_interval), "--interval", "4").exit_code == 0
    broken = tmp_path / "broken.geojson"
    broken.write_text('{"type": "Point", "coordinates": [1, 2]}')
    result = invoke(str(broken))
    assert result.exit_code == 2 and result.stderr.startswith("error: field: ")


def test_a_long_single_run_completes_with_its_progress_bar(tmp_path: Path) -> None:
    import shapely

    from planner import local_frame

    field = local_frame(115.298, -8.6265).to_lonlat(
        shapely.Polygon([(0, 0), (40, 0), (40, 60), (0, 60)])
    )
    doc = {
        "type": "Feature",
        "properties": {"interval_m": 2.0, "name": "long"},
        "geometry": shapely.geometry.mapping(field),
    }
    path = tmp_path / "long.geojson"
    path.write_text(json.dumps(doc))
    result = invoke(str(path), "--gps", "rtk", "--guidance", "line")
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["scenario"]["waypoints"] >= 40
    assert out["metrics"]["completed"] is True
