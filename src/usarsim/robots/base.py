"""Drive models: how a kind of robot moves (design.md 4.8).

A robot file names its drive (``drive: skid``); the drive model of that name accepts the
parts of a DRIVE its kind understands (:mod:`usarsim.controls`), keeps the state they set,
writes its controls into MuJoCo before the physics steps, and reports its STA steering
angles.  Everything that is the same for every robot (the headlight, joint servos,
batteries, self-righting) lives in the simulation, not here.

Adding a kind of drive is one module that subclasses :class:`DriveModel` and registers it
with ``@DRIVES.register("name")``, plus robot files that say ``drive: name``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Generic, TypeVar, cast

from usarsim.config.reader import Section, did_you_mean
from usarsim.config.robot import RobotConfig, Wheel
from usarsim.controls import DrivePart
from usarsim.errors import ConfigError, PluginNotFoundError
from usarsim.registry import Registry
from usarsim.sim.outputs import RobotNumbers, VelocityLimits

if TYPE_CHECKING:
    import mujoco
    import numpy as np

    from usarsim.sim.context import WorldContext
    from usarsim.sim.robot import SimRobot
    from usarsim.sim.view import RobotHandle

DRIVES = Registry("drive")


@dataclass(frozen=True)
class Treads:
    """How a robot's wheels meet the floor when it turns by skidding them sideways (tracks
    and the tyres of skid-steered robots): the tread's friction across its rolling direction
    as a fraction of the friction along it, the drivetrain's inertia reflected to the
    wheel's rim, as a mass (kg: a wheel's rotor inertia is this times its radius squared),
    and how the tread's contact with the floor gives (MuJoCo's solref: time constant in
    seconds and damping ratio; MuJoCo's default is 0.02 s, critically damped)."""

    lateral_ratio: float
    drive_inertia_kg: float
    solref: tuple[float, float] = (0.02, 1.0)


P = TypeVar("P", bound=DrivePart)  # the kind of DRIVE part a drive applies
S = TypeVar("S")  # a kind's settings (its own section of the robot file); None for a kind without


class DriveModel(Generic[P, S]):
    """One robot's drive: its kind's commands, state and controls.

    Class attributes say what the simulation must do for the kind: ``ACCEPTS`` the kinds
    of DRIVE part it applies (the others are ignored), ``GRAVITY_COMPENSATED`` (links
    float: aerial robots), ``SET_DOWN_AT_START`` (put on the surface below a start pose;
    a vessel starts where the pose is), ``SET_DOWN_ALWAYS`` (wherever it is put: a
    walking robot would not survive a drop).  What a kind needs done between physics steps
    is a world system registered beside it (an aerial robot's levelling, a walking robot's
    gait: :mod:`usarsim.sim.systems`).

    A kind with settings of its own declares them in its module, as a sensor declares its
    Config: their type as the second type argument (``DriveModel[Velocities, AerialLimits]``),
    the robot file's section that holds them (``SETTINGS = "aerial"``; ``SETTINGS_REQUIRED``
    when a robot of the kind cannot do without), and :meth:`read_settings`, which reads that
    section with the loader every robot file is read by (:class:`usarsim.config.reader.Section`).
    ``self.settings`` holds them.
    """

    TYPE: ClassVar[str] = ""  # the robot file's drive key (set by DRIVES.register)
    ACCEPTS: ClassVar[frozenset[type]] = frozenset()
    GRAVITY_COMPENSATED: ClassVar[bool] = False
    SET_DOWN_AT_START: ClassVar[bool] = True
    SET_DOWN_ALWAYS: ClassVar[bool] = False
    SETTINGS: ClassVar[str] = ""  # the robot file's section of this kind's settings ("": it has none)
    SETTINGS_REQUIRED: ClassVar[bool] = False
    settings: S

    def __init__(self, robot: RobotConfig) -> None:
        self.robot = robot
        self.settings = self.settings_of(robot)
        # driven wheels whose speed a joint order (or a holonomic DRIVE) set, rad/s: they
        # keep it until the kind's own wheel command takes them back
        self.wheel_speed: dict[str, float] = {}

    # The robot file and the model ---------------------------------------------------------
    @classmethod
    def read_settings(cls, section: Section, robot: RobotConfig) -> S:
        """This kind's settings from its section of ``robot``'s file (an empty section when
        the file has none); ConfigError naming the key when a value is wrong."""
        section.finish()
        return cast(S, None)  # a kind without settings of its own

    @classmethod
    def settings_of(cls, robot: RobotConfig) -> S:
        """This kind's settings as ``robot``'s file gives them (defaults where it is silent)."""
        raw = robot.drive_sections.get(cls.SETTINGS, {}) if cls.SETTINGS else {}
        return cls.read_settings(Section(raw, path=robot.path, key=cls.SETTINGS), robot)

    @classmethod
    def check_sections(cls, robot: RobotConfig) -> None:
        """The drive's sections of the robot file: only this kind's own (a section of another
        kind, or one no kind has, is a mistake), there when required, and right."""
        kinds = {name: cast("type[DriveModel[Any, Any]]", DRIVES.get(name)) for name in DRIVES.names()}
        owners = {k.SETTINGS: name for name, k in kinds.items() if k.SETTINGS}
        for key in robot.drive_sections:
            if key == cls.SETTINGS:
                continue
            if key in owners:
                msg = f"the '{key}' section is for robots of drive: {owners[key]}; this robot's drive is {cls.TYPE}"
            else:  # no key of a robot file, nor any drive's section
                msg = f"unknown section '{key}'{did_you_mean(key, owners)}"
            raise ConfigError(msg, path=robot.path, key=key)
        if cls.SETTINGS_REQUIRED and cls.SETTINGS not in robot.drive_sections:
            raise ConfigError(
                f"a robot of drive: {cls.TYPE} needs its '{cls.SETTINGS}' section", path=robot.path, key=cls.SETTINGS
            )
        cls.settings_of(robot)

    @classmethod
    def check(cls, robot: RobotConfig) -> None:
        """Raise ConfigError when the robot file lacks what this kind needs."""

    @classmethod
    def lowest_point_m(cls, robot: RobotConfig) -> float:
        """How far below its origin the robot reaches when level: where it stands on a floor
        (Z down, positive).  Its body's lowest point, unless the kind stands on something
        else (a walking robot on its legs)."""
        return robot.body_lowest_point_m

    @classmethod
    def velocity_limits(cls, robot: RobotConfig) -> VelocityLimits | None:
        """The velocities a DRIVE of velocities may ask of the robot (the console scales its
        stick by them); None for a kind not driven by velocities."""
        return None

    @classmethod
    def build(cls, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, robot: RobotConfig, prefix: str) -> None:
        """Add what the kind needs to the robot's chassis body in the model (rotors)."""

    @classmethod
    def treads(cls, robot: RobotConfig) -> Treads | None:
        """The treads of a robot that skids its wheels sideways to turn (the model builder
        gives its wheels direction-dependent friction on the floor); None for the others."""
        return None

    def resolve(self, model: mujoco.MjModel, handle: RobotHandle) -> None:
        """Look the kind's own MuJoCo ids up by name, after every model build."""

    def own_actuators(self) -> list[tuple[int, float]]:
        """Actuators of the kind's own beyond wheels and links, with the mechanical power
        (W) each contributes to the robot's rating (the battery drains faster under load)."""
        return []

    # Commands and controls ------------------------------------------------------------------
    def command(self, part: P, normalized: bool) -> None:
        """Apply one part of a DRIVE (only kinds in ``ACCEPTS`` are given)."""

    def wheel_target(self, w: Wheel) -> float:
        """The spin speed (rad/s) of a driven wheel no joint order has taken."""
        return 0.0

    def ordered_speed(self, w: Wheel) -> float | None:
        """The spin speed (rad/s) a joint order gave a driven wheel, or None."""
        return self.wheel_speed.get(w.name)

    def steer_target(self, w: Wheel) -> float:
        """The angle (rad, positive right) of a steered wheel."""
        return 0.0

    def apply_own(self, ctrl: np.ndarray, powered: bool) -> None:
        """Write the kind's own controls (not wheels)."""

    def apply(self, r: SimRobot, ctrl: np.ndarray) -> None:
        """Write every control of the drive: its own, each steered wheel's angle, each
        driven wheel's speed (a joint order's, else the kind's; 0 without power)."""
        powered = not r.battery_empty
        self.apply_own(ctrl, powered)
        handle = r.handle
        for w in self.robot.wheels:
            if w.steer != "none":
                ctrl[handle.steer_actuator[w.name]] = self.steer_target(w)
            if not w.driven:
                continue
            a = handle.actuator[w.name]
            ordered = self.ordered_speed(w) if powered else None
            if not powered:
                ctrl[a] = 0.0
            elif ordered is not None:
                ctrl[a] = ordered
            else:
                ctrl[a] = self.wheel_target(w)

    def on_battery_empty(self) -> None:
        """The battery ran out: the wheels stop (the controls are written after this)."""
        self.wheel_speed.clear()

    # What it reports --------------------------------------------------------------------------
    @classmethod
    def numbers(cls, robot: RobotConfig) -> RobotNumbers:
        """GEO and CONF of the robot (protocol.md 6.7, 6.8): its file's figures (a kind may
        report others, or leave the wheel keys out with None)."""
        g = robot.geometry
        return RobotNumbers(
            vehicle_type=robot.vehicle_type,
            class_name=robot.class_name,
            steering_type=robot.steering_type,
            mass_kg=robot.mass_kg,
            max_speed=robot.max_speed_rad_s,
            max_torque=robot.max_torque_nm,
            max_front_steer=robot.max_front_steer_rad,
            max_rear_steer=robot.max_rear_steer_rad,
            dimensions=g.dimensions,
            cog=g.cog,
            wheel_radius=g.wheel_radius_m,
            wheel_separation=g.wheel_separation_m,
            wheel_base=g.wheel_base_m,
        )

    def steer_angles(self, data: mujoco.MjData, handle: RobotHandle) -> tuple[float, float]:
        """STA ``FrontSteer`` and ``RearSteer``: the axles' current angles (rad)."""
        return 0.0, 0.0

    # Hooks of the simulation --------------------------------------------------------------------
    def on_spawn(self, sim: WorldContext, r: SimRobot) -> None:
        """Right after the robot was built into the world."""


def drive_class(robot: RobotConfig) -> type[DriveModel[Any, Any]]:
    """The drive model class a robot file names (ConfigError naming the file when unknown)."""
    try:
        return DRIVES.get(robot.drive)
    except PluginNotFoundError as exc:
        raise ConfigError(str(exc), path=robot.path, key="drive") from None


def make_drive(robot: RobotConfig) -> DriveModel[Any, Any]:
    """A new drive model for one robot (its file checked for what the kind needs)."""
    cls = drive_class(robot)
    cls.check_sections(robot)
    cls.check(robot)
    return cls(robot)


def clamp(value: float, top: float) -> float:
    """``value`` within [-top, top]."""
    return max(-top, min(top, value))
