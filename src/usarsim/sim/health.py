"""The blow-up guard: a robot that goes numerically wrong (a non-finite state, or joints
faster than anything real) is put back where it last was healthy, at rest, before it can
disturb the others; the others are not touched."""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.config.robot import RobotConfig

if TYPE_CHECKING:
    from usarsim.sim.robot import SimRobot

log = logging.getLogger("usarsim.sim")

# No joint of a robot moves faster than this (m/s or rad/s): a robot beyond it has
# blown up numerically (wheels top out near 5 rad/s, a fall from 10 m reaches 14 m/s).
MAX_SANE_VELOCITY = 100.0
# What a physics step changes: kept before each stretch of steps to replay it on a blow-up.
STATE = int(mujoco.mjtState.mjSTATE_INTEGRATION)


def sane_velocity(robot: RobotConfig) -> float:
    """Above this speed (m/s or rad/s) a joint of ``robot`` has blown up: MAX_SANE_VELOCITY, or
    three times its top wheel speed for fast vehicles (a car's wheels spin at 180 rad/s)."""
    return max(MAX_SANE_VELOCITY, 3.0 * robot.max_speed_rad_s)


class BlowUpGuard:
    """Runs stretches of physics steps; if a robot blows up on the way, the stretch is run
    again one step at a time from its start, and each robot is caught at the step where it
    goes wrong."""

    def __init__(self) -> None:
        self.good_qpos: np.ndarray | None = None
        self.resets = 0
        self._sane = MAX_SANE_VELOCITY
        self._snapshot: np.ndarray | None = None
        self._snapshot_model: mujoco.MjModel | None = None

    def index(self, robots: Iterable[SimRobot]) -> None:
        """After a model build: the fastest speed any robot of the world may reach."""
        self._sane = max([MAX_SANE_VELOCITY] + [sane_velocity(r.config) for r in robots])

    def mark_good(self, d: mujoco.MjData) -> None:
        self.good_qpos = d.qpos.copy()

    def step(self, m: mujoco.MjModel, d: mujoco.MjData, n: int, robots: list[SimRobot]) -> None:
        """``n`` physics steps in one call, repaired as needed."""
        if not robots:  # nothing the guard could put back (a world without robots)
            mujoco.mj_step(m, d, n)
            return
        if n == 1:  # one step: repaired where it ended (the same as replaying it from its start)
            self._step_one(m, d, robots)
            return
        if self._snapshot is None or self._snapshot_model is not m:  # a model rebuilt: its state's size
            self._snapshot = np.empty(mujoco.mj_stateSize(m, STATE))
            self._snapshot_model = m
        mujoco.mj_getState(m, d, self._snapshot, STATE)
        mujoco.mj_step(m, d, n)
        if self._healthy(d):
            self.good_qpos = d.qpos.copy()
            return
        mujoco.mj_setState(m, d, self._snapshot, STATE)
        robots = list(robots)
        self._repair(m, d, robots)
        for _ in range(n):
            self._step_one(m, d, robots)

    def _step_one(self, m: mujoco.MjModel, d: mujoco.MjData, robots: list[SimRobot]) -> None:
        """One physics step, each robot that went wrong in it put back."""
        mujoco.mj_step(m, d)
        if self._healthy(d):
            self.good_qpos = d.qpos.copy()
        else:
            self._repair(m, d, robots)

    def _healthy(self, d: mujoco.MjData) -> bool:
        """No velocity beyond the sane one and nothing non-finite (a NaN or an infinity
        makes the max and the sum non-finite)."""
        v = d.qvel
        if v.size == 0:
            return True
        # the sum of the squared speeds bounds the largest (and is NaN when any speed is): with a
        # few robots it is below the sane speed squared, and the largest need not be found
        if not float(v.dot(v)) < self._sane * self._sane and not float(np.abs(v).max()) < self._sane:
            return False
        return math.isfinite(float(d.qpos.sum()))

    def _repair(self, m: mujoco.MjModel, d: mujoco.MjData, robots: list[SimRobot]) -> None:
        """Put every robot whose state is not finite, or whose joints move faster than
        anything real, back where it last was healthy, at rest."""
        good = self.good_qpos if self.good_qpos is not None and len(self.good_qpos) == len(d.qpos) else None
        for r in robots:
            h = r.handle
            nq, nv = 7 + len(h.joint_qpos), 6 + len(h.joint_qvel)
            qs, vs = slice(h.root_qpos, h.root_qpos + nq), slice(h.root_qvel, h.root_qvel + nv)
            v = d.qvel[vs]
            finite = np.isfinite(v).all() and np.isfinite(d.qpos[qs]).all()
            if finite and float(np.abs(v).max()) < sane_velocity(r.config):
                continue
            self.resets += 1
            r.resets += 1
            log.error(
                "robot '%s' (id %d) became physically unstable at t=%.3f; it is put back where it last "
                "was stable, at rest",
                r.name,
                r.uid,
                d.time,
            )
            if good is not None and np.isfinite(good[qs]).all():
                d.qpos[qs] = good[qs]
            else:  # no healthy pose known: its spawn pose
                q = d.qpos[qs]
                q[:7] = r.spawn_qpos
                q[7:] = 0.0
            d.qvel[vs] = 0.0
            d.qacc_warmstart[vs] = 0.0
        # whatever else is not finite (not part of a robot) is cleared too
        for arr in (d.qpos, d.qvel, d.qacc_warmstart, d.act):
            bad = ~np.isfinite(arr)
            if bad.any():
                arr[bad] = 0.0
        mujoco.mj_forward(m, d)
