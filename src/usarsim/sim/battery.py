"""Batteries (protocol.md 6.2, 7.12): a robot's battery lasts ``battery_s`` seconds at
rest and runs down faster under load; at zero the robot stops and reports STA only."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numba import njit

if TYPE_CHECKING:
    from usarsim.sim.robot import SimRobot

# At the rated mechanical power of all its motors a battery drains this much faster than
# at rest (one extra second per second): our model of UT2004's faster drain under load.
BATTERY_LOAD_FACTOR = 1.0


@njit(cache=True)
def _drain_all(
    owners: np.ndarray,
    force: np.ndarray,
    velocity: np.ndarray,
    rated: np.ndarray,
    capacity: np.ndarray,
    used: np.ndarray,
    seconds: float,
    factor: float,
) -> int:
    """Drain every robot's battery (``used``, in place) by ``seconds`` of use at the load of
    its actuators now (``owners[a]``: the robot of actuator ``a``, counted from 1; 0: none);
    returns how many batteries are out (``capacity - used`` not above 0, NaN too).

    One compiled call that keeps the interpreter lock: the numpy calls it replaces each let
    the lock go on arrays of a thousand actuators, and with hundreds of robots the
    simulation thread then waited for it after every stretch of physics steps.  The
    operations are those numpy did, element by element and in the same order, so the numbers
    are the same to the bit."""
    power = np.zeros(rated.size + 1)
    for a in range(owners.size):
        power[owners[a]] += abs(force[a] * velocity[a])
    out = 0
    for i in range(used.size):
        if seconds > 0.0:
            load = power[i + 1] / rated[i]
            if load > 1.0:  # min(load, 1.0), NaN kept
                load = 1.0
            used[i] += seconds * (1.0 + load * factor)
        if not capacity[i] - used[i] > 0.0:
            out += 1
    return out


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

    def used_now(self) -> np.ndarray:
        """A copy of the seconds every robot has used, by a robot's place (its battery as
        it is now, for :meth:`usarsim.sim.robot.SimRobot.battery_left`)."""
        return self._used.copy()

    def drain(self, m: mujoco.MjModel, d: mujoco.MjData, robots: list[SimRobot], seconds: float) -> list[SimRobot]:
        """Drain every battery by ``seconds`` of use: one second per second at rest, up to
        twice as fast at the rated mechanical power of all the robot's motors (the battery
        ran down "faster under load" in UT2004, protocol.md 6.2).  Returns the robots whose
        battery has just run out."""
        if not robots:
            return []
        known = self._robots
        if len(robots) != len(known) or robots[0] is not known[0] or robots[-1] is not known[-1]:
            return self._drain_each(robots, seconds)  # not indexed for these robots (a rebuild indexes them)
        owners = self._owner
        if owners is None or len(owners) != m.nu:  # not indexed for this model: as at rest
            owners = np.zeros(0, dtype=np.intp)
        used = self._used
        if not _drain_all(
            owners,
            d.actuator_force,
            d.actuator_velocity,
            self._rated,
            self._capacity,
            used,
            float(seconds),
            BATTERY_LOAD_FACTOR,
        ):
            return []
        empty = np.flatnonzero(~(self._capacity - used > 0.0))  # battery_left() <= 0 (NaN too)
        out = []
        for i in empty.tolist():
            r = robots[i]
            if not r.battery_empty:
                r.battery_empty = True
                out.append(r)
        return out

    @staticmethod
    def _drain_each(robots: list[SimRobot], seconds: float) -> list[SimRobot]:
        """:meth:`drain` one robot at a time, as at rest (robots not indexed together)."""
        if seconds > 0:
            for r in robots:
                r.battery_used_s += seconds  # at rest: one second per second
        out = []
        for r in robots:
            if not r.battery_empty and r.battery_left() <= 0.0:
                r.battery_empty = True
                out.append(r)
        return out
