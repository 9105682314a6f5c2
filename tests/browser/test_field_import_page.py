"""Importing field files on the map page: Google Earth KML, a zipped UTM Shapefile, 30 fields."""

from __future__ import annotations

from pathlib import Path

import pytest
from playwright.sync_api import Page, expect

from planner import plan_coverage
from planner.io import read_fields
from tests.browser.test_map_page import button, figure, generate
from tests.conftest import FIELDS_DIR
from tests.planner.field_files import kml_bytes, shared_polygon, zipped_utm_shapefile_bytes

pytestmark = pytest.mark.browser


def choose_file(page: Page, name: str, data: bytes, mime: str) -> None:
    with page.expect_file_chooser() as chooser:
        button(page, "Import field").click()
    chooser.value.set_files(files=[{"name": name, "mimeType": mime, "buffer": data}])


@pytest.mark.parametrize(
    ("name", "mime", "maker"),
    [
        ("field.kml", "application/vnd.google-earth.kml+xml", kml_bytes),
        ("field_utm.zip", "application/zip", zipped_utm_shapefile_bytes),
    ],
)
def test_kml_and_zipped_utm_shapefile_import_and_plan_as_the_cli(
    page: Page, tmp_path: Path, name: str, mime: str, maker: object
) -> None:
    polygon = shared_polygon("rwanda-3")
    data = maker(tmp_path, polygon)  # type: ignore[operator]
    (spec,) = read_fields(data, filename=name)
    expected = plan_coverage(spec.field_lonlat, interval_m=8.0)
    choose_file(page, name, data, mime)
    expect(page.get_by_role("status")).to_contain_text(f"Imported {name}")
    page.get_by_label("Interval (m)").fill("8")
    plan = generate(page)
    assert plan["stats"]["line_count"] == expected.stats.line_count
    expect(figure(page, "Lines")).to_have_text(str(expected.stats.line_count))
    expect(page.get_by_role("alert")).to_be_hidden()


def test_a_thirty_field_file_lists_all_thirty_to_choose_from(page: Page) -> None:
    data = (FIELDS_DIR / "rwanda_2021.geojson").read_bytes()
    choose_file(page, "rwanda_2021.geojson", data, "application/geo+json")
    chooser = page.locator("#field-chooser")
    expect(chooser.get_by_role("heading")).to_have_text(
        "rwanda_2021.geojson holds 30 fields: choose one"
    )
    expect(chooser.locator("button.field-choice")).to_have_count(30)
    expect(page.locator("path.field-choice-shape")).to_have_count(30)
    chooser.get_by_role("button", name="rwanda_2021-5").click()
    expect(chooser).to_have_count(0)
    expect(page.locator("path.field-choice-shape")).to_have_count(0)
    expect(page.get_by_label("Plan name")).to_have_value("rwanda_2021-5")
    page.get_by_label("Interval (m)").fill("6")
    plan = generate(page)
    fields = read_fields(data, filename="rwanda_2021.geojson")
    expected = plan_coverage(fields[5].field_lonlat, interval_m=6.0)
    assert plan["stats"]["line_count"] == expected.stats.line_count


def test_a_field_is_chosen_by_clicking_it_on_the_map(page: Page) -> None:
    data = (FIELDS_DIR / "rwanda_2021.geojson").read_bytes()
    choose_file(page, "rwanda_2021.geojson", data, "application/geo+json")
    shapes = page.locator("path.field-choice-shape")
    expect(shapes).to_have_count(30)
    shapes.nth(2).click()  # rwanda_2021-2 is convex: its middle is inside it
    expect(page.locator("#field-chooser")).to_have_count(0)
    expect(page.get_by_label("Plan name")).to_have_value("rwanda_2021-2")


def test_all_thirty_fields_are_added_to_the_registry_from_the_chooser(page: Page) -> None:
    data = (FIELDS_DIR / "rwanda_2021.geojson").read_bytes()
    choose_file(page, "rwanda_2021.geojson", data, "application/geo+json")
    with page.expect_response("**/api/fields/import") as answer:
        page.get_by_role("button", name="Add all 30 to my fields").click()
    assert answer.value.status == 201, answer.value.text()
    expect(page.get_by_role("status")).to_contain_text("Added 30 fields of rwanda_2021.geojson")
    expect(page.locator("#field-chooser")).to_have_count(1)  # still open to pick one to plan
