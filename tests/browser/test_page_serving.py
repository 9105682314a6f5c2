"""How ``tillpath serve`` serves the map page and its libraries, checked over plain HTTP.

These share the browser suite's server (a real ``tillpath serve``), so they carry its marker.
"""

from __future__ import annotations

import html
import re
import urllib.error
import urllib.request

import pytest

from tests.browser.conftest import NO_TILES

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
    assert attributes["plans-url"] == f"{server_url}/api/plans"
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
    outside = [url for url in sources if not url.startswith(server_url + "/")]
    assert outside == []
