"""``swarmtag console`` as a real process, for the CLI and browser tests."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import urllib.request
from dataclasses import dataclass
from pathlib import Path

SWARMTAG = Path(sys.executable).with_name("swarmtag")


@dataclass
class Console:
    process: subprocess.Popen[str]
    url: str
    token: str
    folder: Path

    @property
    def base(self) -> str:
        return self.url.split("/?")[0]

    def get(self, path: str, *, token: str | None = None) -> tuple[int, bytes]:
        request = urllib.request.Request(self.base + path)
        if token is not None:
            request.add_header("Authorization", f"Bearer {token}")
        try:
            with urllib.request.urlopen(request, timeout=5) as answer:
                return answer.status, answer.read()
        except urllib.error.HTTPError as error:
            return error.code, error.read()

    def post(self, path: str, body: bytes) -> tuple[int, bytes]:
        request = urllib.request.Request(self.base + path, data=body, method="POST")
        request.add_header("Authorization", f"Bearer {self.token}")
        try:
            with urllib.request.urlopen(request, timeout=5) as answer:
                return answer.status, answer.read()
        except urllib.error.HTTPError as error:
            return error.code, error.read()

    def close(self) -> None:
        """Kill the process if it still runs; close its pipes."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.communicate()

    def interrupt(self) -> float:
        """Send SIGINT; seconds until the process exited."""
        start = time.monotonic()
        self.process.send_signal(signal.SIGINT)
        self.process.wait(timeout=10)
        return time.monotonic() - start


def start(folder: Path, *args: str, source: tuple[str, ...] = ("--sim",)) -> Console:
    """Start ``swarmtag console SOURCE --port 0`` in ``folder``; wait for its URL line."""
    process = subprocess.Popen(
        [str(SWARMTAG), "console", *source, "--port", "0", "--token-file", "token", *args],
        cwd=folder,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert process.stdout is not None
    line = process.stdout.readline()
    if not line.startswith("swarmtag console: http://127.0.0.1:"):
        process.kill()
        _out, err = process.communicate()
        raise AssertionError(f"no URL line: {line!r} {err}")
    url = line.split(": ", 1)[1].strip()
    return Console(process, url, url.split("token=")[1], folder)
