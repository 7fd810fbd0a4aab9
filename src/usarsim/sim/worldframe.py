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
class LinkTraffic:
    """What the radio channel carried from one robot to another (names lower case) since the
    start: messages and bytes delivered, messages dropped by cause (out of ``range``, ``loss``,
    no room in the queue: ``capacity``), bytes dropped, and the delivered messages' mean delay."""

    src: str
    dst: str
    delivered: int
    delivered_bytes: int
    dropped_range: int
    dropped_loss: int
    dropped_capacity: int
    dropped_bytes: int
    mean_delay_s: float

    @property
    def dropped(self) -> int:
        return self.dropped_range + self.dropped_loss + self.dropped_capacity


@dataclass(frozen=True, slots=True)
class RelayFrame:
    """A radio relay a robot dropped: its name, its owner and where its antenna is (USARSim frame)."""

    name: str
    owner: str
    location: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class WorldFrame:
    """The world at one simulated instant (s): every robot and movable object, and the radio links when they were
    sampled, as the recording, the score and the live views take it."""

    time: float
    robots: tuple[RobotFrame, ...]
    objects: tuple[ObjectFrame, ...]
    links: tuple[LinkFrame, ...] | None  # None: not sampled in this frame
    # what the radio channel carried so far, by link (sampled with the links; None: not in
    # this frame, or no channel beyond USARSim's), and the relays robots dropped
    traffic: tuple[LinkTraffic, ...] | None = None
    relays: tuple[RelayFrame, ...] = ()
