"""Opt-in real-radio test of the writer: one harmless operator write to a real or software tag.

Runs only with ``pytest --radio`` and these environment variables (it skips
without them):

- ``SWARMTAG_RADIO_TAG``: the tag's address (``swarmtag tag scan`` shows it);
- ``SWARMTAG_RADIO_KEY``: an operator key file of that tag's site
  (``swarmtag tag keygen --role operator --from SITE.key --out operator.key``);
- ``SWARMTAG_RADIO_WRITER``: this machine's writer id (default 65000).

It reads the tag's state, writes its own urgency back to it (an operator
write that changes nothing but the writer's counter), and checks that the
tag accepted it; the counter is kept next to the key file as ``tag write``
keeps it, so the test can be run again::

    SWARMTAG_RADIO_TAG=C4:7F:0E:12:34:56 SWARMTAG_RADIO_KEY=operator.key \\
        pytest -q -p no:cacheprovider --radio -s tests/tag/test_radio_writer.py
"""

from __future__ import annotations

import asyncio
import os
from pathlib import Path

import pytest

pytestmark = pytest.mark.radio


def test_one_operator_write_over_the_air():
    bleak = pytest.importorskip("bleak")
    address, key_file = os.environ.get("SWARMTAG_RADIO_TAG"), os.environ.get("SWARMTAG_RADIO_KEY")
    if not address or not key_file:
        pytest.skip("set SWARMTAG_RADIO_TAG and SWARMTAG_RADIO_KEY (see this file's docstring)")
    from swarmtag.cli.tag_write import counter_file_for
    from swarmtag.tag import STATE_CHAR_UUID, Change, Role
    from swarmtag.tag.backends.bleak_writer import BleakTagWriter

    async def urgency_now() -> int:
        async with bleak.BleakClient(address, timeout=20.0) as client:
            return int((await client.read_gatt_char(STATE_CHAR_UUID))[0])

    writer = BleakTagWriter.from_key_file(
        key_file,
        writer=int(os.environ.get("SWARMTAG_RADIO_WRITER", "65000")),
        counters=counter_file_for(Path(key_file)),
        role=Role.OPERATOR,
        timeout=20.0,
    )
    urgency = asyncio.run(urgency_now())
    outcome = writer.write(address, Change(urgency=urgency))
    print(
        f"accepted by tag {outcome.before.marker}: counter {outcome.counter}, now {outcome.after}"
    )
    assert outcome.confirmed
    assert outcome.after.urgency == urgency
