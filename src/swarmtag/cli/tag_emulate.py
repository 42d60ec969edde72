"""``swarmtag tag emulate``: run a software tag on this computer's Bluetooth adapter.

The tag (``swarmtag.tag.emulator``) is served by bless on BlueZ (the
``tag-emulator`` extra; Linux only): it advertises its 6-byte payload and
serves the authenticated write and the state characteristics, as the
nRF52833 firmware does. One line is printed per write: accepted with the
new state, or refused with its reason and ATT error code. It runs until
Ctrl-C (exit 130, the state kept) or ``--timeout`` seconds.

The state file (``--state-file``) is the tag's flash: if it exists the tag
boots from it, keeping its state and every writer's counter, and it must be
the same tag (``--marker``); ``--urgency``/``--status``/``--destination``
only set up a new tag and are refused then. If it does not exist the tag is
provisioned there (urgency 0, IDLE, destination 0 unless given). Without
it the tag lives in memory and forgets its counters when the command ends.
Robots sign with their own keys (``tag keygen --role robot --writer ID``);
``--shared-robot-key`` makes the tag also accept the legacy key shared by
all robots (a tag booted from a state file written before per-robot keys
accepts it until ``--no-shared-robot-key``, which is saved in the file).
Nothing is written until the tag is on the air: then a new state file and
the first ``--eink`` picture appear together (a radio that fails leaves
neither); the picture is redrawn after every accepted write.

A radio that cannot be used (no adapter, no BlueZ, no permission) is one
line saying what is missing, exit 2. The hidden ``--replay FILE`` serves the
writes in FILE (hex, one per line; blank lines and ``#`` comments skipped)
instead of the radio, for scripted bench tests and tests without a radio.
"""

from __future__ import annotations

import errno
import math
import string
import threading
import time
from pathlib import Path

import click

from swarmtag._inputs import regular_file
from swarmtag._interrupt import acknowledge, checkpoint
from swarmtag._outputs import OutputPlan
from swarmtag.cli._tag_options import adapter, seconds_between, status
from swarmtag.errors import ConfigError, FieldRangeError, OutputError
from swarmtag.tag import FileStore, MemoryStore, TagState, TagStatus, TagStore, read_key_file
from swarmtag.tag.backends.server import ReplayTagServer, TagServer
from swarmtag.tag.emulator import ACCEPTED, SoftwareTag, describe_outcome

__all__ = ["emulate_cmd"]

_TICK = 0.1
"""Seconds between two looks at the server (outcomes, failure, the clock)."""
MAX_TIMEOUT = 7 * 86400.0
"""The longest run asked for with --timeout: a week (without it, the tag runs until Ctrl-C)."""
_MAX_REPLAY_BYTES = 1 << 20
_COMMIT_WAIT = 30.0
"""Seconds a write that arrives as the tag goes live waits for its new state file."""
_SEPARATORS = str.maketrans("", "", ":- \t")


def read_replay(path: Path) -> list[bytes]:
    """The writes of a replay file: one hex value per line; blank lines and ``# ...`` skipped."""
    regular_file(path, what="replay file", error=ConfigError)
    try:
        with path.open("rb") as stream:
            data = stream.read(_MAX_REPLAY_BYTES + 1)
    except OSError as error:
        raise ConfigError(f"--replay {path}: cannot read it ({error.strerror})") from None
    if len(data) > _MAX_REPLAY_BYTES:
        raise ConfigError(f"--replay {path}: larger than {_MAX_REPLAY_BYTES} bytes")
    writes = []
    for number, raw in enumerate(data.split(b"\n"), start=1):
        text = raw.decode("ascii", "replace").strip()
        if not text or text.startswith("#"):
            continue
        digits = text.lower().removeprefix("0x").translate(_SEPARATORS)
        if not digits or len(digits) % 2 or any(c not in string.hexdigits for c in digits):
            shown = text if len(text) <= 60 else text[:57] + "..."
            raise ConfigError(f"--replay {path}: line {number} is not a hex byte string: {shown!r}")
        writes.append(bytes.fromhex(digits))
    return writes


def _open_server(tag: SoftwareTag, replay: list[bytes] | None, adapter: str | None) -> TagServer:
    """The transport: the replayed writes, or bless on ``adapter`` (tests replace this function)."""
    if replay is not None:
        return ReplayTagServer(tag, replay)
    # the extra; off Linux the import itself is the RadioError that says why
    from swarmtag.tag.backends.bless import BlessTagServer  # noqa: PLC0415

    return BlessTagServer(tag, adapter=adapter)


class _PendingStore:
    """A new tag's flash until the tag is on the air: then its state file appears.

    The record is held in memory while the radio starts; ``commit`` hands
    over the real store once the command has put its outputs in place. A
    write that arrives before that waits for it (the tag must not act on a
    write it has not persisted), and fails if the command gave up.
    """

    def __init__(self) -> None:
        self._record: bytes | None = None
        self._store: FileStore | None = None
        self._decided = threading.Event()

    def load(self) -> bytes | None:
        """The record: the committed file's, or the one held so far."""
        return self._record if self._store is None else self._store.load()

    def save(self, record: bytes) -> None:
        """Hold the provisioning record; after that, wait for the file and save there."""
        if self._record is None and not self._decided.is_set():
            self._record = bytes(record)
            return
        self._decided.wait(_COMMIT_WAIT)
        if self._store is None:
            raise OSError(errno.EAGAIN, "the state file was never created")
        self._store.save(record)

    def held(self) -> bytes:
        """The provisioning record, to be written as the new state file."""
        assert self._record is not None  # SoftwareTag.open saved it
        return self._record

    def commit(self, store: FileStore | None) -> None:
        """Save to ``store`` from now on (``None``: the command gave up; saves fail)."""
        self._store = store
        self._decided.set()


def _open_tag(
    *,
    marker: int,
    site_key: bytes,
    state_file: Path | None,
    urgency: int | None,
    status: TagStatus | None,
    destination: int | None,
    shared_robot_key: bool | None,
) -> tuple[SoftwareTag, _PendingStore | None]:
    """Boot the tag from ``state_file``, or set up a new one (pending until it serves)."""
    pending = _PendingStore() if state_file is not None and not state_file.exists() else None
    store: TagStore = MemoryStore() if state_file is None else pending or FileStore(state_file)
    try:
        tag = SoftwareTag.open(
            marker=marker,
            site_key=site_key,
            store=store,
            urgency=urgency,
            status=status,
            destination=destination,
            shared_robot_key=shared_robot_key,
        )
    except FieldRangeError as error:
        raise ConfigError(f"--state-file {state_file}: {error}") from None
    return tag, pending


def _go_live(
    plan: OutputPlan,
    tag: SoftwareTag,
    pending: _PendingStore | None,
    state_file: Path | None,
    eink: Path | None,
) -> None:
    """Write the new state file and the first E-ink picture together (all or none)."""
    if pending is None and eink is None:
        return
    try:
        with plan.writing() as stage:
            if pending is not None and state_file is not None:
                FileStore(stage.path(state_file)).save(pending.held())
            if eink is not None:
                _draw(tag.state, stage.path(eink))
    except BaseException:
        if pending is not None:
            pending.commit(None)
        raise
    if pending is not None and state_file is not None:
        pending.commit(FileStore(state_file))


def _serve(server: TagServer, timeout: float | None, eink: Path | None) -> bool:
    """Print each write's outcome until timeout, failure or the end; whether Ctrl-C ended it."""
    deadline = None if timeout is None else time.monotonic() + timeout
    interrupted = False
    try:
        while True:
            server.poll()
            _report(server, eink)
            left = math.inf if deadline is None else deadline - time.monotonic()
            if server.failure is not None or server.finished or left <= 0:
                break
            time.sleep(min(_TICK, left))
            checkpoint()
    except KeyboardInterrupt:
        acknowledge()  # taken: what was served is reported, then the command ends
        interrupted = True
    finally:
        server.stop()
    _report(server, eink)
    return interrupted


def _report(server: TagServer, eink: Path | None) -> None:
    """One line per write served since the last report; redraw the E-ink picture if it changed."""
    accepted = None
    for outcome in server.outcomes():
        click.echo(describe_outcome(outcome))
        if outcome.accepted:
            accepted = outcome.state
    if accepted is not None and eink is not None:
        _draw(accepted, eink)


def _draw(state: TagState, eink: Path) -> None:
    """Write the E-ink picture of ``state`` to ``eink`` atomically; else ``OutputError``."""
    from swarmtag.tag.eink import save_png  # noqa: PLC0415 - Pillow, the eink extra

    try:
        save_png(state, eink)
    except OSError as error:
        raise OutputError(f"--eink: {str(eink)!r} cannot be written ({error.strerror})") from None


def _summary(tag: SoftwareTag) -> str:
    counts = tag.counts
    refusals = ", ".join(f"{name} {n}" for name, n in sorted(counts.items()) if name != ACCEPTED)
    line = f"served {tag.accepted + tag.refused} writes: {tag.accepted} accepted, "
    return line + f"{tag.refused} refused" + (f" ({refusals})" if refusals else "")


@click.command("emulate")
@click.option(
    "--marker", required=True, type=click.IntRange(0, 255), help="The tag's ArUco marker id 0-255."
)
@click.option(
    "--key-file",
    required=True,
    metavar="FILE",
    type=click.Path(path_type=Path),
    help="The site key file (swarmtag tag keygen); the tag derives every writer's key from it.",
)
@click.option(
    "--state-file",
    metavar="FILE",
    type=click.Path(path_type=Path),
    help="The tag's flash: booted from if it exists, else provisioned there. "
    "Without it the tag forgets its writers' counters at exit.",
)
@click.option("--urgency", type=click.IntRange(0, 9), help="Urgency 0-9 of a new tag (default 0).")
@click.option(
    "--status",
    metavar="STATUS",
    callback=status,
    help="Status of a new tag: idle (default), awaiting_pickup or picked_up, or 0-2.",
)
@click.option(
    "--destination", type=click.IntRange(0, 255), help="Destination 0-255 of a new tag (default 0)."
)
@click.option(
    "--shared-robot-key/--no-shared-robot-key",
    default=None,
    help="Also accept the legacy key shared by all robots, or stop accepting it (saved in "
    "--state-file) [default: a new tag does not; a stored tag keeps its setting].",
)
@click.option(
    "--timeout",
    type=float,
    callback=seconds_between(0.0, MAX_TIMEOUT),
    metavar="S",
    help="Stop after S seconds (default: run until Ctrl-C).",
)
@click.option(
    "--eink",
    metavar="PNG",
    type=click.Path(path_type=Path),
    help="Keep the tag's E-ink picture in this .png, redrawn after every accepted write.",
)
@click.option(
    "--adapter",
    metavar="hciN",
    callback=adapter,
    help="The BlueZ adapter to serve with (default: the system's first).",
)
@click.option("--replay", metavar="FILE", type=click.Path(path_type=Path), hidden=True)
def emulate_cmd(
    *,
    marker: int,
    key_file: Path,
    state_file: Path | None,
    urgency: int | None,
    status: TagStatus | None,
    destination: int | None,
    shared_robot_key: bool | None,
    timeout: float | None,
    eink: Path | None,
    adapter: str | None,
    replay: Path | None,
) -> None:
    """Run a software tag with this computer's Bluetooth adapter (Linux, BlueZ, bless).

    It advertises the tag's payload and serves the authenticated write and
    the state characteristics (docs/tag-protocol.md), printing one line per
    write. It runs until Ctrl-C or --timeout; needs the tag-emulator extra.
    """
    plan = OutputPlan()
    plan.input("--key-file", key_file)
    if replay is not None:
        plan.input("--replay", replay)
    if state_file is not None:
        plan.file("--state-file", state_file)
    if eink is not None:
        plan.file("--eink", eink, suffixes=(".png",))
    site_key = read_key_file(key_file)
    writes = None if replay is None else read_replay(replay)
    if eink is not None:  # Pillow (the eink extra) is checked before anything is saved
        from swarmtag.tag.eink import png_bytes  # noqa: PLC0415 - Pillow, the eink extra

        png_bytes(TagState(urgency=0, status=TagStatus.IDLE, destination=0, marker=marker))
    tag, pending = _open_tag(
        marker=marker,
        site_key=site_key,
        state_file=state_file,
        urgency=urgency,
        status=status,
        destination=destination,
        shared_robot_key=shared_robot_key,
    )
    server = _open_server(tag, writes, adapter)
    try:
        server.start()
        if server.failure is not None:
            raise server.failure
        _go_live(plan, tag, pending, state_file, eink)
    except BaseException:
        if pending is not None:
            pending.commit(None)  # a write waiting for the state file fails: none will come
        server.stop()
        raise
    state = tag.state
    how = "provisioned" if tag.provisioned else "booted"
    where = f" in {state_file}" if state_file is not None else " in memory"
    stop = "" if isinstance(server, ReplayTagServer) else "; Ctrl-C stops it"
    click.echo(
        f"software tag {state.marker} ({how}{where}) on {server.name}: urgency {state.urgency}, "
        f"{state.status.name}, destination {state.destination}{stop}"
    )
    if tag.shared_robot_key:
        click.echo(
            "note: this tag also accepts the legacy shared robot key (--no-shared-robot-key)"
        )
    interrupted = _serve(server, timeout, eink)
    click.echo(_summary(tag))
    if server.failure is not None:
        raise server.failure
    if interrupted:
        kept = f"; its state is in {state_file}" if state_file is not None else ""
        raise KeyboardInterrupt(f"software tag stopped by Ctrl-C{kept}")
