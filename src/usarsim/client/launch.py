"""Starting a simulator for a script: ``usarsim serve`` in a subprocess on free ports, stopped
when the ``with`` block ends."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from typing import Any

from .blocking import World
from .core import DEFAULT_TIMEOUT_S, ClientError

_LISTENING = re.compile(r"usarsim: (\w+) listening on ([\w.:\-]+):(\d+)")
START_TIMEOUT_S = 120.0


class Server:
    """A ``usarsim serve`` subprocess: its ``host``, control ``port`` and every listener's
    port in ``ports`` (``control``, ``truth``, and ``image``, ``web``, ``comserver``, ``wss``,
    ``cominterface`` when started)."""

    def __init__(
        self,
        args: list[str],
        lockstep: bool,
        timeout: float,
        expected: frozenset[str] = frozenset({"control", "truth"}),
        more: bool = True,
    ):
        """Start ``usarsim serve`` with ``args`` and wait until every listener in ``expected``
        has said where it listens; ``more``: others may follow in the same burst (options
        this class did not choose), which are given a tenth of a second."""
        self.lockstep = lockstep
        self.timeout = timeout
        self._stderr = tempfile.TemporaryFile(mode="w+")
        env = dict(os.environ)
        env.setdefault("MUJOCO_GL", "egl")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "usarsim", "serve", *args],
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            stdin=subprocess.DEVNULL,
            text=True,
            env=env,
        )
        self.ports: dict[str, int] = {}
        self.host = "127.0.0.1"

        ready = threading.Event()  # every expected listener has said where it listens, or stdout ended

        def read_ports() -> None:  # every stdout line, to the end (the pipe never fills)
            assert self.proc.stdout is not None
            for line in self.proc.stdout:
                m = _LISTENING.search(line)
                if m:
                    self.host = m.group(2)
                    self.ports[m.group(1)] = int(m.group(3))
                    if expected <= set(self.ports):
                        ready.set()
            ready.set()  # the process has ended (or closed its output): no more to wait for

        self._reader = threading.Thread(target=read_ports, name="usarsim-launch", daemon=True)
        self._reader.start()
        ready.wait(START_TIMEOUT_S)
        if more:
            time.sleep(0.1)  # the other listener lines, printed in the same burst
        if not expected <= set(self.ports):
            self.close(keep_stderr=True)
            tail = self.stderr_tail()
            self._stderr.close()
            raise ClientError(f"the simulator did not start: {tail}")

    @property
    def port(self) -> int:
        return self.ports["control"]

    def connect(self, timeout: float | None = None) -> World:
        """A :class:`World` on this server (lock-step if the server is)."""
        return World(
            self.host,
            self.port,
            lockstep=self.lockstep,
            truth_port=self.ports.get("truth"),
            image_port=self.ports.get("image"),
            comserver_port=self.ports.get("comserver"),
            timeout=self.timeout if timeout is None else timeout,
        )

    def stderr_tail(self, n: int = 2000) -> str:
        try:
            self._stderr.seek(0)
            return self._stderr.read()[-n:].strip() or "(nothing on stderr)"
        except (OSError, ValueError):
            return "(stderr unavailable)"

    def close(self, keep_stderr: bool = False) -> None:
        """Stop the simulator (SIGTERM, then kill if it does not end within 30 s)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        self._reader.join(5)
        if self.proc.stdout is not None:
            self.proc.stdout.close()
        if not keep_stderr:
            self._stderr.close()

    def __enter__(self) -> Server:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def launch(
    world: str = "DM-USAR_yellow",
    *,
    seed: int = 0,
    lockstep: bool = True,
    speed: float | None = 1.0,
    wireless: bool = False,
    image: bool = False,
    web: bool = False,
    robot_dirs: tuple[str, ...] = (),
    record: str | os.PathLike | None = None,
    foxglove: bool = False,
    extra_args: tuple[str, ...] = (),
    timeout: float = DEFAULT_TIMEOUT_S,
    transport: str = "tcp",
    variant: int | None = None,
) -> Any:
    """Start a simulator on free ports of 127.0.0.1: ``world`` (a shipped name or a file; its
    ``variant``, ``usarsim serve --variant``, when given), ``seed``, lock-step (default) or
    real time at ``speed`` (None: as fast as it can).
    ``wireless``, ``image`` and ``web`` start those services too; ``record`` records the run
    to that MCAP file (written as it goes, closed when the server stops); ``foxglove`` serves it live to
    Foxglove (its port in ``ports["foxglove"]``).  Use it in a ``with`` block, or call
    :meth:`Server.close`.

    ``transport="inproc"`` runs the simulator in this process instead, lock-step, driven on
    the caller's thread without sockets or text (:mod:`usarsim.client.direct`): the same
    readings, bit for bit, several times faster; it serves no port, so pictures, the radio
    and the web console are not available on it."""
    if transport not in TRANSPORTS:
        raise ValueError(f"transport must be one of {', '.join(TRANSPORTS)}, got {transport!r}")
    if transport == "inproc":
        return _launch_inproc(
            world,
            seed=seed,
            variant=variant,
            lockstep=lockstep,
            robot_dirs=robot_dirs,
            timeout=timeout,
            asked={
                "wireless": wireless,
                "image": image,
                "web": web,
                "record": record is not None,
                "foxglove": foxglove,
                "extra_args": bool(extra_args),
            },
        )
    args = ["--world", str(world), "--seed", str(int(seed)), "--port", "0", "--truth-port", "0"]
    if variant is not None:
        args += ["--variant", str(int(variant))]
    expected = {"control", "truth"} | ({"image"} if image else set()) | ({"web"} if web else set())
    expected |= {"comserver", "wss", "cominterface"} if wireless else set()
    expected |= {"foxglove"} if foxglove else set()
    if lockstep:
        args.append("--lockstep")
    else:
        args += ["--speed", "max" if speed is None else repr(float(speed))]
    args += ["--image-port", "0"] if image else ["--no-image"]
    args += ["--web-port", "0"] if web else ["--no-web"]
    args += ["--wcs-port", "0", "--wss-port", "0", "--cominterface-port", "0"] if wireless else ["--no-wireless"]
    for d in robot_dirs:
        args += ["--robot-dir", str(d)]
    if record is not None:
        args += ["--record", os.fspath(record)]
    if foxglove:
        args += ["--foxglove", "0"]
    args += list(extra_args)
    # every listener asked for is waited for by name; options of the caller's may open others
    return Server(args, lockstep, timeout, frozenset(expected), more=bool(extra_args))


TRANSPORTS = ("tcp", "inproc")


def _launch_inproc(
    world: str,
    *,
    seed: int,
    variant: int | None,
    lockstep: bool,
    robot_dirs: tuple[str, ...],
    timeout: float,
    asked: dict[str, bool],
) -> Any:
    """An in-process simulator (:class:`usarsim.client.direct.InprocServer`)."""
    if not lockstep:
        raise ValueError("an in-process simulator runs in lock-step only (launch(..., lockstep=True))")
    unserved = [name for name, wanted in asked.items() if wanted]
    if unserved:
        raise ValueError(
            f"an in-process simulator serves no port: {', '.join(unserved)} need(s) transport='tcp' "
            "(a usarsim serve process)"
        )
    from .direct import InprocServer  # loads the simulation: only when asked for

    return InprocServer(world, seed=seed, variant=variant, robot_dirs=robot_dirs, timeout=timeout)
