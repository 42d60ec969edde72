"""The root ``swarmtag`` group and the error boundary of the command line."""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Sequence
from typing import NamedTuple, TextIO

import click

from swarmtag._checks import show
from swarmtag._interrupt import acknowledge, checkpoint
from swarmtag.errors import BackendFallback, SwarmtagError

__all__ = ["COMMANDS", "EXIT_BAD_INPUT", "EXIT_INTERRUPTED", "app", "run"]

EXIT_BAD_INPUT = 2
"""Exit status for every refused input, ours or the CLI framework's."""
EXIT_INTERRUPTED = 130
"""Exit status after Ctrl-C (128 + SIGINT), as shells report it."""


class Entry(NamedTuple):
    """Where a top-level command lives, and the line ``swarmtag --help`` shows for it."""

    module: str
    attribute: str
    summary: str


COMMANDS: dict[str, Entry] = {
    "aruco": Entry(
        "swarmtag.cli.aruco",
        "aruco",
        "The cameras' ArUco markers (ARUCO_MIP_36h12, 50 mm): synthetic images and detection.",
    ),
    "calibrate": Entry(
        "swarmtag.cli.calibrate",
        "calibrate_cmd",
        "Fit free parameters within bounds to a baseline; write the profile and the fit report.",
    ),
    "console": Entry(
        "swarmtag.cli.console",
        "console_cmd",
        "Serve the operator's web console: the floor, the tags, KPIs and writes (console extra).",
    ),
    "demo": Entry(
        "swarmtag.cli.demo",
        "demo",
        "A tour of the building blocks: tag payloads, writes, selection, trial-log metrics.",
    ),
    "log": Entry(
        "swarmtag.cli.log",
        "log_group",
        "Trial logs: event logs from ROS 2 bags of physical (or simulated) trials.",
    ),
    "metrics": Entry(
        "swarmtag.cli.metrics",
        "metrics",
        "KPIs of an event log EVENTS (.csv or .parquet) with 95 % bootstrap CIs over runs.",
    ),
    "policies": Entry(
        "swarmtag.cli.policies",
        "policies_cmd",
        "List the selection rules: name, kind, definition, parameter, reference, backends.",
    ),
    "policy": Entry(
        "swarmtag.cli.policies",
        "policy_group",
        "Work with score rules of one's own (docs/policy.md).",
    ),
    "profiles": Entry(
        "swarmtag.cli.profiles",
        "profiles_cmd",
        "List the shipped profiles with their values, or show one profile (a name or a file).",
    ),
    "reproduce": Entry(
        "swarmtag.cli.study",
        "reproduce",
        "Run the published studies (resuming what is stored) and write the report.",
    ),
    "robot": Entry(
        "swarmtag.cli.robot",
        "robot",
        "The robot's controller (the behaviour tree of docs/controller.md; the robot extra).",
    ),
    "simulate": Entry(
        "swarmtag.cli.simulate",
        "simulate_cmd",
        "Simulate conditions on a scenario and print their KPIs with 95 % CIs.",
    ),
    "study": Entry(
        "swarmtag.cli.study",
        "study",
        "Run the published studies, or your own study files (see docs/experiments.md).",
    ),
    "tag": Entry(
        "swarmtag.cli.tag",
        "tag",
        "The smart tag: its payload, its E-ink picture, site key files, scanning, a software tag.",
    ),
}
"""The top-level commands, imported only when one is run or asked for.

``swarmtag --help`` lists them from here, so that it loads neither numpy nor
the simulator; each summary is its command's first help sentence, and a test
(tests/cli/test_help.py) holds the two equal.
"""


class _Interrupted(Exception):
    """Ctrl-C inside a command, carried past click (which would print a blank line first)."""


class _Root(click.Group):
    """The root group: commands load on first use; a Ctrl-C in any leaves as ``_Interrupted``."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name not in self.commands and cmd_name in COMMANDS:
            entry = COMMANDS[cmd_name]
            command = getattr(importlib.import_module(entry.module), entry.attribute)
            self.add_command(command, cmd_name)
        return self.commands.get(cmd_name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        width = formatter.width - 6 - max(map(len, COMMANDS))
        # a help-only command per entry: click's own cutting of a summary to the width
        rows = [
            (name, click.Command(name, help=entry.summary).get_short_help_str(width))
            for name, entry in sorted(COMMANDS.items())
        ]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt as interrupt:
            raise _Interrupted(str(interrupt)) from None


@click.group(
    cls=_Root,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)
@click.version_option(package_name="swarmtag", prog_name="swarmtag")  # looked up when asked
def app() -> None:
    """Urgency-aware robot-swarm intralogistics: tags, policies, simulation, metrics."""


def _one_line(text: str) -> str:
    return " ".join(part.strip() for part in text.splitlines() if part.strip())


def _fail(message: str, status: int) -> None:
    click.echo(f"swarmtag: error: {_one_line(message)}", err=True)
    sys.exit(status)


def _note(  # noqa: PLR0917 - warnings.showwarning's signature
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    """Print our own notes (``BackendFallback``) as one line; others as Python does."""
    if issubclass(category, BackendFallback):
        click.echo(f"swarmtag: note: {_one_line(str(message))}", err=True)
        return
    _SHOW(message, category, filename, lineno, file, line)


_SHOW = warnings.showwarning


def run(argv: Sequence[str] | None = None) -> None:
    """Run the command line: exit 0, 2 with one line on stderr on bad input, 130 on Ctrl-C.

    A command may end with its own status by returning it (``tag write``
    returns 1 when the tag refused the write). ``swarmtag.cli.main`` installs
    the SIGINT handler before calling this.
    """
    for position, word in enumerate(argv or (), start=1):
        if "\0" in word:  # no shell can pass one; click's path checks would raise ValueError
            _fail(f"argument {position} ({show(word)}) contains a NUL byte", EXIT_BAD_INPUT)
    try:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("default", BackendFallback)  # once per rule, as a note
                warnings.showwarning = _note
                result = app.main(args=argv, prog_name="swarmtag", standalone_mode=False)
        finally:
            checkpoint()  # an interrupt swallowed on the way out still ends as one
    except (_Interrupted, KeyboardInterrupt, click.Abort) as interrupt:
        acknowledge()  # taken: the watchdog that re-sends a lost Ctrl-C can stop
        note = str(interrupt) if isinstance(interrupt, _Interrupted) else ""
        _fail("aborted" + (f"; {note}" if note else ""), EXIT_INTERRUPTED)
    except click.exceptions.NoArgsIsHelpError as error:
        # A bare group prints its help, as a user asking "what is here?" expects.
        click.echo(error.ctx.get_help() if error.ctx else error.format_message())
        sys.exit(0)
    except click.UsageError as error:
        hint = f" (see '{error.ctx.command_path} --help')" if error.ctx else ""
        _fail(error.format_message() + hint, EXIT_BAD_INPUT)
    except click.ClickException as error:
        _fail(error.format_message(), EXIT_BAD_INPUT)
    except SwarmtagError as error:
        _fail(str(error), EXIT_BAD_INPUT)
    sys.exit(result if isinstance(result, int) else 0)
