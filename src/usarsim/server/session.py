"""One control connection's state machine: before INIT -> robot alive -> closed.

A dispatch table maps each command type to a handler; handlers call the
simulation facade and return message objects.  No string building happens here:
the protocol layer formats every message.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.config.catalog import resolve_robot
from usarsim.config.robot import RobotConfig
from usarsim.errors import ConfigError, ProtocolError, UsarsimError
from usarsim.protocol import commands as C
from usarsim.protocol import messages as M
from usarsim.server.articulation import Articulation
from usarsim.server.connection import LogOnce
from usarsim.server.queries import NO_ROBOT, Queries
from usarsim.sim.api import Facade, when_done

log = logging.getLogger("usarsim.server")

NEW, SPAWNING, ALIVE, CLOSED = "new", "spawning", "alive", "closed"

# Commands a client waits for an answer to: a malformed one is answered with an ERROR.
ANSWERED = ("INIT", "STEP", "SET", "GETGEO", "GETCONF", "GETSTARTPOSES", "GETPATHNODES", "GETCLOSESTPATHNODE", "REPORT")


def _copied(sent, exact) -> bool:
    """Whether ``sent`` is ``exact`` as GETSTARTPOSES prints it (2 decimals): a pose copied
    from the reply spawns a robot exactly where ``{Start name}`` does."""
    return all(abs(a - float(f"{b:.2f}")) < 0.006 for a, b in zip(sent, exact))


@dataclass
class SessionContext:
    """What a session needs of the world around it, and nothing else (it is tested
    without sockets with a context of its own).

    ``emit(msg)`` sends a message to the client (on the event loop); ``threadsafe(fn)``
    wraps ``fn`` so that calling it from another thread (the simulation's) runs it on the
    event loop; ``admit()`` says why one more robot is refused (None: admitted);
    ``log_once`` logs each kind of problem once per connection (shared with the connection;
    by default one of the session's own)."""

    facade: Facade
    peer: str
    emit: Callable[[Any], None]
    threadsafe: Callable[[Callable], Callable]
    admit: Callable[[], str | None]
    robot_dirs: tuple[str, ...] = ()  # extra folders of robot files (serve --robot-dir)
    camera_bindings: Any = None  # the image server's CameraBindings
    log_once: LogOnce | None = None
    # the connection handles the lines it holds back (Session.holding) once the hold ends
    resume: Callable[[], None] | None = None
    # lock-step: where STEPs fall among every connection's lines (usarsim.server.ordering),
    # and this connection as the ordering sees it; None: a STEP is carried out at once
    step_order: Any = None
    reader: Any = None

    def __post_init__(self) -> None:
        if self.log_once is None:
            self.log_once = LogOnce(log, self.peer)


class Session(Articulation, Queries):
    """One control connection's robot, from before INIT through alive to closed (protocol.md 4): each command parsed
    from the client's lines goes to its handler, which calls the simulation facade and answers with message objects
    for the protocol layer to format."""

    def __init__(self, ctx: SessionContext, uid: int):
        self.ctx = ctx
        self.uid = uid
        self.state = NEW
        self.robot: RobotConfig | None = None
        self.robot_name: str | None = None
        self.handlers: dict[type, Callable] = {
            C.Init: self.on_init,
            C.GetStartPoses: self.on_get_start_poses,
            C.Drive: self.on_drive,
            C.GetGeo: self.on_get_geo,
            C.GetConf: self.on_get_conf,
            C.Set: self.on_set,
            C.Step: self.on_step,
            C.MultiDrive: self.on_multidrive,
            C.MisPkg: self.on_mispkg,
            C.Camera: self.on_camera,
            C.Act: self.on_act,
            C.Ping: self.on_ping,
            C.Report: self.on_report,
            C.GetPathNodes: self.on_get_path_nodes,
            C.GetClosestPathNode: self.on_get_closest_path_node,
            C.Control: self.on_control,
        }
        # the client speaks the UDK actuator API (ACT, or a query of {Type Actuator}): its
        # robot's mission packages are reported as ASTA too, each status period
        self.actuator_api = False
        self.reports = 0  # REPORTs so far (one without a Name is named Victim<n>)
        self._spawn_done = ctx.threadsafe(self.spawn_done)
        self._stepped = ctx.threadsafe(self._step_done)
        self._step_refused = ctx.threadsafe(self._step_not_done)
        # STEPs asked for and not answered yet: the outputs of the robot meanwhile go out with
        # the next reply (its STEPPED), in one write (usarsim.server.control)
        self.steps_waiting = 0
        # a STEP read here waits for the lines of the other connections (usarsim.server.ordering)
        self.step_held = False
        # requests sent to the simulation whose answer (RES, PONG...) is not written yet
        self.awaiting = 0

    @property
    def holding(self) -> bool:
        """The next lines wait: a request answered by the simulation (INIT, STEP, SET, REPORT,
        PING) has not been answered yet, so that the requests of a connection are answered in
        the order they were sent, whatever the segmentation; and what follows a STEP is for the
        next STEP."""
        return self.awaiting > 0 or self.steps_waiting > 0 or self.step_held or self.state == SPAWNING

    def _answered(
        self,
        command: str,
        then: Callable[[Any], None] | None = None,
        refused: Callable[[BaseException], None] | None = None,
    ) -> Callable:
        """A request's ``on_done(result, error)`` (called from the simulation thread) that
        holds this connection's next lines until it is answered: ``then(result)`` sends the
        answer (a RES the simulation outputs itself needs none: its outputs are written
        before ``on_done`` runs), an error is answered by ``refused(error)`` (by default an
        ERROR), and the lines waiting are handled."""
        self.awaiting += 1

        def done(result, error) -> None:
            self.awaiting -= 1
            if self.state != CLOSED:
                if error is not None:
                    (refused or (lambda e: self._not_done(command, e)))(error)
                elif then is not None:
                    then(result)
            self._resume()

        return self.ctx.threadsafe(done)

    def _resume(self) -> None:
        if self.ctx.resume is not None:
            self.ctx.resume()

    @property
    def has_robot(self) -> bool:
        """The robot is spawned or being spawned (its requests are carried out in order)."""
        return self.state in (SPAWNING, ALIVE)

    @property
    def facade(self) -> Facade:
        return self.ctx.facade

    def log_once(self, kind: str, msg: str, *args, level: int = logging.WARNING) -> None:
        """Log the first problem of each kind at ``level``, its repetitions at DEBUG, within
        a bound on the kinds (:class:`~usarsim.server.connection.LogOnce`)."""
        log_once = self.ctx.log_once
        assert log_once is not None  # SessionContext.__post_init__ gives one
        log_once(kind, msg, *args, level=level)

    # Entry point ---------------------------------------------------------------------
    def handle_line(self, line: str) -> None:
        try:
            cmd = C.parse_command(line)
        except ProtocolError as exc:
            word = line.strip().split(" ", 1)[0].upper()
            if word in ANSWERED:
                self.refuse(word, "malformed", str(exc))
            else:
                self.log_once("malformed", "ignored a malformed line (%s): %.200r", exc, line)
            return
        self.handle_command(cmd)

    def handle_command(self, cmd: C.Command) -> None:
        """A parsed command (a line's, or one the direct path hands over), to its handler."""
        handler = self.handlers.get(type(cmd))
        if handler is None:
            if isinstance(cmd, C.UnknownCommand):
                self.log_once(f"unknown:{cmd.type}", "ignored unknown command %s", cmd.type, level=logging.INFO)
            else:
                self.log_once(
                    f"unsupported:{type(cmd).__name__}",
                    "command %s is not supported by this robot; ignored",
                    type(cmd).__name__.upper(),
                    level=logging.INFO,
                )
            return
        handler(cmd)

    def send(self, msg) -> None:
        self.ctx.emit(msg)

    def refuse(self, command: str, kind: str, reason: str, level: int = logging.WARNING) -> None:
        """Answer a request that cannot be carried out with ``ERROR {Command c} {Reason r}`` (the
        client would otherwise wait for a reply that never comes), logged once per kind."""
        self.log_once(kind, "%s refused: %s", command, reason, level=level)
        self.send(M.error_reply(command, reason))

    # Handlers ------------------------------------------------------------------------
    def on_control(self, cmd: C.Control) -> None:
        """``CONTROL`` (UDK world controller, protocol.md 5.8): not simulated.  ``{Type GetSTA}``,
        the one request of it with a reply, is answered with an ERROR saying so; the others
        have no reply and are logged once."""
        if (cmd.type or "").lower() == "getsta":
            self.refuse(
                "CONTROL",
                "control",
                "this simulator has no world controller (the UDK's CONTROL Create, "
                "Kill, Move and GetSTA are not simulated): the ground-truth port lists every robot, victim "
                "and movable object",
                level=logging.INFO,
            )
            return
        self.log_once(
            "control",
            "CONTROL {Type %s}: this simulator has no world controller; ignored",
            cmd.type,
            level=logging.INFO,
        )

    def on_init(self, cmd: C.Init) -> None:
        if self.state != NEW:
            self.refuse(
                "INIT",
                "init-twice",
                "this connection has its robot already (one robot per connection: "
                "open another connection for another robot)",
            )
            return
        if not cmd.class_name:
            self.refuse("INIT", "init", "INIT needs {ClassName USARBot.<class>}")
            return
        try:
            robot = resolve_robot(cmd.class_name, extra_dirs=self.ctx.robot_dirs)
            self.facade.drive_accepts(robot)  # its drive is known (a plugin's drive may be missing)
        except ConfigError as exc:
            self.refuse("INIT", "init", str(exc))
            return
        if cmd.start:
            pose = next((p for p in self.facade.start_poses if p.name.lower() == cmd.start.lower()), None)
            if pose is None:
                names = ", ".join(p.name for p in self.facade.start_poses)
                self.refuse("INIT", "init", f"unknown start pose {cmd.start!r} (known: {names})")
                return
            location, rotation = pose.location, pose.rotation  # exactly as the world file has it
            set_down = True
        elif cmd.location is not None:
            location = cmd.location
            rotation = cmd.rotation or (0.0, 0.0, 0.0)
            # a location copied from GETSTARTPOSES (2 decimals) is that start pose (MOAST spawns
            # this way): it spawns exactly where {Start name} does, with the rotation copied too
            copied = next((p for p in self.facade.start_poses if _copied(location, p.location)), None)
            set_down = copied is not None
            if copied is not None:
                location = copied.location
                if cmd.rotation is not None and _copied(cmd.rotation, copied.rotation):
                    rotation = copied.rotation
        else:
            poses = self.facade.start_poses
            if not poses:
                self.refuse("INIT", "init", "no {Location x,y,z} and the world has no start pose")
                return
            location, rotation = poses[0].location, poses[0].rotation
            set_down = True
            log.info("%s: INIT without Location or Start: using start pose %s", self.ctx.peer, poses[0].name)
        if not all(math.isfinite(v) for v in (*location, *rotation)):
            self.refuse("INIT", "init", "location and rotation must be finite numbers")
            return
        if not set_down:
            solid = self._solid_at(robot, location, rotation)
            if solid is not None:
                x, y, z = location
                self.refuse(
                    "INIT",
                    "init",
                    f"location {x:.2f},{y:.2f},{z:.2f} is inside {solid} of "
                    f"{self.facade.world_name}: choose a free place (GETSTARTPOSES lists where "
                    f"robots may start)",
                )
                return
        refused = self.ctx.admit()
        if refused is not None:
            self.refuse("INIT", "init", refused)
            return
        self.robot = robot
        self.robot_name = cmd.name or f"Robot{self.uid}"
        self.state = SPAWNING
        spawned = self.facade.spawn(
            self.uid, robot, self.robot_name, location, rotation, set_down=set_down, controller=self.ctx.peer
        )
        when_done(spawned, self._spawn_done)

    def _solid_at(self, robot: RobotConfig, location, rotation) -> str | None:
        """The solid of the world (not a movable object, which may have been pushed away) that
        the robot's origin would be inside; a level robot put into the floor is lifted onto it
        (as the simulation does when it spawns), so only what is there counts."""
        x, y, z = location
        level = abs(rotation[0]) < 1e-6 and abs(rotation[1]) < 1e-6
        lowest = self.facade.lowest_point_m(robot)
        if level and z > -lowest:
            z = -lowest - 0.005
        return self.facade.world.solid_at((x, y, z), movable=False)

    def spawn_done(self, result, error) -> None:
        if self.state == CLOSED:
            return
        if error is not None:
            self.state = NEW
            self.robot = None
            log.warning("%s: INIT failed: %s", self.ctx.peer, error)
            self.send(M.error_reply("INIT", str(error)))
        else:
            self.state = ALIVE
        self._resume()  # the lines after the INIT

    def on_ping(self, cmd: C.Ping) -> None:
        """``PING [{Id x}]`` -> ``PONG [{Id x}] {Time t}`` (an extension) once the simulation has
        carried out every request sent before it (an INIT's spawn, or its ERROR) and every
        message it produced so far is written to this connection."""
        when_done(
            self.facade.barrier(),
            self._answered(
                "PING",
                then=lambda t: self.send(M.Pong(id=cmd.id, time=t)),
                refused=lambda error: self.send(M.Pong(id=cmd.id, time=None)),
            ),
        )

    def on_report(self, cmd: C.Report) -> None:
        """``REPORT {Type Victim} {Location x,y,z} [{Name label}]`` (an extension): a victim the
        controller reports, for the score; answered with RES (after the spawn it follows).  A
        report without a Name is named ``Victim<n>``, n counting this connection's reports."""
        if self.state not in (SPAWNING, ALIVE):
            self.refuse("REPORT", "before-init-query", NO_ROBOT, level=logging.INFO)
            return
        self.reports += 1
        reported = self.facade.report_victim(self.uid, cmd.name or f"Victim{self.reports}", cmd.location)
        when_done(reported, self._answered("REPORT"))

    def on_drive(self, cmd: C.Drive) -> None:
        # SPAWNING too: the spawn request is ahead of this one in the simulation's queue
        if self.state not in (SPAWNING, ALIVE):
            self.log_once("before-init", "commands before the robot exists are ignored", level=logging.INFO)
            return
        command = cmd.command()
        if self.robot is not None and command.parts:
            accepts = self.facade.drive_accepts(self.robot)
            for part in command.parts:
                if type(part) not in accepts:
                    kind = type(part).__name__
                    self.log_once(
                        f"drive-part:{kind}",
                        "DRIVE: a %s robot (drive %s) ignores %s keys",
                        self.robot.class_name,
                        self.robot.drive,
                        kind,
                        level=logging.INFO,
                    )
        self.facade.drive(self.uid, command)

    def _alive(self) -> bool:
        if self.state not in (SPAWNING, ALIVE):
            self.log_once("before-init", "commands before the robot exists are ignored", level=logging.INFO)
            return False
        return True

    MAX_STEP_S = 3600.0

    def on_step(self, cmd: C.Step) -> None:
        seconds = cmd.time_s
        if seconds > self.MAX_STEP_S:
            self.log_once(
                "step", "STEP {Time %g} is longer than %g s; the world was not advanced", seconds, self.MAX_STEP_S
            )
            seconds = 0.0
        self.steps_waiting += 1
        order = self.ctx.step_order
        if order is None or order.at_once(self.ctx.reader):
            when_done(self.facade.step(seconds), self._step_answered)
            return
        self.step_held = True

        def carry_out() -> None:
            self.step_held = False
            when_done(self.facade.step(seconds), self._step_answered)

        order.submit(self.ctx.reader, carry_out)

    def _step_answered(self, time_s: float, error: BaseException | None) -> None:
        """A STEP's answer (on the thread that carried it out): STEPPED on the event loop, or
        an ERROR when it was refused."""
        if error is not None:
            self._step_refused(error)
        else:
            self._stepped(time_s)

    def _step_done(self, time_s: float) -> None:
        self.steps_waiting -= 1
        self.send(M.Stepped(time=time_s))
        self._resume()  # the lines after the STEP

    def _not_done(self, command: str, error: BaseException) -> None:
        """A request the simulation did not carry out (it has stopped, or the request failed
        on an unexpected error, logged with its traceback): an ERROR instead of the reply that
        will not come."""
        reason = (
            str(error)
            if isinstance(error, UsarsimError)
            else (
                f"the request failed on an unexpected error ({type(error).__name__}; "
                "the server's log has the traceback)"
            )
        )
        self.refuse(command, f"{command.lower()}-not-done", reason, level=logging.ERROR)

    def _step_not_done(self, error: BaseException) -> None:
        """The simulation has stopped (it stopped on an error, or the server is going down):
        the STEP is answered with an ERROR instead of a STEPPED that would never come."""
        self.steps_waiting -= 1
        self._not_done("STEP", error)
        self._resume()
