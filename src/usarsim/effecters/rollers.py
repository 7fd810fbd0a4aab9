"""Roller tables (the RollerTable effecter): what lies on a table's top is carried along."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.effecters.roller_table import ROLLER_FRICTION, RollerTable
from usarsim.sim.systems.base import SYSTEMS, System, mounted

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext

# How quickly the rollers bring a load to their speed: a first-order time constant (s), the
# force capped at the rollers' grip x the load's weight.  An estimate (no roller table's
# data): a load placed on running rollers is at their speed within a few centimetres of
# travel, as on a powered roller conveyor.  The force is renewed every physics step while a
# table carries something: renewed every 10 (40 ms), a push that stiff overshoots.
GRIP_TAU_S = 0.05
# Below this speed (m/s) over the table top, its friction on a sliding load is taken as
# growing from zero (the sign of a slide that has not started is not known)
SLIDE_M_S = 0.005


@SYSTEMS.register("rollers")
class RollerTables(System):
    """Every body touching a table's top (other than the robot) is pushed along the robot's
    X towards the rollers' speed relative to the robot, with up to grip x its weight;
    stopped rollers hold their load."""

    ORDER = 50

    def __init__(self, sim: WorldContext) -> None:
        super().__init__(sim)
        self._pushed: set[int] = set()
        self._model = sim.model  # body ids are the model's: they change with a rebuild

    def max_steps(self) -> int | None:
        # every step while a table carries a load (see GRIP_TAU_S), else every EVERY_STEPS
        return 1 if self._pushed else self.EVERY_STEPS

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return bool(mounted(sim, RollerTable))

    def pre_step(self) -> None:
        sim = self.sim
        m, d = sim.model, sim.data
        if m is not self._model:  # rebuilt: the ids pushed before name other bodies now
            self._pushed, self._model = set(), m
        pushed: set[int] = set()
        tables = {t.geom: t for t in mounted(sim, RollerTable)}
        if tables:
            g = sim.world.gravity_m_s2
            for i in range(d.ncon):
                c = d.contact[i]
                t = tables.get(c.geom1) or tables.get(c.geom2)
                if t is None:
                    continue
                other = c.geom2 if t.geom == c.geom1 else c.geom1
                b = int(m.geom_bodyid[other])
                if b in pushed or m.body_rootid[b] == t.handle.body_id or m.body_weldid[b] == 0:
                    continue
                pushed.add(b)
                rot = d.xmat[t.handle.body_id].reshape(3, 3)
                axis = rot[:, 0]
                vel = np.empty(6)
                mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)
                robot_vel = np.empty(6)
                mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, t.handle.body_id, robot_vel, 0)
                along = float(axis @ (vel[3:] - robot_vel[3:]))  # the load's speed on the table
                mass = float(m.body_subtreemass[b])
                # towards the rollers' speed with time constant GRIP_TAU_S, and, while they
                # turn, against the table top's own friction as the load slides on it
                push = mass * (t.speed - along) / GRIP_TAU_S
                if t.speed != 0.0:
                    push += ROLLER_FRICTION * mass * g * max(-1.0, min(1.0, along / SLIDE_M_S))
                limit = t.config.grip * mass * g
                d.xfrc_applied[b, :3] = axis * max(-limit, min(limit, push))
        for b in self._pushed - pushed:
            d.xfrc_applied[b, :3] = 0.0
        self._pushed = pushed
