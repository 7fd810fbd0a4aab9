"""Test doubles of the fast tier: a facade with no physics behind it.

:class:`FakeFacade` has the interface the servers are written against
(:class:`usarsim.sim.api.Facade`); it builds no MuJoCo model.  A robot stands where it was
spawned, simulated time moves only by STEP, and every call is kept in ``calls`` for the test to
read.  What the real simulation would compute from a robot's model (its GETGEO numbers, its
items' descriptions) is given by the test, or a plain default.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

from usarsim.config.robot import MissionPackage, RobotConfig
from usarsim.config.world import StartPose, WorldConfig
from usarsim.controls import DriveCommand, JointOrder, WheelSpeeds
from usarsim.errors import UsarsimError
from usarsim.readings import CommandResult
from usarsim.sim.api import OutputsHandler, RobotEntry
from usarsim.sim.outputs import ItemDescription, LinkFrame, Output, RobotNumbers, VelocityLimits


@dataclass
class Spawned:
    uid: int
    robot: RobotConfig
    name: str
    location: tuple[float, float, float]
    rotation: tuple[float, float, float]
    set_down: bool


@dataclass
class FakeFacade:
    """A facade in lock-step with no physics (see the module's docstring)."""

    world: WorldConfig
    lockstep: bool = True
    speed: float | None = None
    numbers: RobotNumbers | None = None
    descriptions: list[ItemDescription] = field(default_factory=list)
    spawn_error: str | None = None  # the next spawn fails with this
    calls: list[tuple[str, tuple]] = field(default_factory=list)
    spawned: dict[int, Spawned] = field(default_factory=dict)
    directory: dict[int, RobotEntry] = field(default_factory=dict)
    now: float = 0.0
    started: bool = False
    stopped: bool = False

    def __post_init__(self) -> None:
        self._deliver: OutputsHandler = lambda outs: None
        self._watchers: list[OutputsHandler] = []
        self._failure: BaseException | None = None

    # what the simulation thread would do ---------------------------------------------
    def output(self, outs: list[Output]) -> None:
        """Hand outputs to the servers, as the simulation does after a step."""
        self._deliver(outs)
        for w in list(self._watchers):
            w(outs)

    def fail(self, error: BaseException) -> None:
        """The simulation stops on ``error``: every request after it is refused."""
        self._failure = error

    def _answer(self, result: Any) -> Future[Any]:
        """A request answered at once (refused when the simulation has stopped)."""
        future: Future[Any] = Future()
        if self._failure is not None:
            future.set_exception(UsarsimError(f"the simulation has stopped: {self._failure}"))
        else:
            future.set_result(result)
        return future

    # lifecycle and delivery ------------------------------------------------------------
    def set_deliver(self, deliver: OutputsHandler) -> None:
        self._deliver = deliver

    def add_output_watcher(self, watcher: OutputsHandler) -> None:
        self._watchers.append(watcher)

    def remove_output_watcher(self, watcher: OutputsHandler) -> None:
        self._watchers = [w for w in self._watchers if w != watcher]

    def start(self) -> None:
        self.started = True

    def stop(self) -> None:
        self.stopped = True

    def when_failed(self, fn: Callable[[BaseException], None]) -> None:
        self.calls.append(("when_failed", (fn,)))

    @property
    def failure(self) -> BaseException | None:
        return self._failure

    # static facts ------------------------------------------------------------------------
    @property
    def world_name(self) -> str:
        return self.world.name

    @property
    def start_poses(self) -> tuple[StartPose, ...]:
        return self.world.start_poses

    @property
    def time(self) -> float:
        return self.now

    def describe(self, robot: RobotConfig) -> list[ItemDescription]:
        return list(self.descriptions)

    def describe_robot(self, robot: RobotConfig) -> tuple[RobotNumbers, list[ItemDescription]]:
        return self.robot_numbers(robot), self.describe(robot)

    def drive_accepts(self, robot: RobotConfig) -> frozenset[type]:
        return frozenset({WheelSpeeds})

    def package_frames(self, robot: RobotConfig, package: MissionPackage) -> tuple[LinkFrame, ...]:
        return ()

    def lowest_point_m(self, robot: RobotConfig) -> float:
        return robot.body_lowest_point_m  # the fake's robots stand on their bodies

    def velocity_limits(self, robot: RobotConfig) -> VelocityLimits | None:
        return None

    def robot_numbers(self, robot: RobotConfig) -> RobotNumbers:
        if self.numbers is not None:
            return self.numbers
        return RobotNumbers(
            vehicle_type="GroundVehicle",
            class_name=robot.class_name,
            steering_type="SkidSteered",
            mass_kg=14.0,
            max_speed=1.0,
            max_torque=10.0,
            max_front_steer=0.0,
            max_rear_steer=0.0,
            dimensions=(0.5, 0.4, 0.3),
            cog=(0.0, 0.0, 0.0),
            wheel_radius=0.1,
            wheel_separation=0.4,
            wheel_base=0.3,
        )

    def canonical_item_type(self, name: str) -> str:
        return name

    def live_conf(self, uid: int, item_type: str, name: str) -> Any:
        return None

    # robots ------------------------------------------------------------------------------
    def spawn(
        self,
        uid: int,
        robot: RobotConfig,
        name: str,
        location: Any,
        rotation: Any,
        set_down: bool = False,
        controller: str = "",
    ) -> Future[object]:
        self.calls.append(("spawn", (uid, robot.class_name, name, tuple(location), tuple(rotation), set_down)))
        if self._failure is not None:
            return self._answer(None)
        if self.spawn_error is not None:
            error, self.spawn_error = self.spawn_error, None
            refused: Future[object] = Future()
            refused.set_exception(UsarsimError(error))
            return refused
        self.spawned[uid] = Spawned(uid, robot, name, tuple(location), tuple(rotation), set_down)
        self.directory[uid] = RobotEntry(uid, name, robot, controller)
        return self._answer(uid)

    def barrier(self) -> Future[float]:
        return self._answer(self.now)

    def remove(self, uid: int) -> None:
        self.calls.append(("remove", (uid,)))
        self.spawned.pop(uid, None)
        self.directory.pop(uid, None)

    def robots(self) -> tuple[RobotEntry, ...]:
        return tuple(self.directory.values())

    def robot(self, uid: int) -> RobotEntry | None:
        return self.directory.get(uid)

    def find_robot(self, name: str) -> RobotEntry | None:
        exact = next((e for e in self.directory.values() if e.name == name), None)
        return exact or next((e for e in self.directory.values() if e.name.lower() == name.lower()), None)

    def drive(self, uid: int, command: DriveCommand) -> None:
        self.calls.append(("drive", (uid, command)))

    def drive_joints(self, uid: int, orders: list[JointOrder]) -> None:
        self.calls.append(("drive_joints", (uid, list(orders))))

    def operate(self, uid: int, item_type: Any, name: Any, opcode: Any, params: Any) -> Future[object]:
        self.calls.append(("operate", (uid, item_type, name, opcode, params)))
        return self._answer(CommandResult(str(item_type), str(name or ""), ok=False))

    def set_viewports(self, uid: int, names: list[str | None]) -> Future[tuple[float, list[tuple[str, str]]]]:
        self.calls.append(("set_viewports", (uid, list(names))))
        return self._answer((self.now, [(n, "OK" if n else "Failed") for n in names]))

    def report_victim(self, uid: int, name: str, location: Any) -> Future[None]:
        self.calls.append(("report_victim", (uid, name, tuple(location))))
        return self._answer(None)

    def step(self, seconds: float) -> Future[float]:
        self.calls.append(("step", (seconds,)))
        if self._failure is None:
            self.now = round(self.now + seconds, 9)
        return self._answer(self.now)

    # ground truth and pictures -------------------------------------------------------------
    def truth(self, class_name: str | None, name: str | None) -> Future[list[tuple[Any, ...]]]:
        return self._answer([])

    def set_multiview_cameras(self, count: int) -> None:
        self.calls.append(("set_multiview_cameras", (count,)))

    def render_service(self, max_fps: float) -> Any:
        raise NotImplementedError("the fake facade renders no pictures")

    # the radio -------------------------------------------------------------------------------
    def open_radio(
        self,
        model: Any,
        on_change: Callable[[float, list[tuple[Any, bool]]], None],
        channel: Any = None,
        on_views: Any = None,
    ) -> Any:
        self.calls.append(("open_radio", (model,)))
        return None

    def radio_watch(self, pairs: frozenset[Any]) -> None:
        self.calls.append(("radio_watch", (pairs,)))

    def radio_check(self, a: str, b: str) -> Future[tuple[float, Any]]:
        return self._answer((self.now, None))

    def radio_link(self, a: str, b: str) -> Future[Any]:
        return self._answer(None)

    def radio_neighbours(self, a: str) -> Future[list[Any]]:
        return self._answer([])

    def radio_counts(self) -> Future[dict[Any, Any]]:
        return self._answer({})

    def robot_positions(self) -> Future[list[Any]]:
        return self._answer([(s.name, s.location, False) for s in self.spawned.values()])

    def walls_between_robots(self, a: str, b: str) -> Future[int]:
        return self._answer(0)

    def walls_between(self, start: Any, end: Any) -> Future[int]:
        return self._answer(0)

    def watch_frames(
        self, period_s: float, on_frame: Callable[[Any], None], *, radio_model: Any = None, links_period_s: float = 1.0
    ) -> None:
        self.calls.append(("watch_frames", (period_s,)))
