"""Site keys, the writer keys derived from them, and their key files.

Who holds what: a *tag* holds the site key; a *robot* holds only its own
**robot key**, bound to its writer id, ``derive_robot_key(site_key, writer)``;
an *operator* holds the operator key, ``derive_role_key(site_key,
Role.OPERATOR)``. A tag recomputes, for each write, the key of the role and
writer id the write names, and checks the MAC under it: a write verifies only
under the key of the role and writer id it claims. All keys come from
HKDF-SHA256 (RFC 5869, extract then expand, built here on the standard
library's ``hmac``), each with its own ``info``::

    PRK       = HMAC-SHA256(key=HKDF_SALT, msg=site key)                     # extract
    key       = HMAC-SHA256(key=PRK, msg=info || 0x01)                       # expand, L = 32
    info      = ROBOT_KEY_INFO || writer id (uint16 little-endian)           # robot key
              | ROLE_KEY_INFO[Role.OPERATOR]                                  # operator key
              | ROLE_KEY_INFO[Role.ROBOT]                     # legacy shared robot key

HKDF's outputs for different ``info`` strings are independent pseudorandom
keys: robot 7's key reveals nothing about robot 9's, the operator key or the
site key. The shared robot key (one for all robots) is kept only for tags set
to accept it (``TagModel.shared_robot_key``; docs/tag-protocol.md §4).

The site key file (``write_key_file``, ``read_key_file``) is ASCII text of
exactly two lines, each ending in a line feed::

    swarmtag-site-key-v1
    <64 hex digits: the 32-byte site key>

A robot key file (``write_robot_key_file``) has three lines: the header
``swarmtag-robot-writer-key-v1``, the writer id in decimal, and the 32-byte
key. A role key file (``write_role_key_file``) has two: the header
``swarmtag-operator-key-v1`` (or, legacy, ``swarmtag-robot-key-v1``) and the
key. ``read_writer_key_file`` reads any writer's file; each reader refuses the
other kinds by name (a site key on a robot would undo the separation; a
writer's key on a tag verifies nothing).

Key files are created with mode 0600 and refused when group or others have
any access to them, like an ssh private key. Errors are ``KeyFileError`` and
name the file, never its content.
"""

from __future__ import annotations

import contextlib
import hashlib
import hmac
import os
import secrets
import stat
import string
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Final

from swarmtag._atomic import fsync_folder
from swarmtag._inputs import as_path
from swarmtag.errors import ConfigError, FieldRangeError, KeyFileError
from swarmtag.tag._arguments import as_bytes, check_int, describe
from swarmtag.tag.lifecycle import Role, check_role

__all__ = [
    "HKDF_SALT",
    "KEY_FILE_HEADER",
    "MIN_KEY_LENGTH",
    "ROBOT_KEY_FILE_HEADER",
    "ROBOT_KEY_INFO",
    "ROLE_KEY_FILE_HEADERS",
    "ROLE_KEY_INFO",
    "ROLE_KEY_LENGTH",
    "SITE_KEY_LENGTH",
    "WriterKey",
    "check_role_key",
    "check_site_key",
    "derive_robot_key",
    "derive_role_key",
    "generate_site_key",
    "hkdf_sha256",
    "read_key_file",
    "read_role_key_file",
    "read_writer_key_file",
    "robot_key_info",
    "write_key_file",
    "write_robot_key_file",
    "write_role_key_file",
]

MIN_KEY_LENGTH: Final = 16
"""Site keys shorter than 128 bits are refused."""
SITE_KEY_LENGTH: Final = 32
"""Bytes of a generated site key, and of the key in a key file."""
ROLE_KEY_LENGTH: Final = 32
"""Bytes of a writer's key (robot, operator or shared robot key): one SHA-256 output."""
HKDF_SALT: Final = b"swarmtag hkdf salt v1"
"""The fixed HKDF salt (21 ASCII bytes)."""
ROLE_KEY_INFO: Final = MappingProxyType(
    {
        Role.ROBOT: b"swarmtag write key v1 robot",
        Role.OPERATOR: b"swarmtag write key v1 operator",
    }
)
"""The HKDF ``info`` of each role key (ASCII, no terminator); the robot one is legacy."""
ROBOT_KEY_INFO: Final = b"swarmtag writer key v1 robot"
"""The HKDF ``info`` of a robot key, before the writer id's 2 bytes (28 ASCII bytes)."""
KEY_FILE_HEADER: Final = "swarmtag-site-key-v1"
"""First line of a site key file."""
ROLE_KEY_FILE_HEADERS: Final = MappingProxyType(
    {Role.ROBOT: "swarmtag-robot-key-v1", Role.OPERATOR: "swarmtag-operator-key-v1"}
)
"""First line of a role key file, by role (the robot one holds the legacy shared key)."""
ROBOT_KEY_FILE_HEADER: Final = "swarmtag-robot-writer-key-v1"
"""First line of a robot key file; its second line is the writer id."""

_MAX_WRITER: Final = 0xFFFF
_HASH_LENGTH: Final = 32
_MAX_FILE_BYTES: Final = 4096
_PRIVATE_BITS: Final = 0o077
_FORMAT_HINT: Final = (
    f"expected the line {KEY_FILE_HEADER!r}, then a line of {2 * SITE_KEY_LENGTH} hex digits "
    "(make one with 'swarmtag tag keygen --out FILE')"
)
_DERIVE_HINT: Final = (
    "derive one with 'swarmtag tag keygen --role robot --writer ID --from SITE.key --out FILE' "
    "or '--role operator --from SITE.key --out FILE'"
)
_ROLE_BY_HEADER: Final = {header: role for role, header in ROLE_KEY_FILE_HEADERS.items()}
_WRITER_ID: Final = frozenset(string.digits)


@dataclass(frozen=True, slots=True)
class WriterKey:
    """What a writer's key file holds: its role, its 32-byte key, and the writer id it is bound to.

    ``writer`` is ``None`` for a key shared by a role: the operator key, or
    the legacy shared robot key.
    """

    role: Role
    key: bytes
    writer: int | None = None

    def __post_init__(self) -> None:
        """Refuse fields no key file holds (``FieldRangeError``); only robot keys name a writer."""
        object.__setattr__(self, "role", check_role(self.role))
        object.__setattr__(self, "key", check_role_key(self.key))
        if self.writer is not None:
            check_int("writer", self.writer, _MAX_WRITER)
            if self.role is not Role.ROBOT:
                raise FieldRangeError("writer: only a robot key is bound to a writer id")

    def writer_id(self, writer: int | None, path: str | os.PathLike[str]) -> int:
        """The writer id to sign with: this key's own, or ``writer`` for a shared key.

        ``ConfigError`` (naming the key file ``path``) when a robot key is given
        another ``writer`` (every tag would refuse its writes as forged), or a
        shared key none.
        """
        given: object = writer
        if given is not None and (
            isinstance(given, bool) or not isinstance(given, int) or not 0 <= given <= _MAX_WRITER
        ):
            raise ConfigError(f"writer: {describe(given)} is not a writer id in 0-{_MAX_WRITER}")
        shown = os.fspath(path) if isinstance(path, str | os.PathLike) else describe(path)
        if self.writer is None:
            if writer is None:
                raise ConfigError(
                    f"the key file {shown} holds the {self.role.name.lower()} key, shared by its "
                    "writers: give this writer's id (--writer ID)"
                )
            return writer
        if writer is not None and writer != self.writer:
            raise ConfigError(
                f"writer {writer} does not match the key file {shown}, which is robot "
                f"{self.writer}'s key (a robot key signs only for its own writer id); "
                "nothing was sent"
            )
        return self.writer


def check_site_key(key: object) -> bytes:
    """Return ``key`` as bytes if it is a usable site key (bytes-like, at least 16 bytes)."""
    data = as_bytes("site_key", key, FieldRangeError)
    if len(data) < MIN_KEY_LENGTH:
        raise FieldRangeError(f"site_key: must be at least {MIN_KEY_LENGTH} bytes, got {len(data)}")
    return data


def check_role_key(key: object) -> bytes:
    """Return ``key`` as bytes if it has the shape of a writer's key (bytes-like, 32 bytes)."""
    data = as_bytes("key", key, FieldRangeError)
    if len(data) != ROLE_KEY_LENGTH:
        raise FieldRangeError(
            f"key: a writer's key is {ROLE_KEY_LENGTH} bytes, got {len(data)}; "
            "get one with derive_robot_key(site_key, writer) or derive_role_key(site_key, role)"
        )
    return data


def hkdf_sha256(ikm: bytes, *, salt: bytes, info: bytes, length: int) -> bytes:
    """HKDF-SHA256 of RFC 5869: ``length`` bytes of key from ``ikm``, ``salt`` and ``info``.

    An empty ``salt`` is HMAC's all-zero key, as the RFC specifies.

    >>> hkdf_sha256(bytes([11] * 22), salt=b"", info=b"", length=42).hex()[:16]  # RFC 5869 A.3
    '8da4e775a563c18f'
    """
    secret = as_bytes("ikm", ikm, FieldRangeError)
    salt = as_bytes("salt", salt, FieldRangeError)
    info = as_bytes("info", info, FieldRangeError)
    check_int("length", length, 255 * _HASH_LENGTH, low=1)
    prk = hmac.new(salt, secret, hashlib.sha256).digest()
    block, output = b"", b""
    for counter in range(1, -(-length // _HASH_LENGTH) + 1):
        block = hmac.new(prk, block + info + bytes((counter,)), hashlib.sha256).digest()
        output += block
    return output[:length]


def derive_role_key(site_key: object, role: object) -> bytes:
    """The 32-byte key shared by the writers of ``role``: the operator key (or legacy robot key).

    Robots get ``derive_robot_key`` instead; the shared robot key verifies only
    on tags set to accept it (``TagModel.shared_robot_key``).

    >>> robot = derive_role_key(bytes(range(16)), Role.ROBOT)
    >>> len(robot), robot == derive_role_key(bytes(range(16)), Role.OPERATOR)
    (32, False)
    """
    info = ROLE_KEY_INFO[check_role(role)]
    return hkdf_sha256(check_site_key(site_key), salt=HKDF_SALT, info=info, length=ROLE_KEY_LENGTH)


def robot_key_info(writer: int) -> bytes:
    r"""The HKDF ``info`` of robot ``writer``'s key: ``ROBOT_KEY_INFO`` + the id, uint16 LE.

    The id's two bytes are bytes 2-3 of the robot's writes, as they are.

    >>> robot_key_info(7)[-2:]
    b'\x07\x00'
    """
    return ROBOT_KEY_INFO + check_int("writer", writer, _MAX_WRITER).to_bytes(2, "little")


def derive_robot_key(site_key: object, writer: int) -> bytes:
    """The 32-byte key of robot ``writer``: it signs only writes that carry that writer id.

    >>> key = bytes(range(16))
    >>> derive_robot_key(key, 7) == derive_robot_key(key, 9), len(derive_robot_key(key, 7))
    (False, 32)
    """
    info = robot_key_info(writer)
    return hkdf_sha256(check_site_key(site_key), salt=HKDF_SALT, info=info, length=ROLE_KEY_LENGTH)


def generate_site_key() -> bytes:
    """A new random 32-byte site key from the operating system's CSPRNG (``secrets``)."""
    return secrets.token_bytes(SITE_KEY_LENGTH)


def _failed(target: Path, doing: str, error: OSError) -> KeyFileError:
    return KeyFileError(f"cannot {doing} key file {target}: {error.strerror or error}")


def write_key_file(path: str | os.PathLike[str], key: bytes) -> Path:
    """Save the 32-byte site ``key`` to a new file ``path`` (mode 0600); return its path.

    Never overwrites: an existing ``path`` is refused, and so is a missing
    folder. The file appears complete or not at all (temporary file, fsync,
    hard link into place, which fails if the name was taken meanwhile).
    """
    return _write(path, [KEY_FILE_HEADER], key, SITE_KEY_LENGTH)


def write_role_key_file(path: str | os.PathLike[str], role: object, key: bytes) -> Path:
    """Save the 32-byte key of ``role`` to a new role key file ``path`` (mode 0600).

    ``key`` is ``derive_role_key(site_key, role)``; the same rules as
    ``write_key_file`` apply (never overwrites, complete or absent).
    """
    header = ROLE_KEY_FILE_HEADERS[check_role(role)]
    return _write(path, [header], key, ROLE_KEY_LENGTH)


def write_robot_key_file(path: str | os.PathLike[str], writer: int, key: bytes) -> Path:
    """Save robot ``writer``'s 32-byte key to a new robot key file ``path`` (mode 0600).

    ``key`` is ``derive_robot_key(site_key, writer)``; the same rules as
    ``write_key_file`` apply (never overwrites, complete or absent).
    """
    check_int("writer", writer, _MAX_WRITER)
    return _write(path, [ROBOT_KEY_FILE_HEADER, str(writer)], key, ROLE_KEY_LENGTH)


def _write(path: str | os.PathLike[str], lines: list[str], key: bytes, length: int) -> Path:
    """Create the key file ``path``: the ``lines``, then ``key`` (``length`` bytes) in hex."""
    target = as_path(path, what="key file path", error=KeyFileError)
    data = as_bytes("key", key, FieldRangeError)
    if len(data) != length:
        raise FieldRangeError(f"key: a key file holds a {length}-byte key, got {len(data)}")
    if not os.path.isdir(target.parent):  # noqa: PTH112 - Path.is_dir raises ENAMETOOLONG
        raise KeyFileError(f"cannot write key file {target}: folder {target.parent} does not exist")
    if os.path.lexists(target):
        raise KeyFileError(f"key file {target} already exists; refusing to overwrite a key")
    text = "".join(f"{line}\n" for line in [*lines, data.hex()]).encode("ascii")
    temp = target.parent / f".{target.name}.{secrets.token_hex(6)}.tmp"
    try:
        _write_private(temp, text)
        os.link(temp, target)  # unlike a rename, never replaces an existing file
    except FileExistsError:
        raise KeyFileError(
            f"key file {target} already exists; refusing to overwrite a key"
        ) from None
    except OSError as error:
        raise _failed(target, "write", error) from None
    finally:
        with contextlib.suppress(OSError):  # never created (e.g. a name too long)
            temp.unlink()
    fsync_folder(target.parent)
    return target


def _write_private(path: Path, text: bytes) -> None:
    """Create ``path`` (it must not exist) with mode 0600, write ``text`` and flush it to disk."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        if hasattr(os, "fchmod"):
            os.fchmod(fd, 0o600)  # exactly 0600, whatever the umask says
        view = memoryview(text)
        while view:
            view = view[os.write(fd, view) :]
        os.fsync(fd)
    finally:
        os.close(fd)


def read_key_file(path: str | os.PathLike[str]) -> bytes:
    """The site key in the key file ``path``; ``KeyFileError`` if it is missing, shared or bad.

    On POSIX systems the file must give group and others no access at all
    (``chmod 600``): a key others can read is no longer a secret. A writer's
    key file is refused by name: a tag needs the site key.
    """
    target, lines = _read(path)
    kind = _writer_kind(lines[0]) if lines else None
    if kind is not None:
        raise KeyFileError(
            f"key file {target} is {kind}, not a site key file: a tag holds the site key "
            "(made by 'swarmtag tag keygen --out FILE'), writers their own key"
        )
    if lines[:1] != [KEY_FILE_HEADER] or not _key_line(lines[1:], SITE_KEY_LENGTH):
        raise KeyFileError(f"key file {target} is not a swarmtag site key file: {_FORMAT_HINT}")
    return bytes.fromhex(lines[1])


def read_role_key_file(path: str | os.PathLike[str]) -> tuple[Role, bytes]:
    """The role and the shared key in the role key file ``path``; ``KeyFileError`` if unusable.

    Only role key files (the operator key, the legacy shared robot key); a
    robot key file (bound to a writer id) is read by ``read_writer_key_file``.
    """
    found = read_writer_key_file(path)
    if found.writer is not None:
        raise KeyFileError(
            f"key file {Path(path)} is robot {found.writer}'s key file, bound to its writer id, "
            "not a role key file: read it with read_writer_key_file"
        )
    return found.role, found.key


def read_writer_key_file(path: str | os.PathLike[str]) -> WriterKey:
    """The key in a writer's key file ``path`` (robot, operator or legacy shared robot key).

    The same rules as ``read_key_file`` apply. The site key file is refused by
    name: a writer's machine must hold only its own key.
    """
    target, lines = _read(path)
    header = lines[0] if lines else ""
    if header == KEY_FILE_HEADER:
        raise KeyFileError(
            f"key file {target} is the site key file, not a writer's key file: a writer holds "
            "only its own key; derive one with 'swarmtag tag keygen --role robot --writer ID "
            f"--from {target} --out FILE' (or --role operator)"
        )
    role = _ROLE_BY_HEADER.get(header)
    if role is not None and _key_line(lines[1:], ROLE_KEY_LENGTH):
        return WriterKey(role=role, key=bytes.fromhex(lines[1]))
    if (
        header == ROBOT_KEY_FILE_HEADER
        and len(lines) == 3
        and _is_writer_id(lines[1])
        and _key_line(lines[2:], ROLE_KEY_LENGTH)
    ):
        return WriterKey(role=Role.ROBOT, key=bytes.fromhex(lines[2]), writer=int(lines[1]))
    raise KeyFileError(
        f"key file {target} is not a swarmtag writer's key file: expected the line "
        f"{ROBOT_KEY_FILE_HEADER!r}, a writer id and {2 * ROLE_KEY_LENGTH} hex digits, or "
        f"{ROLE_KEY_FILE_HEADERS[Role.OPERATOR]!r} (or {ROLE_KEY_FILE_HEADERS[Role.ROBOT]!r}) "
        f"and {2 * ROLE_KEY_LENGTH} hex digits ({_DERIVE_HINT})"
    )


def _writer_kind(header: str) -> str | None:
    """What kind of writer's key file ``header`` starts, in words (``None``: none)."""
    if header == ROBOT_KEY_FILE_HEADER:
        return "a robot key file"
    role = _ROLE_BY_HEADER.get(header)
    return None if role is None else f"a {role.name.lower()} key file"


def _read(path: str | os.PathLike[str]) -> tuple[Path, list[str]]:
    """A private key file's path and lines (``[]`` if not all end in a line feed)."""
    target = as_path(path, what="key file path", error=KeyFileError)
    try:
        fd = os.open(target, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))  # a FIFO cannot hang us
    except FileNotFoundError:
        raise KeyFileError(f"key file {target} does not exist") from None
    except OSError as error:
        raise _failed(target, "open", error) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise KeyFileError(f"key file {target} is not a regular file")
        mode = stat.S_IMODE(info.st_mode)
        if os.name == "posix" and mode & _PRIVATE_BITS:
            raise KeyFileError(
                f"key file {target} is accessible to other users (mode {mode:04o}); "
                f"a key must be private: run 'chmod 600 {target}'"
            )
        data = os.read(fd, _MAX_FILE_BYTES + 1)
    except OSError as error:
        raise _failed(target, "read", error) from None
    finally:
        os.close(fd)
    if not data.endswith(b"\n") or len(data) > _MAX_FILE_BYTES:
        return target, []  # not whole lines: no header can match
    return target, data[:-1].decode("ascii", "replace").split("\n")


def _key_line(lines: list[str], length: int) -> bool:
    """Whether ``lines`` is exactly one line of ``length`` bytes in hex (never shown)."""
    return len(lines) == 1 and _is_hex(lines[0], length)


def _is_writer_id(text: str) -> bool:
    """Whether ``text`` is a writer id 0-65535 in decimal, without sign or leading zeros."""
    plain = 0 < len(text) <= 5 and set(text) <= _WRITER_ID and (text == "0" or text[0] != "0")
    return plain and int(text) <= _MAX_WRITER


def _is_hex(digits: str, length: int) -> bool:
    """Whether ``digits`` is exactly ``length`` bytes in hex (never shown in a message)."""
    return len(digits) == 2 * length and all(char in string.hexdigits for char in digits)
