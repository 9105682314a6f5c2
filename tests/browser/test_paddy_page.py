"""In the paddy: no signal, no map pictures, a phone's GPS; and the slips a new user hit."""

from __future__ import annotations

import re
import uuid

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import MapPageOpener
from tests.browser.test_map_page import (
    FIELD_PX,
    button,
    click_map,
    expect_no_plan,
    figure,
    generate,
    import_paper_field,
    save,
)

pytestmark = pytest.mark.browser


def wait_for_service_worker(page: Page) -> None:
    """Wait until the service worker controls the page and has cached the shell."""
    page.wait_for_function("() => navigator.serviceWorker && navigator.serviceWorker.controller")
    page.wait_for_function(
        """async () => {
            const name = (await caches.keys()).find((key) => key.startsWith('tillpath-shell-'));
            if (!name) return false;
            const cache = await caches.open(name);
            const urls = (await cache.keys()).map((r) => new URL(r.url).pathname);
            return ['/', '/static/js/map.js', '/static/js/messages.js', '/i18n/id.json',
                    '/vendor/leaflet-geoman/leaflet-geoman.min.js']
                .every((path) => urls.includes(path));
        }"""
    )


def test_offline_reload_shows_the_page_and_the_draft(page: Page) -> None:
    wait_for_service_worker(page)
    import_paper_field(page)
    page.get_by_label("Line angle (°)").fill("12")
    page.context.set_offline(True)
    try:
        page.reload()
        page.wait_for_selector("#app[data-ready='true']")
        expect(button(page, "Generate path")).to_be_attached()
        # The draft: the field, both markers and the inputs, as they were.
        expect(page.locator("path.leaflet-interactive")).not_to_have_count(0)
        expect(page.locator(".endpoint-start")).to_have_count(1)
        expect(page.locator(".endpoint-finish")).to_have_count(1)
        expect(page.get_by_label("Interval (m)")).to_have_value("4")
        expect(page.get_by_label("Line angle (°)")).to_have_value("12")
        expect(page.locator("#notice")).to_contain_text("No connection")
        # Planning needs the server: the page says so plainly, and keeps the work.
        button(page, "Generate path").click()
        alert = page.get_by_role("alert")
        expect(alert).to_contain_text("Cannot reach the tillpath server")
        expect(alert).to_contain_text("kept on this phone")
        expect(page.locator(".endpoint-start")).to_have_count(1)
    finally:
        page.context.set_offline(False)


def test_a_save_made_offline_arrives_when_the_network_returns(page: Page) -> None:
    wait_for_service_worker(page)
    import_paper_field(page)
    name = f"Offline {uuid.uuid4().hex[:6]}"
    page.get_by_label("Plan name").fill(name)
    page.context.set_offline(True)
    try:
        button(page, "Save plan").click()
        expect(page.locator("#notice")).to_contain_text("1 saved plan is waiting to be sent")
        assert len(page.evaluate("JSON.parse(localStorage.getItem('tillpath.outbox'))")) == 1
    finally:
        with page.expect_response(
            lambda r: r.request.method == "POST" and r.url.endswith("/api/plans")
        ) as answer:
            page.context.set_offline(False)
    assert answer.value.status == 201
    assert answer.value.json()["name"] == name
    saved = page.get_by_role("list", name="Saved plans")
    expect(saved.get_by_role("button", name=f"Open {name}")).to_be_visible()
    expect(page.locator("#notice")).to_be_hidden()
    assert page.evaluate("JSON.parse(localStorage.getItem('tillpath.outbox'))") == []


def test_without_tiles_the_map_says_so_and_goes_to_coordinates(page: Page) -> None:
    # The test server's tile URLs are refused (app.testing.NO_TILES).
    notice = page.get_by_role("region", name="Map pictures")
    expect(notice).to_be_visible()
    expect(notice).to_contain_text("The map pictures cannot load")
    notice.get_by_role("button", name="Go to coordinates").click()
    coordinates = page.get_by_label("Go to coordinates")
    expect(coordinates).to_be_focused()
    coordinates.fill("8.5069 S, 115.2625 E")
    button(page, "Go").click()
    page.wait_for_function(
        "() => Math.abs(JSON.parse(localStorage.getItem('tillpath.view')).lat + 8.5069) < 1e-6"
    )
    coordinates.fill("somewhere")
    button(page, "Go").click()
    expect(page.get_by_role("alert")).to_contain_text("“somewhere” is not a position")


def test_walking_the_boundary_records_the_gps_positions_as_the_field(
    open_map: MapPageOpener,
) -> None:
    corners = [(-8.62600, 115.29800), (-8.62600, 115.29840), (-8.62640, 115.29840)]
    corners.append((-8.62640, 115.29800))
    page = open_map(
        geolocation={"latitude": corners[0][0], "longitude": corners[0][1], "accuracy": 4},
        permissions=["geolocation"],
    )
    page.get_by_role("complementary", name="Controls").get_by_role(
        "button", name="Walk the boundary"
    ).click()
    bar = page.get_by_role("region", name="Walking the boundary")
    expect(bar).to_contain_text("1 points recorded")
    for n, (lat, lon) in enumerate(corners[1:], start=2):
        page.context.set_geolocation({"latitude": lat, "longitude": lon, "accuracy": 4})
        expect(bar).to_contain_text(f"{n} points recorded")
    expect(bar).to_contain_text("GPS accuracy: ± 4.00 m")
    bar.get_by_role("button", name="Finish the field").click()
    expect(page.locator("#status")).to_contain_text("Field walked: 4 points")
    page.get_by_label("Interval (m)").fill("4")
    plan = generate(page)
    ring = plan["request"]["field"]["coordinates"][0]
    assert len(ring) == 5
    assert {(round(lat, 5), round(lon, 5)) for lon, lat in ring} == set(corners)


def test_gps_without_https_says_https_is_needed(page: Page) -> None:
    message = page.evaluate(
        """async () => {
            Object.defineProperty(window, 'isSecureContext', { value: false });
            const walk = await import('/static/js/walk.js');
            return walk.locationProblem(null);
        }"""
    )
    assert "HTTPS" in message and "--certfile" in message
    assert "Allow location" not in message


def test_an_invalid_interval_clears_the_previous_path(page: Page) -> None:
    import_paper_field(page)
    generate(page)
    expect(figure(page, "Lines")).to_have_text("4")
    page.get_by_label("Interval (m)").fill("four")
    button(page, "Generate path").click()
    alert = page.get_by_role("alert")
    expect(alert).to_have_text(
        "Interval (m): “four” is not a number. Type a number, for example 4."
    )
    expect_no_plan(page)
    expect(page.locator(".waypoint")).to_have_count(0)
    page.get_by_label("Line angle (°)").fill("x")
    page.get_by_label("Interval (m)").fill("4")
    button(page, "Generate path").click()
    expect(alert).to_contain_text("Line angle (°): “x” is not a number")
    expect(alert).not_to_contain_text("for example automatic")


def test_a_drawn_bow_tie_is_refused_in_words(page: Page) -> None:
    (a, b, c, d) = FIELD_PX
    button(page, "Draw field").click()
    for x, y in [a, b, d, c]:  # the last two swapped: the edges cross
        click_map(page, x, y)
    click_map(page, *a)
    expect(page.get_by_role("alert")).to_contain_text("crosses itself")
    page.get_by_label("Interval (m)").fill("4")
    with page.expect_response("**/api/plans/preview") as answer:
        button(page, "Generate path").click()
    assert answer.value.status == 422
    assert "self-intersecting" in answer.value.json()["detail"]
    expect(page.get_by_role("alert")).to_contain_text("Field: polygon is self-intersecting")


def test_simulations_are_listed_with_their_plan_after_a_reload(page: Page) -> None:
    import_paper_field(page)
    plan = save(page, f"Listed {uuid.uuid4().hex[:6]}")
    with page.expect_response(lambda r: "/simulations" in r.url and r.status == 201) as answer:
        button(page, "Simulate").click()
    simulation = answer.value.json()
    page.reload()
    page.wait_for_selector("#app[data-ready='true']")
    expect(figure(page, "Lines")).to_have_text(str(plan["stats"]["line_count"]))
    runs = page.get_by_role("list", name="Simulations and runs of this plan")
    item = runs.get_by_role("button", name=f"Open simulation Simulation {simulation['id']}")
    expect(item).to_be_visible()
    item.click()
    expect(page.get_by_role("region", name="Simulation")).to_be_visible()
    expect(page.locator("path.simulated-track")).to_have_count(1)


def test_saved_plans_are_searchable(page: Page) -> None:
    tag = uuid.uuid4().hex[:6]
    import_paper_field(page)
    save(page, f"Sawah utara {tag}")
    save(page, f"Sawah selatan {tag}")
    search = page.get_by_label("Search saved plans")
    saved = page.get_by_role("list", name="Saved plans")
    with page.expect_response(re.compile(r"/api/plans\?.*q=utara")):
        search.fill(f"utara {tag}")
    expect(saved.get_by_role("button", name=re.compile(r"^Open "))).to_have_count(1)
    expect(saved).to_contain_text(f"Sawah utara {tag}")
    search.fill(f"nothing {tag}")
    expect(page.locator("#saved-empty")).to_contain_text("No saved plan has")


def test_direction_arrows_turn_with_the_path_under_the_csp(page: Page) -> None:
    # The Content-Security-Policy drops inline style="" attributes; the arrows are turned
    # through the DOM instead, so they point the ways the tractor drives, not all east.
    import_paper_field(page)
    generate(page)
    arrows = page.locator(".path-arrow span")
    expect(arrows.first).to_be_attached()
    turns = arrows.evaluate_all("els => els.map((el) => getComputedStyle(el).transform)")
    assert "none" not in turns
    assert len(set(turns)) >= 2  # up and down the lines at least
