"""The Simulate button on the map page: a saved plan is driven and its run drawn with metrics."""

from __future__ import annotations

import math
import re
import uuid
from urllib.parse import urlsplit

import pytest
from playwright.sync_api import Page, expect

from tests.browser.test_map_page import button, generate, import_paper_field, save

pytestmark = pytest.mark.browser


def metric(page: Page, region: str, label: str):
    box = page.get_by_role("region", name=region)
    return box.locator(f"xpath=.//dt[normalize-space()='{label}']/following-sibling::dd[1]")


def test_simulate_draws_the_true_track_and_shows_its_metrics(page: Page) -> None:
    import_paper_field(page)
    generate(page)
    plan = save(page, f"Simulate {uuid.uuid4().hex[:6]}")
    page.get_by_label("Guidance").select_option("line")
    with page.expect_response(
        lambda r: (
            r.request.method == "POST"
            and urlsplit(r.url).path.endswith(f"/plans/{plan['id']}/simulations")
        )
    ) as answer:
        button(page, "Simulate").click()
    assert answer.value.status == 201, answer.value.text()
    simulation = answer.value.json()
    assert simulation["config"]["guidance"] == "line"
    metrics = simulation["metrics"]

    region = page.get_by_role("region", name="Simulation")
    expect(region).to_be_visible()
    minutes, seconds = divmod(math.floor(metrics["time_s"] + 0.5), 60)  # as Math.round
    expect(metric(page, "Simulation", "Time")).to_have_text(f"{minutes}:{seconds:02d} min")
    expect(metric(page, "Simulation", "Waypoint error max")).to_have_text(
        f"{metrics['waypoint_error_max_m']:.2f} m"
    )
    expect(metric(page, "Simulation", "Waypoint error mean")).to_have_text(
        f"{metrics['waypoint_error_mean_m']:.2f} m"
    )
    expect(metric(page, "Simulation", "Cross-track RMS")).to_have_text(
        f"{metrics['cross_track_rms_m']:.2f} m"
    )
    expect(metric(page, "Simulation", "Coverage")).to_have_text(
        f"{metrics['coverage_ratio'] * 100:.1f} %"
    )
    # The Plan summary stays beside it.
    expect(page.get_by_role("region", name="Plan summary")).to_contain_text("Lines")

    # The simulated track is drawn: one SVG path, a wandering line (Leaflet simplifies away
    # the vertices that are collinear on screen, so not all of them), over the field.
    track = page.locator("path.simulated-track")
    expect(track).to_have_count(1)
    d = track.get_attribute("d") or ""
    (true,) = [f for f in simulation["tracks"]["features"] if f["properties"]["source"] == "true"]
    vertices = len(re.findall(r"[ML]", d))
    assert 10 <= vertices <= len(true["geometry"]["coordinates"])
    # The page asked for the track thinned for drawing: fewer vertices than the stored one.
    assert len(true["geometry"]["coordinates"]) < true["properties"]["stored_vertices"]
    assert len(true["properties"]["time_s"]) == len(true["geometry"]["coordinates"])
    track_box = track.bounding_box()
    field_box = page.locator("path.leaflet-interactive").first.bounding_box()
    assert track_box is not None and field_box is not None
    assert track_box["width"] > 0.5 * field_box["width"]
    assert track_box["height"] > 0.5 * field_box["height"]

    download = page.get_by_role("link", name="Download simulation GPX")
    expect(download).to_have_attribute(
        "href", re.compile(rf"/api/simulations/{simulation['id']}/export/gpx$")
    )
