"""What the servers may ask of the simulation: the facade's interface, as a protocol.

The servers (``usarsim.server``, ``usarsim.web``) are written against :class:`Facade`, never
against the simulation itself: the composition root (:mod:`usarsim.server.app`) hands them the
real one (:class:`usarsim.sim.facade.SimFacade`), and the fast test tier a fake that builds no
MuJoCo model.  This module imports no physics: a server module that needs nothing else of the
simulation layer than this and :mod:`usarsim.sim.types` loads without MuJoCo.

A request that has an answer returns it as a typed future (:class:`concurrent.futures.Future`:
``Future[float]`` for a barrier's time); it is settled on the thread that ran the request (the
simulation's, or the caller's for a short lock-step STEP), after every message the request
produced was handed to the servers, and a callback added once it is settled runs at once on the
thread that adds it.  A server therefore hands the answer to its event loop
(:func:`when_done` with a thread-safe callback, or :func:`asyncio.wrap_future`), behind those
messages.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Future
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, TypeVar, cast

if TYPE_CHECKING:
    from usarsim.config.channel import ChannelConfig
    from usarsim.config.robot import MissionPackage, RobotConfig
    from usarsim.config.world import StartPose, WorldConfig
    from usarsim.controls import DriveCommand, JointOrder
    from usarsim.readings import ItemParams
    from usarsim.sim.channel import Channel, LinkCounts, LinkView
    from usarsim.sim.outputs import ItemDescription, LinkFrame, Output, RobotNumbers, VelocityLimits
    from usarsim.sim.radio import Link, RadioModel
    from usarsim.sim.render import RenderService
    from usarsim.sim.worldframe import WorldFrame

T = TypeVar("T")
# ``on_done(result, error)``: the request's result (its type given, Done[float]) or the error it
# was refused with
Done = Callable[[T, BaseException | None], None]


def when_done(future: Future[T], on_done: Done[T]) -> None:
    """``on_done(result, None)``, or ``on_done(None, error)`` when the request was refused or
    failed, once ``future`` is settled (at once when it is)."""

    def call(f: Future[T]) -> None:
        error = f.exception()
        on_done(cast(T, None) if error is not None else f.result(), error)

    future.add_done_callback(call)


def settle(future: Future[T]) -> Done[T]:
    """An ``on_done(result, error)`` that settles ``future`` with what it is given."""

    def done(result: T, error: BaseException | None) -> None:
        if error is not None:
            future.set_exception(error)
        else:
            future.set_result(result)

    return done


Position = tuple[str, tuple[float, float, float], bool]  # a robot's name, where it is, its battery empty


@dataclass(frozen=True)
class RobotEntry:
    """A robot in the world, as the robot directory lists it: its connection's ``uid``, its
    ``name``, its class and who drives it (``controller``: its client, as logs name it)."""

    uid: int
    name: str
    robot: RobotConfig
    controller: str = ""


OutputsHandler = Callable[[list["Output"]], None]


class Facade(Protocol):
    """The narrow, thread-safe door from the servers into the simulation
    (:class:`usarsim.sim.facade.SimFacade` is the real one)."""

    world: WorldConfig
    lockstep: bool
    speed: float | None

    # lifecycle and delivery
    def set_deliver(self, deliver: OutputsHandler) -> None: ...
    def add_output_watcher(self, watcher: OutputsHandler) -> None: ...
    def remove_output_watcher(self, watcher: OutputsHandler) -> None: ...
    def start(self) -> None: ...
    def stop(self) -> None: ...
    def when_failed(self, fn: Callable[[BaseException], None]) -> None: ...
    @property
    def failure(self) -> BaseException | None: ...

    # static facts
    @property
    def world_name(self) -> str: ...
    @property
    def start_poses(self) -> tuple[StartPose, ...]: ...
    @property
    def time(self) -> float: ...
    def describe(self, robot: RobotConfig) -> list[ItemDescription]: ...
    def describe_robot(self, robot: RobotConfig) -> tuple[RobotNumbers, list[ItemDescription]]: ...
    def drive_accepts(self, robot: RobotConfig) -> frozenset[type]: ...
    def package_frames(self, robot: RobotConfig, package: MissionPackage) -> tuple[LinkFrame, ...]: ...
    def robot_numbers(self, robot: RobotConfig) -> RobotNumbers: ...
    def lowest_point_m(self, robot: RobotConfig) -> float: ...
    def velocity_limits(self, robot: RobotConfig) -> VelocityLimits | None: ...
    def canonical_item_type(self, name: str) -> str: ...
    def live_conf(self, uid: int, item_type: str, name: str) -> Any: ...

    # robots
    def spawn(
        self,
        uid: int,
        robot: RobotConfig,
        name: str,
        location: Sequence[float],
        rotation: Sequence[float],
        set_down: bool = False,
        controller: str = "",
    ) -> Future[object]: ...
    def barrier(self) -> Future[float]: ...
    def remove(self, uid: int) -> None: ...
    def robots(self) -> tuple[RobotEntry, ...]: ...
    def robot(self, uid: int) -> RobotEntry | None: ...
    def find_robot(self, name: str) -> RobotEntry | None: ...
    def drive(self, uid: int, command: DriveCommand) -> None: ...
    def drive_joints(self, uid: int, orders: list[JointOrder]) -> None: ...
    def operate(
        self,
        uid: int,
        item_type: str | None,
        name: str | None,
        opcode: str | None,
        params: ItemParams,
    ) -> Future[object]: ...
    def set_viewports(self, uid: int, names: list[str | None]) -> Future[tuple[float, list[tuple[str, str]]]]: ...
    def report_victim(self, uid: int, name: str, location: Sequence[float]) -> Future[None]: ...
    def step(self, seconds: float) -> Future[float]: ...

    # ground truth and pictures
    def truth(self, class_name: str | None, name: str | None) -> Future[list[tuple[Any, ...]]]: ...
    def set_multiview_cameras(self, count: int) -> None: ...
    def render_service(self, max_fps: float) -> RenderService: ...

    # the radio (protocol.md 12)
    def open_radio(
        self,
        model: RadioModel,
        on_change: Callable[[float, list[tuple[Any, bool]]], None],
        channel: ChannelConfig | None = None,
        on_views: Callable[[float, dict[Any, LinkView | None]], None] | None = None,
    ) -> Channel | None: ...
    def radio_watch(self, pairs: frozenset[Any]) -> None: ...
    def radio_check(self, a: str, b: str) -> Future[tuple[float, Link | None]]: ...
    def radio_link(self, a: str, b: str) -> Future[Link | None]: ...
    def radio_neighbours(self, a: str) -> Future[list[tuple[str, Link, float]]]: ...
    def radio_counts(self) -> Future[dict[tuple[str, str], LinkCounts]]: ...
    def robot_positions(self) -> Future[list[Position]]: ...
    def walls_between_robots(self, a: str, b: str) -> Future[int]: ...
    def walls_between(self, start: Sequence[float], end: Sequence[float]) -> Future[int]: ...

    # recording and live views
    def watch_frames(
        self,
        period_s: float,
        on_frame: Callable[[WorldFrame], None],
        *,
        radio_model: RadioModel | None = None,
        links_period_s: float = 1.0,
    ) -> None: ...


__all__ = ["Done", "Facade", "OutputsHandler", "Position", "RobotEntry"]
