"""Field runs on the map page: upload a GPX track and see it drawn with its metrics; watch a
live run grow while fixes are posted."""

from __future__ import annotations

import datetime as dt
import json
import math
import urllib.request
import uuid
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Page, expect

from app.testing import ServerUrl
from tests.app.track_files import RUN_START, gpx_file, simulated_run
from tests.browser.test_map_page import button, generate, import_paper_field, save

pytestmark = pytest.mark.browser


def metric(page: Page, label: str):
    box = page.get_by_role("region", name="Run", exact=True)
    return box.locator(f"xpath=.//dt[normalize-space()='{label}']/following-sibling::dd[1]")


def api(server_url: ServerUrl, method: str, path: str, body: Any = None) -> Any:
    data = None if body is None else json.dumps(body).encode()
    headers = {"Content-Type": "application/json", **server_url.headers}
    request = urllib.request.Request(server_url + path, data=data, method=method, headers=headers)
    with urllib.request.urlopen(request, timeout=30) as response:
        return json.loads(response.read())


def saved_paper_plan(page: Page) -> dict[str, Any]:
    import_paper_field(page)
    generate(page)
    return save(page, f"Runs {uuid.uuid4().hex[:6]}")


def test_upload_gpx_track_draws_the_run_with_its_metrics(page: Page, tmp_path: Path) -> None:
    plan = saved_paper_plan(page)
    track_file = tmp_path / "tractor-log.gpx"
    track_file.write_bytes(gpx_file(simulated_run()))

    with page.expect_response(
        lambda r: r.request.method == "POST" and r.url.endswith(f"/plans/{plan['id']}/runs")
    ) as answer:
        with page.expect_file_chooser() as chooser:
            button(page, "Upload track").click()
        chooser.value.set_files(track_file)
    assert answer.value.status == 201, answer.value.text()
    run = answer.value.json()
    metrics = run["metrics"]
    assert run["fix_count"] == len(simulated_run().time_s)

    expect(page.get_by_role("region", name="Run", exact=True)).to_be_visible()
    expect(page.get_by_role("region", name="Run", exact=True)).to_contain_text("tractor-log.gpx")
    expect(metric(page, "Fixes")).to_have_text(str(run["fix_count"]))
    expect(metric(page, "Waypoint error max")).to_have_text(
        f"{metrics['waypoint_error_max_m']:.2f} m"
    )
    expect(metric(page, "Cross-track RMS")).to_have_text(f"{metrics['cross_track_rms_m']:.2f} m")
    expect(metric(page, "Coverage")).to_have_text(f"{metrics['coverage_ratio'] * 100:.1f} %")
    minutes, seconds = divmod(math.floor(metrics["time_s"] + 0.5), 60)  # as Math.round
    expect(metric(page, "Time")).to_have_text(f"{minutes}:{seconds:02d} min")
    n = len(metrics["stretches"])
    assert n > 0  # the m8n run strays over 1 m: there is something to highlight
    expect(metric(page, "Off the line")).to_contain_text(f"{n} stretch")

    # The track and each stretch over the threshold are drawn.
    expect(page.locator("path.run-track")).to_have_count(1)
    expect(page.locator("path.off-line-stretch")).to_have_count(n)
    # The run is listed under the plan, and its GPX can be downloaded.
    runs = page.get_by_role("list", name="Runs of this plan")
    expect(runs.get_by_role("button", name="Open run tractor-log.gpx")).to_be_visible()
    expect(page.get_by_role("link", name="Download run GPX")).to_have_attribute(
        "href", f"/api/runs/{run['id']}/export/gpx"
    )


def test_bad_track_file_shows_an_alert_and_no_run(page: Page, tmp_path: Path) -> None:
    saved_paper_plan(page)
    bad = tmp_path / "photo.gpx"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n not a track")
    with page.expect_file_chooser() as chooser:
        button(page, "Upload track").click()
    chooser.value.set_files(bad)
    expect(page.get_by_role("alert")).to_contain_text("track file")
    expect(page.get_by_role("region", name="Run", exact=True)).to_be_hidden()


def test_live_run_grows_on_the_map_while_fixes_arrive(page: Page, server_url: ServerUrl) -> None:
    plan = saved_paper_plan(page)
    run = api(server_url, "POST", f"/api/plans/{plan['id']}/runs", {})
    sim = simulated_run()

    def post(start: int, stop: int) -> None:
        batch = [
            {
                "t": (RUN_START + dt.timedelta(seconds=float(sim.time_s[i]))).isoformat(),
                "lat": float(sim.lat[i]),
                "lon": float(sim.lon[i]),
            }
            for i in range(start, stop)
        ]
        api(server_url, "POST", f"/api/runs/{run['id']}/fixes", batch)

    post(0, 300)
    # The run shows in the plan's list once the list is refreshed: reopen the plan.
    page.reload()
    page.wait_for_selector("#app[data-ready='true']")
    page.get_by_role("button", name=f"Open {plan['name']}").click()
    page.get_by_role("button", name=f"Open run Run {run['id']}").click()
    expect(metric(page, "Fixes")).to_have_text("300")
    expect(page.get_by_role("region", name="Run", exact=True)).to_contain_text("live")
    tractor = page.locator(".tractor-marker")
    expect(tractor).to_have_count(1)
    first = tractor.bounding_box()

    post(300, 900)
    # Polled every few seconds: the count grows and the tractor moves.
    expect(metric(page, "Fixes")).to_have_text("900", timeout=10_000)
    expect(tractor).to_have_count(1)
    moved = tractor.bounding_box()
    assert first is not None and moved is not None
    assert (first["x"], first["y"]) != (moved["x"], moved["y"])


def test_a_run_that_skipped_a_line_shows_its_missed_ground_and_plans_a_follow_up(
    page: Page, tmp_path: Path
) -> None:
    from tests.app.test_run_quality import _skipping_track

    plan = saved_paper_plan(page)
    lon, lat = _skipping_track(skip_line=2)
    rows = ["time,lat,lon"] + [
        f"{1767225600 + 0.2 * i:.1f},{la:.9f},{lo:.9f}"
        for i, (lo, la) in enumerate(zip(lon, lat, strict=True))
    ]
    track_file = tmp_path / "skipped.csv"
    track_file.write_text("\n".join(rows) + "\n")
    with page.expect_response(
        lambda r: r.request.method == "POST" and r.url.endswith(f"/plans/{plan['id']}/runs")
    ) as answer:
        with page.expect_file_chooser() as chooser:
            button(page, "Upload track").click()
        chooser.value.set_files(track_file)
    run = answer.value.json()
    gaps = run["missed"]["features"]
    assert gaps
    # The gaps are drawn, counted, and the receiver's worth is said plainly.
    expect(page.locator("path.missed-ground")).to_have_count(len(gaps))
    expect(metric(page, "Missed ground")).to_contain_text(f"{len(gaps)} gap")
    expect(page.get_by_role("note")).to_contain_text("metre-level estimates")
    # One click plans the missed ground: a new saved plan, opened on the map.
    with page.expect_response(lambda r: r.url.endswith(f"/runs/{run['id']}/follow-up")) as made:
        button(page, "Plan the missed ground").click()
    assert made.value.status == 201, made.value.text()
    follow_up = made.value.json()
    saved = page.get_by_role("list", name="Saved plans")
    expect(saved).to_contain_text(f"follow-up of run {run['id']}")
    expect(page.get_by_role("status")).to_contain_text(follow_up["name"][:20])
