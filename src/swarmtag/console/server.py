"""Putting the console together and serving it: source, desk, audit log, token, uvicorn.

``build_core`` wires a ``ConsoleCore`` for a live simulation from plain
settings, ``replay_core`` one for a recording and ``scan_core`` one for a
scanner and its writer (tests use them without a server); ``serve`` binds
the socket first (so the URL printed is the one served, even for port 0),
prints the token URL once and runs uvicorn until Ctrl-C. uvicorn takes
SIGINT while it runs, closes the connections (event streams end at their
next beat, or are cut after ``SHUTDOWN_S``) and raises the signal again
once it has stopped, so the command line ends as any interrupted command
does (exit 130); the source is stopped then (a scanner's radio released).
"""

from __future__ import annotations

import socket
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Final, cast

from swarmtag.console.api import ConsoleCore
from swarmtag.console.audit import AuditLog
from swarmtag.console.auth import RateLimiter
from swarmtag.console.replay_file import Recording
from swarmtag.console.replay_source import REPLAY_REFUSAL, ReplaySource
from swarmtag.console.scan_source import ScanDesk, ScanSource
from swarmtag.console.sim_source import SimSource
from swarmtag.console.writes import OperatorDesk, ReadOnlyDesk
from swarmtag.errors import ConfigError
from swarmtag.policy import Policy
from swarmtag.sim import Scenario
from swarmtag.tag import Role
from swarmtag.tag.counter import CounterFile
from swarmtag.tag.keys import derive_role_key

__all__ = [
    "SHUTDOWN_S",
    "ConsoleSettings",
    "bind",
    "build_core",
    "replay_core",
    "scan_core",
    "serve",
]

SHUTDOWN_S: Final = 0.5
"""Seconds uvicorn waits for open requests (event streams) before it cuts them at Ctrl-C."""


@dataclass(frozen=True)
class ConsoleSettings:
    """Everything ``swarmtag console --sim`` needs besides the network address."""

    scenario: Scenario
    policy: Policy
    audit_log: Path
    counter_file: Path
    seed: int = 0
    speed: float = 1.0
    writer: int = 0xFFFD
    operator_key: bytes | None = None
    """The operator key; None: the simulated site's (``SIM_SITE_KEY``'s) operator key."""
    overdue_s: float = 90.0
    writes_per_second: float = 5.0


def build_core(settings: ConsoleSettings) -> ConsoleCore:
    """The console's core for a live simulation of ``settings``."""
    source = SimSource(settings.scenario, settings.policy, seed=settings.seed, speed=settings.speed)
    key = settings.operator_key or derive_role_key(source.site_key, Role.OPERATOR)
    desk = OperatorDesk(
        source, key=key, writer=settings.writer, counters=CounterFile(settings.counter_file)
    )
    return ConsoleCore(
        source,
        desk,
        AuditLog(settings.audit_log),
        limiter=RateLimiter(per_second=settings.writes_per_second),
        overdue_s=settings.overdue_s,
    )


def replay_core(
    recording: Recording,
    *,
    audit_log: Path,
    speed: float = 1.0,
    overdue_s: float = 90.0,
    writes_per_second: float = 5.0,
) -> ConsoleCore:
    """The console's core for a recorded run: played back, every write refused (409)."""
    return ConsoleCore(
        ReplaySource(recording, speed=speed),
        ReadOnlyDesk(REPLAY_REFUSAL),
        AuditLog(audit_log),
        limiter=RateLimiter(per_second=writes_per_second),
        overdue_s=overdue_s,
    )


def scan_core(
    source: ScanSource,
    writer: object | None,
    *,
    audit_log: Path,
    overdue_s: float = 90.0,
    writes_per_second: float = 5.0,
) -> ConsoleCore:
    """The console's core for real tags: ``writer`` is a ``BleakTagWriter`` (None: no key)."""
    return ConsoleCore(
        source,
        ScanDesk(source, writer),
        AuditLog(audit_log),
        limiter=RateLimiter(per_second=writes_per_second),
        overdue_s=overdue_s,
    )


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (port 0: any free one)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as error:
        sock.close()
        raise ConfigError(
            f"--host {host} --port {port}: cannot listen ({error.strerror})"
        ) from None
    sock.listen(128)
    return sock


def serve(
    core: ConsoleCore,
    *,
    token: str,
    sock: socket.socket,
    host: str,
    say: Callable[[str], None],
) -> None:
    """Serve ``core`` on ``sock`` (``bind``'s) until interrupted; ``say`` prints the URL line.

    ``token`` is ``auth.load_or_create_token``'s: the command reads (or
    writes) it last of all its checks, so that a refused start leaves no file.
    """
    import uvicorn  # noqa: PLC0415 - the console extra

    from swarmtag.console.app import make_app  # noqa: PLC0415 - needs starlette

    bound = sock.getsockname()[1]
    shown = f"[{host}]" if ":" in host else host
    say(f"swarmtag console: http://{shown}:{bound}/?token={token}")
    server: uvicorn.Server | None = None

    def stopping() -> bool:
        return server is not None and server.should_exit

    config = uvicorn.Config(
        make_app(core, token, stopping=stopping),
        log_level="warning",
        # typed int, but uvicorn hands it to asyncio.timeout, which takes any seconds
        timeout_graceful_shutdown=cast("int", SHUTDOWN_S),
        lifespan="on",
        access_log=False,
    )
    server = uvicorn.Server(config)
    try:
        server.run(sockets=[sock])
    finally:
        sock.close()
        core.source.stop()
