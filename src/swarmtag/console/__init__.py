"""The operator's web console (``swarmtag console``; the ``console`` extra): docs/console.md.

Layers, pure ones first:

- sources (``source.ConsoleSource``): ``sim_source.SimSource`` (a live
  simulated floor, stepped in real time), ``scan_source.ScanSource`` (real
  tags through a BLE scanner) and ``replay_source.ReplaySource`` (a recorded
  run from ``replay_file``, played back);
- desks (``source.Desk``): ``writes.OperatorDesk`` (operator writes signed on
  the server, verified by the simulated tag), ``scan_source.ScanDesk`` (the
  GATT writer) and ``writes.ReadOnlyDesk`` (a replay: refused);
- ``audit.AuditLog``, ``auth`` (token, cookie, write rate);
- ``api.ConsoleCore``: every API answer as a ``Reply``, no HTTP;
- ``app.make_app`` (Starlette) and ``server.serve`` (uvicorn): the thin HTTP layer.

Only ``app`` and ``server`` import the extra's libraries (and ``scan_source``'s
bench radio, the ``ble`` extra, when asked for).
"""

from __future__ import annotations

from swarmtag.console.api import ConsoleCore, Reply
from swarmtag.console.server import ConsoleSettings, build_core, replay_core, scan_core, serve
from swarmtag.console.source import ConsoleSource, Desk

__all__ = [
    "ConsoleCore",
    "ConsoleSettings",
    "ConsoleSource",
    "Desk",
    "Reply",
    "build_core",
    "replay_core",
    "scan_core",
    "serve",
]
