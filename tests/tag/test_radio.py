"""Opt-in real-radio test: scan for 10 s with the bleak backend on this machine's adapter.

Runs only with ``pytest --radio`` on a machine with a Bluetooth adapter and
BlueZ (Linux) or the platform's stack; with a tag (or a software tag)
advertising nearby it also prints what was heard::

    pytest -q -p no:cacheprovider --radio -s tests/tag/test_radio.py
"""

from __future__ import annotations

import time

import pytest

pytestmark = pytest.mark.radio

SCAN_SECONDS = 10.0


def test_scan_ten_seconds_with_bleak():
    pytest.importorskip("bleak")
    from swarmtag.tag.backends import open_scanner

    scanner = open_scanner("bleak")
    with scanner:
        deadline = time.monotonic() + SCAN_SECONDS
        while time.monotonic() < deadline and scanner.failure is None:
            time.sleep(0.1)
    assert scanner.failure is None, str(scanner.failure)
    for marker, sighting in scanner.states().items():
        print(f"marker {marker}: {sighting.state} rssi {sighting.rssi} from {sighting.address}")
    print(f"accepted {scanner.accepted}, foreign {scanner.foreign}, malformed {scanner.malformed}")
    assert scanner.malformed == 0
