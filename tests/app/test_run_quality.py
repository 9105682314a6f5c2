"""What a run's receiver was worth, live figures, and missed ground with its follow-up plan
(product.md §8), on every database of the ``engine`` fixture."""

from __future__ import annotations

import datetime as dt
import json
from typing import Any

import numpy as np
import shapely
from sqlalchemy import select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app.models import Fix
from planner import field_frame
from tests.app.test_runs_api import create_plan, upload
from tests.app.track_files import RUN_START, csv_file, nmea_lines, paper_plan, simulated_run


def _nmea_log(quality: list[int]) -> bytes:
    run = simulated_run()
    n = len(quality)
    times = [RUN_START + dt.timedelta(seconds=round(float(t), 2)) for t in run.time_s[:n]]
    lines = nmea_lines(times, run.lon[:n], run.lat[:n], quality=quality)
    return ("\r\n".join(lines) + "\r\n").encode()


def test_an_nmea_log_keeps_each_fixs_quality_and_reports_the_shares(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    # 600 epochs: 360 RTK fixed (GGA 4), 180 RTK float (5), 60 single (1).
    quality = [4] * 360 + [5] * 180 + [1] * 60
    response = upload(client, plan["id"], "rtk.nmea", _nmea_log(quality))
    assert response.status_code == 201, response.text
    receiver = response.json()["receiver"]
    assert receiver["shares"]["rtk_fixed"] == 0.6
    assert receiver["shares"]["rtk_float"] == 0.3
    assert receiver["shares"]["single"] == 0.1
    assert receiver["shares"]["unknown"] == 0.0
    assert receiver["hdop_median"] == 0.86 and receiver["satellites_median"] == 9
    # 90 % RTK (fixed or float): decimetres, not metres.
    assert receiver["accuracy"] == "decimetre" and receiver["metre_level"] is False
    stored = session.scalars(select(Fix.quality).order_by(Fix.t)).all()
    assert stored[:2] == ["rtk_fixed", "rtk_fixed"] and stored[-1] == "single"
    assert session.scalar(select(Fix.hdop).limit(1)) == 0.86


def test_an_m8n_grade_log_says_its_figures_are_metre_level_estimates(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    run = upload(client, plan["id"], "m8n.nmea", _nmea_log([1] * 400)).json()
    receiver = run["receiver"]
    assert receiver["shares"]["single"] == 1.0
    assert receiver["accuracy"] == "metre" and receiver["metre_level"] is True
    assert "metre-level accuracy" in receiver["note"]
    # A CSV says nothing about its fixes: unknown, and the note says to treat it as metres.
    csv_run = upload(client, plan["id"], "log.csv", csv_file(simulated_run())).json()
    assert csv_run["receiver"]["accuracy"] == "unknown"
    assert csv_run["receiver"]["metre_level"] is True
    assert "metre-level estimates" in csv_run["receiver"]["note"]


def test_a_live_run_with_six_fixes_has_no_error_for_waypoints_not_reached(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    run = client.post(f"/api/plans/{plan['id']}/runs", json={}).json()
    sim = simulated_run()
    fixes = [
        {
            "t": (RUN_START + dt.timedelta(seconds=float(sim.time_s[i]))).isoformat(),
            "lat": float(sim.lat[i]),
            "lon": float(sim.lon[i]),
            "quality": "single",
            "hdop": 1.1,
            "satellites": 8,
        }
        for i in range(0, 60, 10)
    ]
    assert client.post(f"/api/runs/{run['id']}/fixes", json=fixes).status_code == 200
    answer = client.get(f"/api/runs/{run['id']}").json()
    metrics = answer["metrics"]
    errors = metrics["waypoint_errors_m"]
    assert answer["fix_count"] == 6
    assert errors[0] is not None
    assert all(e is None for e in errors[2:])
    # Not the 200 m "error" of the far end of the field.
    assert metrics["waypoint_error_max_m"] < 5.0
    assert metrics["waypoints_reached"] <= 2
    assert answer["receiver"]["shares"]["single"] == 1.0


def _skipping_track(skip_line: int) -> tuple[list[float], list[float]]:
    """The paper plan driven exactly, but line ``skip_line`` left out.

    From the end of the line before it, the tractor runs along the field's end to the line
    after it and drives that one the other way (then on to the finish), as a driver who
    skipped a line would.
    """
    plan = paper_plan()
    frame = field_frame(plan.field_lonlat)
    # Line ends only: the driven turns' points next to the skipped line would trace it.
    wps = [w for w in plan.waypoints if w.role != "turn"]
    keep = [w for w in wps if w.line != skip_line]
    if 0 <= skip_line:
        after = [w for w in keep if w.line == skip_line + 1]
        at = keep.index(after[0])
        keep[at : at + 2] = [after[1], after[0]]
    x, y = frame.to_local_xy([w.lon for w in keep], [w.lat for w in keep])
    line = shapely.LineString(np.column_stack([x, y]))
    pts = [line.interpolate(d) for d in np.arange(0.0, line.length, 0.1)]
    lon, lat = frame.to_lonlat_xy([p.x for p in pts], [p.y for p in pts])
    return list(lon), list(lat)


def test_a_run_that_skipped_a_line_gets_its_gap_and_a_follow_up_plan_over_it(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    lon, lat = _skipping_track(skip_line=2)
    lines = ["time,lat,lon"] + [
        f"{1767225600 + 0.2 * i:.1f},{la:.9f},{lo:.9f}"
        for i, (lo, la) in enumerate(zip(lon, lat, strict=True))
    ]
    run = upload(client, plan["id"], "skipped.csv", ("\n".join(lines) + "\n").encode()).json()
    missed = run["missed"]
    assert missed["features"], "the skipped line left no gap"
    gap = shapely.from_geojson(json.dumps(missed["features"][0]["geometry"]))
    # About one 4 m strip of the 4 lines' 302 m² field.
    assert 0.15 < missed["properties"]["field_share"] < 0.35
    assert all(f["properties"]["kind"] == "missed" for f in missed["features"])

    response = client.post(f"/api/runs/{run['id']}/follow-up")
    assert response.status_code == 201, response.text
    follow_up = response.json()
    assert response.headers["location"] == f"/api/plans/{follow_up['id']}"
    assert follow_up["request"]["follow_up"]["run_id"] == run["id"]
    # It is a plan like any other: read back, exported.
    assert client.get(f"/api/plans/{follow_up['id']}").status_code == 200
    assert client.get(f"/api/plans/{follow_up['id']}/export/gpx").status_code == 200
    # Its tillage lines' footprint covers the gap.
    frame = field_frame(gap)
    gap_local = frame.to_local(gap)
    footprints = []
    for feature in follow_up["geojson"]["features"]:
        if feature["properties"].get("kind") == "line":
            line = frame.to_local(shapely.from_geojson(json.dumps(feature["geometry"])))
            footprints.append(line.buffer(2.0, cap_style="flat"))
    covered = shapely.union_all(footprints).intersection(gap_local).area / gap_local.area
    assert covered > 0.9
    assert follow_up["stats"]["line_count"] >= 1


def test_a_run_that_covered_everything_has_no_follow_up(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    lon, lat = _skipping_track(skip_line=-1)
    lines = ["time,lat,lon"] + [
        f"{1767225600 + 0.2 * i:.1f},{la:.9f},{lo:.9f}"
        for i, (lo, la) in enumerate(zip(lon, lat, strict=True))
    ]
    run = upload(client, plan["id"], "full.csv", ("\n".join(lines) + "\n").encode()).json()
    # The planned path's footprint leaves only slivers along the slanted ends: no gap.
    assert run["missed"]["features"] == []
    response = client.post(f"/api/runs/{run['id']}/follow-up")
    assert response.status_code == 409
    assert "no missed ground" in response.json()["detail"]


def test_gpx_points_keep_their_fix_hdop_and_satellites():
    from app.tracks import parse_track

    gpx = b"""<?xml version="1.0" encoding="UTF-8"?>
<gpx version="1.1" creator="logger" xmlns="http://www.topografix.com/GPX/1/1">
 <trk><trkseg>
  <trkpt lat="-8.62652" lon="115.29797"><time>2026-11-22T03:14:15Z</time>
   <fix>dgps</fix><sat>11</sat><hdop>0.9</hdop></trkpt>
  <trkpt lat="-8.62651" lon="115.29798"><time>2026-11-22T03:14:16Z</time>
   <fix>3d</fix><sat>7</sat><hdop>1.6</hdop></trkpt>
  <trkpt lat="-8.62650" lon="115.29799"><time>2026-11-22T03:14:17Z</time></trkpt>
 </trkseg></trk>
</gpx>"""
    fixes = parse_track(gpx).fixes
    assert [(f.quality, f.hdop, f.satellites) for f in fixes] == [
        ("dgps", 0.9, 11),
        ("single", 1.6, 7),
        (None, None, None),
    ]
