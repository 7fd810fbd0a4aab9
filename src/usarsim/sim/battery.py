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


class Batteries:
    """Which robot each actuator belongs to, each robot's rated power, and the drain."""

    def __init__(self) -> None:
        self._owner: np.ndarray | None = None
        self._count = 1

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

    def drain(self, m: mujoco.MjModel, d: mujoco.MjData, robots: list[SimRobot], seconds: float) -> list[SimRobot]:
        """Drain every battery by ``seconds`` of use: one second per second at rest, up to
        twice as fast at the rated mechanical power of all the robot's motors (the battery
        ran down "faster under load" in UT2004, protocol.md 6.2).  Returns the robots whose
        battery has just run out."""
        if seconds > 0 and robots:
            owners = self._owner
            if owners is not None and len(owners) == m.nu and m.nu:
                power = np.bincount(owners, weights=np.abs(d.actuator_force * d.actuator_velocity),
                                    minlength=self._count)
            else:
                power = None
            for r in robots:
                load = float(power[r.owner_index]) / r.rated_power_w if power is not None else 0.0
                r.battery_used_s += seconds * (1.0 + min(load, 1.0) * BATTERY_LOAD_FACTOR)
        out = []
        for r in robots:
            if not r.battery_empty and r.battery_left() <= 0.0:
                r.battery_empty = True
                out.append(r)
        return out
