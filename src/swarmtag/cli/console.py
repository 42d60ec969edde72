"""``swarmtag console``: the operator's web console over a live simulation (the console extra).

Serves the page and the JSON API of docs/console.md on 127.0.0.1 (``--host``
to change, with a warning), to holders of the token in ``--token-file``
(printed once as a URL). Operator writes from the page are signed with the
operator key on the server and verified by the tag before they change
anything; each attempt goes to the audit log.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Final

import click

from swarmtag.cli._scenario import build_scenario, scenario_options
from swarmtag.errors import ConfigError

__all__ = ["console_cmd"]

DEFAULT_TOKEN_FILE: Final = "swarmtag-console.token"  # noqa: S105 - a file name
DEFAULT_COUNTER_FILE: Final = "swarmtag-console-operator.counters"
"""The operator's write counters, next to the token file unless --counter-file says."""
_LOCAL: Final = frozenset({"127.0.0.1", "::1", "localhost"})


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
@click.option(
    "--sim",
    is_flag=True,
    help="Show a live simulation (the default, and for now the only source).",
)
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
    help="Simulated seconds per second of wall time (a slow machine falls behind).",
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
    help="The operator's write counters [default: swarmtag-console-operator.counters "
    "next to the token file].",
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

    Prints the URL with the access token once; open it in a browser. The API
    (docs/console.md) takes the token as Authorization: Bearer. Ctrl-C stops.
    """
    del sim  # the only source so far
    from swarmtag.console.audit import DEFAULT_AUDIT_LOG  # noqa: PLC0415 - lazy
    from swarmtag.console.auth import load_or_create_token  # noqa: PLC0415 - lazy
    from swarmtag.console.server import ConsoleSettings, bind, build_core, serve  # noqa: PLC0415
    from swarmtag.policy import parse_policy  # noqa: PLC0415 - loads numpy

    _needs_extra()
    folder = token_file.parent
    if not folder.is_dir():
        raise ConfigError(f"--token-file {token_file}: the folder {folder} does not exist")
    scenario = build_scenario(profile=profile, config=config, flags=flags, settings=settings)
    core = build_core(
        ConsoleSettings(
            scenario=scenario,
            policy=parse_policy(condition),
            audit_log=audit_log or folder / DEFAULT_AUDIT_LOG,
            counter_file=counter_file or folder / DEFAULT_COUNTER_FILE,
            seed=seed,
            speed=speed,
            overdue_s=overdue,
        )
    )
    sock = bind(host, port)
    try:
        token = load_or_create_token(token_file)  # the last check, and the first file
    except BaseException:
        sock.close()
        raise
    if host not in _LOCAL:
        click.echo(
            f"swarmtag: warning: --host {host} serves the console beyond this machine; "
            "the token is all that guards it, and it travels unencrypted",
            err=True,
        )
    serve(core, token=token, sock=sock, host=host, say=_say)


def _say(line: str) -> None:
    click.echo(line)
