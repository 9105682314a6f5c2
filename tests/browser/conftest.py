"""Fixtures for the browser tests: a real ``tillpath serve`` and Debian's headless Chromium.

The server runs in a subprocess on a free loopback port with its own SQLite file, exactly as a
person would start it, and the browser may talk to nothing but that server: every other request
is aborted and recorded, and a test that caused one fails.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Protocol

import pytest
from playwright.sync_api import Browser, BrowserContext, Page, Playwright, Route, sync_playwright

from app.testing import CHROMIUM_ARGS, TEST_PASSWORD, TEST_USERNAME, ServerUrl, running_server

SHARED = Path(__file__).resolve().parents[3] / "shared"
PAPER_FIELD = SHARED / "fields" / "paper_ketewel.geojson"
GPX_SCHEMA = SHARED / "schemas" / "gpx-1.1.xsd"

SERVER_START_TIMEOUT_S = 60.0
DESKTOP = {"width": 1280, "height": 800}


def chromium_path() -> str:
    """Return Debian's Chromium, failing (never skipping) the tests when it is missing."""
    found = os.environ.get("TILLPATH_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
    if not Path(found).is_file():
        pytest.fail(
            f"Chromium not found ({found}): the browser tests need it. "
            "Install it with `apt-get install chromium` (scripts/ensure-chromium does)."
        )
    return found


@pytest.fixture(scope="session")
def server_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ServerUrl]:
    """Start ``tillpath serve`` on a fresh SQLite database with a first account; yield its URL."""
    workdir = tmp_path_factory.mktemp("server")
    with running_server(
        f"sqlite:///{workdir / 't.db'}",
        log=workdir / "serve.log",
        timeout_s=SERVER_START_TIMEOUT_S,
    ) as base:
        yield base


@pytest.fixture(scope="module")
def playwright() -> Iterator[Playwright]:
    with sync_playwright() as p:
        yield p


@pytest.fixture(scope="module")
def browser(playwright: Playwright) -> Iterator[Browser]:
    browser = playwright.chromium.launch(executable_path=chromium_path(), args=list(CHROMIUM_ARGS))
    yield browser
    browser.close()


def open_context(
    browser: Browser, server_url: str, viewport: dict[str, int], **options: Any
) -> BrowserContext:
    """Return a fresh context (no storage) that only reaches ``server_url``."""
    options.setdefault("locale", "en-GB")
    context = browser.new_context(viewport=viewport, accept_downloads=True, **options)
    context.outside_requests = []  # type: ignore[attr-defined]

    def guard(route: Route) -> None:
        url = route.request.url
        if url.startswith(server_url + "/"):
            route.continue_()
            return
        if not url.startswith("http://127.0.0.1:9/"):  # the refused tile server is expected
            context.outside_requests.append(url)  # type: ignore[attr-defined]
        route.abort()

    context.route("**/*", guard)
    return context


def sign_in(
    context: BrowserContext,
    server_url: str,
    username: str = TEST_USERNAME,
    password: str = TEST_PASSWORD,
) -> None:
    """Sign the context in as the page would (``POST /api/auth/login``; the cookie is kept)."""
    response = context.request.post(
        server_url + "/api/auth/login", data={"username": username, "password": password}
    )
    assert response.status == 200, response.text()


def open_page(context: BrowserContext, server_url: str) -> Page:
    """Open the map page and wait until its script is ready."""
    page = context.new_page()
    page.page_errors = []  # type: ignore[attr-defined]
    page.on("pageerror", lambda error: page.page_errors.append(str(error)))  # type: ignore[attr-defined]
    page.goto(server_url + "/")
    page.wait_for_selector("#app[data-ready='true']")
    return page


def check_clean(context: BrowserContext, pages: list[Page]) -> None:
    """Fail on uncaught JavaScript errors or on requests that left the test server."""
    errors = [error for page in pages for error in page.page_errors]  # type: ignore[attr-defined]
    assert errors == [], f"JavaScript errors on the page: {errors}"
    outside = context.outside_requests  # type: ignore[attr-defined]
    assert outside == [], f"the page tried to reach outside the test server: {outside}"


class MapPageOpener(Protocol):
    """Opens the map page in a fresh, signed-in browser context.

    ``open_map(viewport, signed_in=True, **context_options)``; with ``signed_in=False`` the
    page is left at its sign-in screen (not waited for as ready).
    """

    def __call__(
        self, viewport: dict[str, int] = ..., *, signed_in: bool = ..., **options: Any
    ) -> Page: ...


@pytest.fixture
def open_map(browser: Browser, server_url: str) -> Iterator[MapPageOpener]:
    """Open the map page in fresh contexts; at the end, check them and close them."""
    contexts: list[BrowserContext] = []

    def opener(
        viewport: dict[str, int] = DESKTOP, *, signed_in: bool = True, **options: Any
    ) -> Page:
        context = open_context(browser, server_url, viewport, **options)
        contexts.append(context)
        if not signed_in:
            page = context.new_page()
            page.page_errors = []  # type: ignore[attr-defined]
            page.on("pageerror", lambda error: page.page_errors.append(str(error)))  # type: ignore[attr-defined]
            page.goto(server_url + "/")
            return page
        sign_in(context, server_url)
        return open_page(context, server_url)

    yield opener
    try:
        for context in contexts:
            check_clean(context, context.pages)
    finally:
        for context in contexts:
            context.close()


@pytest.fixture
def page(open_map: MapPageOpener) -> Page:
    """The map page on a desktop screen (1280 × 800)."""
    return open_map()


@pytest.fixture
def phone_page(open_map: MapPageOpener) -> Page:
    """The map page on a phone-sized screen (390 × 844, touch)."""
    return open_map({"width": 390, "height": 844}, is_mobile=True, has_touch=True)
