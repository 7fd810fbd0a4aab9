"""Robot files: one YAML file per robot class (geometry, masses, wheels, mounts,
default sensors, battery).  Adding a robot needs no code unless it has a new kind
of drive.  Coordinates are in the robot's USARSim frame (X forward, Y right,
Z down) relative to the chassis origin; metres, radians, kilograms.

This module holds the robot as a whole and :func:`load_robot`; its parts and their sections
(chassis, wheels, links, sensors) are in usarsim.config.robot_parts.  A kind of drive's own
section (an aerial robot's ``aerial`` limits, a vessel's ``nautical`` hull, a walking robot's
``gait``) is kept as written, in ``drive_sections``, for the drive model to read and check,
as a mounted item's settings are (the drive's module declares them: usarsim.robots).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

from usarsim.config.reader import FieldDefaults, Section, did_you_mean, load_yaml, name_entries
from usarsim.config.robot_parts import JOINT_TYPES as JOINT_TYPES
from usarsim.config.robot_parts import SHAPES as SHAPES
from usarsim.config.robot_parts import STEER_GROUPS as STEER_GROUPS
from usarsim.config.robot_parts import ChassisBox as ChassisBox
from usarsim.config.robot_parts import Link as Link
from usarsim.config.robot_parts import Look as Look
from usarsim.config.robot_parts import LookPiece as LookPiece
from usarsim.config.robot_parts import MountedItem as MountedItem
from usarsim.config.robot_parts import Shape as Shape
from usarsim.config.robot_parts import Wheel as Wheel
from usarsim.config.robot_parts import read_items, read_links, read_look, read_shape, read_wheels
from usarsim.errors import ConfigError

Vec3 = tuple[float, float, float]

VEHICLE_TYPES = ("GroundVehicle", "AerialVehicle", "LeggedRobot", "NauticalVehicle", "StaticPlatform")
STEERING_TYPES = ("SkidSteered", "AckermanSteered", "HolonomSteered", "OmniDrive", "None")
# The drives built in (usarsim.robots); a robot file may name any drive registered there
# (a plugin's own), checked with the drive registry when the robot is validated or spawned.
DRIVES = ("skid", "ackermann", "holonomic", "aerial", "static", "nautical", "legged")


@dataclass(frozen=True, kw_only=True)
class MissionPackage:
    """A named group of links, numbered from 1 in the order given (MISPKG, MISSTA)."""

    name: str
    links: tuple[str, ...]


@dataclass(frozen=True, kw_only=True)
class RobotGeometryConfig:
    """The robot's overall geometry as GEO reports it: its bounding box (the chassis origin
    is its centre), centre of gravity and wheel layout (0: not given)."""

    dimensions: Vec3
    cog: Vec3 = (0.0, 0.0, 0.0)
    wheel_radius_m: float = 0.0
    wheel_separation_m: float = 0.0
    wheel_base_m: float = 0.0


@dataclass(frozen=True, kw_only=True)
class RobotConfig:
    """A robot class as its robot file describes it: the identity CONF and GEO report (vehicle and steering type,
    geometry), its drive, mass and limits, and the parts it is built from (chassis pieces, wheels, links, mission
    packages and mounted sensors and effecters)."""

    class_name: str
    description: str = ""
    path: str
    vehicle_type: str
    steering_type: str
    drive: str
    mass_kg: float
    max_speed_rad_s: float
    max_torque_nm: float
    max_front_steer_rad: float = 0.0
    max_rear_steer_rad: float = 0.0
    battery_s: float = 1200.0  # battery life at rest (STA Battery)
    status_interval_s: float = 0.2  # STA and MISSTA period
    geometry: RobotGeometryConfig
    chassis: tuple[ChassisBox, ...]
    wheels: tuple[Wheel, ...]
    items: tuple[MountedItem, ...]
    links: tuple[Link, ...] = ()
    mission_packages: tuple[MissionPackage, ...] = ()
    wheel_friction: float = 1.0
    # skid steering: the wheels of each side turn together, through a chain or a track (False:
    # each wheel has its own motor; see usarsim/robots/skid.py)
    chained: bool = True
    wheel_gain: float = 20.0
    wheel_torque_nm: float | None = None
    steer_torque_nm: float = 50.0  # steering servo torque of each steered wheel
    status_joints: tuple[str, ...] = ()  # links whose angles STA reports (TeleMax flippers, protocol.md 6.2)
    # the sections of the file the loader does not know, as written (name -> mapping): the
    # drive's own settings, read and checked by its drive model (usarsim.robots.base)
    drive_sections: dict[str, Any] = field(default_factory=dict)
    # how far above the surface below a start pose the robot's lowest point is set (the
    # per-robot Z of USARSim's start poses; manual section 5.3)
    spawn_clearance_m: float = 0.02
    # the body's colour (red, green, blue from 0 to 1) in camera pictures only: the Pioneers'
    # red aluminium by default
    color: tuple[float, float, float] = (0.75, 0.10, 0.10)
    look: Look = Look()  # what cameras see beyond the solid pieces (tracks, hubs, bumpers)

    @property
    def wheel_torque_limit_nm(self) -> float:
        """The physical torque limit of each driven wheel (``max_torque_nm`` is the
        value CONF reports, in USARSim's engine units)."""
        return self.max_torque_nm if self.wheel_torque_nm is None else self.wheel_torque_nm

    @property
    def total_mass_kg(self) -> float:
        return (
            sum(c.mass_kg for c in self.chassis)
            + sum(w.mass_kg for w in self.wheels)
            + sum(sh.mass_kg for ln in self.links for sh in ln.shapes)
        )

    @property
    def body_lowest_point_m(self) -> float:
        """How far below its origin the robot's body reaches when level (its wheels, balls,
        boxes and capsules on the chassis; Z down, positive).  Where the robot stands is its
        drive's to say (a walking robot stands on its legs): the drive model's
        ``lowest_point_m``."""
        low = [w.position[2] + w.radius_m for w in self.wheels if w.parent == "chassis"]
        for p in self.chassis:
            if p.shape == "box":
                low.append(p.center[2] + p.size[2] / 2.0)
            elif p.shape == "sphere":
                low.append(p.center[2] + p.radius_m)
            else:  # cylinders and capsules along their own (rotated) Z axis
                import math

                r, pch, _ = p.rotation
                axis_z = abs(math.cos(r) * math.cos(pch))  # how vertical the axis is
                lean = math.sqrt(max(0.0, 1.0 - axis_z**2))
                extra = p.radius_m if p.shape == "capsule" else p.radius_m * lean
                low.append(p.center[2] + p.length_m / 2.0 * axis_z + extra)
        return max(low) if low else 0.0

    def link(self, name: str) -> Link | None:
        for ln in self.links:
            if ln.name == name:
                return ln
        return None

    def link_origin(self, name: str) -> Vec3:
        """Where the joint of link ``name`` sits in the chassis frame, at rest (the sum of
        the locations along its chain; links are assumed not to be turned)."""
        x = y = z = 0.0
        ln = self.link(name)
        while ln is not None:
            x, y, z = x + ln.location[0], y + ln.location[1], z + ln.location[2]
            ln = self.link(ln.parent)
        return (x, y, z)

    def package(self, name: str) -> MissionPackage | None:
        low = name.lower()
        for p in self.mission_packages:
            if p.name.lower() == low:
                return p
        return None


def _geometry(g: Section) -> RobotGeometryConfig:
    """The ``geometry`` section; its wheel keys lack the ``_m`` of the fields they fill."""
    d = FieldDefaults(RobotGeometryConfig)
    out = RobotGeometryConfig(
        dimensions=cast(Vec3, g.vec("dimensions", positive=True)),  # vec reads 3 numbers unless told otherwise
        cog=cast(Vec3, g.vec("cog", 3, d.cog)),
        wheel_radius_m=g.float("wheel_radius", d.wheel_radius_m, min=0.0),
        wheel_separation_m=g.float("wheel_separation", d.wheel_separation_m, min=0.0),
        wheel_base_m=g.float("wheel_base", d.wheel_base_m, min=0.0),
    )
    g.finish()
    return out


def load_robot(path: str | Path) -> RobotConfig:
    path = str(path)
    data = load_yaml(path)
    try:
        return _robot(data, path)
    except ConfigError as exc:
        name_entries(exc, data)
        raise


def _robot(data: dict, path: str) -> RobotConfig:
    d = FieldDefaults(RobotConfig)
    top = Section(data, path=path)
    class_name = top.str("class_name")
    if any(c in class_name for c in "{} \t."):
        raise top.error("class_name", f"a class name may not contain spaces, dots or braces, got {class_name!r}")
    desc = top.str("description", d.description)
    vehicle_type = top.str("vehicle_type", choices=VEHICLE_TYPES)
    steering = top.str("steering_type", choices=STEERING_TYPES)
    drive = top.str("drive")
    if not drive.isidentifier() or drive != drive.lower():
        raise top.error("drive", f"a drive name is a lower-case word (built in: {', '.join(DRIVES)}), got {drive!r}")
    mass = top.float("mass_kg", min=0.01)
    max_speed = top.float("max_speed_rad_s", min=0.0, min_exclusive=True)
    max_torque = top.float("max_torque_nm", min=0.0, min_exclusive=True)
    mfs = top.float("max_front_steer_rad", d.max_front_steer_rad, min=0.0)
    mrs = top.float("max_rear_steer_rad", d.max_rear_steer_rad, min=0.0)
    battery = top.float("battery_s", d.battery_s, min=0.0, min_exclusive=True)
    status_interval = top.float("status_interval_s", d.status_interval_s, min=0.01, max=10.0)
    spawn_clearance = top.float("spawn_clearance_m", d.spawn_clearance_m, min=0.0, max=2.0)
    wheel_friction = top.float("wheel_friction", d.wheel_friction, min=0.0, max=10.0)
    chained = top.bool("chained", d.chained)
    color = top.vec("color", 3, d.color)
    if not all(0.0 <= c <= 1.0 for c in color):
        raise top.error("color", f"a colour is red, green, blue from 0 to 1, got {list(color)}")
    wheel_gain = top.float("wheel_gain", d.wheel_gain, min=0.0, min_exclusive=True)
    wheel_torque = top.float("wheel_torque_nm", d.wheel_torque_nm, min=0.0, min_exclusive=True)
    steer_torque = top.float("steer_torque_nm", d.steer_torque_nm, min=0.0, min_exclusive=True)
    geometry = _geometry(top.section("geometry"))

    chassis = [read_shape(s) for s in top.entries("chassis", required=True)]
    if not chassis:
        raise top.error("chassis", "a robot needs at least one chassis box")

    wheels = read_wheels(top)
    wnames = {w.name for w in wheels}

    links = read_links(top, wnames)
    lnames = {ln.name for ln in links}

    for i, w in enumerate(wheels):
        if w.parent != "chassis" and w.parent not in lnames:
            raise ConfigError(
                f"unknown parent '{w.parent}'{did_you_mean(w.parent, ['chassis', *lnames])}",
                path=path,
                key=f"wheels[{i}].parent",
            )
        if w.steer != "none" and w.parent != "chassis":
            raise ConfigError("a steered wheel must sit on the chassis", path=path, key=f"wheels[{i}].steer")
    # what a kind of drive needs of the wheels (sides, steered axles, numbers) is checked by
    # its drive model (usarsim.robots), when the robot is validated or spawned
    status_joints = tuple(str(x) for x in top.list("status_joints", []))
    for j in status_joints:
        if j not in lnames:
            raise top.error("status_joints", f"unknown link '{j}'{did_you_mean(j, lnames)}")

    packages: list[MissionPackage] = []
    for s in top.entries("mission_packages"):
        pname = s.str("name")
        plinks = s.list("links")
        for ln in plinks:
            if ln not in lnames:
                raise s.error("links", f"unknown link '{ln}'{did_you_mean(str(ln), lnames)}")
        if not plinks:
            raise s.error("links", "a mission package needs at least one link")
        packages.append(MissionPackage(name=pname, links=tuple(str(x) for x in plinks)))

    items = read_items(top, [*wnames, *lnames])
    look = read_look(top, ["chassis", *lnames], cast(Vec3, tuple(float(c) for c in color)))
    # a section (a mapping) no key above took belongs to the drive (its model checks it);
    # anything else unread is a mistake
    drive_sections = {str(k): v for k, v in top.data.items() if isinstance(v, dict) and not top.has_read(str(k))}
    top.finish(allowed_extra=drive_sections)

    total = (
        sum(c.mass_kg for c in chassis)
        + sum(w.mass_kg for w in wheels)
        + sum(sh.mass_kg for ln in links for sh in ln.shapes)
    )
    if abs(total - mass) > 0.01 * mass + 1e-6:
        raise ConfigError(
            f"chassis, wheel and link masses add up to {total:.3f} kg but mass_kg is {mass}; make them agree",
            path=path,
            key="mass_kg",
        )
    return RobotConfig(
        class_name=class_name,
        description=desc,
        path=path,
        vehicle_type=vehicle_type,
        steering_type=steering,
        drive=drive,
        mass_kg=mass,
        max_speed_rad_s=max_speed,
        max_torque_nm=max_torque,
        max_front_steer_rad=mfs,
        max_rear_steer_rad=mrs,
        battery_s=battery,
        status_interval_s=status_interval,
        spawn_clearance_m=spawn_clearance,
        geometry=geometry,
        chassis=tuple(chassis),
        wheels=tuple(wheels),
        items=tuple(items),
        wheel_friction=wheel_friction,
        chained=chained,
        wheel_gain=wheel_gain,
        wheel_torque_nm=wheel_torque,
        steer_torque_nm=steer_torque,
        links=tuple(links),
        mission_packages=tuple(packages),
        status_joints=status_joints,
        drive_sections=drive_sections,
        color=cast(Vec3, tuple(float(c) for c in color)),  # read as 3 numbers
        look=look,
    )


def class_name_problem(cfg: RobotConfig) -> str | None:
    """Why a robot file's ``class_name`` does not fit its file name, or None: a client asks
    for a robot class by name (``INIT {ClassName USARBot.P2AT}``), and the server finds the
    file of that name, so P2AT.yaml must say ``class_name: P2AT``."""
    p = Path(cfg.path)
    if cfg.class_name == p.stem:
        return None
    return (
        f"class_name is '{cfg.class_name}' but the file is {p.name}: INIT finds a robot class by its file's "
        f"name, so the two must agree; rename the file {cfg.class_name}{p.suffix} or write "
        f"class_name: {p.stem}"
    )
