"""What leaves the simulation for the servers: outputs for a robot's client, and the
description of a robot's mounted items (GETGEO/GETCONF)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, slots=True)
class Output:
    """One message-worth of data for the client that owns robot ``uid``.

    ``key`` identifies the periodic stream (``STA``, ``SEN:Sonar``, ``SEN:RangeScanner:Scanner1``)
    for latest-wins dropping; ``periodic`` is False for replies that must not be dropped.
    """

    uid: int
    time: float | None
    value: Any
    key: str
    periodic: bool = True


@dataclass(frozen=True)
class ItemDescription:
    """What GETGEO/GETCONF report for one mounted item."""

    item_type: str
    name: str
    location: tuple[float, float, float]
    orientation: tuple[float, float, float]
    mount: str
    conf: tuple[tuple[str, Any], ...]


@dataclass(frozen=True)
class RobotNumbers:
    """What ``GETGEO`` and ``GETCONF {Type Robot}`` report of a robot class (protocol.md 6.7,
    6.8): contributed by its drive model (:meth:`usarsim.robots.DriveModel.numbers`)."""

    vehicle_type: str
    class_name: str
    steering_type: str
    mass_kg: float
    max_speed: float
    max_torque: float
    max_front_steer: float
    max_rear_steer: float
    dimensions: tuple[float, float, float]
    cog: tuple[float, float, float]
    wheel_radius: float | None
    wheel_separation: float | None
    wheel_base: float | None
