"""Issue 5 on the map page: a drawn L-shaped field with a hole plans, and the path stays inside."""

from __future__ import annotations

from pathlib import Path

import pytest
import shapely
from playwright.sync_api import Page, expect
from shapely.geometry import shape

from planner.projection import field_frame
from tests.browser.test_map_page import (
    click_map,
    draw_field,
    figure,
    generate,
    set_start_and_finish,
)

pytestmark = pytest.mark.browser

#: An L in map pixels: a 400 × 150 px arm along the top and a 200 × 350 px arm down the left.
L_FIELD_PX = [(150, 100), (550, 100), (550, 250), (350, 250), (350, 450), (150, 450)]
#: A hut in the lower arm, clear of every edge (and of Geoman's Finish/Cancel bar, which
#: opens beside the cut tool at the top left).
HUT_PX = [(200, 320), (300, 320), (300, 400), (200, 400)]


def cut_hole(page: Page, corners: list[tuple[int, int]]) -> None:
    page.get_by_role("button", name="Cut out a hole (pond, hut, tree)").click()
    for x, y in corners:
        click_map(page, x, y)
    click_map(page, *corners[0])


def assert_path_inside(plan: dict) -> None:
    """R1 on what the page was answered: lines, turns and headland passes in the field."""
    field = shape(plan["request"]["field"])
    frame = field_frame(field)
    grown = frame.to_local(field).buffer(0.01)
    pieces = [
        f
        for f in plan["geojson"]["features"]
        if f["properties"]["kind"] in ("line", "turn", "headland")
    ]
    assert pieces
    for feature in pieces:
        local = frame.to_local(shape(feature["geometry"]))
        assert grown.covers(local), f"{feature['properties']} leaves the field"


def test_drawn_l_field_with_a_hole_plans_inside_the_field(page: Page, tmp_path: Path) -> None:
    draw_field(page, L_FIELD_PX)
    cut_hole(page, HUT_PX)
    set_start_and_finish(page)
    page.get_by_label("Interval (m)").fill("4")

    plan = generate(page)

    field = shape(plan["request"]["field"])
    assert len(field.interiors) == 1, "the cut hole reached the planner"
    hull = field.convex_hull
    assert field.area < 0.8 * hull.area, "the field sent is the L, not its hull"
    assert_path_inside(plan)
    cells = [f for f in plan["geojson"]["features"] if f["properties"]["kind"] == "cell"]
    assert len(cells) >= 2, "an L with a hole is more than one cell"
    covered = shapely.union_all([shape(c["geometry"]) for c in cells])
    # The cells tile where the tractor may drive: the field less half its width round the
    # bund and the hut.
    assert covered.difference(field).area < 1e-6 * field.area, "the cells lie in the field"
    assert covered.area > 0.95 * field.area, "the cells tile the field, less a narrow band"
    expect(page.get_by_role("alert")).to_be_hidden()
    lines = int(figure(page, "Lines").inner_text())
    assert lines == plan["stats"]["line_count"] > 10

    page.get_by_label("Headland passes").select_option("1")
    with_headland = generate(page)
    assert_path_inside(with_headland)
    kinds = [f["properties"]["kind"] for f in with_headland["geojson"]["features"]]
    assert kinds.count("headland") >= 2, "one round outside and one round the hut"
    assert with_headland["stats"]["coverage_ratio"] >= plan["stats"]["coverage_ratio"]
    page.screenshot(path=str(tmp_path / "l-field.png"))
