"""The ``--scan`` page in a real browser, on the bench radio (the hidden ``--backend sim``):
the table fills with the tags in range, there is no floor, a click writes over the GATT path.
"""

import re

import pytest

from tests.console.conftest import SCREENSHOTS
from tests.console.server_process import start

pytest.importorskip("uvicorn", reason="the console extra")  # installed by make test (dev)
pytest.importorskip("bleak", reason="the ble extra")
sync_api = pytest.importorskip("playwright.sync_api", reason="the dev extra")


@pytest.fixture
def page(tmp_path, browser):
    running = start(tmp_path, "--backend", "sim", source=("--scan",))
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(running.url)
    yield page
    context.close()
    running.close()
    assert errors == []


def test_the_tags_in_range_and_a_write(page):
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(3)
    sync_api.expect(page.locator("#floor-note")).to_contain_text("no floor positions")
    sync_api.expect(page.locator("#floor")).to_be_hidden()
    sync_api.expect(page.locator("#kpi-tags")).to_have_text("3")
    page.locator('#tags tbody tr[data-marker="12"]').click()
    page.locator('#urgency-buttons button[data-urgency="2"]').click()
    sync_api.expect(page.locator("#message")).to_have_text(
        re.compile(r"tag 12: urgency set to 2 \(counter 0\)")
    )
    row = page.locator('#tags tbody tr[data-marker="12"] td.urgency')
    sync_api.expect(row).to_have_text("2", timeout=3000)
    sync_api.expect(page.locator("#kpi-writes")).to_have_text("1", timeout=3000)
    if SCREENSHOTS:
        page.wait_for_timeout(500)  # the E-ink picture of the written state loads
        page.screenshot(path=f"{SCREENSHOTS}/console-scan.png", full_page=True)
