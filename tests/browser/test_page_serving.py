"""How ``tillpath serve`` serves the map page and its libraries, checked over plain HTTP.

These share the browser suite's server (a real ``tillpath serve``), so they carry its marker.
"""

from __future__ import annotations

import html
import re
import urllib.error
import urllib.request

import pytest
from playwright.sync_api import expect

from app.testing import NO_TILES
from tests.browser.conftest import MapPageOpener

pytestmark = pytest.mark.browser


def fetch(url: str) -> tuple[int, str, str]:
    """Return status, content type and body of a GET (errors included)."""
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            body = response.read().decode("utf-8", errors="replace")
            return response.status, response.headers.get("content-type", ""), body
    except urllib.error.HTTPError as error:
        with error:
            return error.code, error.headers.get("content-type", ""), ""


def test_page_passes_api_and_tile_urls_from_settings(server_url: str) -> None:
    status, content_type, body = fetch(server_url + "/")

    assert status == 200
    assert content_type.startswith("text/html")
    attributes = dict(re.findall(r'data-([a-z-]+)="([^"]*)"', body))
    # Paths, not absolute URLs: the request's Host header cannot redirect the page.
    assert attributes["plans-url"] == "/api/plans"
    assert html.unescape(attributes["satellite-tile-url"]) == NO_TILES
    assert html.unescape(attributes["street-tile-url"]) == NO_TILES


@pytest.mark.parametrize(
    ("path", "kind"),
    [
        ("/vendor/leaflet/leaflet.js", "javascript"),
        ("/vendor/leaflet/leaflet.css", "text/css"),
        ("/vendor/leaflet/images/layers.png", "image/png"),
        ("/vendor/leaflet-geoman/leaflet-geoman.min.js", "javascript"),
        ("/vendor/leaflet-geoman/leaflet-geoman.css", "text/css"),
        ("/static/js/map.js", "javascript"),
        ("/static/css/app.css", "text/css"),
    ],
)
def test_page_assets_are_served_by_the_app(server_url: str, path: str, kind: str) -> None:
    status, content_type, _ = fetch(server_url + path)
    assert status == 200
    assert kind in content_type


@pytest.mark.parametrize(
    "path",
    [
        "/vendor/leaflet/package.json",
        "/vendor/leaflet/src/Leaflet.js",
        "/vendor/lodash/package.json",
    ],
)
def test_only_the_dist_folders_of_node_modules_are_served(server_url: str, path: str) -> None:
    status, _, _ = fetch(server_url + path)
    assert status == 404


def test_page_loads_no_code_from_elsewhere(server_url: str) -> None:
    _, _, body = fetch(server_url + "/")
    sources = re.findall(r'<(?:script|link|img)\b[^>]*?(?:src|href)="([^"]+)"', body)
    assert sources, "the page references no scripts or styles"
    outside = [url for url in sources if not url.startswith("/") or url.startswith("//")]
    assert outside == []


def test_api_docs_load_swagger_ui_from_the_app(server_url: str) -> None:
    status, content_type, body = fetch(server_url + "/docs")
    assert status == 200 and content_type.startswith("text/html")
    sources = re.findall(r'(?:src|href|url): ?["\']([^"\']+)["\']', body)
    sources += re.findall(r'<(?:script|link)\b[^>]*?(?:src|href)="([^"]+)"', body)
    assert any("swagger-ui-bundle.js" in url for url in sources)
    outside = [url for url in sources if not url.startswith("/") or url.startswith("//")]
    assert outside == []
    for url in sources:
        assert fetch(server_url + url)[0] == 200, url


def test_api_docs_render_offline(open_map: MapPageOpener, server_url: str) -> None:
    # open_map's context aborts and fails on any request that leaves the test server.
    page = open_map()
    page.goto(server_url + "/docs")
    expect(page.get_by_text("/api/plans/preview", exact=True)).to_be_visible(timeout=20_000)
