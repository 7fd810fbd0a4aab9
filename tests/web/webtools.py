"""Tools of the console's tests: where Chromium is, whether pictures can be rendered here,
and a direct question to the ground-truth service."""

from __future__ import annotations

import re
import shutil
import socket
import threading
from functools import lru_cache

from helpers import DEFAULT_TIMEOUT


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


@lru_cache(maxsize=None)
def gl_problem() -> str:
    """'' when an offscreen OpenGL context can be made here (pictures can be rendered), else why not."""
    import mujoco

    box: dict[str, str] = {}

    def probe():
        try:
            m = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
            r = mujoco.Renderer(m, 8, 8)
            r.render()
            r.close()
            box["ok"] = ""
        except Exception as exc:  # no display, no EGL, no OSMesa
            box["ok"] = f"no OpenGL context for rendering: {exc}"

    t = threading.Thread(target=probe)
    t.start()
    t.join(60)
    return box.get("ok", "the OpenGL probe did not finish")


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
            out.append({"name": m.group(1), "class": m.group(2),
                        "location": tuple(float(v) for v in m.group(3).split(",")),
                        "rotation": tuple(float(v) for v in m.group(4).split(","))})
    return out
