"""The page on a phone: 44 px targets, the sheet folds to show the path, nothing overlaps."""

from __future__ import annotations

import pytest
from playwright.sync_api import Page, expect

from tests.browser.conftest import MapPageOpener
from tests.browser.test_map_page import button, figure, generate, import_paper_field

pytestmark = pytest.mark.browser

TAP_PX = 44

#: Everything a finger can press over the map: Leaflet's, Geoman's and ours.
MAP_CONTROLS = (
    ".leaflet-control a, .leaflet-control button,"
    " .leaflet-pm-toolbar a.leaflet-buttons-control-button, #panel-toggle, .tile-notice button"
)

#: The controls in the sheet.
PANEL_CONTROLS = "#panel button, #panel input:not([type=file]), #panel select, #panel a[href]"

MEASURE = """([selector, scroll]) => [...document.querySelectorAll(selector)]
    .filter((el) => !el.closest('.leaflet-control-attribution'))
    .filter((el) => el.offsetParent !== null && getComputedStyle(el).visibility !== 'hidden')
    .map((el) => {
        if (scroll) el.scrollIntoView({ block: 'center' });
        const r = el.getBoundingClientRect();
        const x = r.left + r.width / 2, y = r.top + r.height / 2;
        const top = document.elementFromPoint(x, y);
        return {
            name: el.getAttribute('aria-label') || el.title || el.textContent.trim() || el.id,
            x: r.left, y: r.top, width: r.width, height: r.height,
            covered: !(top === el || el.contains(top)),
            inside: r.left >= 0 && r.top >= 0 && r.right <= innerWidth && r.bottom <= innerHeight,
        };
    })"""


def phone(open_map: MapPageOpener, width: int) -> Page:
    return open_map({"width": width, "height": 844}, is_mobile=True, has_touch=True)


def overlaps(a: dict, b: dict) -> bool:
    return not (
        a["x"] + a["width"] <= b["x"]
        or b["x"] + b["width"] <= a["x"]
        or a["y"] + a["height"] <= b["y"]
        or b["y"] + b["height"] <= a["y"]
    )


@pytest.mark.parametrize("width", [360, 390, 430])
def test_after_generate_the_path_shows_and_every_control_is_a_finger_wide(
    open_map: MapPageOpener, width: int
) -> None:
    page = phone(open_map, width)
    button(page, "Controls").click()
    import_paper_field(page)
    plan = generate(page)

    # The sheet folded away to show the result, and the status says how to get it back.
    expect(button(page, "Controls")).to_have_attribute("aria-expanded", "false")
    expect(page.locator("#panel")).to_be_hidden()
    expect(page.locator("#status")).to_contain_text("Tap Controls")
    # The path is on screen, not under anything.
    waypoints = page.locator(".waypoint")
    # Numbered markers for the line ends; a turn's half-metre points show as the turn's line.
    ends = [w for w in plan["waypoints"] if w["role"] not in ("start", "finish", "turn")]
    expect(waypoints).to_have_count(len(ends))
    for i in range(waypoints.count()):
        box = waypoints.nth(i).bounding_box()
        assert box is not None
        assert 0 <= box["x"] and box["x"] + box["width"] <= width
        assert 0 <= box["y"] and box["y"] + box["height"] <= 844

    controls = page.evaluate(MEASURE, [MAP_CONTROLS, False])
    assert len(controls) >= 10  # zoom ×2, layers, locate, Geoman ×6, toggle
    small = [c for c in controls if min(c["width"], c["height"]) < TAP_PX]
    assert small == [], small
    hidden = [c for c in controls if c["covered"] or not c["inside"]]
    assert hidden == [], hidden
    # Nothing over the map overlaps anything else (the status pill included).
    status = page.locator("#status").bounding_box()
    boxes = controls + ([{"name": "status", **status}] if status else [])
    clashes = [
        (a["name"], b["name"])
        for i, a in enumerate(boxes)
        for b in boxes[i + 1 :]
        if overlaps(a, b)
    ]
    assert clashes == []

    button(page, "Controls").click()
    expect(figure(page, "Lines")).to_have_text(str(plan["stats"]["line_count"]))
    in_panel = page.evaluate(MEASURE, [PANEL_CONTROLS, True])
    small = [c for c in in_panel if c["height"] < TAP_PX or c["width"] < TAP_PX]
    assert small == [], small
    covered = [c for c in in_panel if c["covered"]]
    assert covered == [], covered


def test_a_tapped_toggle_keeps_its_colours(open_map: MapPageOpener) -> None:
    # On touch screens hover styles used to stick after a tap and wash the toggle out.
    page = phone(open_map, 390)
    toggle = button(page, "Controls")
    before = toggle.evaluate("el => getComputedStyle(el).backgroundColor")
    toggle.tap()
    toggle.tap()
    expect(toggle).to_have_attribute("aria-expanded", "false")
    assert toggle.evaluate("el => getComputedStyle(el).backgroundColor") == before


def test_status_messages_fade(page: Page) -> None:
    import_paper_field(page)
    expect(page.locator("#status")).to_contain_text("Imported")
    expect(page.locator("#status")).to_be_empty(timeout=10_000)
