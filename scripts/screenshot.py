"""Take the README's screenshots of the map page with a saved plan.

Starts ``tillpath serve`` on a free loopback port with a throw-away SQLite database and no map
tiles (nothing leaves the machine, so the map background is blank and the page says the map
pictures are missing), imports a small rice field near Ketewel, Bali, plans it, saves it,
simulates it and photographs the page in Debian's headless Chromium: on a desktop, or with
``--phone`` on a 390 × 844 touch screen, where the sheet folds to show the path.

Run from the repository root (``make screenshot`` takes all three)::

    .venv/bin/python scripts/screenshot.py [-o docs/screenshot.png]
    .venv/bin/python scripts/screenshot.py --phone --lang id -o docs/phone-id.png
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


#: The names of the controls the script presses, per language (the catalog's translations).
NAMES = {
    "en": {
        "import": "Import field",
        "save": "Save plan",
        "simulate": "Simulate",
        "menu": "Controls",
    },
    "id": {
        "import": "Buka berkas sawah",
        "save": "Simpan rencana",
        "simulate": "Simulasikan",
        "menu": "Menu",
    },
}


def make_plan(page: Page, base_url: str, *, lang: str = "en", phone: bool = False) -> None:
    """Import the field, plan it, save it and simulate it, as a person would."""
    names = NAMES[lang]
    login = {"username": TEST_USERNAME, "password": TEST_PASSWORD}
    page.request.post(base_url + "/api/auth/login", data=login)
    page.goto(base_url + "/")
    page.wait_for_selector("#app[data-ready='true']")
    if phone:
        page.get_by_role("button", name=names["menu"], exact=True).click()
    with page.expect_file_chooser() as chooser:
        page.get_by_role("button", name=names["import"], exact=True).click()
    chooser.value.set_files(
        files=[
            {
                "name": "sawah-pak-made.geojson",
                "mimeType": "application/geo+json",
                "buffer": json.dumps(FIELD).encode(),
            }
        ]
    )
    page.locator("#headland").select_option("0")
    page.locator("#plan-name").fill(FIELD["name"])
    with page.expect_response(lambda r: r.url.endswith("/api/plans") and r.status == 201):
        page.get_by_role("button", name=names["save"], exact=True).click()
    if phone:
        # The sheet folded to show the path; the status says how to bring it back.
        page.wait_for_timeout(500)
        return
    page.get_by_role("link", name="GPX", exact=True).wait_for()
    with page.expect_response(lambda r: "/simulations" in r.url and r.status == 201):
        page.get_by_role("button", name=names["simulate"], exact=True).click()
    # The notice that the map pictures are missing is true here, but covers the path.
    page.locator("#tile-dismiss").click()
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
    parser.add_argument("--phone", action="store_true", help="390 × 844, touch")
    parser.add_argument("--lang", choices=sorted(NAMES), default="en")
    args = parser.parse_args()
    chromium = shutil.which("chromium") or "/usr/bin/chromium"
    with (
        tempfile.TemporaryDirectory() as tmp,
        running_server(f"sqlite:///{Path(tmp) / 'shot.db'}", serve_args=["--no-access-log"]) as url,
        sync_playwright() as playwright,
    ):
        browser = playwright.chromium.launch(executable_path=chromium, args=list(CHROMIUM_ARGS))
        locale = {"en": "en-GB", "id": "id-ID"}[args.lang]
        if args.phone:
            page = browser.new_page(
                viewport={"width": 390, "height": 844},
                device_scale_factor=1,
                is_mobile=True,
                has_touch=True,
                locale=locale,
            )
        else:
            page = browser.new_page(
                viewport={"width": args.width, "height": args.height},
                device_scale_factor=1,
                locale=locale,
            )
        make_plan(page, url, lang=args.lang, phone=args.phone)
        args.output.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=args.output)
        browser.close()
    print(f"wrote {args.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
