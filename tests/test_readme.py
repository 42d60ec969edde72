"""The README's command lines work as written (README.md, "Command line").

The commands are the lines of README.md's ``console`` blocks that start with ``$ ``
(the lines under one, up to the next, are what it prints) and every line of its
``sh`` and ``bash`` blocks; a line that ends in ``\\`` goes on on the next. They run
one after the other (later ones read what earlier ones wrote) through bash, in one
temporary folder holding a copy of ``examples/`` as the repository's folder does,
with the running interpreter's ``bin`` folder (the virtual environment's) first on
PATH, which is what ``source .venv/bin/activate`` does.

What is not run as written, and why:

- ``make …`` (the two set-up commands, which build the environment this runs in) and
  ``source …`` (PATH does its work) are skipped;
- ``swarmtag tag scan`` needs a Bluetooth adapter and is skipped (tests/tag/test_radio.py
  scans with one, opt-in);
- ``swarmtag reproduce`` and ``swarmtag study run allocators`` simulate for minutes: they
  run under ``SWARMTAG_MEMORY_LIMIT=1KiB``, which stops them at their memory check before
  the first simulation, once their arguments, studies and maps are read; they must be
  refused by that check and nothing else, and the folder their ``--out`` goes in must
  exist (what they check next). ``make demo`` runs ``reproduce --quick`` in full;
- ``swarmtag simulate`` runs one run of at most 1000 ticks per condition (``--runs N``
  becomes ``--runs 1`` and ``--ticks N`` at most ``--ticks 1000``, each added where the
  default applies: 30 runs, 3000 ticks) and ``swarmtag study run`` runs with ``--quick``:
  the same code paths (drawing, recording, KPIs, studies), a fraction of the work.

A command passes when it exits 0 (2 where the README shows it printing ``swarmtag:
error: …``) and every line the README shows under it is a line of what it printed.
All of them take about 75 s of CPU time, a good part of it starting processes that
load the compiled kernel: the test is marked ``first``, so that it starts at once on one
core while the short tests share the others.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
SKIPPED = {
    "make ": "a set-up command: it builds the environment these tests run in",
    "source ": "PATH holds the environment's bin folder first instead",
    "swarmtag tag scan": "needs a Bluetooth adapter (tests/tag/test_radio.py, opt-in)",
}
"""Commands not run, by how they start, and why."""
LONG = ("swarmtag reproduce", "swarmtag study run allocators")
"""Commands run only up to their memory check (minutes of simulation otherwise)."""
MAX_RUNS = 1
"""Runs per condition of every ``swarmtag simulate`` the test runs."""
MAX_TICKS = 1000
"""Ticks per run of every ``swarmtag simulate`` the test runs."""
REFUSED_FOR_MEMORY = re.compile(
    r"^swarmtag: error: .* needs about .+ of memory; 1\.0 KiB is available"
)
SHELL_OPERATORS = frozenset({"&&", "||", "|", ";", ">", ">>", "<", "&"})
TIMEOUT = 300
"""Seconds one command may take (a first compilation of the fast kernel fits)."""


@dataclass(frozen=True)
class Command:
    """A README command: where it is, its text (continued lines joined), what it prints."""

    line: int
    text: str
    shown: tuple[str, ...] = ()

    @property
    def words(self) -> list[str]:
        """The command's words as the shell splits them, comments dropped."""
        return shlex.split(self.text.replace("\\\n", " "), comments=True)

    def starts(self, prefix: str) -> bool:
        """Whether the command (its words, one space apart) starts with ``prefix``."""
        return " ".join(self.words).startswith(prefix)


def readme_commands(text: str) -> list[Command]:
    """The commands of ``text``'s console, sh and bash blocks, in order."""
    commands: list[Command] = []
    language: str | None = None
    lines = text.splitlines()
    index = 0
    while index < len(lines):
        line, number = lines[index], index + 1
        index += 1
        if line.startswith("```"):
            language = None if language is not None else line[3:].strip()
            continue
        if language == "console" and line.startswith("$ "):
            body = [line[2:]]
        elif language in ("sh", "bash") and line.strip() and not line.lstrip().startswith("#"):
            body = [line]
        else:
            if language == "console" and commands and line.strip():
                last = commands[-1]
                commands[-1] = Command(last.line, last.text, (*last.shown, line))
            continue
        while body[-1].rstrip().endswith("\\") and index < len(lines):
            body.append(lines[index])
            index += 1
        commands.append(Command(number, "\n".join(body)))
    return commands


def smaller(words: list[str]) -> list[str]:
    """``words`` with the documented smaller work: runs per condition, quick studies."""
    words = list(words)
    if words[:2] == ["swarmtag", "simulate"]:
        for option, most in (("--runs", MAX_RUNS), ("--ticks", MAX_TICKS)):
            if option in words:
                at = words.index(option) + 1
                words[at] = str(min(int(words[at]), most))
            else:
                words += [option, str(most)]
    if words[:3] == ["swarmtag", "study", "run"] and "--quick" not in words:
        words.append("--quick")
    return words


def run_command(command: Command, folder: Path, bin_folder: Path) -> str | None:
    """Run ``command`` in ``folder``; what went wrong, or ``None`` if it did as the README says."""
    env = {key: value for key, value in os.environ.items() if key != "SWARMTAG_MEMORY_LIMIT"}
    env["PATH"] = f"{bin_folder}{os.pathsep}{env.get('PATH', '')}"
    words = command.words
    script = command.text
    long = any(command.starts(prefix) for prefix in LONG)
    if long:
        env["SWARMTAG_MEMORY_LIMIT"] = "1KiB"
    elif words[:1] == ["swarmtag"] and not SHELL_OPERATORS & set(words):
        script = shlex.join(smaller(words))
    done = subprocess.run(
        ["bash", "-c", script],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
        check=False,
    )
    printed = done.stdout + done.stderr
    where = f"README.md line {command.line}: {script}\nexit {done.returncode}; it printed:\n"
    where += printed[-3000:]
    if long:
        out = words[words.index("--out") + 1] if "--out" in words else "."
        if not (folder / out).parent.is_dir():
            return where + f"\n--out {out}: its folder does not exist"
        if done.returncode != 2 or not REFUSED_FOR_MEMORY.match(done.stderr):
            return where + "\n(expected the memory check's refusal: it ran, or failed before)"
        return None
    expected = 2 if command.shown and command.shown[0].startswith("swarmtag: error:") else 0
    if done.returncode != expected:
        return where + f"\n(expected exit {expected})"
    missing = [line for line in command.shown if line not in printed.splitlines()]
    if missing:
        return where + "\nnot printed, though the README shows it: " + "; ".join(missing)
    return None


def test_the_readme_s_commands_are_found_and_the_environment_comes_first():
    commands = readme_commands(README.read_text(encoding="utf-8"))
    texts = [" ".join(command.words) for command in commands]
    assert texts[:2] == ["make demo", "make test"]
    first = next(i for i, text in enumerate(texts) if text.startswith("swarmtag "))
    assert texts.index("source .venv/bin/activate") < first
    for prefix in (*SKIPPED, *LONG):
        assert any(text.startswith(prefix) for text in texts), prefix  # no stale entries
    simulate = texts.index("swarmtag simulate --runs 1 --mcap run.mcap")
    assert texts.index("swarmtag log import run.mcap --events run.csv") > simulate
    decode = next(c for c in commands if c.text == "swarmtag tag decode ffff0701030c --json")
    shown = '{"company_id": 65535, "urgency": 7, "status": "AWAITING_PICKUP", "destination": 3, '
    assert decode.shown == (shown + '"marker": 12}',)
    continued = next(c for c in commands if "warehouse.map=small-warehouse" in c.text)
    assert "--snapshot" in continued.words


def test_smaller_work_keeps_the_command():
    words = ["swarmtag", "simulate", "--runs", "100", "--ticks", "6000", "--json"]
    assert smaller(words) == ["swarmtag", "simulate", "--runs", "1", "--ticks", "1000", "--json"]
    assert smaller(["swarmtag", "simulate", "--ticks", "10"]) == [
        "swarmtag", "simulate", "--ticks", "10", "--runs", "1"
    ]  # fmt: skip
    assert smaller(["swarmtag", "simulate"])[2:] == ["--runs", "1", "--ticks", "1000"]
    assert smaller(["swarmtag", "study", "run", "x"])[-1] == "--quick"
    assert smaller(["swarmtag", "metrics", "e.csv"]) == ["swarmtag", "metrics", "e.csv"]


@pytest.mark.first
def test_every_readme_command_works_as_written(tmp_path):
    bin_folder = Path(sys.executable).parent
    if not (bin_folder / "swarmtag").exists():
        pytest.fail(f"no swarmtag command beside {sys.executable}: install the package first")
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    failures = []
    ran = 0
    for command in readme_commands(README.read_text(encoding="utf-8")):
        if any(command.starts(prefix) for prefix in SKIPPED):
            continue
        problem = run_command(command, tmp_path, bin_folder)
        ran += 1
        if problem is not None:
            failures.append(problem)
    assert ran >= 25
    assert not failures, "\n\n".join(failures)
