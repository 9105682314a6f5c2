"""What the page and a simulation cost on a rural mobile link: bytes over the wire.

- the map page's first load in Chromium, as transferred (Chrome DevTools' ``encodedDataLength``:
  headers and compressed bodies), with an empty cache (product.md §11: ≤ 250 KB);
- a 4 ha field's simulation as the API sends it, with and without gzip, in full and thinned
  for drawing (``?tracks=display``): submitted as a job (``POST /api/plans/{id}/simulations``,
  202), followed (``GET /api/jobs/{id}``) and fetched when done (``GET /api/simulations/{id}``).

Run from the repository root (starts its own server unless ``--url`` is given)::

    .venv/bin/python -m bench.bench_page [--url http://127.0.0.1:8000]

``make bench`` includes it (``run()``).
"""

from __future__ import annotations

import argparse
import gzip
import json
import math
import shutil
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from playwright.sync_api import sync_playwright

from app.testing import CHROMIUM_ARGS, TEST_PASSWORD, TEST_USERNAME, running_server

#: The signed-in session of the API calls (cookie jar) and its CSRF token.
_OPENER = urllib.request.build_opener(urllib.request.HTTPCookieProcessor())
_CSRF: dict[str, str] = {}


def log_in(base: str) -> None:
    """Sign in as the test user ``running_server`` creates (a server before accounts: no-op)."""
    body = json.dumps({"username": TEST_USERNAME, "password": TEST_PASSWORD}).encode()
    request = urllib.request.Request(
        f"{base}/api/auth/login", data=body, headers={"Content-Type": "application/json"}
    )
    try:
        with _OPENER.open(request, timeout=30) as response:
            token = json.loads(response.read()).get("csrf_token")
            if token:
                _CSRF["X-CSRF-Token"] = token
    except urllib.error.HTTPError:
        pass


#: A 200 m × 200 m square (4 ha) at Ketewel, Bali, planned at 4 m: 50 lines.
LAT0, LON0 = -8.6264, 115.2981
SIDE_M = 200.0


def four_hectare_field() -> dict[str, Any]:
    """A square of 4 ha as a GeoJSON Polygon."""
    dlat = SIDE_M / 111_320.0
    dlon = SIDE_M / (111_320.0 * math.cos(math.radians(LAT0)))
    ring = [
        [LON0, LAT0],
        [LON0 + dlon, LAT0],
        [LON0 + dlon, LAT0 + dlat],
        [LON0, LAT0 + dlat],
        [LON0, LAT0],
    ]
    return {"type": "Polygon", "coordinates": [ring]}


def post(url: str, body: dict[str, Any] | None, *, gzip_ok: bool) -> tuple[int, bytes, str]:
    """POST JSON; return status, the raw body as sent and its Content-Encoding."""
    data = json.dumps(body or {}).encode()
    headers = {"Content-Type": "application/json", **_CSRF}
    if gzip_ok:
        headers["Accept-Encoding"] = "gzip"
    request = urllib.request.Request(url, data=data, headers=headers, method="POST")
    with _OPENER.open(request, timeout=120) as response:
        return response.status, response.read(), response.headers.get("content-encoding", "")


def get(url: str, *, gzip_ok: bool) -> tuple[bytes, str]:
    """GET; return the raw body as sent and its Content-Encoding."""
    headers = {"Accept-Encoding": "gzip"} if gzip_ok else {}
    with _OPENER.open(urllib.request.Request(url, headers=headers), timeout=60) as r:
        return r.read(), r.headers.get("content-encoding", "")


#: How often the job is asked after, as the page does (static/js/jobs.js) [s].
JOB_POLL_S = 0.25
#: How long a 4 ha simulation may take before the benchmark gives up [s].
JOB_TIMEOUT_S = 300.0


def follow_job(base: str, job: dict[str, Any]) -> dict[str, Any]:
    """Poll ``GET /api/jobs/{id}`` until the job is done, as the page does (product.md §13).

    Raises
    ------
    RuntimeError
        If the job fails, is cancelled or is not done within :data:`JOB_TIMEOUT_S`.
    """
    deadline = time.monotonic() + JOB_TIMEOUT_S
    while job["status"] != "done":
        if job["status"] in ("failed", "cancelled"):
            raise RuntimeError(f"simulation job {job['id']} {job['status']}: {job.get('error')}")
        if time.monotonic() > deadline:
            raise RuntimeError(f"simulation job {job['id']} not done in {JOB_TIMEOUT_S:g} s")
        time.sleep(JOB_POLL_S)
        body, _ = get(f"{base}/api/jobs/{job['id']}", gzip_ok=False)
        job = json.loads(body)
    return job


def simulation_sizes(base: str) -> dict[str, int]:
    """Bytes of a 4 ha simulation answer: full and display, with and without gzip.

    A simulation is a background job: it is submitted (202, the job), followed until done,
    and the stored simulation its result names is then fetched, as the page does.
    """
    log_in(base)
    _, plan_body, _ = post(
        f"{base}/api/plans",
        {"name": "4 ha", "field": four_hectare_field(), "interval_m": 4},
        gzip_ok=False,
    )
    plan = json.loads(plan_body)
    sizes: dict[str, int] = {}
    _, started, _ = post(f"{base}/api/plans/{plan['id']}/simulations", {"seed": 1}, gzip_ok=False)
    sizes["simulation job, as submitted (202), identity"] = len(started)
    job = follow_job(base, json.loads(started))
    sim_url = f"{base}/api/simulations/{job['result']['simulation_id']}"
    full, _ = get(sim_url, gzip_ok=False)
    sizes["simulation, full, identity"] = len(full)
    sizes["simulation, full, gzip (computed)"] = len(gzip.compress(full))
    body, encoding = get(sim_url, gzip_ok=True)
    sizes[f"GET simulation, full, as sent ({encoding or 'identity'})"] = len(body)
    try:
        body, encoding = get(f"{sim_url}?tracks=display", gzip_ok=True)
        thinned = gzip.decompress(body) if encoding == "gzip" else body
        if len(thinned) < len(full):  # an older server ignores the parameter
            sizes[f"GET simulation, display, as sent ({encoding or 'identity'})"] = len(body)
            sizes["GET simulation, display, identity"] = len(thinned)
    except urllib.error.HTTPError:
        pass
    gpx, encoding = get(f"{sim_url}/export/gpx", gzip_ok=False)
    sizes["simulation GPX export, identity"] = len(gpx)
    return sizes


def page_weight(base: str) -> dict[str, int]:
    """Bytes Chromium transfers for the page's first load (empty cache), by kind."""
    chromium = shutil.which("chromium") or "/usr/bin/chromium"
    totals: dict[str, int] = {}
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=list(CHROMIUM_ARGS))
        context = browser.new_context(viewport={"width": 390, "height": 844}, locale="id-ID")
        # Tiles come from elsewhere and are not the page's weight.
        context.route(
            "**/*",
            lambda route: (
                route.continue_() if route.request.url.startswith(base) else route.abort()
            ),
        )
        login = {"username": TEST_USERNAME, "password": TEST_PASSWORD}
        context.request.post(base + "/api/auth/login", data=login)
        page = context.new_page()
        cdp = context.new_cdp_session(page)
        cdp.send("Network.enable")
        cdp.send("Network.setCacheDisabled", {"cacheDisabled": True})
        urls: dict[str, str] = {}
        sizes: dict[str, int] = {}
        cdp.on(
            "Network.requestWillBeSent",
            lambda e: urls.__setitem__(e["requestId"], e["request"]["url"]),
        )
        cdp.on(
            "Network.loadingFinished",
            lambda e: sizes.__setitem__(e["requestId"], int(e["encodedDataLength"])),
        )
        page.goto(base + "/")
        page.wait_for_selector("#app[data-ready='true']")
        page.wait_for_load_state("networkidle")
        for request_id, size in sizes.items():
            url = urls.get(request_id, "")
            if not url.startswith(base):
                continue
            kind = "vendor" if "/vendor/" in url else "static" if "/static/" in url else "page, API"
            totals[kind] = totals.get(kind, 0) + size
        totals["total"] = sum(v for k, v in totals.items())
        browser.close()
    return totals


@contextmanager
def server(url: str | None) -> Iterator[str]:
    if url:
        yield url.rstrip("/")
        return
    with tempfile.TemporaryDirectory() as tmp:
        with running_server(
            f"sqlite:///{Path(tmp) / 'w.db'}", serve_args=["--no-access-log"]
        ) as base:
            yield base


#: product.md §11: the map page's first load over the network [bytes].
PAGE_BUDGET_BYTES = 250_000


def run() -> str:
    """Measure on a server of its own; return the Markdown section of docs/benchmarks.md."""
    with server(None) as base:
        page = page_weight(base)
        sizes = simulation_sizes(base)
    verdict = "met" if page["total"] <= PAGE_BUDGET_BYTES else "**missed**"
    rows = [f"| map page, first load, empty cache (transferred) | {page['total'] / 1000:.1f} KB |"]
    rows += [
        f"| of which {kind} | {size / 1000:.1f} KB |"
        for kind, size in page.items()
        if kind != "total"
    ]
    rows += [f"| {name} | {size / 1000:.1f} KB |" for name, size in sizes.items()]
    return "\n".join(
        [
            "## Bytes over the wire (page, 4 ha simulation)",
            "",
            "Chromium, 390 × 844, `id-ID`, cache disabled; `encodedDataLength` per response. "
            f"Budget: first load ≤ 250 KB transferred: {verdict}.",
            "",
            "| what | bytes |",
            "| --- | ---: |",
            *rows,
            "",
        ]
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--url", help="a running server (default: start one)")
    args = parser.parse_args()
    with server(args.url) as base:
        for name, size in {**page_weight(base), **simulation_sizes(base)}.items():
            print(f"{name:48s} {size / 1000:10.1f} KB")


if __name__ == "__main__":
    main()
