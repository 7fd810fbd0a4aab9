"""What leaves the simulation for the servers: outputs for a robot's client, and the
description of a robot's mounted items (GETGEO/GETCONF)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


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


@dataclass(frozen=True)
class VelocityLimits:
    """How fast a robot driven by velocities may go (m/s forward, sideways and up; rad/s of
    yaw): its drive model's (:meth:`usarsim.robots.DriveModel.velocity_limits`)."""

    linear: float
    lateral: float
    vertical: float
    yaw_rate: float


@dataclass(frozen=True)
class LinkFrame:
    """What ``GETGEO {Type MisPkg}`` and ``{Type Actuator}`` report of one link of a mission
    package: its number (from 1), its parent's (``-1``: the chassis, or a link of no package
    listed), and its joint's pose relative to the parent's frame as USARSim reported it."""

    link: int
    parent: int
    location: tuple[float, float, float]
    orientation: tuple[float, float, float]


def _clean(v: float) -> float:
    """A coordinate computed through rotations, rounding noise (1e-17) reported as 0."""
    return 0.0 if abs(v) < 1e-9 else float(v)


def package_frames(robot, package) -> tuple[LinkFrame, ...]:
    """The frames GEO reports for each link of ``package`` (a ``MissionPackage`` of the
    ``RobotConfig`` ``robot``).  A link's reported orientation is its ``geo_orientation``
    (the joint frame USARSim's robot class gave it, protocol.md 6.8; by default its own
    orientation), relative to its parent's reported frame, and its location is given in that
    frame: the P2AT's pan-tilt, built with level frames, reports link 1 turned over (roll pi)
    and link 2 at 0.0599 m along link 1's Z, as USARSim did.  Without ``geo_orientation`` the
    link's own location and orientation are reported."""
    from usarsim.sim.frames import euler_to_mat, mat_to_euler

    links = {ln.name: ln for ln in robot.links}
    absolute: dict[str, tuple] = {}  # link name -> (position, own rotation, reported rotation) on the chassis

    def frame_of(name: str):
        if name not in links:  # the chassis
            return np.zeros(3), np.eye(3), np.eye(3)
        if name not in absolute:
            ln = links[name]
            p, own, shown = frame_of(ln.parent)
            reported = ln.geo_orientation if ln.geo_orientation is not None else ln.orientation
            absolute[name] = (
                p + own @ np.asarray(ln.location, dtype=float),
                own @ euler_to_mat(*ln.orientation),
                shown @ euler_to_mat(*reported),
            )
        return absolute[name]

    out = []
    for i, name in enumerate(package.links):
        ln = links[name]
        parent = package.links.index(ln.parent) + 1 if ln.parent in package.links else -1
        if ln.geo_orientation is None and (ln.parent not in links or links[ln.parent].geo_orientation is None):
            location, orientation = tuple(ln.location), tuple(ln.orientation)
        else:
            p, _, shown = frame_of(ln.parent)
            q, _, mine = frame_of(name)
            location = tuple(_clean(v) for v in shown.T @ (q - p))
            orientation = tuple(_clean(v) for v in mat_to_euler(shown.T @ mine))
        out.append(LinkFrame(link=i + 1, parent=parent, location=location, orientation=orientation))
    return tuple(out)
