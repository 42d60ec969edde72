"""The replay page in a real browser (Playwright, Debian's Chromium, headless).

Play/pause, the time slider and the speed change what the table (and, for
an MCAP run, the floor) shows; a write is refused on the page with the
server's reason. As ``test_browser.py``, without Chromium these tests fail
with one line saying how to install it (conftest.py).
"""

import re

import pytest

from tests.console.conftest import SCREENSHOTS
from tests.console.recordings import simulate_mcap, write_log
from tests.console.server_process import start

pytest.importorskip("uvicorn", reason="the console extra")  # installed by make test (dev)
sync_api = pytest.importorskip("playwright.sync_api", reason="the dev extra")

UPDATE_MS = 3000
"""How long the page may take to show a new moment (it asks at once; CI is shared)."""


@pytest.fixture(scope="module")
def log_console(tmp_path_factory):
    folder = tmp_path_factory.mktemp("replay-log")
    write_log(folder)
    running = start(folder, "--tick", "0.1", source=("--replay", "run.csv"))
    yield running
    running.close()


@pytest.fixture(scope="module")
def mcap_console(tmp_path_factory):
    pytest.importorskip("mcap", reason="the bags extra")
    folder = tmp_path_factory.mktemp("replay-mcap")
    simulate_mcap(folder)
    running = start(folder, "--speed", "2", source=("--replay", "run.mcap"))
    yield running
    running.close()


def _open(browser, console):
    context = browser.new_context(viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(console.url)
    sync_api.expect(page.locator("#link")).to_have_text("live")
    sync_api.expect(page.locator("#replay-play")).to_be_enabled()  # the first state is drawn
    return context, page, errors


def _page(browser, console):
    context, page, errors = _open(browser, console)
    yield page
    context.close()
    assert errors == []


@pytest.fixture
def log_page(browser, log_console):
    yield from _page(browser, log_console)


@pytest.fixture
def mcap_page(browser, mcap_console):
    yield from _page(browser, mcap_console)


def _statuses(page):
    rows = page.locator("#tags tbody tr[data-marker]")
    return {
        rows.nth(i).get_attribute("data-marker"): rows.nth(i).locator("td.status").text_content()
        for i in range(rows.count())
    }


def _pause(page):
    if page.locator("#replay-play").text_content() == "pause":
        page.locator("#replay-play").click()
    sync_api.expect(page.locator("#replay-play")).to_have_text("play")


def _seek(page, seconds):
    page.locator("#replay-slider").fill(str(seconds))  # input, then change: the page seeks


def test_the_slider_and_pause_change_what_the_table_shows(log_page):
    page = log_page
    sync_api.expect(page.locator("#replay-controls")).to_be_visible()
    sync_api.expect(page.locator("#floor-note")).to_contain_text("no robot poses")
    sync_api.expect(page.locator("#floor")).to_be_hidden()
    _pause(page)
    _seek(page, 0)
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(1, timeout=UPDATE_MS)
    assert _statuses(page) == {"0": "awaiting_pickup"}
    _seek(page, 8)  # run 0 at 80 ticks: 0 delivered, 1 on robot, 2 waiting
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(3, timeout=UPDATE_MS)
    sync_api.expect(page.locator('#tags tbody tr[data-marker="0"] td.status')).to_have_text("idle")
    assert _statuses(page) == {"0": "idle", "1": "picked_up", "2": "awaiting_pickup"}
    sync_api.expect(page.locator("#kpi-deliveries")).to_have_text(re.compile(r"^1 \(1 run\)"))
    position = page.locator("#replay-position").text_content()
    page.wait_for_timeout(600)
    assert page.locator("#replay-position").text_content() == position  # paused: still
    _shot(page, "console-replay-log.png")


def test_play_moves_the_play_head_on(log_page):
    page = log_page
    _pause(page)
    _seek(page, 0)
    sync_api.expect(page.locator("#replay-position")).to_have_text(re.compile(r"^0\.0 /"))
    page.locator("#replay-speed").select_option("5")
    page.locator("#replay-play").click()
    sync_api.expect(page.locator("#replay-play")).to_have_text("pause")
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(
        2, timeout=UPDATE_MS
    )  # 1 ordered
    sync_api.expect(page.locator("#replay-position")).not_to_have_text(re.compile(r"^0\.0 /"))
    _pause(page)


def test_a_write_is_refused_on_the_page(log_page):
    page = log_page
    _pause(page)
    _seek(page, 8)
    sync_api.expect(page.locator("#tags tbody tr[data-marker]")).to_have_count(3, timeout=UPDATE_MS)
    page.locator('#tags tbody tr[data-marker="2"]').click()
    page.locator('#urgency-buttons button[data-urgency="9"]').click()
    sync_api.expect(page.locator("#message")).to_have_text(
        re.compile(r"tag 2: refused: a replay cannot be re-prioritised")
    )
    sync_api.expect(page.locator('#tags tbody tr[data-marker="2"] td.urgency')).to_have_text("7")


def test_an_mcap_run_draws_robots_and_moves_with_the_slider(mcap_page):
    page = mcap_page
    sync_api.expect(page.locator("#floor")).to_be_visible()
    sync_api.expect(page.locator("#floor-note")).to_be_hidden()
    _pause(page)
    _seek(page, 0)
    sync_api.expect(page.locator("#replay-position")).to_have_text(re.compile(r"^0\.0 /"))
    start = _statuses(page)
    assert set(start.values()) == {"awaiting_pickup"}
    end = float(page.locator("#replay-slider").get_attribute("max"))
    _seek(page, end)
    sync_api.expect(page.locator("#tags tbody td.status", has_text="idle").first).to_be_visible(
        timeout=UPDATE_MS
    )
    assert _statuses(page) != start
    _seek(page, end / 2)
    page.locator('#tags th[data-key="marker"]').click()
    _shot(page, "console-replay.png")


def _shot(page, name):
    if SCREENSHOTS:
        from pathlib import Path

        page.screenshot(path=str(Path(SCREENSHOTS) / name), full_page=True)
