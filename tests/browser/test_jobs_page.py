"""Long simulations on the map page run as jobs: a progress bar that moves, Cancel, a summary."""

from __future__ import annotations

import time
import uuid

import pytest
from playwright.sync_api import Page, expect

from tests.browser.test_map_page import button, generate, import_paper_field, save

pytestmark = pytest.mark.browser


def test_monte_carlo_progress_bar_moves_and_cancel_stops_it(page: Page) -> None:
    import_paper_field(page)
    generate(page)
    save(page, f"Monte Carlo {uuid.uuid4().hex[:6]}")
    page.get_by_role("spinbutton", name="Monte Carlo runs").fill("500")
    button(page, "Simulate").click()
    bar = page.get_by_label("Simulation progress")
    expect(bar).to_be_visible()
    seen: list[float] = []
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len({v for v in seen if v > 0}) < 3:
        seen.append(float(bar.evaluate("el => el.value")))
        page.wait_for_timeout(200)
    moving = sorted({v for v in seen if v > 0})
    assert len(moving) >= 3, seen
    assert seen == sorted(seen)
    expect(page.locator("#sim-progress-label")).to_contain_text("Simulating 500 runs: ")
    # The server answers the page at once meanwhile: the job runs in a worker process.
    started = time.monotonic()
    assert page.evaluate("() => fetch('/api/plans?limit=1').then((r) => r.status)") == 200
    assert time.monotonic() - started < 2

    with page.expect_response(lambda r: r.request.method == "DELETE" and "/api/jobs/" in r.url):
        button(page, "Cancel").click()
    expect(page.get_by_text("Simulation cancelled.")).to_be_visible(timeout=10_000)
    expect(bar).to_be_hidden()
    expect(page.get_by_role("region", name="Simulation")).to_be_hidden()
    expect(button(page, "Simulate")).to_be_enabled()


def test_a_small_monte_carlo_batch_draws_its_median_run_with_a_summary(page: Page) -> None:
    import_paper_field(page)
    generate(page)
    save(page, f"Batch {uuid.uuid4().hex[:6]}")
    page.get_by_role("spinbutton", name="Monte Carlo runs").fill("3")
    button(page, "Simulate").click()
    region = page.get_by_role("region", name="Simulation")
    expect(region).to_be_visible(timeout=60_000)
    expect(region).to_contain_text("the median of 3 runs")
    expect(page.locator("#simulation-summary")).to_contain_text("3 runs, 100.0 % completed")
    expect(page.locator("path.simulated-track")).to_have_count(1)
    expect(page.get_by_label("Simulation progress")).to_be_hidden()
