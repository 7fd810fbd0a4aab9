"""Aerial robots (protocol.md 5.3d): the AirRobot, helicopters, airships.

They hover: gravity is compensated on their bodies, and velocity servos on a site at the
chassis origin push along and turn about its axes (forward, left, up in MuJoCo's frame)
with up to ``max_accel_m_s2`` x mass; roll and pitch are damped, and their own world system,
:class:`Levelling`, keeps them upright.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.config.reader import FieldDefaults, Section
from usarsim.config.robot import RobotConfig
from usarsim.controls import Velocities
from usarsim.robots.base import DRIVES, DriveModel, clamp
from usarsim.sim.constants import LEVEL_STIFFNESS, UP
from usarsim.sim.outputs import VelocityLimits
from usarsim.sim.systems.base import SYSTEMS, System
from usarsim.sim.view import RobotHandle

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext

AERIAL_AXES = ("linear", "lateral", "vertical", "roll", "pitch", "yaw")


@dataclass(frozen=True, kw_only=True)
class AerialLimits:
    """Speed limits of an aerial robot (protocol.md 5.3d; UDK AirRobot: 2 m/s linear, lateral
    and vertical, 100 degrees/s of yaw) and how hard its rotors can push: the robot file's
    ``aerial`` section."""

    max_linear_m_s: float = 2.0
    max_lateral_m_s: float = 2.0
    max_vertical_m_s: float = 2.0
    max_yaw_rate_rad_s: float = 1.7453
    max_accel_m_s2: float = 4.0


@DRIVES.register("aerial")
class Aerial(DriveModel[Velocities, AerialLimits]):
    """``DRIVE {AltitudeVelocity} {LinearVelocity} {LateralVelocity} {RotationalVelocity}``:
    m/s up, forward, right and rad/s clockwise; unsent ones keep their value; limited to
    the robot's maxima (percentages of them when Normalized); all zero: hover."""

    ACCEPTS = frozenset({Velocities})
    GRAVITY_COMPENSATED = True
    SETTINGS = "aerial"

    @classmethod
    def read_settings(cls, section: Section, robot: RobotConfig) -> AerialLimits:
        d = FieldDefaults(AerialLimits)
        out = AerialLimits(
            **{
                name: section.float(name, getattr(d, name), min=0.0, min_exclusive=True)
                for name in ("max_linear_m_s", "max_lateral_m_s", "max_vertical_m_s", "max_yaw_rate_rad_s")
            },
            max_accel_m_s2=section.float("max_accel_m_s2", d.max_accel_m_s2, min=0.0, min_exclusive=True),
        )
        section.finish()
        return out

    @classmethod
    def velocity_limits(cls, robot: RobotConfig) -> VelocityLimits:
        lim = cls.settings_of(robot)
        return VelocityLimits(lim.max_linear_m_s, lim.max_lateral_m_s, lim.max_vertical_m_s, lim.max_yaw_rate_rad_s)

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        self.fly = {"altitude": 0.0, "linear": 0.0, "lateral": 0.0, "rotational": 0.0}
        self.rotor: dict[str, int] = {}  # actuator per axis

    @classmethod
    def build(cls, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, robot: RobotConfig, prefix: str) -> None:
        chassis.gravcomp = 1.0
        site = chassis.add_site()
        site.name = f"{prefix}/rotors"
        lim = cls.settings_of(robot)
        force = lim.max_accel_m_s2 * robot.mass_kg
        dims = robot.geometry.dimensions
        inertia = robot.mass_kg * (dims[0] ** 2 + dims[1] ** 2) / 12.0
        for i, axis in enumerate(AERIAL_AXES):
            a = spec.add_actuator()
            a.name = f"{prefix}/{axis}"
            a.target = f"{prefix}/rotors"
            a.trntype = mujoco.mjtTrn.mjTRN_SITE
            gear = [0.0] * 6
            gear[i] = 1.0
            a.gear = gear
            limit = force if i < 3 else 4.0 * inertia * lim.max_yaw_rate_rad_s / 0.25
            kv = limit / (0.25 * (lim.max_linear_m_s if i < 3 else lim.max_yaw_rate_rad_s))
            a.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            a.biastype = mujoco.mjtBias.mjBIAS_AFFINE
            a.gainprm[0] = kv
            a.biasprm[0], a.biasprm[1], a.biasprm[2] = 0.0, 0.0, -kv
            a.forcelimited = 1
            a.forcerange = [-limit, limit]

    def resolve(self, model: mujoco.MjModel, handle: RobotHandle) -> None:
        self.rotor = {axis: model.actuator(f"{handle.prefix}/{axis}").id for axis in AERIAL_AXES}

    def own_actuators(self) -> list[tuple[int, float]]:
        lim, mass = self.settings, self.robot.mass_kg
        return [
            (a, lim.max_accel_m_s2 * mass * lim.max_linear_m_s if axis in ("linear", "lateral", "vertical") else 0.0)
            for axis, a in self.rotor.items()
        ]

    def command(self, part: Velocities, normalized: bool) -> None:
        lim = self.settings
        for key, value, top in (
            ("altitude", part.altitude, lim.max_vertical_m_s),
            ("linear", part.linear, lim.max_linear_m_s),
            ("lateral", part.lateral, lim.max_lateral_m_s),
            ("rotational", part.rotational, lim.max_yaw_rate_rad_s),
        ):
            if value is not None and math.isfinite(value):
                self.fly[key] = clamp(value * top / 100.0 if normalized else value, top)

    def apply_own(self, ctrl: np.ndarray, powered: bool) -> None:
        f = self.fly if powered else dict.fromkeys(self.fly, 0.0)
        rot = self.rotor
        # MuJoCo's site axes: x forward, y left, z up; USARSim's lateral is to the right and
        # its yaw clockwise seen from above
        ctrl[rot["linear"]] = f["linear"]
        ctrl[rot["lateral"]] = -f["lateral"]
        ctrl[rot["vertical"]] = f["altitude"]
        ctrl[rot["yaw"]] = -f["rotational"]
        ctrl[rot["roll"]] = ctrl[rot["pitch"]] = 0.0


@SYSTEMS.register("levelling")
class Levelling(System):
    """Aerial robots keep level: a restoring torque towards upright, before each stretch of
    physics steps (their roll and pitch rates are damped by their servos)."""

    ORDER = 30

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return any(isinstance(r.drive, Aerial) for r in sim.robots.values())

    def pre_step(self) -> None:
        d = self.sim.data
        for r in self.sim.robots.values():
            if not isinstance(r.drive, Aerial):
                continue
            b = r.handle.body_id
            up = d.xmat[b].reshape(3, 3)[:, 2]
            d.xfrc_applied[b, 3:] = np.cross(up, UP) * (LEVEL_STIFFNESS * r.config.mass_kg)
