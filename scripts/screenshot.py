"""Take the README's screenshot of the map page with a saved plan: ``docs/screenshot.png``.

Starts ``tillpath serve`` on a free loopback port with a throw-away SQLite database and no map
tiles (nothing leaves the machine, so the map background is blank), imports a small rice field
near Ketewel, Bali, plans it with one headland pass, saves it and photographs the page in
Debian's headless Chromium.

Run from the repository root::

    .venv/bin/python scripts/screenshot.py [-o docs/screenshot.png]
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

from playwright.sync_api import Page, sync_playwright

from app.testing import CHROMIUM_ARGS, TEST_PASSWORD, TEST_USERNAME, running_server

REPO = Path(__file__).resolve().parents[1]

#: A five-cornered sawah of about 0.26 ha beside the paper's field, with the tractor's way in
#: and out at the road to the south.
FIELD = {
    "type": "FeatureCollection",
    "name": "Sawah Pak Made, Ketewel",
    "features": [
        {
            "type": "Feature",
            "properties": {"role": "field", "interval_m": 4},
            "geometry": {
                "type": "Polygon",
                "coordinates": [
                    [
                        [115.29842, -8.62628],
                        [115.29893, -8.62622],
                        [115.29899, -8.62661],
                        [115.29866, -8.62668],
                        [115.29846, -8.62664],
                        [115.29842, -8.62628],
                    ]
                ],
            },
        },
        {
            "type": "Feature",
            "properties": {"role": "start"},
            "geometry": {"type": "Point", "coordinates": [115.29838, -8.62674]},
        },
        {
            "type": "Feature",
            "properties": {"role": "finish"},
            "geometry": {"type": "Point", "coordinates": [115.29906, -8.62674]},
        },
    ],
}


def make_plan(page: Page, base_url: str) -> None:
    """Import the field, plan it with a headland pass and save it, as a person would."""
    login = {"username": TEST_USERNAME, "password": TEST_PASSWORD}
    page.request.post(base_url + "/api/auth/login", data=login)
    page.goto(base_url + "/")
    page.wait_for_selector("#app[data-ready='true']")
    with page.expect_file_chooser() as chooser:
        page.get_by_role("button", name="Import field", exact=True).click()
    chooser.value.set_files(
        files=[
            {
                "name": "sawah-pak-made.geojson",
                "mimeType": "application/geo+json",
                "buffer": json.dumps(FIELD).encode(),
            }
        ]
    )
    page.get_by_label("Headland passes").select_option("0")
    page.get_by_label("Plan name").fill(FIELD["name"])
    with page.expect_response(lambda r: r.url.endswith("/api/plans") and r.status == 201):
        page.get_by_role("button", name="Save plan", exact=True).click()
    page.get_by_role("link", name="GPX", exact=True).wait_for()
    # Show the figures and the downloads: the part of the panel a reader wants to see.
    page.locator("#summary").evaluate("el => el.scrollIntoView({block: 'start'})")
    page.evaluate("document.activeElement && document.activeElement.blur()")
    page.wait_for_timeout(300)  # let the status pill and the arrows settle


def main() -> None:
    """Take the screenshot."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=REPO / "docs" / "screenshot.png")
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=760)
    args = parser.parse_args()
    chromium = shutil.which("chromium") or "/usr/bin/chromium"
    with (
        tempfile.TemporaryDirectory() as tmp,
        running_server(f"sqlite:///{Path(tmp) / 'shot.db'}", serve_args=["--no-access-log"]) as url,
        sync_playwright() as playwright,
    ):
        browser = playwright.chromium.launch(executable_path=chromium, args=list(CHROMIUM_ARGS))
        page = browser.new_page(
            viewport={"width": args.width, "height": args.height}, device_scale_factor=1
        )
        make_plan(page, url)
        args.output.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=args.output)
        browser.close()
    print(f"wrote {args.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
