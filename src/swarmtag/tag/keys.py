"""Site keys, the role keys derived from them, and their key files.

Who holds what: a *tag* holds the site key; a *writer* holds only the key of
its role, ``derive_role_key(site_key, role)``. A tag recomputes the role key
of the role named in a write's flags and checks the MAC under it, so a write
verifies only under the key of the role it claims. The derivation is
HKDF-SHA256 (RFC 5869, extract then expand, built here on the standard
library's ``hmac``)::

    PRK      = HMAC-SHA256(key=HKDF_SALT, msg=site key)          # extract
    role key = HMAC-SHA256(key=PRK, msg=ROLE_KEY_INFO[role] || 0x01)  # expand, L = 32

HKDF's outputs for different ``info`` strings are independent pseudorandom
keys: a robot's key reveals nothing about the operator key or the site key,
so a compromised robot cannot sign an operator's write.

The site key file (``write_key_file``, ``read_key_file``) is ASCII text of
exactly two lines, each ending in a line feed::

    swarmtag-site-key-v1
    <64 hex digits: the 32-byte site key>

A role key file (``write_role_key_file``, ``read_role_key_file``) is the
same, with the header ``swarmtag-robot-key-v1`` or ``swarmtag-operator-key-v1``
and the 32-byte role key: it is what a writer's machine holds. Each reader
refuses the other kind by name (a site key on a robot would undo the role
separation; a role key on a tag verifies nothing).

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
from pathlib import Path
from types import MappingProxyType
from typing import Final

from swarmtag._atomic import fsync_folder
from swarmtag._inputs import as_path
from swarmtag.errors import FieldRangeError, KeyFileError
from swarmtag.tag._arguments import as_bytes, check_int
from swarmtag.tag.lifecycle import Role, check_role

__all__ = [
    "HKDF_SALT",
    "KEY_FILE_HEADER",
    "MIN_KEY_LENGTH",
    "ROLE_KEY_FILE_HEADERS",
    "ROLE_KEY_INFO",
    "ROLE_KEY_LENGTH",
    "SITE_KEY_LENGTH",
    "check_role_key",
    "check_site_key",
    "derive_role_key",
    "generate_site_key",
    "hkdf_sha256",
    "read_key_file",
    "read_role_key_file",
    "write_key_file",
    "write_role_key_file",
]

MIN_KEY_LENGTH: Final = 16
"""Site keys shorter than 128 bits are refused."""
SITE_KEY_LENGTH: Final = 32
"""Bytes of a generated site key, and of the key in a key file."""
ROLE_KEY_LENGTH: Final = 32
"""Bytes of a role key: one SHA-256 output."""
HKDF_SALT: Final = b"swarmtag hkdf salt v1"
"""The fixed HKDF salt (21 ASCII bytes)."""
ROLE_KEY_INFO: Final = MappingProxyType(
    {
        Role.ROBOT: b"swarmtag write key v1 robot",
        Role.OPERATOR: b"swarmtag write key v1 operator",
    }
)
"""The HKDF ``info`` string of each role (ASCII, no terminator)."""
KEY_FILE_HEADER: Final = "swarmtag-site-key-v1"
"""First line of a site key file."""
ROLE_KEY_FILE_HEADERS: Final = MappingProxyType(
    {Role.ROBOT: "swarmtag-robot-key-v1", Role.OPERATOR: "swarmtag-operator-key-v1"}
)
"""First line of a role key file, by role."""

_HASH_LENGTH: Final = 32
_MAX_FILE_BYTES: Final = 4096
_PRIVATE_BITS: Final = 0o077
_FORMAT_HINT: Final = (
    f"expected the line {KEY_FILE_HEADER!r}, then a line of {2 * SITE_KEY_LENGTH} hex digits "
    "(make one with 'swarmtag tag keygen --out FILE')"
)
_ROLE_FORMAT_HINT: Final = (
    f"expected the line {ROLE_KEY_FILE_HEADERS[Role.ROBOT]!r} or "
    f"{ROLE_KEY_FILE_HEADERS[Role.OPERATOR]!r}, then a line of {2 * ROLE_KEY_LENGTH} hex digits "
    "(derive one with 'swarmtag tag keygen --role robot|operator --from SITE.key --out FILE')"
)
_ROLE_BY_HEADER: Final = {header: role for role, header in ROLE_KEY_FILE_HEADERS.items()}


def check_site_key(key: object) -> bytes:
    """Return ``key`` as bytes if it is a usable site key (bytes-like, at least 16 bytes)."""
    data = as_bytes("site_key", key, FieldRangeError)
    if len(data) < MIN_KEY_LENGTH:
        raise FieldRangeError(f"site_key: must be at least {MIN_KEY_LENGTH} bytes, got {len(data)}")
    return data


def check_role_key(key: object) -> bytes:
    """Return ``key`` as bytes if it has the shape of a role key (bytes-like, 32 bytes)."""
    data = as_bytes("key", key, FieldRangeError)
    if len(data) != ROLE_KEY_LENGTH:
        raise FieldRangeError(
            f"key: a role key is {ROLE_KEY_LENGTH} bytes, got {len(data)}; "
            "get one with derive_role_key(site_key, role)"
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
    """The 32-byte key that writers of ``role`` sign with: give each writer only this.

    >>> robot = derive_role_key(bytes(range(16)), Role.ROBOT)
    >>> len(robot), robot == derive_role_key(bytes(range(16)), Role.OPERATOR)
    (32, False)
    """
    info = ROLE_KEY_INFO[check_role(role)]
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
    return _write(path, KEY_FILE_HEADER, key, SITE_KEY_LENGTH)


def write_role_key_file(path: str | os.PathLike[str], role: object, key: bytes) -> Path:
    """Save the 32-byte key of ``role`` to a new role key file ``path`` (mode 0600).

    ``key`` is ``derive_role_key(site_key, role)``; the same rules as
    ``write_key_file`` apply (never overwrites, complete or absent).
    """
    header = ROLE_KEY_FILE_HEADERS[check_role(role)]
    return _write(path, header, key, ROLE_KEY_LENGTH)


def _write(path: str | os.PathLike[str], header: str, key: bytes, length: int) -> Path:
    """Create the key file ``path``: ``header``, then ``key`` (``length`` bytes) in hex."""
    target = as_path(path, what="key file path", error=KeyFileError)
    data = as_bytes("key", key, FieldRangeError)
    if len(data) != length:
        raise FieldRangeError(f"key: a key file holds a {length}-byte key, got {len(data)}")
    if not os.path.isdir(target.parent):  # noqa: PTH112 - Path.is_dir raises ENAMETOOLONG
        raise KeyFileError(f"cannot write key file {target}: folder {target.parent} does not exist")
    if os.path.lexists(target):
        raise KeyFileError(f"key file {target} already exists; refusing to overwrite a key")
    text = f"{header}\n{data.hex()}\n".encode("ascii")
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
    (``chmod 600``): a key others can read is no longer a secret. A role key
    file is refused by name: a tag needs the site key.
    """
    target, header, digits = _read(path)
    role = _ROLE_BY_HEADER.get(header)
    if role is not None:
        raise KeyFileError(
            f"key file {target} is a {role.name.lower()} key file, not a site key file: a tag "
            "holds the site key (made by 'swarmtag tag keygen --out FILE'), writers their role key"
        )
    if header != KEY_FILE_HEADER or not _is_hex(digits, SITE_KEY_LENGTH):
        raise KeyFileError(f"key file {target} is not a swarmtag site key file: {_FORMAT_HINT}")
    return bytes.fromhex(digits)


def read_role_key_file(path: str | os.PathLike[str]) -> tuple[Role, bytes]:
    """The role and the role key in the role key file ``path``; ``KeyFileError`` if unusable.

    The same rules as ``read_key_file`` apply. The site key file is refused by
    name: a writer's machine must hold only its role's key.
    """
    target, header, digits = _read(path)
    if header == KEY_FILE_HEADER:
        raise KeyFileError(
            f"key file {target} is the site key file, not a role key file: a writer holds only "
            f"its role's key; derive one with 'swarmtag tag keygen --role robot|operator --from "
            f"{target} --out ROLE.key'"
        )
    role = _ROLE_BY_HEADER.get(header)
    if role is None or not _is_hex(digits, ROLE_KEY_LENGTH):
        raise KeyFileError(
            f"key file {target} is not a swarmtag role key file: {_ROLE_FORMAT_HINT}"
        )
    return role, bytes.fromhex(digits)


def _read(path: str | os.PathLike[str]) -> tuple[Path, str, str]:
    """A private key file's path, header line and key line; refuses anything unsafe to read."""
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
    header, _, rest = data.partition(b"\n")
    line, newline, tail = rest.partition(b"\n")
    if not newline or tail:
        return target, "", ""  # not two lines: no header can match
    return target, header.decode("ascii", "replace"), line.decode("ascii", "replace")


def _is_hex(digits: str, length: int) -> bool:
    """Whether ``digits`` is exactly ``length`` bytes in hex (never shown in a message)."""
    return len(digits) == 2 * length and all(char in string.hexdigits for char in digits)
