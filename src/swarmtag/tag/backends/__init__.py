"""Tag transports behind one interface: ``open_scanner(backend=...)`` (bleak-style facade).

Every backend is a ``Scanner`` (``base.py``): ``start``/``stop`` or a
``with`` block, ``states()`` with the latest ``Sighting`` per carrier, and
the ``ScanFilter`` counters. The backend modules are imported only when
asked for, so the core never imports a BLE library:

- ``bleak``: the robot-side scanner on a real adapter (the ``ble`` extra);
- ``sim``: a virtual radio (interval, phase, range, loss, delay, duplicate
  filtering), deterministic and driven by ``advance(now)``;
- ``fake``: in memory, fed by a test.

>>> with open_scanner("fake", clock=lambda: 0.0) as scanner:
...     _ = scanner.feed("AA", {0xFFFF: bytes([7, 1, 3, 12])})
>>> list(scanner.states())
[12]
"""

from __future__ import annotations

from swarmtag.tag.backends._facade import BACKENDS, open_scanner, scanner_class
from swarmtag.tag.backends.base import DEFAULT_MAX_AGE, Scanner, Sighting, TagTable

__all__ = [
    "BACKENDS",
    "DEFAULT_MAX_AGE",
    "Scanner",
    "Sighting",
    "TagTable",
    "open_scanner",
    "scanner_class",
]
