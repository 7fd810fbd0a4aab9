"""Vessels (protocol.md 5.3e): the Submarine.  The water system
(:mod:`usarsim.sim.systems.water`) carries them (buoyancy, drag, righting); their drive is
the propeller, the rudder and the stern planes."""

from __future__ import annotations

import math

import numpy as np

from usarsim.config.robot import NauticalSpec, RobotConfig
from usarsim.controls import NauticalDrive
from usarsim.errors import ConfigError
from usarsim.robots.base import DRIVES, DriveModel, clamp

DOWN = np.array([0.0, 0.0, -1.0])  # MuJoCo: a clockwise turn seen from above is about -z


@DRIVES.register("nautical")
class Nautical(DriveModel[NauticalDrive]):
    """``DRIVE {Propeller} {Rudder} {SternPlane}``: the propeller as a fraction of full thrust,
    -1..1 (percent when Normalized); rudder and stern planes in radians (positive: turn
    right, rise), within the vessel's limits.  Unsent values are kept."""

    ACCEPTS = frozenset({NauticalDrive})
    SET_DOWN_AT_START = False  # a vessel starts where the pose is: in water

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        assert robot.nautical is not None  # make_drive checks the robot (check()) before building its drive
        self.spec: NauticalSpec = robot.nautical
        self.sail = {"propeller": 0.0, "rudder": 0.0, "stern_plane": 0.0}

    @classmethod
    def check(cls, robot: RobotConfig) -> None:
        if robot.nautical is None:
            raise ConfigError("a vessel (drive: nautical) needs its nautical settings", path=robot.path, key="nautical")

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
