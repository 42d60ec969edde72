"""The operator's web console (``swarmtag console``; the ``console`` extra): docs/console.md.

Layers, pure ones first:

- ``sim_source.SimSource``: a live simulated floor, stepped in real time;
- ``writes.OperatorDesk``: operator writes signed on the server, verified by the tag;
- ``audit.AuditLog``, ``auth`` (token, cookie, write rate);
- ``api.ConsoleCore``: every API answer as a ``Reply``, no HTTP;
- ``app.make_app`` (Starlette) and ``server.serve`` (uvicorn): the thin HTTP layer.

Only ``app`` and ``server`` import the extra's libraries.
"""

from __future__ import annotations

from swarmtag.console.api import ConsoleCore, Reply
from swarmtag.console.server import ConsoleSettings, build_core, serve

__all__ = ["ConsoleCore", "ConsoleSettings", "Reply", "build_core", "serve"]
