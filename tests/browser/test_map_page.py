"""What a person does on the map page, in headless Chromium against a real ``tillpath serve``.

Each test starts from a fresh browser (no stored map view), so the map opens at the default view
(Ketewel, Bali, zoom 18), where one screen pixel is about 0.59 m.
"""

from __future__ import annotations

import math
import re
import uuid
from collections.abc import Callable
from pathlib import Path

import gpxpy
import pytest
from lxml import etree
from playwright.sync_api import APIResponse, Locator, Page, Route, expect

from tests.browser.conftest import GPX_SCHEMA, PAPER_FIELD, MapPageOpener

pytestmark = pytest.mark.browser

#: Web Mercator ground resolution at the default view [m/px]: 156543.03 m·cos(lat) / 2^zoom.
DEFAULT_LAT = -8.6264
DEFAULT_ZOOM = 18
METRES_PER_PIXEL = 156543.03392 * math.cos(math.radians(DEFAULT_LAT)) / 2**DEFAULT_ZOOM

#: A four-sided field, in pixels from the map's top-left corner (the map is 920 × 800 px).
FIELD_PX = [(330, 260), (560, 250), (580, 440), (320, 450)]
START_PX = (280, 520)
FINISH_PX = (640, 520)


def button(page: Page, name: str) -> Locator:
    return page.get_by_role("button", name=name, exact=True)


def figure(page: Page, label: str) -> Locator:
    """The value shown for ``label`` in the Plan summary."""
    summary = page.get_by_role("region", name="Plan summary")
    return summary.locator(f"xpath=.//dt[normalize-space()='{label}']/following-sibling::dd[1]")


def expect_no_plan(page: Page) -> None:
    """The Plan summary says there is no path and shows no figures."""
    summary = page.get_by_role("region", name="Plan summary")
    expect(summary).to_contain_text("No path yet")
    expect(summary.get_by_text("Lines", exact=True)).to_be_hidden()


def click_map(page: Page, x: float, y: float) -> None:
    box = page.locator("#map").bounding_box()
    assert box is not None
    page.mouse.click(box["x"] + x, box["y"] + y)


def draw_field(page: Page, corners: list[tuple[int, int]]) -> None:
    """Press Draw field, click the corners, and close the polygon on the first corner."""
    button(page, "Draw field").click()
    for x, y in corners:
        click_map(page, x, y)
    click_map(page, *corners[0])


def set_start_and_finish(page: Page) -> None:
    button(page, "Set start").click()
    click_map(page, *START_PX)
    button(page, "Set finish").click()
    click_map(page, *FINISH_PX)


def import_paper_field(page: Page) -> None:
    with page.expect_file_chooser() as chooser:
        button(page, "Import field").click()
    chooser.value.set_files(PAPER_FIELD)
    expect(page.get_by_label("Interval (m)")).to_have_value("4")


def answer_to(page: Page, path: str, act: Callable[[], object], *, method: str) -> APIResponse:
    """Do ``act``; return the server's answer, body and all, to its ``method`` request to ``path``.

    The answer is relayed (``route.fetch``, then ``route.fulfill`` with it), so its body is the
    one Playwright fetched, not Chromium's record of the page's own request. Chromium does not
    always keep the body of a response the page has read, and Playwright (1.63 on) then gives a
    POST's answer an empty body rather than an error: ``json()`` failed on a 200 now and then.
    """
    answers: list[APIResponse] = []

    def relay(route: Route) -> None:
        if route.request.method != method:
            route.fallback()
            return
        answer = route.fetch()
        answers.append(answer)
        route.fulfill(response=answer)

    url = f"**{path}"
    page.route(url, relay)
    try:
        # The page has its answer too: what it shows next is drawn from it.
        with page.expect_response(lambda r: r.request.method == method and r.url.endswith(path)):
            act()
    finally:
        page.unroute(url, relay)
    assert answers, f"no {method} {path} relayed"
    return answers[0]


def generate(page: Page) -> dict:
    """Press Generate path and return the plan the API answered with."""
    answer = answer_to(
        page, "/api/plans/preview", button(page, "Generate path").click, method="POST"
    )
    assert answer.status == 200, answer.text()
    plan: dict = answer.json()
    return plan


def save(page: Page, name: str) -> dict:
    page.get_by_label("Plan name").fill(name)
    answer = answer_to(page, "/api/plans", button(page, "Save plan").click, method="POST")
    assert answer.status == 201, answer.text()
    plan: dict = answer.json()
    return plan


def shoelace_area(points: list[tuple[int, int]]) -> float:
    """Area of a simple polygon given in pixels [px²]."""
    pairs = zip(points, points[1:] + points[:1], strict=True)
    twice = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in pairs)
    return abs(twice) / 2


def test_draw_field_set_start_finish_and_generate_shows_plan_summary(page: Page) -> None:
    expect_no_plan(page)
    draw_field(page, FIELD_PX)
    set_start_and_finish(page)
    page.get_by_label("Interval (m)").fill("4")

    plan = generate(page)

    summary = page.get_by_role("region", name="Plan summary")
    expect(summary).to_be_visible()
    lines = int(figure(page, "Lines").inner_text())
    # The field is about 140 m × 110 m: 4 m apart, that is roughly 28 to 35 lines.
    assert 24 <= lines <= 40
    assert lines == plan["stats"]["line_count"]
    assert int(figure(page, "Waypoints").inner_text()) == plan["stats"]["waypoint_count"]
    # The drawn shape reached the API as drawn: its area is the clicked polygon's.
    expected_ha = shoelace_area(FIELD_PX) * METRES_PER_PIXEL**2 / 10_000
    shown_ha = float(re.fullmatch(r"([\d.]+) ha", figure(page, "Area").inner_text())[1])
    assert shown_ha == pytest.approx(expected_ha, rel=0.02)
    expect(figure(page, "Path length")).to_have_text(re.compile(r"^[\d.]+ (m|km)$"))
    expect(figure(page, "Estimated time")).to_have_text(re.compile(r"^\d+:\d\d(:\d\d)? (min|h)$"))
    expect(figure(page, "Coverage")).to_have_text(re.compile(r"^\d+\.\d %$"))
    # Start and finish went with the request, and the path begins and ends there.
    assert plan["request"]["start"] is not None and plan["request"]["finish"] is not None
    assert plan["waypoints"][0]["role"] == "start" and plan["waypoints"][-1]["role"] == "finish"
    # The path is on the map: numbered waypoints (start and finish are pins) and arrows.
    # Numbered markers for the line ends (the turns' half-metre points show as the turn line).
    ends = [w for w in plan["waypoints"] if w["role"] not in ("start", "finish", "turn")]
    expect(page.locator(".waypoint")).to_have_count(len(ends))
    expect(page.locator(".endpoint-start")).to_have_count(1)
    expect(page.locator(".endpoint-finish")).to_have_count(1)
    arrows = page.locator(".path-arrow span")
    expect(arrows.first).to_have_attribute("style", re.compile(r"rotate\(-?[\d.]+deg\)"))
    # An unsaved plan offers no downloads.
    expect(page.get_by_role("link", name="GPX", exact=True)).to_be_hidden()


def test_saved_plan_opens_from_saved_plans_after_reload(page: Page) -> None:
    draw_field(page, FIELD_PX)
    set_start_and_finish(page)
    page.get_by_label("Interval (m)").fill("4")
    generated = generate(page)
    name = f"North sawah {uuid.uuid4().hex[:6]}"

    saved = save(page, name)

    assert saved["stats"]["line_count"] == generated["stats"]["line_count"]
    gpx_link = page.get_by_role("link", name="GPX", exact=True)
    expect(gpx_link).to_have_attribute("href", re.compile(rf"/api/plans/{saved['id']}/export/gpx$"))
    page.reload()
    page.wait_for_selector("#app[data-ready='true']")
    # The draft brings the stored plan back after the reload ...
    expect(figure(page, "Lines")).to_have_text(str(saved["stats"]["line_count"]))
    # ... and Start over (after asking) clears the map, not the saved plans.
    page.once("dialog", lambda dialog: dialog.accept())
    button(page, "Start over").click()
    expect_no_plan(page)
    page.reload()
    page.wait_for_selector("#app[data-ready='true']")
    expect_no_plan(page)

    saved_plans = page.get_by_role("list", name="Saved plans")
    saved_plans.get_by_role("button", name=f"Open {name}").click()

    expect(figure(page, "Lines")).to_have_text(str(saved["stats"]["line_count"]))
    expect(figure(page, "Waypoints")).to_have_text(str(saved["stats"]["waypoint_count"]))
    expect(page.get_by_label("Plan name")).to_have_value(name)
    expect(page.get_by_label("Interval (m)")).to_have_value(re.compile(r"^4(\.0)?$"))
    expect(page.locator(".endpoint-start")).to_have_count(1)
    for fmt, label in [("gpx", "GPX"), ("geojson", "GeoJSON"), ("csv", "CSV")]:
        link = page.get_by_role("link", name=label, exact=True)
        expect(link).to_have_attribute(
            "href", re.compile(rf"/api/plans/{saved['id']}/export/{fmt}$")
        )


def test_gpx_download_parses_and_validates_against_gpx_1_1(page: Page, tmp_path: Path) -> None:
    import_paper_field(page)
    saved = save(page, f"Ketewel {uuid.uuid4().hex[:6]}")

    with page.expect_download() as download_info:
        page.get_by_role("link", name="GPX", exact=True).click()
    download = download_info.value
    assert download.suggested_filename.endswith(".gpx")
    path = tmp_path / download.suggested_filename
    download.save_as(path)

    gpx = gpxpy.parse(path.read_text(encoding="utf-8"))
    assert len(gpx.routes) == 1
    points = gpx.routes[0].points
    assert len(points) == saved["stats"]["waypoint_count"]
    # Line ends, start and finish; the hand tractor's pivots are "turn" points between them.
    assert sum(p.type != "turn" for p in points) == 2 * saved["stats"]["line_count"] + 2
    assert (points[0].longitude, points[0].latitude) == pytest.approx(
        (saved["waypoints"][0]["lon"], saved["waypoints"][0]["lat"]), abs=1e-7
    )
    schema = etree.XMLSchema(etree.parse(str(GPX_SCHEMA)))
    document = etree.parse(str(path))
    assert schema.validate(document), schema.error_log


def test_interval_zero_shows_an_alert_naming_the_interval(page: Page) -> None:
    import_paper_field(page)
    page.get_by_label("Interval (m)").fill("0")

    with page.expect_response("**/api/plans/preview") as answer:
        button(page, "Generate path").click()

    assert answer.value.status == 422
    alert = page.get_by_role("alert")
    expect(alert).to_be_visible()
    expect(alert).to_contain_text("Interval (m)")
    expect(alert).to_contain_text("0.2")
    expect(alert).not_to_contain_text("interval_m")
    expect(page.get_by_label("Interval (m)")).to_have_attribute("aria-invalid", "true")
    expect_no_plan(page)

    # Fixing the input and planning again clears the alert.
    page.get_by_label("Interval (m)").fill("4")
    generate(page)
    expect(alert).to_be_hidden()


def test_generate_without_a_field_says_what_to_do(page: Page) -> None:
    page.get_by_label("Interval (m)").fill("4")
    button(page, "Generate path").click()
    expect(page.get_by_role("alert")).to_contain_text("Draw field")


def test_import_paper_field_shows_its_plan_figures(page: Page) -> None:
    import_paper_field(page)
    expect(page.locator(".endpoint-start")).to_have_count(1)
    expect(page.locator(".endpoint-finish")).to_have_count(1)

    plan = generate(page)

    # The count follows the heading the search keeps (R5: coverage first), 4 or 5 lines.
    lines = plan["stats"]["line_count"]
    assert lines in (4, 5)
    expect(figure(page, "Lines")).to_have_text(str(lines))
    # Line ends, start and finish, and the hand tractor's pivots between the lines.
    expect(figure(page, "Waypoints")).to_have_text(str(plan["stats"]["waypoint_count"]))
    assert sum(w["role"] != "turn" for w in plan["waypoints"]) == 2 * lines + 2
    expect(figure(page, "Area")).to_have_text(re.compile(r"^30[23]\.\d m²"))
    assert plan["request"]["start"] == pytest.approx([115.29797264, -8.62652248])
    assert plan["request"]["finish"] == pytest.approx([115.29816889, -8.62652064])


def test_import_of_a_file_that_is_no_field_file_shows_an_alert_naming_it(page: Page) -> None:
    with page.expect_file_chooser() as chooser:
        button(page, "Import field").click()
    chooser.value.set_files(
        files=[
            {"name": "photo.geojson", "mimeType": "application/json", "buffer": bytes(range(256))}
        ]
    )
    expect(page.get_by_role("alert")).to_contain_text("photo.geojson: is binary data")


def test_dragging_the_finish_marker_plans_again(page: Page) -> None:
    import_paper_field(page)
    first = generate(page)
    length_before = figure(page, "Path length").inner_text()
    finish = page.locator(".endpoint-finish")
    finish.hover()  # waits until the pin stands still
    box = finish.bounding_box()
    assert box is not None
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2

    with page.expect_response("**/api/plans/preview") as answer:
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x + 60, y + 120, steps=8)
        page.mouse.up()

    moved = answer.value.json()
    assert moved["request"]["finish"] != first["request"]["finish"]
    # Dragged down and to the right, away from the field: the finish leg grows by metres.
    assert moved["stats"]["path_length_m"] > first["stats"]["path_length_m"] + 1
    expect(figure(page, "Path length")).not_to_have_text(length_before)


def test_delete_removes_a_saved_plan_from_the_list(page: Page) -> None:
    import_paper_field(page)
    name = f"To delete {uuid.uuid4().hex[:6]}"
    save(page, name)
    saved_plans = page.get_by_role("list", name="Saved plans")
    expect(saved_plans.get_by_role("button", name=f"Open {name}")).to_be_visible()

    page.once("dialog", lambda dialog: dialog.accept())
    saved_plans.get_by_role("button", name=f"Delete {name}").click()

    expect(saved_plans.get_by_role("button", name=f"Open {name}")).to_have_count(0)
    expect(page.get_by_role("link", name="GPX", exact=True)).to_be_hidden()


def test_satellite_and_openstreetmap_layers_are_offered(page: Page) -> None:
    page.locator(".leaflet-control-layers").hover()
    satellite = page.get_by_role("radio", name="Satellite")
    street = page.get_by_role("radio", name="OpenStreetMap")
    expect(satellite).to_be_checked()
    street.check()
    expect(street).to_be_checked()


def test_simulate_and_upload_track_are_enabled_once_the_plan_is_saved(page: Page) -> None:
    for name in ["Simulate", "Upload track"]:
        expect(button(page, name)).to_be_disabled()
    import_paper_field(page)
    generate(page)
    for name in ["Simulate", "Upload track"]:
        expect(button(page, name)).to_be_disabled()
    save(page, f"Enable {uuid.uuid4().hex[:6]}")
    for name in ["Simulate", "Upload track"]:
        expect(button(page, name)).to_be_enabled()


def test_every_control_has_its_accessible_name(page: Page) -> None:
    for label in [
        "Plan name",
        "Interval (m)",
        "Line angle (°)",
        "Objective",
        "Headland passes",
        "Vehicle",
        "Implement width (m)",
        "Pattern",
    ]:
        expect(page.get_by_label(label, exact=True)).to_be_visible()
    for name in [
        "Draw field",
        "Set start",
        "Set finish",
        "Import field",
        "Generate path",
        "Save plan",
    ]:
        expect(button(page, name)).to_be_enabled()
    expect(page.get_by_role("region", name="Plan summary")).to_be_visible()
    expect(page.get_by_role("list", name="Saved plans")).to_be_attached()


def test_show_my_location_centres_the_map_on_the_gps_position(open_map: MapPageOpener) -> None:
    here = {"latitude": -8.5069, "longitude": 115.2625, "accuracy": 8}  # Ubud, not the default
    page = open_map(geolocation=here, permissions=["geolocation"])

    button(page, "Show my location").click()

    expect(page.get_by_role("status")).to_contain_text("You are here (± 4 m)")
    page.wait_for_function(
        "() => Math.abs(JSON.parse(localStorage.getItem('tillpath.view')).lat - -8.5069) < 1e-4"
    )
    view = page.evaluate("JSON.parse(localStorage.getItem('tillpath.view'))")
    assert (view["lat"], view["lng"]) == pytest.approx((-8.5069, 115.2625), abs=1e-4)


def test_phone_shows_the_map_full_screen_with_a_panel_toggle(phone_page: Page) -> None:
    page = phone_page
    viewport = page.viewport_size
    assert viewport is not None
    box = page.locator("#map").bounding_box()
    assert box is not None
    assert (box["x"], box["width"]) == (0, viewport["width"])
    assert box["height"] == viewport["height"]
    toggle = button(page, "Controls")
    expect(toggle).to_be_visible()
    expect(toggle).to_have_attribute("aria-expanded", "false")
    expect(button(page, "Generate path")).to_be_hidden()

    toggle.click()

    expect(toggle).to_have_attribute("aria-expanded", "true")
    expect(button(page, "Generate path")).to_be_visible()
    # Choosing a map action folds the panel away so the map can be tapped.
    button(page, "Set start").click()
    expect(button(page, "Generate path")).to_be_hidden()
    click_map(page, 195, 300)
    expect(page.locator(".endpoint-start")).to_have_count(1)


def test_format_helpers_use_human_units(page: Page) -> None:
    shown = page.evaluate(
        """async () => {
            const f = await import("/static/js/format.js");
            return [
                f.formatArea(1234.4), f.formatArea(123456), f.formatLength(101.054),
                f.formatLength(2500), f.formatDuration(217.5), f.formatDuration(3725),
                f.formatPercent(0.99685),
                f.friendlyError(422, "interval_m: must be between 0.2 and 50 m, got 0").message,
                f.friendlyError(422, "field: polygon is self-intersecting near (1, 2)").input,
                f.friendlyError(0, null).message,
                f.friendlyError(422, "file: is not a track file tillpath can read: expected GPX")
                    .message,
            ];
        }"""
    )
    assert shown[:7] == [
        "1234 m² (0.12 ha)",
        "12.35 ha",
        "101 m",
        "2.50 km",
        "3:38 min",
        "1:02:05 h",
        "99.7 %",
    ]
    assert shown[7].startswith("Interval (m): must be between 0.2 and 50 m, got 0.")
    assert shown[8] == "field"
    assert "Cannot reach the tillpath server" in shown[9]
    # A sentence, not "File: is not a track file".
    assert shown[10].startswith("This file is not a track file tillpath can read: expected GPX.")


def test_waypoint_tooltips_number_lines_as_the_exports_do(page: Page) -> None:
    import_paper_field(page)
    plan = generate(page)
    first = plan["waypoints"][1]
    assert first["role"] == "line_start"
    page.locator(".waypoint").first.hover()
    expect(page.locator(".leaflet-tooltip")).to_have_text(
        f"Waypoint {first['seq']}: start of a line, line {first['line']}"
    )
