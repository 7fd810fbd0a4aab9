"""What the world looks like at one instant, as plain frozen values: the poses of every robot
and movable object and the radio links (:mod:`usarsim.sim.snapshot` takes them), for the
recording, the score and the live views."""

from __future__ import annotations

from dataclasses import dataclass

from usarsim.config.robot import RobotConfig


@dataclass(frozen=True, slots=True)
class RobotFrame:
    """A robot at one instant: USARSim frame, metres and radians (rotations in [0, 2 pi))."""

    uid: int
    name: str
    config: RobotConfig
    location: tuple[float, float, float]
    rotation: tuple[float, float, float]
    battery_s: float
    spawn_time: float
    wall_force_n: float = 0.0  # the strongest push against a static solid now (contact_forces)


@dataclass(frozen=True, slots=True)
class ObjectFrame:
    """A movable object (a brick, a pipe) at one instant."""

    name: str
    location: tuple[float, float, float]
    rotation: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class LinkFrame:
    """The radio link between two robots (by name, lower case, sorted) at one instant."""

    a: str
    b: str
    signal_dbm: float
    distance_m: float
    walls: int
    holds: bool


@dataclass(frozen=True, slots=True)
class WorldFrame:
    """The world at one simulated instant (s): every robot and movable object, and the radio links when they were
    sampled, as the recording, the score and the live views take it."""

    time: float
    robots: tuple[RobotFrame, ...]
    objects: tuple[ObjectFrame, ...]
    links: tuple[LinkFrame, ...] | None  # None: not sampled in this frame
