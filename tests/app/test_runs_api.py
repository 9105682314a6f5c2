"""The runs API (product.md §5, §8) on every database of the ``engine`` fixture: uploads of
each format scored like the simulation that made them, bad files refused with nothing stored,
live runs fed with retried batches, listing and GPX export."""

from __future__ import annotations

import datetime as dt
import math
import random
from typing import Any

import gpxpy
import pytest
from lxml import etree
from sqlalchemy import func, select
from sqlalchemy.orm import Session
from starlette.testclient import TestClient

from app.models import Fix, Run
from app.schemas import MAX_FIXES_PER_BATCH
from navigation import score_track
from tests.app.conftest import GPX_XSD, TEST_MAX_UPLOAD_BYTES
from tests.app.test_track_gpx import BILLION_LAUGHS
from tests.app.track_files import (
    RUN_START,
    csv_file,
    gpx_file,
    nmea_file,
    simulated_run,
)

WRITERS = {"gpx": gpx_file, "csv": csv_file, "nmea": nmea_file}


def create_plan(client: TestClient, body: dict[str, Any]) -> dict[str, Any]:
    response = client.post("/api/plans", json=body)
    assert response.status_code == 201, response.text
    plan: dict[str, Any] = response.json()
    return plan


def upload(client: TestClient, plan_id: int, filename: str, data: bytes, **form: str) -> Any:
    return client.post(f"/api/plans/{plan_id}/runs", files={"file": (filename, data)}, data=form)


def stored(session: Session) -> tuple[int, int]:
    session.expire_all()
    runs = session.scalar(select(func.count()).select_from(Run)) or 0
    fixes = session.scalar(select(func.count()).select_from(Fix)) or 0
    return runs, fixes


@pytest.mark.parametrize("fmt", ["gpx", "csv", "nmea"])
def test_uploaded_simulated_run_scores_as_the_simulation(
    client: TestClient, session: Session, paper_body: dict[str, Any], fmt: str
):
    plan = create_plan(client, paper_body)
    run_sim = simulated_run()
    response = upload(client, plan["id"], f"tractor.{fmt}", WRITERS[fmt](run_sim))
    assert response.status_code == 201, response.text
    run = response.json()
    assert response.headers["location"] == f"/api/runs/{run['id']}"
    assert run["source"] == fmt
    assert run["name"] == f"tractor.{fmt}"
    assert run["fix_count"] == len(run_sim.time_s)
    assert run["import_report"]["format"] == fmt
    assert run["started_at"].startswith("2026-11-21T23:58:30")

    got, simulated = run["metrics"], run_sim.log.metrics
    # An upload carries no intent: the line being driven is inferred from the track in route
    # order. Scored the same way in process, the figures agree to the format's precision; and
    # the inferred intent agrees with the simulator's known one to a few centimetres (M8N,
    # seeds 0–19: median 1.3 cm, at most 8.6 cm; this seed 2.8 cm).
    want = score_track(run_sim.plan, run_sim.time_s, run_sim.lon, run_sim.lat, completed=True)
    assert math.isclose(want.cross_track_rms_m, simulated.cross_track_rms_m, abs_tol=0.05)
    assert math.isclose(want.cross_track_max_m, simulated.cross_track_max_m, abs_tol=0.05)
    assert got["completed"] is True
    assert got["fix_count"] == want.fix_count
    assert math.isclose(got["time_s"], want.time_s, abs_tol=0.02)
    # NMEA keeps positions to 1e-5 minutes (1.9 cm): at 10 Hz (5.6 cm steps) that jitter
    # lengthens the polyline by about 1 %.
    distance_tol = 0.02 if fmt == "nmea" else 1e-6
    # And any one position is off by at most half that step in each axis [m].
    tol = 0.015 if fmt == "nmea" else 1e-4
    assert math.isclose(got["distance_m"], want.distance_m, rel_tol=distance_tol)
    for name in ("cross_track_max_m", "cross_track_rms_m", "cross_track_p95_m"):
        assert math.isclose(got[name], getattr(want, name), abs_tol=tol), name
    assert math.isclose(got["waypoint_error_max_m"], want.waypoint_error_max_m, abs_tol=tol)
    assert math.isclose(got["waypoint_error_mean_m"], want.waypoint_error_mean_m, abs_tol=tol)
    assert math.isclose(got["coverage_ratio"], want.coverage_ratio, abs_tol=0.002)
    # Where the tractor pivots at a line's end, that jitter also moves fixes between the line
    # and the turn in the inferred intent: stretches shorter than a second come and go, and a
    # stretch's start moves by up to 2 s (the paper plan, seeds 0–19, scored in process with
    # and without NMEA's rounding; seed 5: a 0.6 s stretch, a start moved 1.1 s).
    shortest_s = 1.0 if fmt == "nmea" else 0.0
    got_stretches = [a for a in got["stretches"] if a["duration_s"] >= shortest_s]
    want_stretches = [b for b in want.stretches if b.duration_s >= shortest_s]
    assert len(got_stretches) == len(want_stretches)
    for a, b in zip(got_stretches, want_stretches, strict=True):
        assert a["line"] == b.line
        assert math.isclose(a["start_s"], b.start_s, abs_tol=2.0 if fmt == "nmea" else 0.01)
        assert math.isclose(a["max_error_m"], b.max_error_m, abs_tol=tol)
    # The stretches come with their piece of track, for the map.
    features = run["stretches"]["features"]
    assert len(features) == len(got["stretches"])
    assert all(len(f["geometry"]["coordinates"]) >= 2 for f in features)
    assert stored(session) == (1, len(run_sim.time_s))


@pytest.mark.parametrize("fmt", ["gpx", "csv", "nmea"])
def test_read_run_returns_what_the_upload_answered(
    client: TestClient, paper_body: dict[str, Any], fmt: str
):
    # The upload is scored from the columns it just stored, a read from the database: the same.
    plan = create_plan(client, paper_body)
    created = upload(client, plan["id"], f"a.{fmt}", WRITERS[fmt](simulated_run())).json()
    again = client.get(f"/api/runs/{created['id']}")
    assert again.status_code == 200
    assert again.json() == created


def test_stretches_are_drawn_no_finer_than_the_track(
    client: TestClient, paper_body: dict[str, Any], monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.setattr("app.runs.MAX_TRACK_POINTS", 50)
    plan = create_plan(client, paper_body)
    run = upload(client, plan["id"], "a.csv", csv_file(simulated_run())).json()
    view = client.get(f"/api/runs/{run['id']}", params={"threshold_m": 0.01}).json()
    stride = math.ceil(view["fix_count"] / 50)
    features = view["stretches"]["features"]
    assert len(features) == len(view["metrics"]["stretches"]) > 0
    drawn = sum(len(f["geometry"]["coordinates"]) for f in features)
    flagged = sum(s["duration_s"] * 10 + 1 for s in view["metrics"]["stretches"])  # 10 Hz
    assert drawn <= flagged / stride + 2 * len(features)
    assert all(len(f["geometry"]["coordinates"]) >= 2 for f in features)


def test_threshold_changes_the_reported_stretches(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    run = upload(client, plan["id"], "a.gpx", gpx_file(simulated_run())).json()
    strict = client.get(f"/api/runs/{run['id']}", params={"threshold_m": 0.3}).json()
    loose = client.get(f"/api/runs/{run['id']}", params={"threshold_m": 50}).json()
    assert strict["metrics"]["threshold_m"] == 0.3

    # A lower threshold flags more of the track (stretches may merge, so count seconds).
    def seconds(metrics: dict[str, Any]) -> float:
        return sum(s["duration_s"] for s in metrics["stretches"])

    assert seconds(strict["metrics"]) > seconds(run["metrics"])
    assert loose["metrics"]["stretches"] == [] and loose["stretches"]["features"] == []
    bad = client.get(f"/api/runs/{run['id']}", params={"threshold_m": 0})
    assert bad.status_code == 422
    assert bad.json()["detail"] == "threshold_m: must be greater than 0.0"


def test_upload_form_name_wins_over_the_file_name(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    run = upload(client, plan["id"], "LOG0001.TXT", nmea_file(simulated_run()), name="Pak Made")
    assert run.status_code == 201, run.text
    assert run.json()["name"] == "Pak Made"


def _truncated(data: bytes) -> bytes:
    return data[: len(data) // 3]


MALFORMED = {
    "gpx truncated": (lambda: _truncated(gpx_file(simulated_run())), "file: is not well-formed"),
    "gpx xml bomb": (lambda: BILLION_LAUGHS, "file: GPX with a DTD"),
    "csv truncated": (
        lambda: csv_file(simulated_run())[:1000].rsplit(b",", 1)[0],
        "file: line ",
    ),
    "csv wrong columns": (lambda: b"when,x,y\n2026-11-22T00:00:00Z,1,2\n", "file: is not a track"),
    "csv missing lon": (
        lambda: b"time,lat,heading\n1795318455,-8.6,3\n",
        "file: the CSV header must name time, lat and lon",
    ),
    "nmea bad checksums": (
        lambda: b"\n".join(
            line[:-2] + b"00" for line in nmea_file(simulated_run()).splitlines()[:40]
        ),
        "file: has no usable fix (NMEA; bad sentences: 40",
    ),
    "nmea truncated": (lambda: nmea_file(simulated_run())[:30], "file: has no usable fix"),
    "unknown format": (lambda: b"\x89PNG\r\n\x1a\n" + bytes(range(256)), "file: is not a track"),
    "empty file": (lambda: b"", "file: is not a track"),
}


@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_file_is_refused_with_422_and_nothing_is_stored(
    client: TestClient, session: Session, paper_body: dict[str, Any], case: str
):
    plan = create_plan(client, paper_body)
    make, message = MALFORMED[case]
    response = upload(client, plan["id"], "bad", make())
    assert response.status_code == 422, response.text
    assert response.json()["detail"].startswith(message), response.json()
    assert stored(session) == (0, 0)


def test_upload_over_the_limit_returns_413_and_stores_nothing(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    data = nmea_file(simulated_run())
    data = data * (TEST_MAX_UPLOAD_BYTES // len(data) + 1)
    response = upload(client, plan["id"], "huge.nmea", data)
    assert response.status_code == 413
    assert response.json()["detail"] == (
        f"file: the upload is larger than the limit of {TEST_MAX_UPLOAD_BYTES} bytes"
    )
    assert stored(session) == (0, 0)


def test_upload_to_unknown_plan_returns_404(client: TestClient):
    response = upload(client, 987654, "a.csv", csv_file(simulated_run()))
    assert response.status_code == 404
    assert response.json() == {"detail": "plan 987654 not found"}


@pytest.mark.parametrize("how", ["no body", "empty json", "form without file"])
def test_create_live_run_without_a_file(client: TestClient, paper_body: dict[str, Any], how: str):
    plan = create_plan(client, paper_body)
    url = f"/api/plans/{plan['id']}/runs"
    if how == "no body":
        response = client.post(url)
    elif how == "empty json":
        response = client.post(url, json={})
    else:
        response = client.post(url, data={"name": "live one"})
    assert response.status_code == 201, response.text
    run = response.json()
    assert run["source"] == "live"
    assert run["fix_count"] == 0
    assert run["metrics"] is None and run["track"] is None and run["last_fix"] is None
    assert run["name"] == ("live one" if how == "form without file" else None)


def fixes_of_simulation(step: int = 10) -> list[dict[str, Any]]:
    """The simulated true track at 1 Hz as the logger would post it (ISO times)."""
    sim = simulated_run()
    out = []
    for t, lon, lat in zip(sim.time_s[::step], sim.lon[::step], sim.lat[::step], strict=True):
        when = RUN_START + dt.timedelta(seconds=round(float(t), 3))
        out.append({"t": when.isoformat(), "lat": float(lat), "lon": float(lon)})
    return out


def test_live_run_keeps_each_timestamp_once_in_time_order(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    run = client.post(f"/api/plans/{plan['id']}/runs").json()
    fixes = fixes_of_simulation()
    rng = random.Random(4)
    shuffled = fixes[:]
    rng.shuffle(shuffled)
    batches = [shuffled[i : i + 37] for i in range(0, len(shuffled), 37)]
    batches += batches[::3]  # retried
    batches.append(shuffled[10:90])  # overlapping
    rng.shuffle(batches)
    total_stored = 0
    for batch in batches:
        response = client.post(f"/api/runs/{run['id']}/fixes", json=batch)
        assert response.status_code == 200, response.text
        body = response.json()
        assert body["received"] == len(batch)
        total_stored += body["stored"]
    assert total_stored == len(fixes)
    assert body["fix_count"] == len(fixes)

    view = client.get(f"/api/runs/{run['id']}").json()
    assert view["fix_count"] == len(fixes)
    times = view["track"]["properties"]["time_s"]
    assert times == sorted(times) and len(set(times)) == len(times)
    last = fixes[-1]
    assert view["last_fix"]["lat"] == last["lat"] and view["last_fix"]["lon"] == last["lon"]
    assert view["metrics"]["completed"] is True
    assert stored(session) == (1, len(fixes))


def test_same_time_in_another_notation_is_the_same_fix(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    run = client.post(f"/api/plans/{plan['id']}/runs").json()
    url = f"/api/runs/{run['id']}/fixes"
    first = client.post(url, json=[{"t": "2026-11-22T03:34:15.2Z", "lat": -8.6265, "lon": 115.298}])
    again = client.post(url, json=[{"t": 1795318455.2, "lat": -8.6265, "lon": 115.298}])
    other = client.post(url, json=[{"t": "2026-11-22T11:34:15.3+08:00", "lat": -8.6, "lon": 115.3}])
    assert [r.json()["stored"] for r in (first, again, other)] == [1, 0, 1]
    assert other.json()["fix_count"] == 2


@pytest.mark.parametrize(
    ("batch", "detail"),
    [
        ([{"t": "noon", "lat": 1, "lon": 2}], "[0].t: 'noon' is neither"),
        ([{"t": 1795318455, "lat": 91, "lon": 2}], "[0].lat: must be at most 90"),
        ([{"t": 1795318455, "lon": 2}], "[0].lat: is required"),
        ({"t": 1795318455, "lat": 1, "lon": 2}, "body: must be a list"),
    ],
)
def test_bad_fixes_return_422_naming_them_and_store_nothing(
    client: TestClient, session: Session, paper_body: dict[str, Any], batch: Any, detail: str
):
    plan = create_plan(client, paper_body)
    run = client.post(f"/api/plans/{plan['id']}/runs").json()
    good = {"t": 1795318000, "lat": 1, "lon": 2}
    payload = [good, *batch] if isinstance(batch, list) else batch
    response = client.post(f"/api/runs/{run['id']}/fixes", json=payload)
    assert response.status_code == 422
    expected = detail.replace("[0]", "[1]") if isinstance(batch, list) else detail
    assert response.json()["detail"].startswith(expected), response.json()
    assert stored(session) == (1, 0)


def test_fixes_to_an_uploaded_run_return_409(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    run = upload(client, plan["id"], "a.csv", csv_file(simulated_run())).json()
    response = client.post(
        f"/api/runs/{run['id']}/fixes", json=[{"t": 1795318455, "lat": 1, "lon": 2}]
    )
    assert response.status_code == 409
    assert response.json()["detail"].startswith(f"run {run['id']}: is an uploaded CSV track")


def test_unknown_run_returns_404(client: TestClient):
    for method, url in [
        ("GET", "/api/runs/55555"),
        ("GET", "/api/runs/55555/export/gpx"),
        ("POST", "/api/runs/55555/fixes"),
    ]:
        kwargs: dict[str, Any] = {"json": []} if method == "POST" else {}
        response = client.request(method, url, **kwargs)
        assert response.status_code == 404, url
        assert response.json() == {"detail": "run 55555 not found"}


def test_list_runs_newest_first_with_fix_counts(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    other = create_plan(client, paper_body)
    first = upload(client, plan["id"], "a.csv", csv_file(simulated_run())).json()
    live = client.post(f"/api/plans/{plan['id']}/runs").json()
    upload(client, other["id"], "b.csv", csv_file(simulated_run()))
    listing = client.get(f"/api/plans/{plan['id']}/runs").json()
    assert listing["total"] == 2
    assert [r["id"] for r in listing["items"]] == [live["id"], first["id"]]
    assert [r["fix_count"] for r in listing["items"]] == [0, first["fix_count"]]
    assert client.get("/api/plans/424242/runs").status_code == 404


def test_export_run_gpx_has_timed_track_and_plan_route(
    client: TestClient, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    sim = simulated_run()
    run = upload(client, plan["id"], "field day.nmea", nmea_file(sim)).json()
    response = client.get(f"/api/runs/{run['id']}/export/gpx")
    assert response.status_code == 200
    assert response.headers["content-disposition"] == (
        f'attachment; filename="sawah-ketewel-run-{run["id"]}.gpx"'
    )
    schema = etree.XMLSchema(etree.parse(str(GPX_XSD)))
    assert schema.validate(etree.fromstring(response.content)), schema.error_log
    gpx = gpxpy.parse(response.text)
    (route,) = gpx.routes
    assert len(route.points) == plan["stats"]["waypoint_count"]
    (track,) = gpx.tracks
    points = track.segments[0].points
    assert len(points) == len(sim.time_s)
    assert points[0].time == RUN_START
    assert all(a.time < b.time for a, b in zip(points, points[1:], strict=False))
    # And it uploads again as the same run.
    again = upload(client, plan["id"], "again.gpx", response.content).json()
    assert again["fix_count"] == run["fix_count"]
    assert math.isclose(
        again["metrics"]["cross_track_rms_m"], run["metrics"]["cross_track_rms_m"], abs_tol=1e-6
    )


def test_export_of_an_empty_live_run_returns_409(client: TestClient, paper_body: dict[str, Any]):
    plan = create_plan(client, paper_body)
    run = client.post(f"/api/plans/{plan['id']}/runs").json()
    response = client.get(f"/api/runs/{run['id']}/export/gpx")
    assert response.status_code == 409
    assert (
        response.json()["detail"] == f"run {run['id']}: has no fix yet; there is no track to export"
    )


def test_deleting_the_plan_deletes_its_runs_and_fixes(
    client: TestClient, session: Session, paper_body: dict[str, Any]
):
    plan = create_plan(client, paper_body)
    run = upload(client, plan["id"], "a.csv", csv_file(simulated_run())).json()
    assert stored(session)[1] > 0
    assert client.delete(f"/api/plans/{plan['id']}").status_code == 204
    assert stored(session) == (0, 0)
    assert client.get(f"/api/runs/{run['id']}").status_code == 404


def test_openapi_documents_simulation_and_run_routes(client: TestClient):
    paths = client.get("/openapi.json").json()["paths"]
    assert set(paths["/api/plans/{plan_id}/simulations"]) == {"get", "post"}
    assert set(paths["/api/simulations/{simulation_id}"]) == {"get"}
    assert set(paths["/api/simulations/{simulation_id}/export/gpx"]) == {"get"}
    assert set(paths["/api/plans/{plan_id}/runs"]) == {"get", "post"}
    assert set(paths["/api/runs/{run_id}"]) == {"get"}
    assert set(paths["/api/runs/{run_id}/fixes"]) == {"post"}
    assert set(paths["/api/runs/{run_id}/export/gpx"]) == {"get"}
    upload_body = paths["/api/plans/{plan_id}/runs"]["post"]["requestBody"]
    assert "multipart/form-data" in upload_body["content"]
    assert {"413", "422"} <= set(paths["/api/plans/{plan_id}/runs"]["post"]["responses"])


def test_batch_over_the_limit_returns_422_and_stores_nothing(
    client: TestClient,
    session: Session,
    paper_body: dict[str, Any],
    monkeypatch: pytest.MonkeyPatch,
):
    # The test app's body limit is too small for MAX_FIXES_PER_BATCH fixes: lower the count.
    assert MAX_FIXES_PER_BATCH == 10_000
    monkeypatch.setattr("app.runs.MAX_FIXES_PER_BATCH", 100)
    plan = create_plan(client, paper_body)
    run = client.post(f"/api/plans/{plan['id']}/runs").json()
    batch = [{"t": 1795318000 + i, "lat": 1, "lon": 2} for i in range(101)]
    response = client.post(f"/api/runs/{run['id']}/fixes", json=batch)
    assert response.status_code == 422
    assert response.json()["detail"] == "body: has 101 fixes; send at most 100 per batch"
    assert stored(session) == (1, 0)
    assert client.post(f"/api/runs/{run['id']}/fixes", json=batch[:100]).json()["stored"] == 100
