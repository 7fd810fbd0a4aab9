"""Isolated controllers for competitions (docs/experiments.md, "Isolation"): with
``isolate: true`` a sweep runs each robot's controller command in a Linux network and mount
namespace of its own (``unshare --net --mount``).  There it can reach the simulator's control,
image and wireless (ComServer, ComServerInterface) ports, at the addresses it is given, and
nothing else: not the other controllers, not the ground truth, not the network.  Its POSIX
shared memory (/dev/shm) is its own; the file system is shared.  What one robot's controller
learns of another's then comes through the simulated radio.

The worker serves each simulator port as a Unix socket in a folder of the controller's
(:class:`HostRelay`); the launcher inside the namespace (:mod:`usarsim.sweep.isolated`) serves the
same port numbers on its own loopback interface and relays them to those sockets.
"""

from __future__ import annotations

import asyncio
import functools
import os
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

from usarsim.sweep.isolated import join, namespaces

# The simulator's listeners a controller may reach (launch.Server.ports names); not the ground
# truth, the console, Foxglove or ROS 2.  The WSS is not among them: it connects to ports the
# robots open, which an isolated controller's namespace does not let in.
REACHABLE = ("control", "image", "comserver", "interface")


def isolation_problem() -> str | None:
    """None when controllers can be isolated here, else why not (to show the user)."""
    if not sys.platform.startswith("linux"):
        return "isolation needs Linux network namespaces"
    if shutil.which("unshare") is None:
        return "isolation needs the unshare program (Debian's util-linux)"
    try:
        r = subprocess.run(["unshare", "--net", "--mount", "true"], capture_output=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"unshare cannot run: {exc}"
    if r.returncode != 0:
        why = r.stderr.decode("utf-8", "replace").strip() or f"exit status {r.returncode}"
        return f"this machine refuses new network namespaces ({why}); isolation needs root, or user namespaces"
    return None


def socket_root() -> Path:
    """Where the relays' folders go (root's /run, else ~/.cache)."""
    for base in (Path("/run"), Path.home() / ".cache"):
        root = base / "usarsim-isolation"
        try:
            root.mkdir(mode=0o755, parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(root, os.W_OK):
            return root
    raise OSError("no writable folder for the isolation sockets (/run or ~/.cache)")


class HostRelay:
    """A folder of Unix sockets, ``PORT.sock`` for each port of ``ports``, each connection to one
    relayed to that port of ``host``; served by a thread of its own until :meth:`close`."""

    def __init__(self, host: str, ports: list[int]):
        self.host = host
        self.ports = list(ports)
        self.dir = Path(tempfile.mkdtemp(prefix="c-", dir=socket_root()))
        self._loop = asyncio.new_event_loop()
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="usarsim-isolation-relay", daemon=True)
        self._thread.start()
        self._ready.wait(30)
        if self._error is not None:
            self.close()
            raise OSError(f"the isolation relay cannot start: {self._error}")

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._servers = [self._loop.run_until_complete(self._serve(p)) for p in self.ports]
        except OSError as exc:
            self._error = exc
            self._ready.set()
            return
        self._ready.set()
        self._loop.run_forever()
        for srv in self._servers:
            srv.close()
        self._loop.close()

    async def _serve(self, port: int) -> asyncio.AbstractServer:
        peer = functools.partial(asyncio.open_connection, self.host, port)
        return await asyncio.start_unix_server(functools.partial(join, peer=peer), str(self.dir / f"{port}.sock"))

    def launcher(self, command: list[str]) -> list[str]:
        """The command line that runs ``command`` isolated, reaching these ports."""
        return [
            "unshare",
            "--net",
            "--mount",
            "--propagation",
            "private",
            "--",
            sys.executable,
            "-m",
            "usarsim.sweep.isolated",
            "--dir",
            str(self.dir),
            "--ports",
            ",".join(str(p) for p in self.ports),
            "--outside",
            namespaces(),
            "--",
            *command,
        ]

    def close(self) -> None:
        if self._loop.is_running():
            self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(10)
        shutil.rmtree(self.dir, ignore_errors=True)
