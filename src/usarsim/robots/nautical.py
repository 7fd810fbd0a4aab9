"""Vessels (protocol.md 5.3e): the Submarine.  The water system
(:mod:`usarsim.sim.systems.water`) carries them (buoyancy, drag, righting); their drive is
the propeller, the rudder and the stern planes."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usarsim.config.reader import FieldDefaults, Section
from usarsim.config.robot import RobotConfig
from usarsim.controls import NauticalDrive
from usarsim.robots.base import DRIVES, DriveModel, clamp

DOWN = np.array([0.0, 0.0, -1.0])  # MuJoCo: a clockwise turn seen from above is about -z


@dataclass(frozen=True, kw_only=True)
class NauticalSpec:
    """A vessel (protocol.md 5.3e): its displaced volume (buoyancy), its propeller's thrust,
    and how its rudder and stern planes turn it: the robot file's ``nautical`` section."""

    volume_m3: float = 0.0
    max_thrust_n: float = 50.0
    max_rudder_rad: float = 0.5
    max_stern_plane_rad: float = 0.5
    rudder_gain: float = 20.0  # N m of yaw torque per rad of rudder per m/s of speed
    stern_plane_gain: float = 20.0  # N m of pitch torque per rad of plane per m/s
    drag_n_per_m_s: float = 40.0  # linear drag in water
    angular_drag: float = 20.0  # N m per rad/s


@DRIVES.register("nautical")
class Nautical(DriveModel[NauticalDrive, NauticalSpec]):
    """``DRIVE {Propeller} {Rudder} {SternPlane}``: the propeller as a fraction of full thrust,
    -1..1 (percent when Normalized); rudder and stern planes in radians (positive: turn
    right, rise), within the vessel's limits.  Unsent values are kept."""

    ACCEPTS = frozenset({NauticalDrive})
    SET_DOWN_AT_START = False  # a vessel starts where the pose is: in water
    SETTINGS = "nautical"
    SETTINGS_REQUIRED = True

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        self.spec: NauticalSpec = self.settings
        self.sail = {"propeller": 0.0, "rudder": 0.0, "stern_plane": 0.0}

    @classmethod
    def read_settings(cls, section: Section, robot: RobotConfig) -> NauticalSpec:
        n, d = section, FieldDefaults(NauticalSpec)
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

    @property
    def vessel(self) -> NauticalSpec:
        """The hull (buoyancy, drag) the water carries (:class:`usarsim.sim.context.Vessel`)."""
        return self.spec

    def command(self, part: NauticalDrive, normalized: bool) -> None:
        n = self.spec
        for key, value, top, scale in (
            ("propeller", part.propeller, 1.0, 0.01),
            ("rudder", part.rudder, n.max_rudder_rad, n.max_rudder_rad / 100.0),
            ("stern_plane", part.stern_plane, n.max_stern_plane_rad, n.max_stern_plane_rad / 100.0),
        ):
            if value is not None and math.isfinite(value):
                self.sail[key] = clamp(value * scale if normalized else value, top)

    def propulsion(
        self, rot: np.ndarray, lin: np.ndarray, frac: float
    ) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """The propeller's thrust along the hull, and the torques of the rudder (turn right:
        clockwise seen from above) and the stern planes (rise: nose up, about the body's
        right axis, -y as +y is its left), which grow with the speed through the water."""
        n = self.spec
        forward = rot[:, 0]
        speed = float(forward @ lin)
        thrust = forward * (self.sail["propeller"] * n.max_thrust_n * frac)
        return thrust, (
            DOWN * (n.rudder_gain * self.sail["rudder"] * speed),
            rot[:, 1] * (-n.stern_plane_gain * self.sail["stern_plane"] * speed),
        )
