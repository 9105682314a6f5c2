"""app.track_formats: gpsbabel unicsv, RTKLIB .pos, u-blox UBX (pyubx2), KML tracks; NMEA quality.

The files come from the tools and libraries that write them where we have them: gpsbabel
converts our GPX, pyubx2 writes UBX frames, simplekml (our export) and a Google Earth style
LineString give KML. RTKLIB .pos lines are laid out as RTKPOST writes them (no observation data
here to run RTKLIB on).
"""

from __future__ import annotations

import datetime as dt
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from pyubx2 import GET, UBXMessage
from sqlalchemy import func, select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app.models import Run
from app.track_fixes import TrackFormatError, datetime_to_us
from app.track_formats import gps_to_utc
from app.tracks import parse_track
from planner.export.gpx import GpxTrack, plan_to_gpx
from planner.export.kml import tracks_to_kml
from tests.app.conftest import wait_for_job
from tests.app.track_files import RUN_START, nmea_lines, simulated_run
from tests.planner.test_io_safety import BILLION_LAUGHS

STEP = 5  # every 5th epoch of the 10 Hz run: 2 Hz, plenty for these checks


def true_track() -> tuple[list[dt.datetime], np.ndarray, np.ndarray]:
    run = simulated_run()
    times = [RUN_START + dt.timedelta(seconds=round(float(t), 3)) for t in run.time_s[::STEP]]
    return times, run.lon[::STEP], run.lat[::STEP]


def test_gpsbabel_unicsv_of_our_gpx_reads_back(tmp_path: Path) -> None:
    times, lon, lat = true_track()
    gpx = tmp_path / "run.gpx"
    gpx.write_text(plan_to_gpx(None, name="run", tracks=[GpxTrack("run", lon, lat, times)]))
    gpsbabel = shutil.which("gpsbabel")
    assert gpsbabel, "gpsbabel (Debian) is needed; .ci/run installs it"
    out = tmp_path / "run.csv"
    subprocess.run(
        [gpsbabel, "-t", "-i", "gpx", "-f", str(gpx), "-o", "unicsv", "-F", str(out)], check=True
    )
    assert out.read_text().splitlines()[0].split(",")[-2:] == ["Date", "Time"]
    track = parse_track(out.read_bytes())
    assert track.format == "unicsv" and len(track.fixes) == len(times)
    for fix, when, x, y in zip(track.fixes, times, lon, lat, strict=True):
        assert fix.t == datetime_to_us(when)
        # unicsv writes six decimals: 0.11 m
        assert abs(fix.lon - x) <= 5e-7 and abs(fix.lat - y) <= 5e-7


def test_unicsv_keeps_fix_hdop_and_satellites_and_drops_no_fix() -> None:
    data = (
        b"No,Latitude,Longitude,Altitude,Speed,Course,FIX,HDOP,Satellites,Date,Time\n"
        b'1,-8.626500,115.298000,10.0,0.50,90.0,"dgps",0.80,9,2026/11/22,03:14:15.200\n'
        b'2,-8.626400,115.298100,,,,"3d",1.10,8,2026/11/22,03:14:16\n'
        b'3,-8.626300,115.298200,,,,"none",,0,2026/11/22,03:14:17\n'
    )
    track = parse_track(data)
    assert [(f.quality, f.hdop, f.satellites) for f in track.fixes] == [
        ("dgps", 0.8, 9),
        ("single", 1.1, 8),
    ]
    assert track.fixes[0].speed_mps == 0.5 and track.fixes[0].heading_deg == 90.0
    assert track.report["no_fix"] == 1


POS_HEADER = (
    "% program   : RTKPOST ver.2.4.3\n"
    "% inp file  : rover.obs\n"
    "% pos mode  : kinematic\n"
    "% (lat/lon/height=WGS84/ellipsoidal,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp,"
    "ns=# of satellites)\n"
    "%  {time}                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   "
    "sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio\n"
)


def pos_file(times: list[dt.datetime], lon: Any, lat: Any, qualities: list[int]) -> bytes:
    lines = [POS_HEADER.format(time="GPST")]
    for when, x, y, q in zip(times, lon, lat, qualities, strict=True):
        gpst = when + dt.timedelta(seconds=18)  # GPS time runs 18 s ahead of UTC since 2017
        stamp = gpst.strftime("%Y/%m/%d %H:%M:%S.") + f"{gpst.microsecond // 1000:03d}"
        lines.append(
            f"{stamp}  {y:14.9f} {x:14.9f}    35.2000   {q}  12   0.0030   0.0030   0.0080"
            "   0.0000   0.0000   0.0000   1.00  999.9\n"
        )
    return "".join(lines).encode()


def test_rtklib_pos_in_gpst_reads_back_in_utc_with_its_quality() -> None:
    times, lon, lat = true_track()
    qualities = [(1, 2, 5, 4)[i % 4] for i in range(len(times))]
    track = parse_track(pos_file(times, lon, lat, qualities))
    assert track.format == "pos" and len(track.fixes) == len(times)
    names = {1: "rtk_fixed", 2: "rtk_float", 4: "dgps", 5: "single"}
    for fix, when, x, y, q in zip(track.fixes, times, lon, lat, qualities, strict=True):
        assert fix.t == datetime_to_us(when)
        assert abs(fix.lon - x) <= 1e-9 and abs(fix.lat - y) <= 1e-9
        assert fix.quality == names[q] and fix.satellites == 12


def test_gps_leap_seconds_follow_the_date() -> None:
    assert gps_to_utc(dt.datetime(2016, 6, 1, 0, 0, 17)).time() == dt.time(0, 0, 0)
    assert gps_to_utc(dt.datetime(2026, 6, 1, 0, 0, 18)).time() == dt.time(0, 0, 0)


def test_rtklib_pos_in_ecef_is_refused_clearly() -> None:
    data = POS_HEADER.replace(
        "latitude(deg) longitude(deg)  height(m)", "x-ecef(m) y-ecef(m) z-ecef(m)"
    )
    data = (
        data.format(time="GPST") + "2026/11/22 03:14:33.200  -2000000.0 5000000.0 -900000.0 1 9\n"
    )
    with pytest.raises(TrackFormatError, match="ECEF"):
        parse_track(data.encode())


def ubx_log(times: list[dt.datetime], lon: Any, lat: Any, *, nmea_every: int = 0) -> bytes:
    """NAV-PVT and NAV-DOP per epoch as a u-blox receiver sends them, written by pyubx2."""
    chunks: list[bytes] = [b"\x00\xff garbage before sync "]
    nmea = nmea_lines(times, lon, lat)
    for i, (when, x, y) in enumerate(zip(times, lon, lat, strict=True)):
        itow = 1000 * i
        chunks.append(
            UBXMessage(
                "NAV",
                "NAV-PVT",
                GET,
                iTOW=itow,
                year=when.year,
                month=when.month,
                day=when.day,
                hour=when.hour,
                min=when.minute,
                second=when.second,
                nano=when.microsecond * 1000,
                validDate=1,
                validTime=1,
                fullyResolved=1,
                fixType=3,
                gnssFixOk=1,
                carrSoln=2 if i % 2 == 0 else 1,
                numSV=14,
                lon=float(x),
                lat=float(y),
                gSpeed=560,
                headMot=45.0,
            ).serialize()
        )
        chunks.append(UBXMessage("NAV", "NAV-DOP", GET, iTOW=itow, hDOP=0.7, pDOP=1.3).serialize())
        if nmea_every and i % nmea_every == 0:
            chunks.append((nmea[1 + i] + "\r\n").encode())
    return b"".join(chunks)


def test_ubx_nav_pvt_with_nmea_mixed_in_reads_every_epoch_with_rtk_quality() -> None:
    times, lon, lat = true_track()
    track = parse_track(ubx_log(times, lon, lat, nmea_every=3))
    assert track.format == "ubx" and len(track.fixes) == len(times)
    assert track.report["nmea_sentences_ignored"] > 0
    for i, (fix, when, x, y) in enumerate(zip(track.fixes, times, lon, lat, strict=True)):
        assert fix.t == datetime_to_us(when)
        assert abs(fix.lon - x) <= 1e-7 and abs(fix.lat - y) <= 1e-7  # UBX: 1e-7° units
        assert fix.quality == ("rtk_fixed" if i % 2 == 0 else "rtk_float")
        assert (fix.hdop, fix.satellites, fix.speed_mps) == (0.7, 14, 0.56)


def test_nmea_log_with_ubx_frames_but_no_nav_pvt_reads_as_nmea_with_gga_quality() -> None:
    times, lon, lat = true_track()
    lines = nmea_lines(times, lon, lat, quality=[4] * len(times))
    monitor = UBXMessage("NAV", "NAV-DOP", GET, iTOW=0, hDOP=0.7).serialize()
    data = monitor + ("\r\n".join(lines) + "\r\n").encode()
    track = parse_track(data)
    assert track.format == "nmea" and len(track.fixes) == len(times)
    assert {(f.quality, f.hdop, f.satellites) for f in track.fixes} == {("rtk_fixed", 0.86, 9)}


def test_ubx_without_nav_pvt_says_what_to_enable() -> None:
    data = UBXMessage("NAV", "NAV-DOP", GET, iTOW=0, hDOP=0.7).serialize() * 3
    with pytest.raises(TrackFormatError, match="enable UBX-NAV-PVT"):
        parse_track(data)


def test_nmea_log_keeps_gga_quality_hdop_and_satellites() -> None:
    times, lon, lat = true_track()
    quality = [(4, 5, 1, 2)[i % 4] for i in range(len(times))]
    track = parse_track(("\r\n".join(nmea_lines(times, lon, lat, quality=quality))).encode())
    names = {4: "rtk_fixed", 5: "rtk_float", 1: "single", 2: "dgps"}
    assert [f.quality for f in track.fixes] == [names[q] for q in quality]
    assert {(f.hdop, f.satellites) for f in track.fixes} == {(0.86, 9)}


def test_kml_gx_track_of_our_export_reads_back() -> None:
    times, lon, lat = true_track()
    kml = tracks_to_kml(name="run", tracks=[GpxTrack("run", lon, lat, times)])
    track = parse_track(kml.encode())
    assert track.format == "kml" and track.report["kind"] == "gx:Track"
    assert [f.t for f in track.fixes] == [datetime_to_us(t) for t in times]
    assert np.abs(np.array([f.lon for f in track.fixes]) - lon).max() <= 1e-12


def test_kml_linestring_with_a_timespan_is_timed_along_it() -> None:
    times, lon, lat = true_track()
    coords = " ".join(f"{x},{y},0" for x, y in zip(lon, lat, strict=True))
    kml = (
        '<?xml version="1.0" encoding="UTF-8"?>'
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Document><Placemark><name>Tractor</name>'
        "<TimeSpan><begin>2026-11-21T23:58:30Z</begin><end>2026-11-22T00:00:30Z</end></TimeSpan>"
        f"<LineString><tessellate>1</tessellate><coordinates>{coords}</coordinates></LineString>"
        "</Placemark></Document></kml>"
    )
    track = parse_track(kml.encode())
    assert track.report["times_interpolated"] is True
    assert track.fixes[0].t == datetime_to_us(RUN_START)
    assert track.fixes[-1].t == datetime_to_us(RUN_START + dt.timedelta(minutes=2))
    assert all(a.t < b.t for a, b in zip(track.fixes, track.fixes[1:], strict=False))


def test_kml_without_times_or_with_entities_is_refused() -> None:
    untimed = (
        b'<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark><LineString>'
        b"<coordinates>115.298,-8.6265 115.2981,-8.6264</coordinates>"
        b"</LineString></Placemark></kml>"
    )
    with pytest.raises(TrackFormatError, match="no times"):
        parse_track(untimed)
    with pytest.raises(TrackFormatError, match="DTD"):
        parse_track(BILLION_LAUGHS)


def test_uploaded_ubx_run_exports_as_kml_that_reads_back(
    client: TestClient, session: Session, paper_body: dict[str, Any]
) -> None:
    plan = client.post("/api/plans", json=paper_body).json()
    times, lon, lat = true_track()
    response = client.post(
        f"/api/plans/{plan['id']}/runs", files={"file": ("LOG.UBX", ubx_log(times, lon, lat))}
    )
    assert response.status_code == 201, response.text
    run = response.json()
    assert run["source"] == "ubx" and run["fix_count"] == len(times)
    kml = client.get(f"/api/runs/{run['id']}/export/kml")
    assert kml.status_code == 200
    assert kml.headers["content-type"].startswith("application/vnd.google-earth.kml+xml")
    again = parse_track(kml.content)
    assert len(again.fixes) == len(times)
    assert [f.t for f in again.fixes] == [datetime_to_us(t) for t in times]


def test_simulation_exports_as_kml_with_its_three_tracks(
    jobs_client: TestClient, paper_body: dict[str, Any]
) -> None:
    import pyogrio

    client = jobs_client  # simulations are background jobs (issue 14)
    plan = client.post("/api/plans", json=paper_body).json()
    started = client.post(f"/api/plans/{plan['id']}/simulations", json={"seed": 1})
    job = wait_for_job(client, started.headers["location"])
    simulation = client.get(job["result_url"]).json()
    kml = client.get(f"/api/simulations/{simulation['id']}/export/kml")
    assert kml.status_code == 200
    layers = {str(name) for name, _ in pyogrio.list_layers(kml.content)}
    assert {"Field", "Tillage lines", "Waypoints", "Tracks"} <= layers
    assert pyogrio.read_info(kml.content, layer="Tracks")["features"] == 3


def test_malformed_ubx_stores_nothing(
    client: TestClient, session: Session, paper_body: dict[str, Any]
) -> None:
    plan = client.post("/api/plans", json=paper_body).json()
    before = session.scalar(select(func.count()).select_from(Run))
    response = client.post(
        f"/api/plans/{plan['id']}/runs", files={"file": ("x.ubx", b"\xb5\x62\x01\x07\x5c\x00")}
    )
    assert response.status_code == 422 and "NAV-PVT" in response.json()["detail"]
    session.expire_all()
    assert session.scalar(select(func.count()).select_from(Run)) == before
