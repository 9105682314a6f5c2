"""Accounts on the page: the first account, signing in and out, and names shown as text."""

from __future__ import annotations

import json
import re
import urllib.request
import uuid
from collections.abc import Iterator
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, expect

from app.db import get_engine
from app.testing import TEST_PASSWORD, TEST_USERNAME, ServerUrl, running_server
from tests.browser.conftest import (
    DESKTOP,
    PAPER_FIELD,
    MapPageOpener,
    check_clean,
    open_context,
)

pytestmark = pytest.mark.browser

#: A plan name that would run script if the page ever set it as HTML.
HOSTILE_NAME = '<img src=x onerror="window.__xss=1"><script>window.__xss=2</script>&amp; "Sawah"'


def api(server_url: ServerUrl, method: str, path: str, body: Any = None) -> Any:
    data = None if body is None else json.dumps(body).encode()
    headers = {"Content-Type": "application/json", **server_url.headers}
    request = urllib.request.Request(server_url + path, data=data, method=method, headers=headers)
    with urllib.request.urlopen(request, timeout=30) as response:
        return json.loads(response.read())


@pytest.fixture(scope="module")
def empty_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ServerUrl]:
    """A server with no account at all, as after a fresh ``make run``."""
    workdir = tmp_path_factory.mktemp("empty")
    with running_server(
        f"sqlite:///{workdir / 't.db'}", log=workdir / "serve.log", first_account=False
    ) as url:
        yield url
    get_engine.cache_clear()


def test_first_visit_to_an_empty_server_creates_the_first_account(
    browser: Browser, empty_server: ServerUrl
) -> None:
    context = open_context(browser, empty_server, DESKTOP)
    try:
        page = context.new_page()
        page.page_errors = []  # type: ignore[attr-defined]
        page.on("pageerror", lambda error: page.page_errors.append(str(error)))  # type: ignore[attr-defined]
        page.goto(empty_server + "/")
        expect(page.get_by_role("heading", name="Create the first account")).to_be_visible()
        page.get_by_label("Username").fill("made")
        page.get_by_label("Password").fill("a long password")
        page.get_by_label("Organisation", exact=True).fill("Subak Ketewel")
        page.get_by_role("button", name="Create account").click()
        page.wait_for_selector("#app[data-ready='true']")
        expect(page.locator("#account-user")).to_have_text("made (owner)")
        expect(page.locator("#saved-empty")).to_be_visible()

        page.get_by_role("button", name="Sign out").click()
        expect(page.get_by_role("heading", name="Sign in")).to_be_visible()
        check_clean(context, [page])
    finally:
        context.close()


def test_sign_in_says_when_it_fails_then_signs_in(open_map: MapPageOpener) -> None:
    page = open_map(signed_in=False)
    expect(page.get_by_role("heading", name="Sign in")).to_be_visible()
    page.get_by_label("Username").fill(TEST_USERNAME)
    page.get_by_label("Password").fill("not the password")
    page.get_by_role("button", name="Sign in").click()
    expect(page.locator("#auth-error")).to_have_text("Username or password is wrong.")
    page.get_by_label("Password").fill(TEST_PASSWORD)
    page.get_by_role("button", name="Sign in").click()
    page.wait_for_selector("#app[data-ready='true']")
    expect(page.locator("#account-user")).to_have_text(f"{TEST_USERNAME} (owner)")
    expect(page.locator("#auth-screen")).to_be_hidden()


def test_plan_name_with_html_and_script_shows_as_text(
    open_map: MapPageOpener, server_url: ServerUrl
) -> None:
    # The paper field moved 1 km east: a field of its own, whatever other tests registered on
    # this server (a plan of a known field would be filed under that field's name).
    features = json.loads(PAPER_FIELD.read_text())["features"]
    (paper,) = (f["geometry"] for f in features if f["geometry"]["type"] == "Polygon")
    ring = [[lon + 0.01, lat] for lon, lat in paper["coordinates"][0]]
    field = {"type": "Polygon", "coordinates": [ring]}
    plan = api(
        server_url, "POST", "/api/plans", {"name": HOSTILE_NAME, "field": field, "interval_m": 4}
    )
    page: Page = open_map()
    saved = page.locator("#saved-plans")
    item = saved.locator(f"li[data-id='{plan['id']}']")
    expect(item.locator(".plan-name")).to_have_text(HOSTILE_NAME)
    fields = page.locator("#fields-list")
    expect(fields.locator(".plan-name", has_text="onerror").first).to_have_text(HOSTILE_NAME)
    item.get_by_role("button", name=f"Open {HOSTILE_NAME}").click()
    expect(page.get_by_label("Plan name")).to_have_value(HOSTILE_NAME)
    assert page.evaluate("window.__xss") is None
    assert saved.locator("img, script").count() == 0
    assert fields.locator("img, script").count() == 0


def test_settings_show_tokens_with_when_they_were_last_used(
    open_map: MapPageOpener, server_url: ServerUrl
) -> None:
    page = open_map()
    page.get_by_role("button", name="Settings").click()
    tokens = page.locator("#token-list")
    expect(tokens).to_contain_text("tests (personal")  # the harness's token, used above
    page.get_by_label("Token name").fill("tractor 7")
    page.get_by_label("Device token for a tractor's logger (posts fixes only)").check()
    page.get_by_role("button", name="Create token").click()
    token = page.locator("#token-value")
    expect(token).to_have_text(re.compile(r"^tp_[A-Za-z0-9_-]{40,}$"))
    expect(tokens).to_contain_text("tractor 7 (device")
    expect(tokens).to_contain_text("last used never")
    page.get_by_role("button", name="Revoke tractor 7").click()
    expect(page.get_by_role("button", name="Revoke tractor 7")).to_have_count(0)


def test_a_field_of_the_registry_is_planned_again_from_the_list(
    open_map: MapPageOpener, server_url: ServerUrl
) -> None:
    # A boundary of this test only: with the same boundary stored twice, a drawn plan is
    # attached to the older field.
    shift = int(uuid.uuid4().hex[:4], 16) * 1e-7
    polygon = json.loads(PAPER_FIELD.read_text())["features"][0]["geometry"]
    ring = [[lon + shift, lat] for lon, lat in polygon["coordinates"][0]]
    field = {"type": "Polygon", "coordinates": [ring]}
    name = f"Registry field {uuid.uuid4().hex[:6]}"
    made = api(server_url, "POST", "/api/fields", {"name": name, "boundary": field})
    page = open_map()
    item = page.locator(f"#fields-list li[data-id='{made['id']}']")
    expect(item.locator(".plan-meta")).to_have_text("0 plans")
    item.get_by_role("button", name=f"Plan {name}").click()
    expect(page.get_by_label("Plan name")).to_have_value(name)
    page.get_by_label("Interval (m)").fill("4")
    with page.expect_response(lambda r: r.url.endswith("/api/plans") and r.status == 201) as info:
        page.get_by_role("button", name="Save plan").click()
    saved = info.value.json()
    assert saved["field_id"] == made["id"]  # the same boundary: the registry's field, reused
    expect(item.locator(".plan-meta")).to_have_text("1 plan")
    # Deleting it asks what becomes of its plans; keeping them keeps the plan.
    item.get_by_role("button", name=f"Delete {name}").click()
    item.get_by_role("button", name="Delete field, keep plans").click()
    expect(page.locator(f"#fields-list li[data-id='{made['id']}']")).to_have_count(0)
    assert api(server_url, "GET", f"/api/plans/{saved['id']}")["field_id"] is None
