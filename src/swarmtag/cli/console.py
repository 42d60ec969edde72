"""``swarmtag console``: the operator's web console (the console extra).

One source at a time: ``--sim`` (the default) a live simulation, ``--scan``
real tags through the bleak scanner and writer (the ble extra), ``--replay
FILE`` a recorded run (an event log or an MCAP run) with play/pause and a
time slider. Serves the page and the JSON API of docs/console.md on
127.0.0.1 (``--host`` to change, with a warning), to holders of the token in
``--token-file`` (printed once as a URL). Operator writes from the page are
signed with the operator key on the server and verified by the tag before
they change anything; each attempt goes to the audit log. Every check (the
source's file, key, radio) comes before the socket and the token file, so a
refused start leaves nothing behind.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import click

from swarmtag.cli._scenario import build_scenario, scenario_options
from swarmtag.cli._tag_options import adapter as check_adapter_option
from swarmtag.errors import ConfigError

if TYPE_CHECKING:
    from swarmtag.console.api import ConsoleCore
    from swarmtag.sim import Scenario

__all__ = ["console_cmd"]

DEFAULT_TOKEN_FILE: Final = "swarmtag-console.token"  # noqa: S105 - a file name
DEFAULT_COUNTER_FILE: Final = "swarmtag-console-operator.counters"
"""The operator's write counters, next to the token file unless --counter-file says."""
_LOCAL: Final = frozenset({"127.0.0.1", "::1", "localhost"})
SCANNER_STOP_S: Final = 0.5
"""Seconds the console waits for bleak's scanner thread at Ctrl-C; the thread is a daemon,
so a radio slow to let go cannot hold the exit past a second."""


def _needs_extra() -> None:
    try:
        import starlette  # noqa: F401, PLC0415 - only to say what is missing
        import uvicorn  # noqa: F401, PLC0415
    except ImportError as error:
        raise ConfigError(
            f"console needs the {error.name} package, which is not installed: "
            "pip install 'swarmtag[console]'"
        ) from None


@click.command("console")
@click.option("--sim", is_flag=True, help="Show a live simulation (the default source).")
@click.option(
    "--scan",
    is_flag=True,
    help="Show the real tags in range (bleak scanner) and write to them over GATT (ble extra).",
)
@click.option(
    "--replay",
    metavar="FILE",
    type=click.Path(path_type=Path),
    help="Play back a recorded run: an event log (.csv, .parquet) or an MCAP run (.mcap).",
)
@click.option(
    "--key-file",
    metavar="OPERATOR.key",
    type=click.Path(dir_okay=False, path_type=Path),
    help="--scan: the operator key file that signs writes (swarmtag tag keygen --role "
    "operator); without it the tags are shown but not written.",
)
@click.option(
    "--writer",
    type=click.IntRange(0, 0xFFFF),
    default=0xFFFD,
    show_default=True,
    help="--scan: the operator's writer id.",
)
@click.option(
    "--adapter",
    metavar="hciN",
    callback=check_adapter_option,
    help="--scan: the BlueZ adapter (default: the system's first).",
)
@click.option("--backend", type=click.Choice(["bleak", "sim"]), default="bleak", hidden=True)
@scenario_options
@click.option(
    "--condition",
    default="urgency:alpha=0.7",
    show_default=True,
    metavar="NAME",
    help="The robots' selection rule (swarmtag policies lists them).",
)
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=0, show_default=True)
@click.option(
    "--speed",
    type=click.FloatRange(0.01, 100.0),
    default=1.0,
    show_default=True,
    help="Simulated (or replayed) seconds per second of wall time; the replay page changes it.",
)
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on.")
@click.option(
    "--port", type=click.IntRange(0, 65535), default=8765, show_default=True, help="0: any free."
)
@click.option(
    "--token-file",
    type=click.Path(dir_okay=False, path_type=Path),
    default=DEFAULT_TOKEN_FILE,
    show_default=True,
    help="Where the access token is kept (mode 0600; created with a random token if absent).",
)
@click.option(
    "--audit-log",
    type=click.Path(dir_okay=False, path_type=Path),
    help="JSON lines, one per write attempt [default: swarmtag-console-audit.jsonl "
    "next to the token file].",
)
@click.option(
    "--counter-file",
    type=click.Path(dir_okay=False, path_type=Path),
    help="The operator's write counters [default: --scan: the key file's path + .counters, "
    "as swarmtag tag write; else swarmtag-console-operator.counters next to the token file].",
)
@click.option(
    "--overdue",
    type=click.FloatRange(0, 1e9, min_open=True),
    default=90.0,
    show_default=True,
    metavar="S",
    help="Alert for carriers waiting longer than S seconds since their order time.",
)
def console_cmd(
    *,
    sim: bool,
    scan: bool,
    replay: Path | None,
    key_file: Path | None,
    writer: int,
    adapter: str | None,
    backend: str,
    condition: str,
    seed: int,
    speed: float,
    host: str,
    port: int,
    token_file: Path,
    audit_log: Path | None,
    counter_file: Path | None,
    overdue: float,
    profile: str,
    config: Path | None,
    settings: tuple[str, ...],
    **flags: Any,  # noqa: ANN401 - the scenario flags, checked by build_scenario
) -> None:
    """Serve the operator's web console: the floor, the tags, KPIs and writes (console extra).

    Sources, one at a time: --sim (the default), --scan (real tags, ble
    extra), --replay FILE (an event log or an MCAP run). Prints the URL with
    the access token once; open it in a browser. The API (docs/console.md)
    takes the token as Authorization: Bearer. Ctrl-C stops.
    """
    from swarmtag.console.audit import DEFAULT_AUDIT_LOG  # noqa: PLC0415 - lazy
    from swarmtag.console.auth import load_or_create_token  # noqa: PLC0415 - lazy
    from swarmtag.console.server import bind, serve  # noqa: PLC0415

    given = [name for name, on in (("--sim", sim), ("--scan", scan), ("--replay", replay)) if on]
    if len(given) > 1:
        raise click.UsageError(f"{' and '.join(given)}: give one source (the default is --sim)")
    _needs_extra()
    folder = token_file.parent
    if not folder.is_dir():
        raise ConfigError(f"--token-file {token_file}: the folder {folder} does not exist")
    scenario = build_scenario(profile=profile, config=config, flags=flags, settings=settings)
    audit = audit_log or folder / DEFAULT_AUDIT_LOG
    if replay is not None:
        core = _replay(replay, scenario, speed=speed, audit_log=audit, overdue_s=overdue)
    elif scan:
        core = _scan(
            backend,
            key_file,
            writer,
            adapter,
            counter_file,
            folder=folder,
            audit_log=audit,
            overdue_s=overdue,
        )
    else:
        core = _sim(
            scenario,
            condition,
            seed,
            speed,
            counter_file or folder / DEFAULT_COUNTER_FILE,
            audit_log=audit,
            overdue_s=overdue,
        )
    try:
        sock = bind(host, port)
        try:
            token = load_or_create_token(token_file)  # the last check, and the first file
        except BaseException:
            sock.close()
            raise
    except BaseException:
        core.source.stop()
        raise
    if host not in _LOCAL:
        click.echo(
            f"swarmtag: warning: --host {host} serves the console beyond this machine; "
            "the token is all that guards it, and it travels unencrypted",
            err=True,
        )
    serve(core, token=token, sock=sock, host=host, say=_say)


def _sim(
    scenario: Scenario,
    condition: str,
    seed: int,
    speed: float,
    counter_file: Path,
    *,
    audit_log: Path,
    overdue_s: float,
) -> ConsoleCore:
    """The core of ``--sim``: a live simulation of ``scenario`` under ``condition``."""
    from swarmtag.console.server import ConsoleSettings, build_core  # noqa: PLC0415
    from swarmtag.policy import parse_policy  # noqa: PLC0415 - loads numpy

    return build_core(
        ConsoleSettings(
            scenario=scenario,
            policy=parse_policy(condition),
            audit_log=audit_log,
            counter_file=counter_file,
            seed=seed,
            speed=speed,
            overdue_s=overdue_s,
        )
    )


def _replay(
    path: Path, scenario: Scenario, *, speed: float, audit_log: Path, overdue_s: float
) -> ConsoleCore:
    """The core of ``--replay``: the file read (and checked) now; a log in ticks in ``--tick`` s."""
    from swarmtag.console.replay_file import read_recording  # noqa: PLC0415
    from swarmtag.console.server import replay_core  # noqa: PLC0415

    recording = read_recording(path, tick_seconds=float(scenario.tick))
    return replay_core(recording, audit_log=audit_log, speed=speed, overdue_s=overdue_s)


def _scan(
    backend: str,
    key_file: Path | None,
    writer: int,
    adapter: str | None,
    counter_file: Path | None,
    *,
    folder: Path,
    audit_log: Path,
    overdue_s: float,
) -> ConsoleCore:
    """The core of ``--scan``: the key and counters checked, the radio up (or one line why not).

    The counter file defaults to the key file's (``swarmtag tag write``'s), so
    that the console and the command line never reuse one writer's counter.
    """
    try:
        from swarmtag.tag.backends.bleak_writer import BleakTagWriter  # noqa: PLC0415 - ble extra
    except ImportError as error:
        if error.name is None or error.name.split(".")[0] != "bleak":
            raise
        raise ConfigError(
            "console --scan needs the bleak package, which is not installed: "
            "pip install 'swarmtag[ble]'"
        ) from None
    from swarmtag.cli.tag_write import counter_file_for  # noqa: PLC0415
    from swarmtag.console.audit import AuditLog  # noqa: PLC0415
    from swarmtag.console.scan_source import ScanSource, bench_radio  # noqa: PLC0415
    from swarmtag.console.server import scan_core  # noqa: PLC0415
    from swarmtag.sim.world.wms import SIM_SITE_KEY  # noqa: PLC0415
    from swarmtag.tag import Role, derive_role_key  # noqa: PLC0415
    from swarmtag.tag.backends import open_scanner  # noqa: PLC0415
    from swarmtag.tag.counter import CounterFile  # noqa: PLC0415

    AuditLog(audit_log)  # checked before the radio
    factory = heard = None
    if backend == "sim":
        scanner, factory, heard = bench_radio(SIM_SITE_KEY)
    else:
        scanner = open_scanner("bleak", adapter=adapter, join_timeout=SCANNER_STOP_S)
    tag_writer = None
    if key_file is not None:
        counters = CounterFile(counter_file or counter_file_for(key_file))
        tag_writer = BleakTagWriter.from_key_file(
            key_file,
            counters=counters,
            writer=writer,
            role=Role.OPERATOR,
            adapter=adapter,
            client_factory=factory,
        )
        counters.check()
    elif backend == "sim":  # the bench tags hold the simulated site's key
        counters = CounterFile(counter_file or folder / DEFAULT_COUNTER_FILE)
        counters.check()
        tag_writer = BleakTagWriter(
            writer=writer,
            role=Role.OPERATOR,
            key=derive_role_key(SIM_SITE_KEY, Role.OPERATOR),
            counters=counters,
            adapter=adapter,
            client_factory=factory,
        )
    source = ScanSource(scanner, on_written=heard)
    source.start()  # no adapter, no BlueZ: one line, before the socket and the token
    return scan_core(source, tag_writer, audit_log=audit_log, overdue_s=overdue_s)


def _say(line: str) -> None:
    click.echo(line)
