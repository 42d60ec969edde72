"""The root ``swarmtag`` group and the error boundary of the command line."""

from __future__ import annotations

import sys
import warnings
from collections.abc import Sequence
from typing import TextIO

import click

from swarmtag import __version__
from swarmtag._checks import show
from swarmtag._interrupt import acknowledge, checkpoint
from swarmtag.cli.aruco import aruco
from swarmtag.cli.calibrate import calibrate_cmd
from swarmtag.cli.demo import demo
from swarmtag.cli.log import log_group
from swarmtag.cli.metrics import metrics
from swarmtag.cli.policies import policies_cmd, policy_group
from swarmtag.cli.profiles import profiles_cmd
from swarmtag.cli.robot import robot
from swarmtag.cli.simulate import simulate_cmd
from swarmtag.cli.study import reproduce, study
from swarmtag.cli.tag import tag
from swarmtag.errors import BackendFallback, SwarmtagError

__all__ = ["EXIT_BAD_INPUT", "EXIT_INTERRUPTED", "app", "run"]

EXIT_BAD_INPUT = 2
"""Exit status for every refused input, ours or the CLI framework's."""
EXIT_INTERRUPTED = 130
"""Exit status after Ctrl-C (128 + SIGINT), as shells report it."""


class _Interrupted(Exception):
    """Ctrl-C inside a command, carried past click (which would print a blank line first)."""


class _Root(click.Group):
    """The root group: a KeyboardInterrupt in any command leaves as ``_Interrupted``."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt as interrupt:
            raise _Interrupted(str(interrupt)) from None


@click.group(
    cls=_Root,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)
@click.version_option(__version__, prog_name="swarmtag")
def app() -> None:
    """Urgency-aware robot-swarm intralogistics: tags, policies, simulation, metrics."""


app.add_command(tag)
app.add_command(demo)
app.add_command(metrics)
app.add_command(log_group)
app.add_command(simulate_cmd)
app.add_command(study)
app.add_command(reproduce)
app.add_command(policies_cmd)
app.add_command(policy_group)
app.add_command(profiles_cmd)
app.add_command(calibrate_cmd)
app.add_command(robot)
app.add_command(aruco)


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
