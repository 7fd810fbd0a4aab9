"""Batteries (protocol.md 6.2, 7.12): a robot's battery lasts ``battery_s`` seconds at
rest and runs down faster under load; at zero the robot stops and reports STA only."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

if TYPE_CHECKING:
    from usarsim.sim.robot import SimRobot

# At the rated mechanical power of all its motors a battery drains this much faster than
# at rest (one extra second per second): our model of UT2004's faster drain under load.
BATTERY_LOAD_FACTOR = 1.0
# From this many robots on, the batteries are drained as one array; fewer cost less one by one
# (a numpy call costs more than a robot's few float operations).
VECTOR_MIN_ROBOTS = 16


class Batteries:
    """Which robot each actuator belongs to, each robot's rated power, and the drain.

    The seconds of battery every robot has used are one array, drained for all robots at
    once (a robot's ``battery_used_s`` reads and writes its place in it): with hundreds of
    robots a loop over them after every stretch of physics steps cost more than the rest of
    the stretch's bookkeeping together."""

    def __init__(self) -> None:
        self._owner: np.ndarray | None = None
        self._count = 1
        self._robots: list[SimRobot] = []
        self._used = np.zeros(0)  # seconds used, per robot in index order
        self._capacity = np.zeros(0)  # battery_s, per robot
        self._rated = np.zeros(0)  # rated mechanical power (W), per robot

    def index(self, m: mujoco.MjModel, robots: list[SimRobot]) -> None:
        """After a model build: the owner of every actuator, and each robot's rated
        mechanical power (every motor at its top speed and torque)."""
        owners = np.zeros(m.nu, dtype=np.intp)
        for i, r in enumerate(robots, start=1):
            r.owner_index = i
            rated = 0.0
            for name, a in r.handle.actuator.items():
                owners[a] = i
                ln = r.config.link(name)
                if ln is not None:
                    rated += ln.max_torque * ln.max_speed
                else:
                    rated += r.config.wheel_torque_limit_nm * r.config.max_speed_rad_s
            for a, watts in r.drive.own_actuators():
                owners[a] = i
                rated += watts
            r.rated_power_w = max(rated, 1e-6)
        self._owner = owners
        self._count = len(robots) + 1
        used = np.array([r.battery_used_s for r in robots], dtype=float)
        for i, r in enumerate(robots):
            r.bind_battery(used, i)
        self._robots = list(robots)
        self._used = used
        self._capacity = np.array([r.config.battery_s for r in robots], dtype=float)
        self._rated = np.array([r.rated_power_w for r in robots], dtype=float)

    def drain(self, m: mujoco.MjModel, d: mujoco.MjData, robots: list[SimRobot], seconds: float) -> list[SimRobot]:
        """Drain every battery by ``seconds`` of use: one second per second at rest, up to
        twice as fast at the rated mechanical power of all the robot's motors (the battery
        ran down "faster under load" in UT2004, protocol.md 6.2).  Returns the robots whose
        battery has just run out."""
        if not robots:
            return []
        known = self._robots
        if len(robots) != len(known) or robots[0] is not known[0] or robots[-1] is not known[-1]:
            return self._drain_each(robots, None, seconds)  # not indexed for these robots (a rebuild indexes them)
        power = None
        if seconds > 0:
            owners = self._owner
            if owners is not None and len(owners) == m.nu and m.nu:
                power = np.bincount(owners, weights=np.abs(d.actuator_force * d.actuator_velocity),
                                    minlength=self._count)
        if len(robots) < VECTOR_MIN_ROBOTS:
            return self._drain_each(robots, power, seconds)
        used = self._used
        if seconds > 0:
            load = np.minimum(power[1:] / self._rated, 1.0) if power is not None else np.zeros(len(robots))
            # element by element the very operations of _drain_each, so the same numbers
            used += seconds * (1.0 + load * BATTERY_LOAD_FACTOR)
        empty = np.flatnonzero(~(self._capacity - used > 0.0))  # battery_left() <= 0 (NaN too)
        out = []
        for i in empty.tolist():
            r = robots[i]
            if not r.battery_empty:
                r.battery_empty = True
                out.append(r)
        return out

    @staticmethod
    def _drain_each(robots: list[SimRobot], power: np.ndarray | None, seconds: float) -> list[SimRobot]:
        """:meth:`drain` one robot at a time (a few robots, or robots not indexed together:
        ``power`` None, drained as at rest)."""
        if seconds > 0:
            for r in robots:
                load = float(power[r.owner_index]) / r.rated_power_w if power is not None else 0.0
                r.battery_used_s += seconds * (1.0 + min(load, 1.0) * BATTERY_LOAD_FACTOR)
        out = []
        for r in robots:
            if not r.battery_empty and r.battery_left() <= 0.0:
                r.battery_empty = True
                out.append(r)
        return out
