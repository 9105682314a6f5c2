"""The vehicle on the map page: choose a small tractor, plan, and its drawn turns stay inside."""

from __future__ import annotations

import pytest
import shapely
from playwright.sync_api import Page, expect
from shapely.geometry import shape

from planner.projection import field_frame
from tests.browser.test_map_page import generate, import_paper_field

pytestmark = pytest.mark.browser


def test_small_tractor_plans_turns_inside_the_field(page: Page) -> None:
    import_paper_field(page)
    vehicle = page.get_by_label("Vehicle", exact=True)
    # The presets arrive from /api/vehicles, each with its figures beside the choice.
    expect(vehicle.locator("option")).to_have_count(4)
    vehicle.select_option("small_tractor")
    expect(page.locator("#vehicle-figures")).to_contain_text("turns on a 3 m radius")
    page.get_by_label("Pattern", exact=True).select_option("snake")
    page.get_by_label("Implement width (m)", exact=True).fill("4,5")

    plan = generate(page)

    assert plan["request"]["vehicle"] == "small_tractor"
    assert plan["request"]["implement_width_m"] == 4.5
    assert plan["request"]["pattern"] == "snake"
    assert plan["stats"]["vehicle"]["min_turn_radius_m"] == 3.0
    # What the page drew is this collection: every turn, buffered by half the tractor's
    # width, lies inside the field.
    features = plan["geojson"]["features"]
    field_lonlat = shape(
        next(f for f in features if f["properties"]["kind"] == "field")["geometry"]
    )
    frame = field_frame(field_lonlat)
    field_local = frame.to_local(field_lonlat).buffer(0.01)
    half = plan["stats"]["vehicle"]["width_m"] / 2
    turns = [f for f in features if f["properties"]["kind"] == "turn"]
    assert turns, "a plan of several lines has turns"
    for turn in turns:
        body = frame.to_local(shape(turn["geometry"])).buffer(half)
        assert shapely.difference(body, field_local).area < 1e-6
    # Numbered markers for the line ends (the turns' half-metre points show as the turn line).
    ends = [w for w in plan["waypoints"] if w["role"] not in ("start", "finish", "turn")]
    expect(page.locator(".waypoint")).to_have_count(len(ends))


def test_an_implement_width_that_is_not_a_number_is_named(page: Page) -> None:
    import_paper_field(page)
    page.get_by_label("Implement width (m)", exact=True).fill("wide")
    page.get_by_role("button", name="Generate path", exact=True).click()
    expect(page.get_by_role("alert")).to_contain_text("Implement width (m)")
