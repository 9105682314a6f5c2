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


def _static_csv(path: Path, *, seed: int, n: int = 18_000, rate_hz: float = 5.0) -> None:
    """A receiver standing still near Ketewel for an hour, logged as CSV (m8n model)."""
    import numpy as np

    from navigation.sensors import GpsReceiver
    from navigation.types import GPS_PRESETS, VehicleState
    from planner import local_frame

    frame = local_frame(115.298, -8.6265)
    rx = GpsReceiver(GPS_PRESETS["m8n"], np.random.default_rng(seed))
    fixes = [rx.read(VehicleState(0.0, 0.0, 0.0), i / rate_hz) for i in range(n)]
    lon, lat = frame.to_lonlat_xy([f.x_m for f in fixes], [f.y_m for f in fixes])
    lines = ["time,lat,lon"]
    lines += [
        f"{1767225600 + f.time_s:.3f},{la:.9f},{lo:.9f}"
        for f, lo, la in zip(fixes, lon, lat, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")


def test_gps_from_a_static_log_fits_the_receiver_model(tmp_path: Path) -> None:
    log = tmp_path / "static.csv"
    _static_csv(log, seed=11)
    result = invoke(PAPER, "--gps-from", str(log), "--seed", "1")
    assert result.exit_code == 0, result.stderr
    gps = json.loads(result.stdout)["scenario"]["gps"]
    # The log was made with the m8n preset: 2.5 m CEP, 60 s, 5 Hz.
    assert gps["name"] == "fitted:static.csv"
    assert gps["rate_hz"] == pytest.approx(5.0, rel=1e-3)
    assert gps["cep_m"] == pytest.approx(2.5, rel=0.2)
    assert 30.0 < gps["correlation_time_s"] < 120.0


def test_gps_from_a_log_that_moves_is_refused(tmp_path: Path) -> None:
    moving = tmp_path / "moving.csv"
    lines = ["time,lat,lon"] + [
        f"{1767225600 + i},{-8.6265 + i * 1e-4:.7f},115.298" for i in range(200)
    ]
    moving.write_text("\n".join(lines) + "\n")
    result = invoke(PAPER, "--gps-from", str(moving))
    assert result.exit_code == 2
    assert "error: --gps-from: log: moved" in result.stderr


def test_the_papers_date_uses_wmm2020_and_2031_is_a_clear_error() -> None:
    result = invoke(PAPER, "--date", "2021-02-01")
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["scenario"]["declination_deg"] == pytest.approx(0.92, abs=0.01)
    late = invoke(PAPER, "--date", "2031-01-01")
    assert late.exit_code == 2
    assert "error: date: 2031.00 is outside every World Magnetic Model" in late.stderr
    assert "Traceback" not in late.stderr


def test_monte_carlo_reports_filter_consistency() -> None:
    result = invoke(PAPER, "--runs", "4", "--gps", "rtk")
    assert result.exit_code == 0, result.stderr
    nees = json.loads(result.stdout)["summary"]["nees_consistency"]
    assert nees["runs"] == 4 and nees["low"] < nees["mean"] < nees["high"] and nees["within"]
