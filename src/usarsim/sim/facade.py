"""The narrow, thread-safe door from the servers into the simulation.

Servers (asyncio) call these named, typed methods from their own thread; every change of
the world runs on the simulation thread, one at a time, in the order the calls were made (a
short lock-step STEP, and the requests that waited for it, run on the thread that asked for
it when the simulation thread has nothing to do: :mod:`usarsim.sim.runner`).  A request with
an answer returns it as a typed future, settled on the thread that ran the request
(:mod:`usarsim.sim.api`).
The servers import nothing else from the simulation layer but :mod:`usarsim.sim.types`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from typing import TYPE_CHECKING, Any, TypeVar

from usarsim.config.channel import ChannelConfig
from usarsim.config.robot import MissionPackage, RobotConfig
from usarsim.config.world import StartPose, WorldConfig
from usarsim.controls import DriveCommand, JointOrder
from usarsim.readings import CommandResult, ItemParams
from usarsim.sim.api import Position, RobotEntry, settle
from usarsim.sim.channel import Channel, LinkCounts, LinkView
from usarsim.sim.inline import InlineRunner
from usarsim.sim.outputs import ItemDescription, LinkFrame, Output, RobotNumbers, VelocityLimits, package_frames
from usarsim.sim.plugins import PluginSet, builtin_plugins
from usarsim.sim.radio import Link, Pair, RadioModel, RadioNet
from usarsim.sim.runner import Request, SimulationRunner
from usarsim.sim.settings import SimSettings
from usarsim.sim.simulation import Simulation, describe_items
from usarsim.sim.snapshot import FrameWatch
from usarsim.sim.worldframe import WorldFrame

if TYPE_CHECKING:
    from usarsim.sim.render import RenderService, Snapshot

log = logging.getLogger("usarsim.sim")

T = TypeVar("T")

# Outside lock-step the radio links are evaluated at most this often (simulated seconds).
RADIO_INTERVAL_S = 0.02


class SimFacade:
    """The simulation's door for the servers (the :class:`usarsim.sim.api.Facade` they are given): it owns the
    world's :class:`Simulation` and the runner that paces it, queues each request for the simulation thread and hands
    the outputs to the servers and the output watchers."""

    def __init__(
        self,
        world: WorldConfig,
        *,
        seed: int = 0,
        speed: float | None = 1.0,
        lockstep: bool = False,
        deliver: Callable[[list[Output]], None] | None = None,
        settings: SimSettings | None = None,
        plugins: PluginSet | None = None,
        inline: bool = False,
    ):
        """``inline``: no simulation thread; every request is carried out at once on the thread
        that makes it (lock-step only: :mod:`usarsim.sim.inline`, the in-process simulator)."""
        if inline and not lockstep:
            raise ValueError("an inline simulation runs in lock-step only")
        self.world = world
        self.plugins = plugins = plugins or builtin_plugins()
        self.sim = Simulation(
            world, seed=seed, settings=settings, plugins=plugins
        )  # for tests and benchmarks; servers use the methods
        self.lockstep = lockstep
        self.speed = speed
        self._deliver = deliver or (lambda outs: None)
        self.runner = (
            InlineRunner(self.sim, self._on_outputs)
            if inline
            else SimulationRunner(self.sim, self._on_outputs, speed=speed, lockstep=lockstep)
        )
        self._descriptions: dict[str, list[ItemDescription]] = {}
        self._radio: RadioNet | None = None
        self._watchers: tuple[Callable[[list[Output]], None], ...] = ()
        self._frame_watches: dict[tuple[float, float], FrameWatch] = {}  # (period, links period) -> watch
        self._directory: dict[int, RobotEntry] = {}  # the robots in the world, by connection (robots())

    def set_deliver(self, deliver: Callable[[list[Output]], None]) -> None:
        self._deliver = deliver

    def _on_outputs(self, outs: list[Output]) -> None:
        self._deliver(outs)
        for watcher in self._watchers:
            try:
                watcher(outs)
            except Exception:  # an observer must not stop the world: it is dropped
                log.exception("an output watcher failed and was removed")
                self.remove_output_watcher(watcher)

    def add_output_watcher(self, watcher: Callable[[list[Output]], None]) -> None:
        """Also hand every batch of outputs to ``watcher``, after the servers' delivery, on the
        simulation thread: a read-only observer (the operator console showing a robot that
        another client drives).  It must return quickly and must not change the list; one
        that raises is logged and removed."""
        self._watchers = (*self._watchers, watcher)

    def remove_output_watcher(self, watcher: Callable[[list[Output]], None]) -> None:
        self._watchers = tuple(w for w in self._watchers if w != watcher)  # a bound method is a new object each time

    # Lifecycle ---------------------------------------------------------------------
    def start(self) -> None:
        self.runner.start()

    def stop(self) -> None:
        self.runner.stop()

    def when_failed(self, fn: Callable[[BaseException], None]) -> None:
        """``fn(error)``, on the simulation thread, if the simulation stops on an unexpected
        error (a bug: it is logged where it happened); every request after it is refused."""
        self.runner.on_failure = fn

    @property
    def failure(self) -> BaseException | None:
        """The error the simulation stopped on, if it did."""
        return self.runner.error

    # Static facts ------------------------------------------------------------------
    @property
    def world_name(self) -> str:
        return self.world.name

    @property
    def start_poses(self) -> tuple[StartPose, ...]:
        return self.world.start_poses

    @property
    def time(self) -> float:
        """Current simulated time (a plain read; exact in lock-step mode)."""
        return self.sim.time

    def describe(self, robot: RobotConfig) -> list[ItemDescription]:
        d = self._descriptions.get(robot.path)
        if d is None:
            d = describe_items(robot, plugins=self.plugins)
            self._descriptions[robot.path] = d
        return d

    def drive_accepts(self, robot: RobotConfig) -> frozenset[type]:
        """The kinds of DRIVE part (:mod:`usarsim.controls`) the robot's drive applies."""
        return self.plugins.drive_class(robot).ACCEPTS

    @staticmethod
    def package_frames(robot: RobotConfig, package: MissionPackage) -> tuple[LinkFrame, ...]:
        """What GETGEO {Type MisPkg} and {Type Actuator} report of each link of a mission
        package (:func:`usarsim.sim.outputs.package_frames`)."""
        return package_frames(robot, package)

    def robot_numbers(self, robot: RobotConfig) -> RobotNumbers:
        """What GETGEO and GETCONF {Type Robot} report of the robot (its drive model's numbers)."""
        return self.plugins.drive_class(robot).numbers(robot)

    def lowest_point_m(self, robot: RobotConfig) -> float:
        """How far below its origin the robot reaches when level, by its drive (a walking
        robot stands on its legs): where it stands on a floor (Z down, positive)."""
        return self.plugins.drive_class(robot).lowest_point_m(robot)

    def velocity_limits(self, robot: RobotConfig) -> VelocityLimits | None:
        """How fast a robot driven by velocities may go (None: its drive takes none)."""
        return self.plugins.drive_class(robot).velocity_limits(robot)

    def canonical_item_type(self, name: str) -> str:
        """A mounted item's type in USARSim's spelling (``sonar`` -> ``Sonar``), among sensors,
        effecters and cameras, or ``name`` itself when no plugin has it."""
        return self.plugins.canonical_item_type(name) or name

    def live_conf(self, uid: int, item_type: str, name: str) -> Any:
        """CONF fields of a robot's item that changed at run time, or None."""
        return self.sim.live_conf.get((uid, item_type, name))

    # Robots ------------------------------------------------------------------------
    def spawn(
        self,
        uid: int,
        robot: RobotConfig,
        name: str,
        location: Sequence[float],
        rotation: Sequence[float],
        set_down: bool = False,
        controller: str = "",
    ) -> Future[object]:
        """Spawn a robot; once it stands in the world it is in the robot directory
        (:meth:`robots`) under ``name``, driven by ``controller`` (its client, as logs name it)."""
        entry = RobotEntry(uid, name, robot, controller)
        future: Future[object] = Future()
        answer = settle(future)

        def spawned(result: Any, error: BaseException | None) -> None:
            if error is None:
                self._directory = {**self._directory, uid: entry}
            answer(result, error)

        self.runner.submit(
            Request(
                lambda sim: sim.spawn(uid, robot, name, location, rotation, set_down), immediate=True, on_done=spawned
            )
        )
        return future

    def barrier(self) -> Future[float]:
        """The simulated time, once every request submitted before it has been carried out
        and its outputs handed to the server (an immediate request: in lock-step it does not
        wait for a STEP)."""
        return self._ask(lambda sim: sim.time)

    def _ask(self, action: Callable[[Simulation], T], concurrent: bool = False) -> Future[T]:
        """``action(sim)`` at once on the simulation thread; its result, or the error it was
        refused with, settles the future returned."""
        future: Future[T] = Future()
        self.runner.submit(Request(action, immediate=True, on_done=settle(future), concurrent=concurrent))
        return future

    def remove(self, uid: int) -> None:
        if uid in self._directory:
            self._directory = {k: v for k, v in self._directory.items() if k != uid}
        self.runner.submit(Request(lambda sim: sim.remove(uid), immediate=True))

    # The robot directory: who is in the world (any thread; a copy replaced as a whole) -----
    def robots(self) -> tuple[RobotEntry, ...]:
        """Every robot standing in the world, in the order they were spawned."""
        return tuple(self._directory.values())

    def robot(self, uid: int) -> RobotEntry | None:
        """The robot of connection ``uid`` while it is in the world."""
        return self._directory.get(uid)

    def find_robot(self, name: str) -> RobotEntry | None:
        """The robot called ``name`` (exactly, else ignoring case), None if there is none."""
        entries = self.robots()
        exact = next((e for e in entries if e.name == name), None)
        return exact or next((e for e in entries if e.name.lower() == name.lower()), None)

    def read_only(self, uid: int, wanted: frozenset[str] | None) -> Future[object]:
        """Measure only the sensors of robot ``uid`` whose type or name is in ``wanted`` (None:
        every one), for a client that reads no other (:meth:`ReportSchedule.read_only
        <usarsim.sim.reports.ReportSchedule.read_only>`: the readings taken are those it
        would take anyway)."""

        def mute(sim: Simulation) -> None:
            r = sim.robots.get(uid)
            if r is not None:
                sim.reports.read_only(r, wanted)

        return self._ask(mute)

    def drive(self, uid: int, command: DriveCommand) -> None:
        """One DRIVE: its parts go to the robot's drive model, which applies those its kind
        understands; Flip, Light and joint orders apply to any robot."""
        self.runner.submit(Request(lambda sim: sim.drive(uid, command), concurrent=True))

    def drive_joints(self, uid: int, orders: list[JointOrder]) -> None:
        """Joint orders (MULTIDRIVE, MISPKG, SET Joint, CAMERA), applied together."""
        self.runner.submit(Request(lambda sim: sim.drive_joints(uid, orders), concurrent=True))

    def operate(
        self,
        uid: int,
        item_type: str | None,
        name: str | None,
        opcode: str | None,
        params: ItemParams,
    ) -> Future[object]:
        """``SET`` on a mounted item: the RES, then whatever the operation reported (EFF),
        handed to the server before the future is settled; with an error when it was not
        carried out (the simulation has stopped, or the operation failed on an unexpected
        error).  In lock-step it is carried out at once, at the current simulated time, as
        INIT and REPORT are: a request with a reply is answered without a STEP (a PING after it
        is answered after its RES), and what it changes acts from the next STEP on, as a
        DRIVE's speeds do."""
        return self._ask(lambda sim: sim.operate(uid, item_type, name, opcode, params))

    def set_viewports(self, uid: int, names: list[str | None]) -> Future[tuple[float, list[tuple[str, str]]]]:
        """SET {Type Viewports}: (time, [(camera, status), ...])."""
        return self._ask(lambda sim: (sim.time, sim.cameras.set_viewports(uid, names)))

    def report_victim(self, uid: int, name: str, location: Sequence[float]) -> Future[None]:
        """``REPORT {Type Victim}``: recorded at the simulated instant it is carried out, as a
        RES output for the robot's client (observers such as the score see it too), handed to
        the server before the future is settled; with an error when it was not (the
        simulation has stopped)."""
        result = CommandResult("Victim", name, True, (("Location", tuple(float(v) for v in location)),))
        return self._ask(lambda sim: sim.report(uid, result))

    def step(self, seconds: float) -> Future[float]:
        """Lock-step STEP: the simulated time once ``seconds`` more have run (settled at once,
        on the calling thread, when it is short and the simulation has nothing else to do), or
        the error it is refused with (the simulation has stopped)."""
        future: Future[float] = Future()
        self.runner.step(seconds, future.set_result, future.set_exception)
        return future

    # Ground truth and pictures -----------------------------------------------------
    def truth(self, class_name: str | None, name: str | None) -> Future[list[tuple[Any, ...]]]:
        """Everything the ground-truth service knows now (rows of
        :func:`usarsim.sim.truth.truth_rows`), filtered by class and name."""
        return self._ask(lambda sim: sim.truth(class_name, name), concurrent=True)

    def set_multiview_cameras(self, count: int) -> None:
        """How many robot cameras the MultiView shows at most (before the simulation starts)."""
        self.sim.cameras.multiview_cameras = count

    def render_snapshot(self, reuse: Snapshot | None) -> Future[Snapshot]:
        """A copy of the state for the render thread (``reuse``: the previous one)."""
        return self._ask(lambda sim: sim.cameras.render_snapshot(reuse), concurrent=True)

    def render_service(self, max_fps: float) -> RenderService:
        """The render thread of the image server, fed with snapshots of this simulation."""
        from usarsim.sim.render import RenderService

        return RenderService(self.render_snapshot, max_fps=max_fps, shadows=self.sim.settings.shadows)

    # The radio (protocol.md 12) ----------------------------------------------------
    def open_radio(
        self,
        model: RadioModel,
        on_change: Callable[[float, list[tuple[Pair, bool]]], None],
        channel: ChannelConfig | None = None,
        on_views: Callable[[float, dict[Pair, LinkView | None]], None] | None = None,
    ) -> Channel | None:
        """Compute radio links with ``model`` after every advance of the clock (every STEP in
        lock-step, else at most every RADIO_INTERVAL_S); ``on_change(time, [(pair, holds)])``
        is called on the simulation thread for the watched pairs whose state changed.  With a
        ``channel`` that is not ideal, the :class:`Channel` that carries the messages is
        returned, for the caller to drive on its own thread (it is thread-safe), and
        ``on_views(time, views)`` is called on the simulation thread after each evaluation
        with the links its messages are judged by (the watched pairs' and those of pairs with
        messages waiting).  Call before :meth:`start`."""
        net = RadioNet(model, channel, seed=self.sim.seed)
        net.min_interval_s = 0.0 if self.lockstep else RADIO_INTERVAL_S
        net.on_change = on_change
        net.on_views = on_views
        self._radio = net
        self.sim.on_advance(net.evaluate)
        return net.channel

    def radio_watch(self, pairs: frozenset[Pair]) -> None:
        """The pairs whose links are evaluated after every advance (replaced as a whole)."""
        self._net().watched = frozenset(pairs)

    def radio_check(self, a: str, b: str) -> Future[tuple[float, Link | None]]:
        """(time, Link | None) for a link about to be opened; a state that differs from the
        one last reported is reported at once."""
        net = self._net()
        return self._ask(lambda sim: (sim.time, net.check(sim, a, b)))

    def radio_neighbours(self, a: str) -> Future[list[tuple[str, Link, float]]]:
        """Every robot whose link with ``a`` holds now: (name, link, quality)."""
        net = self._net()
        return self._ask(lambda sim: net.neighbours(sim, a))

    def radio_counts(self) -> Future[dict[tuple[str, str], LinkCounts]]:
        """What each link carried through the channel (sender, receiver): delivered, dropped by
        cause, delays."""
        net = self._net()
        return self._ask(lambda sim: net.counts())

    def radio_link(self, a: str, b: str) -> Future[Link | None]:
        """The link between two robots now (None: either is not in the simulation)."""
        net = self._net()
        return self._ask(lambda sim: net.link(sim, a, b))

    def robot_positions(self) -> Future[list[Position]]:
        """[(name, location, battery empty), ...] for every robot."""
        return self._ask(RadioNet.positions)

    def walls_between_robots(self, a: str, b: str) -> Future[int]:
        """Walls between two robots (-1: either is unknown)."""
        return self._ask(lambda sim: RadioNet.walls_between_robots(sim, a, b))

    def walls_between(self, start: Sequence[float], end: Sequence[float]) -> Future[int]:
        """Walls between two points of the world (USARSim frame)."""
        return self._ask(lambda sim: RadioNet.walls_between(sim, start, end))

    @property
    def radio_net(self) -> RadioNet | None:
        """The radio links' state on the simulation thread (tests; servers use the methods)."""
        return self._radio

    def _net(self) -> RadioNet:
        if self._radio is None:
            raise RuntimeError("open_radio() first")
        return self._radio

    # Recording and live views ------------------------------------------------------
    def watch_frames(
        self,
        period_s: float,
        on_frame: Callable[[WorldFrame], None],
        *,
        radio_model: RadioModel | None = None,
        links_period_s: float = 1.0,
    ) -> None:
        """``on_frame(frame)`` on the simulation thread with the poses of every robot and
        movable object (:class:`usarsim.sim.snapshot.WorldFrame`) each time the simulated
        clock reaches a multiple of ``period_s``, and with the radio links under ``radio_model`` every
        ``links_period_s``.  It must return quickly.  Call before :meth:`start`."""
        key = (float(period_s), float(links_period_s))
        watch = self._frame_watches.get(key)
        if watch is None:  # observers with the same periods share one frame (the recording, the score)
            watch = self._frame_watches[key] = FrameWatch(links_period_s, live=lambda: self._radio)
            self.sim.every(period_s, watch)
        watch.add(on_frame, radio_model)

    def describe_robot(self, robot: RobotConfig) -> tuple[RobotNumbers, list[ItemDescription]]:
        """What GETGEO reports of a robot class and of its mounted items (cached)."""
        return self.robot_numbers(robot), self.describe(robot)

    # Tools, tests and benchmarks ---------------------------------------------------
    def call(self, fn: Callable[[Simulation], T], immediate: bool = True) -> Future[T]:
        """Run ``fn(sim)`` in the simulation (tools, tests, benchmarks; not servers): at once
        on the simulation thread, or (``immediate=False`` in lock-step) at the next STEP."""
        future: Future[T] = Future()
        self.runner.submit(Request(fn, immediate=immediate, on_done=settle(future)))
        return future


__all__ = ["Link", "SimFacade"]
