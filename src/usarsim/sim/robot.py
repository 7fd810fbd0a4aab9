"""A robot in the simulation: what every robot has, whatever its drive (the drive's own
state lives in its drive model, :mod:`usarsim.robots`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from usarsim.config.robot import RobotConfig
from usarsim.sim.outputs import ItemDescription
from usarsim.sim.plugins import PluginSet, builtin_plugins
from usarsim.sim.view import RobotHandle

if TYPE_CHECKING:
    from usarsim.robots.base import DriveModel
    from usarsim.sensors.base import Item
    from usarsim.sim.reports import Report


@dataclass(eq=False)
class SimRobot:
    """A robot spawned in the world: its connection's id, name and robot class, its bodies in the model, its mounted
    items and drive model, and what every robot has whatever its drive: headlight, battery, joint orders, viewports
    and self-righting."""

    uid: int
    name: str
    config: RobotConfig
    prefix: str
    spawn_time: float
    handle: RobotHandle
    sensors: list[Item]  # every mounted item: sensors, effecters, cameras
    drive: DriveModel
    reports: list[Report] = field(default_factory=list)
    light: bool = False
    battery_empty: bool = False
    removed: bool = False
    resets: int = 0
    owner_index: int = 0
    spawn_qpos: np.ndarray | None = None
    # link joints: name -> (order, value) with order 0 position, 1 speed, 2 torque
    joints: dict = field(default_factory=dict)
    # the cameras chosen by SET {Type Viewports} (protocol.md 5.4): the first is the one the
    # MultiView shows; empty: the robot's first camera
    viewports: tuple[str, ...] = ()
    in_water: bool = False
    rated_power_w: float = 1.0
    flip_until: float = -1.0  # self-righting torque applied until this simulated time
    # the seconds of battery used: a place in an array of every robot's (usarsim.sim.battery)
    _battery: np.ndarray = field(default_factory=lambda: np.zeros(1), repr=False)
    _battery_at: int = 0

    @property
    def battery_used_s(self) -> float:
        return float(self._battery[self._battery_at])

    @battery_used_s.setter
    def battery_used_s(self, seconds: float) -> None:
        self._battery[self._battery_at] = seconds

    def bind_battery(self, used: np.ndarray, at: int) -> None:
        """Keep the seconds of battery used at ``used[at]`` from now on."""
        self._battery, self._battery_at = used, at

    def battery_left(self, used: np.ndarray | None = None) -> float:
        """Seconds of battery left now; from ``used``, a copy of the array the robot's
        battery is kept in taken at an instant (:meth:`Batteries.used_now`), then."""
        spent = self.battery_used_s if used is None else float(used[self._battery_at])
        return max(0.0, self.config.battery_s - spent)


def describe_items(robot: RobotConfig, seed: int = 0, plugins: PluginSet | None = None) -> list[ItemDescription]:
    """The mounted items of a robot class (sensors, effecters, cameras) as GETGEO/GETCONF
    describe them, CONF fields typed (also validates every item's configuration);
    ``plugins``: the items to make them from (the built-in ones by default)."""
    make_item = (plugins or builtin_plugins()).make_item
    return [make_item(item, robot, seed, "describe").describe() for item in robot.items]
