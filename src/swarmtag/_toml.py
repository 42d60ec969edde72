"""Reading a TOML file with one clear error per failure (missing, unreadable, not TOML)."""

from __future__ import annotations

import os
import tomllib
from typing import Any

from swarmtag._inputs import regular_file
from swarmtag.errors import SwarmtagError

__all__ = ["read_toml"]


def read_toml(
    path: str | os.PathLike[str], *, what: str, error: type[SwarmtagError]
) -> dict[str, Any]:
    """The top table of the TOML file at ``path``; failures raise ``error`` naming the file.

    ``what`` names the kind of file in the "no such ..." message (``"study file"``).
    """
    name = os.fspath(path)
    try:
        with regular_file(path, what=what, error=error).open("rb") as handle:
            return tomllib.load(handle)
    except FileNotFoundError:
        msg = f"{name}: no such {what}"
        raise error(msg) from None
    except OSError as problem:
        msg = f"{name}: cannot read ({problem.strerror})"
        raise error(msg) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as problem:
        msg = f"{name}: not valid TOML ({problem})"
        raise error(msg) from None
