"""The page in a real browser: Playwright driving Debian's Chromium, headless (conftest.py)."""

import re
from pathlib import Path

import pytest

from tests.console.conftest import SCREENSHOTS
from tests.console.server_process import start

pytest.importorskip("uvicorn", reason="the console extra")  # installed by make test (dev)
sync_api = pytest.importorskip("playwright.sync_api", reason="the dev extra")

UPDATE_MS = 3000
"""How long the table and the floor may take to show a write (a second when idle; CI is shared)."""


@pytest.fixture(scope="module")
def console(tmp_path_factory):
    running = start(tmp_path_factory.mktemp("console"), "--speed", "2")
    yield running
    running.close()


@pytest.fixture
def page(browser, console):
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    errors = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(console.url)
    yield page
    context.close()
    assert errors == []


def _shot(page, name):
    if SCREENSHOTS:
        page.screenshot(path=str(Path(SCREENSHOTS) / name), full_page=True)


def _row(page, marker):
    return page.locator(f'#tags tbody tr[data-marker="{marker}"]')


def test_the_token_url_opens_the_page_and_drops_the_token(page):
    assert "token=" not in page.url
    sync_api.expect(page.locator("#link")).to_have_text("live")


def test_the_floor_and_the_table_fill(page):
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(7)
    sync_api.expect(page.locator("#floor")).to_have_attribute(
        "data-urgencies", re.compile(r"\d+:\d")
    )
    sync_api.expect(page.locator("#kpi-deliveries")).not_to_have_text(
        "\u2013"
    )  # the dash shown before the first KPIs
    # the overdue panel says something from the first state on: none, or the waits
    sync_api.expect(page.locator("#alerts")).to_have_text(
        re.compile(r"^(none|carrier \d+: waiting)")
    )
    times = page.locator("#clock").text_content()
    sync_api.expect(page.locator("#clock")).not_to_have_text(times)  # it keeps moving
    _shot(page, "console.png")


def test_reprioritise_a_carrier_by_clicking(page):
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(7)
    rows = page.locator("#tags tbody tr[data-marker]")
    marker = next(
        rows.nth(i).get_attribute("data-marker")
        for i in range(7)
        if rows.nth(i).locator("td.urgency").text_content() not in {"9", "0"}
        and rows.nth(i).locator("td.status").text_content() == "awaiting_pickup"
    )
    _row(page, marker).click()
    sync_api.expect(page.locator("#selected-marker")).to_have_text(marker)
    sync_api.expect(page.locator("#eink")).to_be_visible()
    page.locator('#urgency-buttons button[data-urgency="0"]').click()
    sync_api.expect(page.locator("#message")).to_have_text(
        re.compile(rf"tag {marker}: urgency set to 0")
    )
    sync_api.expect(_row(page, marker).locator("td.urgency")).to_have_text("0", timeout=UPDATE_MS)
    sync_api.expect(page.locator("#floor")).to_have_attribute(
        "data-urgencies", re.compile(rf"(^|,){marker}:0(,|$)"), timeout=UPDATE_MS
    )
    page.locator('#urgency-buttons button[data-urgency="9"]').click()
    sync_api.expect(_row(page, marker).locator("td.urgency")).to_have_text("9", timeout=UPDATE_MS)
    _shot(page, "console-selected.png")


def test_a_forbidden_action_is_refused_and_changes_nothing(page):
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(7)
    _row(page, "2").click()
    status = _row(page, "2").locator("td.status").text_content()
    page.locator("#status-select").select_option("picked_up")
    page.locator("#status-apply").click()
    sync_api.expect(page.locator("#message")).to_have_text(
        re.compile(r"refused: in the simulation only a robot lifts")
    )
    assert "error" in page.locator("#message").get_attribute("class")
    page.wait_for_timeout(300)
    if status != "picked_up":  # a robot may lift it meanwhile; the operator's write did not
        assert _row(page, "2").locator("td.status").text_content() in {status, "picked_up", "idle"}
    _shot(page, "console-refused.png")


def test_the_table_sorts_and_filters(page):
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(7)
    page.locator('#tags th[data-key="marker"]').click()
    first = [int(x) for x in page.locator("#tags tbody td.marker").all_text_contents()]
    assert first == sorted(first)
    page.locator('#tags th[data-key="marker"]').click()
    again = [int(x) for x in page.locator("#tags tbody td.marker").all_text_contents()]
    assert again == sorted(again, reverse=True)
    page.locator("#filter").fill("idle_or_nothing_like_it")
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(0)
    page.locator("#filter").fill("")
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(7)


def test_without_the_token_the_page_is_locked(browser, console):
    context = browser.new_context()
    page = context.new_page()
    answer = page.goto(console.base + "/")
    assert answer is not None
    assert answer.status == 401
    assert "Open the URL" in page.content()
    context.close()
