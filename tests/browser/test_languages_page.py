"""The page in Bahasa Indonesia: a browser set to ``id-ID`` sees Indonesian throughout.

The expected names come from the Indonesian catalog itself (app/i18n.py), so these tests check
that every control of product.md §6 is translated and shown translated, not a copy of the
translation.
"""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Page, expect

from app import i18n
from tests.browser.conftest import MapPageOpener
from tests.browser.test_map_page import FIELD_PX, click_map, import_paper_field

pytestmark = pytest.mark.browser

#: The controls of product.md §6, by their English accessible names.
INPUTS = ["Plan name", "Interval (m)", "Line angle (°)", "Objective", "Headland passes"]
BUTTONS = [
    "Draw field",
    "Set start",
    "Set finish",
    "Import field",
    "Generate path",
    "Save plan",
    "Simulate",
    "Upload track",
]


def id_(text: str) -> str:
    translated = i18n.gettext(text, "id")
    assert translated != text, f"{text!r} has no Indonesian translation"
    return translated


@pytest.fixture
def id_page(open_map: MapPageOpener) -> Page:
    return open_map(locale="id-ID")


def test_indonesian_browser_gets_every_control_in_indonesian(id_page: Page) -> None:
    page = id_page
    expect(page.locator("html")).to_have_attribute("lang", "id")
    for label in INPUTS:
        expect(page.get_by_label(id_(label), exact=True)).to_be_visible()
    for name in BUTTONS:
        expect(page.get_by_role("button", name=id_(name), exact=True)).to_be_attached()
    expect(page.get_by_role("region", name=id_("Plan summary"))).to_be_visible()
    expect(page.get_by_role("list", name=id_("Saved plans"))).to_be_attached()
    expect(page.get_by_role("button", name=id_("Show my location"))).to_be_visible()
    expect(page.get_by_role("button", name=id_("Zoom in"))).to_be_visible()
    expect(page.get_by_placeholder(id_("automatic"))).to_be_visible()
    # The workspace's controls too (issue 11's account card and field registry).
    expect(page.get_by_role("button", name=id_("Sign out"), exact=True)).to_be_visible()
    expect(page.get_by_role("heading", name=id_("Fields"), exact=True)).to_be_visible()
    # The drawing tool speaks Indonesian too, in our words (setLang).
    expect(page.get_by_role("button", name=id_("Cut out a hole (pond, hut, tree)"))).to_be_visible()
    # No English control name is left on the page.
    body = page.locator("#app").inner_text()
    for english in ["Generate path", "Draw field", "Plan summary", "Saved plans", "Interval"]:
        assert english not in body


def test_indonesian_numbers_and_figures(id_page: Page) -> None:
    page = id_page
    shown = page.evaluate(
        """async () => {
            const f = await import("/static/js/format.js");
            return [f.formatArea(39600), f.formatPercent(0.99685), f.formatLength(2500),
                    f.formatDuration(217.5), f.formatArea(302.6)];
        }"""
    )
    assert shown == ["3,96 ha", "99,7 %", "2,50 km", "3:38 menit", "302,6 m² (0,030 ha)"]

    import_paper_field_id(page)
    page.get_by_role("button", name=id_("Generate path"), exact=True).click()
    summary = page.get_by_role("region", name=id_("Plan summary"))
    area = summary.locator(f"xpath=.//dt[normalize-space()='{id_('Area')}']/following-sibling::dd")
    expect(area).to_have_text(re.compile(r"^30[23],\d m² \(0,030 ha\)$"))
    coverage = summary.locator(
        f"xpath=.//dt[normalize-space()='{id_('Coverage')}']/following-sibling::dd"
    )
    expect(coverage).to_have_text(re.compile(r"^\d+,\d %$"))


def import_paper_field_id(page: Page) -> None:
    from tests.browser.conftest import PAPER_FIELD

    with page.expect_file_chooser() as chooser:
        page.get_by_role("button", name=id_("Import field"), exact=True).click()
    chooser.value.set_files(PAPER_FIELD)
    expect(page.get_by_label(id_("Interval (m)"))).to_have_value("4")


def test_api_refusal_is_shown_in_indonesian_with_the_indonesian_label(id_page: Page) -> None:
    page = id_page
    import_paper_field_id(page)
    page.get_by_label(id_("Interval (m)")).fill("0")
    with page.expect_response("**/api/plans/preview") as answer:
        page.get_by_role("button", name=id_("Generate path"), exact=True).click()
    assert answer.value.status == 422
    alert = page.get_by_role("alert")
    expect(alert).to_contain_text(f"{id_('Interval (m)')}: harus antara 0,2 dan 50 m")
    expect(alert).not_to_contain_text("must be")


def test_drawing_tooltip_is_indonesian(id_page: Page) -> None:
    page = id_page
    page.get_by_role("button", name=id_("Draw field"), exact=True).click()
    click_map(page, *FIELD_PX[0])
    tooltip = page.locator(".leaflet-tooltip").last
    expect(tooltip).to_have_text(id_("Click the next corner"))


def test_language_switch_is_remembered(open_map: MapPageOpener) -> None:
    page = open_map(locale="id-ID")
    import_paper_field_id(page)
    page.get_by_label(id_("Language")).select_option("en")
    page.wait_for_selector("html[lang='en']")
    page.wait_for_selector("#app[data-ready='true']")
    expect(page.get_by_role("button", name="Generate path", exact=True)).to_be_attached()
    # The draft came through the reload the switch made.
    expect(page.get_by_label("Interval (m)")).to_have_value("4")
    page.reload()
    page.wait_for_selector("#app[data-ready='true']")
    expect(page.locator("html")).to_have_attribute("lang", "en")
    page.get_by_label("Language").select_option("id")
    page.wait_for_selector("html[lang='id']")


def test_english_browser_says_click_and_a_touch_screen_says_tap(
    open_map: MapPageOpener, page: Page
) -> None:
    expect(page.get_by_text("Click the field's corners on the map", exact=False)).to_be_visible()
    expect(page.get_by_text("Tap the field's corners on the map", exact=False)).to_be_hidden()
    phone = open_map({"width": 390, "height": 844}, is_mobile=True, has_touch=True)
    phone.get_by_role("button", name="Controls", exact=True).click()
    expect(phone.get_by_text("Tap the field's corners on the map", exact=False)).to_be_visible()
    expect(phone.get_by_text("Click the field's corners on the map", exact=False)).to_be_hidden()
    import_paper_field(phone)
    phone.get_by_role("button", name="Set start", exact=True).click()
    expect(phone.locator("#status")).to_have_text("Tap the map where the tractor starts.")


def test_sign_in_screen_speaks_indonesian_and_says_what_went_wrong(
    open_map: MapPageOpener,
) -> None:
    page = open_map(signed_in=False, locale="id-ID", has_touch=True, is_mobile=True)
    screen = page.locator("#auth-screen")
    expect(screen).to_be_visible()
    expect(screen.get_by_role("heading", name=id_("Sign in"))).to_be_visible()
    page.get_by_label(id_("Username")).fill("nobody")
    page.get_by_label(id_("Password")).fill("not the password")
    with page.expect_response("**/api/auth/login") as answer:
        screen.get_by_role("button", name=id_("Sign in")).click()
    assert answer.value.status == 401
    expect(page.locator("#auth-error")).to_have_text("Nama pengguna atau kata sandi salah.")
    for control in ["#auth-username", "#auth-password", "#auth-submit"]:
        box = page.locator(control).bounding_box()
        assert box is not None and box["height"] >= 44, control
