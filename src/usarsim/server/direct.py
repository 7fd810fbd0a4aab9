"""An in-process simulator: the composition root of a lock-step simulation driven on the
caller's thread, without sockets, an event loop or text (the direct path of the Python client
and the environments, :mod:`usarsim.client.direct`).

Each connection is a :class:`~usarsim.server.session.Session`, the same one a control
connection runs: it is handed the client's command lines (or the commands themselves, as the
session would parse them) and answers with message objects,
which go to the connection's ``emit`` instead of being printed; the simulation's outputs for
its robot go there too, as the control server would write them (a mission package's ASTA
after its MISSTA for a client of the actuator API).  The simulation runs inline
(:mod:`usarsim.sim.inline`): every request is carried out before the line that asked for it
has been handled, so there is nothing to wait for and nothing to order between connections.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from usarsim.config.world import WorldConfig
from usarsim.plugins import BUILTIN
from usarsim.protocol import messages as M
from usarsim.readings import PackageState
from usarsim.server.control import actuator_status, output_to_message
from usarsim.server.session import ALIVE, CLOSED, NEW, SPAWNING, Session, SessionContext
from usarsim.sim.facade import SimFacade
from usarsim.sim.settings import SimSettings
from usarsim.sim.types import Output

log = logging.getLogger("usarsim.server")

Emit = Callable[[Any], None]


def _at_once(fn: Callable) -> Callable:
    """A session's thread-safe callback: everything runs on the caller's thread here."""
    return fn


class DirectConnection:
    """One connection of an in-process simulator: its session, fed command lines by
    :meth:`handle`, answering through ``emit``."""

    def __init__(self, server: DirectServer, uid: int, emit: Emit):
        self.server = server
        self.emit = emit
        self.session = Session(
            SessionContext(
                facade=server.facade,
                peer=f"inproc#{uid}",
                emit=emit,
                threadsafe=_at_once,
                admit=server.admit,
                robot_dirs=server.robot_dirs,
            ),
            uid,
        )
        self.closed = False

    def handle(self, text: str) -> None:
        """The client's lines (each ending with CR LF or LF), handled in order."""
        if self.closed:
            return
        for line in text.splitlines():
            if line:
                self.session.handle_line(line)

    def handle_command(self, cmd: Any) -> None:
        """A command as the session would parse it from its line (:func:`usarsim.protocol.commands.as_parsed`)."""
        if not self.closed:
            self.session.handle_command(cmd)

    def read_only(self, wanted: frozenset[str] | None) -> None:
        """Measure only the robot's sensors whose type or name is in ``wanted`` (None: every
        one): the readings of the others would go unread (:meth:`SimFacade.read_only`)."""
        self.server.facade.read_only(self.session.uid, wanted).result()

    def close(self) -> None:
        """The client is gone: its robot leaves the world."""
        if self.closed:
            return
        self.closed = True
        s = self.session
        self.server.connections.pop(s.uid, None)
        if s.state != NEW and self.server.running:
            self.server.facade.remove(s.uid)
        s.state = CLOSED


class DirectServer:
    """A lock-step simulation of ``world`` in this process (``seed``, ``settings`` as ``usarsim
    serve`` takes them), and its connections; :meth:`close` stops it."""

    def __init__(
        self,
        world: WorldConfig,
        *,
        seed: int = 0,
        settings: SimSettings | None = None,
        robot_dirs: tuple[str, ...] = (),
        max_robots: int = 64,
    ):
        self.world = world
        self.robot_dirs = tuple(robot_dirs)
        self.max_robots = max_robots
        self.facade = SimFacade(world, seed=seed, lockstep=True, settings=settings, plugins=BUILTIN, inline=True)
        self.facade.set_deliver(self.dispatch)
        self.connections: dict[int, DirectConnection] = {}
        self._uid = 0
        self._closed = False
        self.facade.start()
        log.info("in-process simulator of %s started (seed %d)", world.name, seed)

    def open(self, emit: Emit) -> DirectConnection:
        """A new connection, greeted as a control connection is (``NFO {Gamename ...}``)."""
        if not self.running:
            raise RuntimeError("the in-process simulator has stopped")
        self._uid += 1
        conn = DirectConnection(self, self._uid, emit)
        self.connections[self._uid] = conn
        emit(M.GameInfo(level=self.facade.world_name, time_limit=self.facade.world.time_limit_min))
        return conn

    def admit(self) -> str | None:
        """Why one more robot is refused (None: it is admitted)."""
        robots = sum(1 for c in self.connections.values() if c.session.state in (SPAWNING, ALIVE))
        if robots >= self.max_robots:
            return f"the world has {robots} robots already (limit {self.max_robots})"
        return None

    def dispatch(self, outs: list[Output]) -> None:
        """Each output to the connection of its robot, as the message the control server
        would print."""
        conns = self.connections
        for o in outs:
            conn = conns.get(o.uid)
            if conn is None:
                continue
            conn.emit(output_to_message(o))
            if isinstance(o.value, PackageState) and conn.session.actuator_api:
                conn.emit(actuator_status(o))

    def truth(self, class_name: str | None, name: str | None) -> list[tuple[Any, ...]]:
        """What the ground-truth service would answer (rows of :func:`usarsim.sim.truth.truth_rows`)."""
        return self.facade.truth(class_name, name).result()

    def close(self) -> None:
        """Stop the simulation (its robots are not removed one by one: the world ends)."""
        for conn in list(self.connections.values()):
            conn.closed = True
            conn.session.state = CLOSED
        self.connections.clear()
        self._closed = True
        self.facade.stop()

    @property
    def running(self) -> bool:
        """Not closed, and not stopped on an error."""
        return not self._closed and self.facade.failure is None
