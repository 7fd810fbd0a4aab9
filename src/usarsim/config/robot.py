"""Robot files: one YAML file per robot class (geometry, masses, wheels, mounts,
default sensors, battery).  Adding a robot needs no code unless it has a new kind
of drive.  Coordinates are in the robot's USARSim frame (X forward, Y right,
Z down) relative to the chassis origin; metres, radians, kilograms.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usarsim.config.reader import FieldDefaults, Section, did_you_mean, load_yaml, name_entries
from usarsim.errors import ConfigError

Vec3 = tuple[float, float, float]

VEHICLE_TYPES = ("GroundVehicle", "AerialVehicle", "LeggedRobot", "NauticalVehicle", "StaticPlatform")
STEERING_TYPES = ("SkidSteered", "AckermanSteered", "HolonomSteered", "OmniDrive", "None")
# The drives built in (usarsim.robots); a robot file may name any drive registered there
# (a plugin's own), checked with the drive registry when the robot is validated or spawned.
DRIVES = ("skid", "ackermann", "holonomic", "aerial", "static", "nautical", "legged")
STEER_GROUPS = ("none", "front", "rear", "free")


SHAPES = ("box", "sphere", "cylinder", "capsule")
JOINT_TYPES = ("revolute", "prismatic")


@dataclass(frozen=True, kw_only=True)
class ChassisBox:
    """A solid piece of a robot body (the chassis or a link): a box by default."""

    center: Vec3 = (0.0, 0.0, 0.0)
    size: Vec3 = (0.0, 0.0, 0.0)  # box: full extents
    mass_kg: float
    shape: str = "box"
    radius_m: float = 0.0  # sphere, cylinder, capsule
    length_m: float = 0.0  # cylinder, capsule: along the piece's own Z axis
    rotation: Vec3 = (0.0, 0.0, 0.0)
    friction: float | None = None  # None: the robot's default (1.0)


Shape = ChassisBox


@dataclass(frozen=True, kw_only=True)
class Link:
    """An articulated part (mission-package link, flipper, arm segment): a body joined
    to its parent (the chassis or another link) by one revolute or prismatic joint whose
    axis is given in the link's own frame.  ``min_range > max_range`` marks an unlimited
    (continuous) joint, as in USARSim's CONF."""

    name: str
    parent: str = "chassis"  # or a link name
    location: Vec3 = (0.0, 0.0, 0.0)  # joint origin in the parent's frame
    orientation: Vec3 = (0.0, 0.0, 0.0)
    joint: str = "revolute"  # JOINT_TYPES
    axis: Vec3 = (0.0, 0.0, 1.0)
    min_range: float = 1.0  # min_range > max_range: continuous unless a range is given
    max_range: float = 0.0
    max_speed: float
    max_torque: float
    shapes: tuple[ChassisBox, ...] = ()
    armature: float = 0.05  # reflected inertia of the geared drive, kg m^2 (or kg)
    collide: bool = True  # False: its shapes touch nothing (a small pan-tilt on top of a robot)
    # the joint frame USARSim's robot class gave the link, relative to its parent's, as GEO
    # {Type MisPkg}/{Type Actuator} report it (None: its orientation); reporting only
    geo_orientation: Vec3 | None = None

    @property
    def limited(self) -> bool:
        return self.min_range <= self.max_range


@dataclass(frozen=True, kw_only=True)
class MissionPackage:
    """A named group of links, numbered from 1 in the order given (MISPKG, MISSTA)."""

    name: str
    links: tuple[str, ...]


@dataclass(frozen=True, kw_only=True)
class Wheel:
    name: str
    position: Vec3
    radius_m: float
    width_m: float
    mass_kg: float
    side: str  # "left" | "right"
    driven: bool = True
    parent: str = "chassis"  # or a link (a flipper's wheels)
    steer: str = "none"  # front/rear: Ackermann axles; free: steered alone (holonomic)
    number: int = -1  # WheelNumber of a holonomic DRIVE (protocol.md 5.3c)


@dataclass(frozen=True, kw_only=True)
class AerialLimits:
    """Speed limits of an aerial robot (protocol.md 5.3d; UDK AirRobot: 2 m/s linear, lateral
    and vertical, 100 degrees/s of yaw) and how hard its rotors can push."""

    max_linear_m_s: float = 2.0
    max_lateral_m_s: float = 2.0
    max_vertical_m_s: float = 2.0
    max_yaw_rate_rad_s: float = 1.7453
    max_accel_m_s2: float = 4.0


@dataclass(frozen=True, kw_only=True)
class NauticalSpec:
    """A vessel (protocol.md 5.3e): its displaced volume (buoyancy), its propeller's thrust,
    and how its rudder and stern planes turn it."""

    volume_m3: float = 0.0
    max_thrust_n: float = 50.0
    max_rudder_rad: float = 0.5
    max_stern_plane_rad: float = 0.5
    rudder_gain: float = 20.0  # N m of yaw torque per rad of rudder per m/s of speed
    stern_plane_gain: float = 20.0  # N m of pitch torque per rad of plane per m/s
    drag_n_per_m_s: float = 40.0  # linear drag in water
    angular_drag: float = 20.0  # N m per rad/s


@dataclass(frozen=True, kw_only=True)
class Leg:
    """One leg of a walking robot: its hip pitch, hip roll and knee links, the lengths of
    its upper and lower segments, and its phase in the gait (0..1).  A biped's leg also
    has a hip yaw (it turns the foot) and ankle pitch and roll links (they keep the sole
    flat); its chain then runs yaw, roll, pitch, knee, ankle pitch, ankle roll, and
    ``knee_forward`` bends its knee forward, as a person's does."""

    hip_pitch: str
    hip_roll: str
    knee: str
    upper_m: float
    lower_m: float
    phase: float = 0.0
    hip_yaw: str | None = None
    ankle_pitch: str | None = None
    ankle_roll: str | None = None
    knee_forward: bool = False

    @property
    def joints(self) -> tuple[str, ...]:
        return tuple(
            j
            for j in (self.hip_yaw, self.hip_roll, self.hip_pitch, self.knee, self.ankle_pitch, self.ankle_roll)
            if j is not None
        )


@dataclass(frozen=True, kw_only=True)
class Gait:
    """A walking robot's gait (DRIVE {LinearVelocity} {LateralVelocity} {RotationalVelocity})."""

    legs: tuple[Leg, ...]
    stand_height_m: float  # hip to foot, standing
    step_height_m: float = 0.02
    period_s: float = 0.5
    max_linear_m_s: float = 0.2
    max_lateral_m_s: float = 0.1
    max_yaw_rate_rad_s: float = 0.8
    # fraction of a period each foot stands: 0.5 trots; above it every step begins and
    # ends with both feet down (a biped's double support)
    duty: float = 0.5
    sway_m: float = 0.0  # how far the body shifts sideways over the standing foot


@dataclass(frozen=True, kw_only=True)
class MountedItem:
    """A sensor (or effecter) entry: its type, name, pose and raw configuration keys.

    ``params`` keeps the keys as written (USARSim ini names or our own); the
    plugin's Config validates them when the robot is checked or spawned.
    """

    item_type: str
    name: str
    location: Vec3 = (0.0, 0.0, 0.0)
    orientation: Vec3 = (0.0, 0.0, 0.0)
    mount: str = "HARD"  # HARD (the chassis), a wheel or a link
    params: dict[str, Any]
    key_path: str = ""


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
    aerial: AerialLimits = field(default_factory=AerialLimits)
    status_joints: tuple[str, ...] = ()  # links whose angles STA reports (TeleMax flippers, protocol.md 6.2)
    nautical: NauticalSpec | None = None
    gait: Gait | None = None
    # how far above the surface below a start pose the robot's lowest point is set (the
    # per-robot Z of USARSim's start poses; manual section 5.3)
    spawn_clearance_m: float = 0.02
    # the body's colour (red, green, blue from 0 to 1) in camera pictures only: the Pioneers'
    # red aluminium by default
    color: tuple[float, float, float] = (0.75, 0.10, 0.10)
    extra: dict = field(default_factory=dict)

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
    def lowest_point_m(self) -> float:
        """How far below its origin the robot reaches when level (its wheels, balls, boxes
        and capsules on the chassis): where it stands on a floor (Z down, positive)."""
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
        if self.gait is not None:  # standing on its legs: hip, leg, foot (a ball or a sole)
            for leg in self.gait.legs:
                if leg.ankle_pitch is None:
                    knee = self.link(leg.knee)
                    foot = max((p.radius_m for p in knee.shapes if p.shape == "sphere"), default=0.0)
                else:
                    sole = self.link(leg.ankle_roll or leg.ankle_pitch)
                    foot = max((p.center[2] + p.size[2] / 2.0 for p in sole.shapes if p.shape == "box"), default=0.0)
                low.append(self.link_origin(leg.hip_pitch)[2] + self.gait.stand_height_m + foot)
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


def _shape(s: Section) -> ChassisBox:
    """One solid piece: ``{shape: box, center, size, mass_kg}``, ``{shape: sphere, center,
    radius, mass_kg}``, ``{shape: cylinder|capsule, center, radius, length, rotation, mass_kg}``."""
    d = FieldDefaults(ChassisBox)
    shape = s.str("shape", d.shape, choices=SHAPES)
    center = s.vec("center", 3, d.center)
    mass = s.float("mass_kg", min=0.001)
    rotation = s.vec("rotation", 3, d.rotation)
    friction = s.float("friction", d.friction, min=0.0, max=10.0)
    if shape == "box":
        return ChassisBox(
            center=center, size=s.vec("size", positive=True), mass_kg=mass, rotation=rotation, friction=friction
        )
    if shape == "sphere":
        return ChassisBox(
            shape=shape, center=center, radius_m=s.float("radius", min=0.001), mass_kg=mass, friction=friction
        )
    return ChassisBox(
        shape=shape,
        center=center,
        radius_m=s.float("radius", min=0.001),
        length_m=s.float("length", min=0.0),
        mass_kg=mass,
        rotation=rotation,
        friction=friction,
    )


def _aerial(a: Section) -> AerialLimits:
    d = FieldDefaults(AerialLimits)
    out = AerialLimits(
        max_linear_m_s=a.float("max_linear_m_s", d.max_linear_m_s, min=0.0, min_exclusive=True),
        max_lateral_m_s=a.float("max_lateral_m_s", d.max_lateral_m_s, min=0.0, min_exclusive=True),
        max_vertical_m_s=a.float("max_vertical_m_s", d.max_vertical_m_s, min=0.0, min_exclusive=True),
        max_yaw_rate_rad_s=a.float("max_yaw_rate_rad_s", d.max_yaw_rate_rad_s, min=0.0, min_exclusive=True),
        max_accel_m_s2=a.float("max_accel_m_s2", d.max_accel_m_s2, min=0.0, min_exclusive=True),
    )
    a.finish()
    return out


def _nautical(n: Section) -> NauticalSpec:
    d = FieldDefaults(NauticalSpec)
    out = NauticalSpec(
        volume_m3=n.float("volume_m3", min=0.0, min_exclusive=True),  # required in a file
        max_thrust_n=n.float("max_thrust_n", d.max_thrust_n, min=0.0, min_exclusive=True),
        max_rudder_rad=n.float("max_rudder_rad", d.max_rudder_rad, min=0.0, max=1.6),
        max_stern_plane_rad=n.float("max_stern_plane_rad", d.max_stern_plane_rad, min=0.0, max=1.6),
        rudder_gain=n.float("rudder_gain", d.rudder_gain, min=0.0),
        stern_plane_gain=n.float("stern_plane_gain", d.stern_plane_gain, min=0.0),
        drag_n_per_m_s=n.float("drag_n_per_m_s", d.drag_n_per_m_s, min=0.0),
        angular_drag=n.float("angular_drag", d.angular_drag, min=0.0),
    )
    n.finish()
    return out


def _gait(gs: Section) -> Gait:
    ld = FieldDefaults(Leg)
    legs = []
    for ls in gs.entries("legs", required=True):
        legs.append(
            Leg(
                hip_pitch=ls.str("hip_pitch"),
                hip_roll=ls.str("hip_roll"),
                knee=ls.str("knee"),
                upper_m=ls.float("upper_m", min=0.001),
                lower_m=ls.float("lower_m", min=0.001),
                phase=ls.float("phase", ld.phase, min=0.0, max=1.0),
                hip_yaw=ls.str("hip_yaw", ld.hip_yaw),
                ankle_pitch=ls.str("ankle_pitch", ld.ankle_pitch),
                ankle_roll=ls.str("ankle_roll", ld.ankle_roll),
                knee_forward=ls.bool("knee_forward", ld.knee_forward),
            )
        )
    d = FieldDefaults(Gait)
    out = Gait(
        legs=tuple(legs),
        stand_height_m=gs.float("stand_height_m", min=0.001),
        step_height_m=gs.float("step_height_m", d.step_height_m, min=0.0),
        period_s=gs.float("period_s", d.period_s, min=0.05),
        max_linear_m_s=gs.float("max_linear_m_s", d.max_linear_m_s, min=0.0, min_exclusive=True),
        max_lateral_m_s=gs.float("max_lateral_m_s", d.max_lateral_m_s, min=0.0, min_exclusive=True),
        max_yaw_rate_rad_s=gs.float("max_yaw_rate_rad_s", d.max_yaw_rate_rad_s, min=0.0, min_exclusive=True),
        duty=gs.float("duty", d.duty, min=0.5, max=0.95),
        sway_m=gs.float("sway_m", d.sway_m, min=0.0),
    )
    gs.finish()
    return out


def _geometry(g: Section) -> RobotGeometryConfig:
    """The ``geometry`` section; its wheel keys lack the ``_m`` of the fields they fill."""
    d = FieldDefaults(RobotGeometryConfig)
    out = RobotGeometryConfig(
        dimensions=g.vec("dimensions", positive=True),
        cog=g.vec("cog", 3, d.cog),
        wheel_radius_m=g.float("wheel_radius", d.wheel_radius_m, min=0.0),
        wheel_separation_m=g.float("wheel_separation", d.wheel_separation_m, min=0.0),
        wheel_base_m=g.float("wheel_base", d.wheel_base_m, min=0.0),
    )
    g.finish()
    return out


def _wheels(top: Section) -> list[Wheel]:
    d = FieldDefaults(Wheel)
    wheels: list[Wheel] = []
    for s in top.entries("wheels"):
        w = Wheel(
            name=s.str("name"),
            position=s.vec("position"),
            radius_m=s.float("radius_m", min=0.001),
            width_m=s.float("width_m", min=0.001),
            mass_kg=s.float("mass_kg", min=0.001),
            side=s.str("side", choices=("left", "right")),
            driven=s.bool("driven", d.driven),
            parent=s.str("parent", d.parent),
            steer=s.str("steer", d.steer, choices=STEER_GROUPS),
            number=s.int("number", d.number, min=-1),
        )
        if any(w.name == other.name for other in wheels):
            raise s.error("name", f"duplicate wheel name '{w.name}'")
        wheels.append(w)
    return wheels


def _links(top: Section, wnames: set[str]) -> list[Link]:
    """The ``links`` list, each after its parent; names unique among links and wheels."""
    d = FieldDefaults(Link)
    links: list[Link] = []
    lnames: set[str] = set()
    for s in top.entries("links"):
        lname = s.str("name")
        if any(c in lname for c in "{} \t/") or lname in lnames or lname in wnames or lname.lower() == "chassis":
            raise s.error("name", f"link names must be unique, without spaces, braces or '/', got {lname!r}")
        parent = s.str("parent", d.parent)
        if parent != "chassis" and parent not in lnames:
            raise s.error(
                "parent",
                f"unknown parent '{parent}' (links must come after their parent)"
                f"{did_you_mean(parent, ['chassis', *lnames])}",
            )
        axis = s.vec("axis", 3, d.axis)
        if sum(a * a for a in axis) < 1e-12:
            raise s.error("axis", "the joint axis must not be zero")
        shapes = tuple(_shape(sh) for sh in s.entries("shapes"))
        links.append(
            Link(
                name=lname,
                parent=parent,
                location=s.vec("location", 3, d.location),
                orientation=s.vec("orientation", 3, d.orientation),
                joint=s.str("joint", d.joint, choices=JOINT_TYPES),
                axis=axis,
                min_range=s.float("min_range", d.min_range),
                max_range=s.float("max_range", d.max_range),
                max_speed=s.float("max_speed", min=0.0, min_exclusive=True),
                max_torque=s.float("max_torque", min=0.0, min_exclusive=True),
                shapes=shapes,
                armature=s.float("armature", d.armature, min=0.0),
                collide=s.bool("collide", d.collide),
                geo_orientation=s.vec("geo_orientation", 3, d.geo_orientation),
            )
        )
        lnames.add(lname)
    return links


def _items(top: Section, mounts: list[str]) -> list[MountedItem]:
    """The ``sensors`` list (sensors and effecters); keys other than the pose stay raw in
    ``params`` for the plugin's Config to check."""
    d = FieldDefaults(MountedItem)
    items: list[MountedItem] = []
    inames: set[tuple[str, str]] = set()
    for i, raw in enumerate(top.list("sensors", [])):
        key = f"sensors[{i}]"
        s = Section(raw, path=top.path, key=key)
        itype = s.str("type")
        iname = s.str("name")
        if any(c in iname for c in "{} \t"):
            raise s.error("name", f"an item name may not contain spaces or braces, got {iname!r}")
        if (itype.lower(), iname.lower()) in inames:
            raise s.error("name", f"duplicate {itype} name '{iname}'")
        inames.add((itype.lower(), iname.lower()))
        loc = s.vec("location", 3, d.location)
        ori = s.vec("orientation", 3, d.orientation)
        mount = s.str("mount", d.mount)
        if mount != "HARD" and mount not in mounts:
            raise s.error("mount", f"unknown mount '{mount}'{did_you_mean(mount, ['HARD', *mounts])}")
        params = {k: v for k, v in s.data.items() if k not in ("type", "name", "location", "orientation", "mount")}
        items.append(
            MountedItem(
                item_type=itype, name=iname, location=loc, orientation=ori, mount=mount, params=params, key_path=key
            )
        )
    return items


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
    aerial = _aerial(top.section("aerial", {}))
    nautical = d.nautical
    if drive == "nautical" or top.has("nautical"):
        if drive != "nautical":
            raise top.error("nautical", "only a vessel (drive: nautical) has nautical settings")
        nautical = _nautical(top.section("nautical"))
    gait = d.gait
    if drive == "legged" or top.has("gait"):
        if drive != "legged":
            raise top.error("gait", "only a walking robot (drive: legged) has a gait")
        gait = _gait(top.section("gait"))
    if top.has("aerial") and drive != "aerial":
        raise top.error("aerial", "only an aerial robot (drive: aerial) has aerial limits")

    geometry = _geometry(top.section("geometry"))

    chassis = [_shape(s) for s in top.entries("chassis", required=True)]
    if not chassis:
        raise top.error("chassis", "a robot needs at least one chassis box")

    wheels = _wheels(top)
    wnames = {w.name for w in wheels}

    links = _links(top, wnames)
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
    if gait is not None:
        two_legs_apart = len(gait.legs) == 2 and abs(abs(gait.legs[0].phase - gait.legs[1].phase) - 0.5) <= 1e-6
        if gait.sway_m > 0.0 and not two_legs_apart:
            raise top.error("gait.sway_m", "only a biped sways: two legs half a period apart (phase 0 and 0.5)")
        for leg in gait.legs:
            for j in leg.joints:
                if j not in lnames:
                    raise top.error("gait", f"unknown leg joint '{j}'{did_you_mean(j, lnames)}")
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

    items = _items(top, [*wnames, *lnames])
    top.finish()

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
        aerial=aerial,
        status_joints=status_joints,
        nautical=nautical,
        gait=gait,
        color=tuple(float(c) for c in color),
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
