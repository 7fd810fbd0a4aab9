"""The client's direct path: a lock-step simulator in this process (``launch(...,
transport="inproc")``), driven through the same sessions as the wire without sockets, an event
loop or threads of ours, and with no text for what the simulator reports.

What a robot's client receives is exactly what it would read from the control port: each
message the session answers with or the simulation reports is handed over as the message a
client parses from its printed line (:func:`usarsim.protocol.received.as_received`: the
numbers at the precision the line prints them), so that an episode gives the same readings,
bit for bit, on either path.  The client's commands are handled by the session before
:meth:`DirectClientConnection.send` returns: every request is answered at once, and a wait that
finds no answer fails at once instead of running into its timeout.  Commands are lines, except
those :func:`usarsim.protocol.commands.as_parsed` covers (a robot's ``DRIVE``), handed over as the
session would parse them from their lines (:meth:`DirectClientConnection.send_command`).

This module loads the simulation (MuJoCo); ``usarsim.client`` imports it only when asked for
the direct path.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from usarsim.maps.variation import load_arena
from usarsim.protocol import commands as C
from usarsim.protocol import messages as M
from usarsim.protocol.received import as_received
from usarsim.protocol.truth import TruthObject, format_truth_object, parse_truth_object, parse_truth_request
from usarsim.server.direct import DirectServer
from usarsim.sim.settings import SimSettings

from .blocking import World, _Connection
from .core import DEFAULT_TIMEOUT_S, ClientError, ClientTimeout, ConnectionState

__all__ = ["DirectClientConnection", "DirectWorld", "InprocServer"]


class DirectClientConnection:
    """A connection to an in-process simulator, with the blocking client's connection's
    interface (``send``, ``read``, ``wait_for``, ``ping``, ``close``, ``state``)."""

    synchronous = True  # every command is carried out before send() returns

    def __init__(self, server: DirectServer, what: str, timeout: float):
        self.what = what
        self.timeout = timeout
        self.state = ConnectionState()
        self.sent = False
        self._end = server.open(self._receive)

    def _receive(self, msg: Any) -> None:
        state = self.state
        if state.closed:
            return
        received = as_received(msg)
        if received is None:  # printed and read back, as the control port's client would
            state.feed(M.format_message(msg).encode("ascii", "replace"))
            return
        for m in received:
            state.record(m)

    def _sending(self) -> None:
        if self.state.closed:
            raise ClientError(f"{self.what}: the connection is closed")
        self.sent = True

    def send(self, line: str) -> None:
        self._sending()
        self._end.handle(line)

    def send_command(self, cmd: Any) -> None:
        """``cmd`` (a protocol command), without its text where the session's parse of it is
        known (:func:`~usarsim.protocol.commands.as_parsed`), else as its line."""
        parsed = C.as_parsed(cmd)
        if parsed is None:
            self.send(C.format_command(cmd))
            return
        self._sending()
        self._end.handle_command(parsed)

    def read(self, wait: float) -> bool:
        """Nothing arrives between two commands: everything has been received already."""
        return not self.state.closed

    def wait_for(
        self, accept: Callable[[Any], bool], what: str, command: str | None, timeout: float | None = None
    ) -> Any:
        """The first reply ``accept`` takes; an ERROR about ``command`` raises
        :class:`ServerError`.  The simulator has answered everything it will answer."""
        msg = self.state.claim(accept, command)
        if msg is not None:
            return msg
        if self.state.closed:
            raise ClientError(f"{self.what}: the connection is closed (waiting for {what})")
        raise ClientTimeout(f"{self.what}: the in-process simulator did not answer with {what}")

    ping = _Connection.ping  # PING, answered at once

    def read_only(self, wanted: frozenset[str] | None) -> None:
        """Have the simulator measure only the robot's sensors whose type or name is in
        ``wanted`` (None: every one again)."""
        self._end.read_only(wanted)

    def close(self) -> None:
        if not self.state.closed:
            self.state.closed = True
            self._end.close()


class DirectWorld(World):
    """A :class:`~usarsim.client.World` on an in-process simulator: the same calls, its
    connections direct ones; ground truth is asked of the simulation itself.  Pictures and
    the radio are served only by ``usarsim serve`` (there is no port to reach here)."""

    def __init__(self, server: InprocServer, timeout: float = DEFAULT_TIMEOUT_S):
        self._server = server
        super().__init__("inproc", 0, lockstep=True, truth_port=0, image_port=0, comserver_port=0, timeout=timeout)

    def _open(self, what: str, timeout: float) -> Any:
        return DirectClientConnection(self._server.direct, what, timeout)

    def _truth_lines(self, request: str) -> list[str]:
        # a {Map} request answered as the ground-truth service answers it
        from usarsim.server.truth import map_answer

        asked = parse_truth_request(request)
        if asked.map is None:
            raise ClientError(f"the direct path answers ground-truth maps here, not {request.strip()!r}")
        lines = map_answer(self._server.direct.world, asked.map).split("\r\n")
        return [line for line in lines if line and line != "{End}"]

    def _truth(self, class_name: str | None, name: str | None) -> list[TruthObject]:
        # each object as the ground-truth service prints it and a client reads it back
        out = []
        for row in self._server.direct.truth(class_name, name):
            obj = parse_truth_object(format_truth_object(TruthObject(*row)))
            if obj is not None:
                out.append(obj)
        return out


class InprocServer:
    """A lock-step simulator of ``world`` in this process, with :class:`~usarsim.client.Server`'s
    ``connect()`` and ``close()`` (a ``with`` block closes it)."""

    lockstep = True
    host = "inproc"

    def __init__(
        self,
        world: str | os.PathLike = "DM-USAR_yellow",
        *,
        seed: int = 0,
        variant: int | None = None,
        robot_dirs: tuple[str, ...] = (),
        settings: SimSettings | None = None,
        timeout: float = DEFAULT_TIMEOUT_S,
    ):
        self.timeout = timeout
        self.ports: dict[str, int] = {}
        self.direct = DirectServer(
            load_arena(os.fspath(world), variant), seed=int(seed), settings=settings, robot_dirs=tuple(robot_dirs)
        )

    def connect(self, timeout: float | None = None) -> DirectWorld:
        return DirectWorld(self, self.timeout if timeout is None else timeout)

    def close(self) -> None:
        self.direct.close()

    def __enter__(self) -> InprocServer:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
