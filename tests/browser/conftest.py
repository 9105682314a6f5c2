"""Fixtures for the browser tests: a real ``tillpath serve`` and Debian's headless Chromium.

The server runs in a subprocess on a free loopback port with its own SQLite file, exactly as a
person would start it, and the browser may talk to nothing but that server: every other request
is aborted and recorded, and a test that caused one fails.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Protocol

import pytest
from playwright.sync_api import Browser, BrowserContext, Page, Playwright, Route, sync_playwright

REPO = Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"
PAPER_FIELD = SHARED / "fields" / "paper_ketewel.geojson"
GPX_SCHEMA = SHARED / "schemas" / "gpx-1.1.xsd"

#: Port 9 (discard) on loopback: Chromium refuses it outright, so tiles never leave the machine.
NO_TILES = "http://127.0.0.1:9/{z}/{x}/{y}.png"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
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


def free_port() -> int:
    """Return a TCP port on 127.0.0.1 that nothing listens on right now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


def tillpath_command() -> list[str]:
    """Return the ``tillpath`` command of this virtual environment.

    ``make install`` puts the console script beside the interpreter; before the project is
    installed, the same entry point runs through the interpreter.
    """
    script = Path(sys.executable).with_name("tillpath")
    if script.is_file():
        return [str(script)]
    return [sys.executable, "-c", "from app.cli import main; main()"]


def wait_for_health(url: str, process: subprocess.Popen[bytes], log: Path) -> None:
    """Poll ``url`` until it answers 200, failing if the server dies or takes too long."""
    deadline = time.monotonic() + SERVER_START_TIMEOUT_S
    while time.monotonic() < deadline:
        if process.poll() is not None:
            pytest.fail(f"tillpath serve exited with {process.returncode}:\n{log.read_text()}")
        try:
            with urllib.request.urlopen(url, timeout=2) as response:
                if response.status == 200:
                    return
        except (urllib.error.URLError, ConnectionError, TimeoutError):
            pass
        time.sleep(0.2)
    pytest.fail(
        f"tillpath serve did not answer {url} in {SERVER_START_TIMEOUT_S} s:\n{log.read_text()}"
    )


@pytest.fixture(scope="session")
def server_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """Start ``tillpath serve`` on a fresh SQLite database; yield its base URL."""
    workdir = tmp_path_factory.mktemp("server")
    log = workdir / "serve.log"
    port = free_port()
    env = {
        **os.environ,
        "TILLPATH_DATABASE_URL": f"sqlite:///{workdir / 't.db'}",
        "TILLPATH_SATELLITE_TILE_URL": NO_TILES,
        "TILLPATH_STREET_TILE_URL": NO_TILES,
    }
    command = [*tillpath_command(), "serve", "--host", "127.0.0.1", "--port", str(port)]
    with log.open("wb") as log_file:
        process = subprocess.Popen(command, cwd=REPO, env=env, stdout=log_file, stderr=log_file)
    base = f"http://127.0.0.1:{port}"
    try:
        wait_for_health(f"{base}/api/health", process, log)
        yield base
    finally:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


@pytest.fixture(scope="session")
def playwright() -> Iterator[Playwright]:
    with sync_playwright() as p:
        yield p


@pytest.fixture(scope="session")
def browser(playwright: Playwright) -> Iterator[Browser]:
    browser = playwright.chromium.launch(executable_path=chromium_path(), args=CHROMIUM_ARGS)
    yield browser
    browser.close()


def open_context(
    browser: Browser, server_url: str, viewport: dict[str, int], **options: Any
) -> BrowserContext:
    """Return a fresh context (no storage) that only reaches ``server_url``."""
    context = browser.new_context(
        viewport=viewport, accept_downloads=True, locale="en-GB", **options
    )
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
    """Opens the map page in a fresh browser context: ``open_map(viewport, **context_options)``."""

    def __call__(self, viewport: dict[str, int] = ..., **options: Any) -> Page: ...


@pytest.fixture
def open_map(browser: Browser, server_url: str) -> Iterator[MapPageOpener]:
    """Open the map page in fresh contexts; at the end, check them and close them."""
    contexts: list[BrowserContext] = []

    def opener(viewport: dict[str, int] = DESKTOP, **options: Any) -> Page:
        context = open_context(browser, server_url, viewport, **options)
        contexts.append(context)
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
