"""Tools of the console's tests: where Chromium is, whether pictures can be rendered here,
and a direct question to the ground-truth service."""

from __future__ import annotations

import re
import shutil
import socket

from helpers import DEFAULT_TIMEOUT, gl_problem  # noqa: F401  (re-exported)


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


def truth(port: int, name: str | None = None) -> list[dict]:
    """Ask the ground-truth service directly: one dict per object (location, rotation)."""
    with socket.create_connection(("127.0.0.1", port), timeout=DEFAULT_TIMEOUT) as s:
        s.sendall((f"{{Name {name}}}" if name else "{Class}").encode() + b"\r\n")
        data = b""
        while not data.endswith(b"{End}\r\n"):
            chunk = s.recv(65536)
            assert chunk, "the ground-truth service closed the connection"
            data += chunk
    out = []
    for line in data.decode().splitlines():
        m = re.match(r"\{Name (\S+)\} \{Class (\S+)\} \{Time \S+\} \{Location (\S+)\} \{Rotation (\S+)\}", line)
        if m:
            out.append(
                {
                    "name": m.group(1),
                    "class": m.group(2),
                    "location": tuple(float(v) for v in m.group(3).split(",")),
                    "rotation": tuple(float(v) for v in m.group(4).split(",")),
                }
            )
    return out
