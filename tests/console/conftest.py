"""The console's browser tests share one headless Chromium per module (Playwright).

The browser is the system's (``/usr/bin/chromium``, or ``SWARMTAG_CHROMIUM``);
Playwright never downloads one. Without it the tests fail with one line
saying how to install it (``.ci/run`` does, as root).
"""

import os
from pathlib import Path

import pytest

CHROMIUM = Path(os.environ.get("SWARMTAG_CHROMIUM", "/usr/bin/chromium"))
HINT = f"the console's browser tests need Chromium at {CHROMIUM}: run 'apt-get install -y chromium' as root (or set SWARMTAG_CHROMIUM)"
SCREENSHOTS = os.environ.get("SWARMTAG_CONSOLE_SCREENSHOTS")
"""A folder to save the page's screenshots in (docs/console/ is made this way)."""


@pytest.fixture(scope="module")
def browser():
    sync_api = pytest.importorskip("playwright.sync_api", reason="the dev extra")
    if not CHROMIUM.is_file():
        pytest.fail(HINT, pytrace=False)
    with sync_api.sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), headless=True)
        yield chromium
        chromium.close()
