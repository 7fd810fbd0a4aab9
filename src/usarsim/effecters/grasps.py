"""Grasps (the Gripper effecter): what a closed gripper holds by friction stays held.

MuJoCo's soft contacts let an object squeezed between two fingers creep down under a
sustained load even well inside the friction cone (a 2.3 kg brick between the Pioneer
Gripper's paddles slid out of them as they were lifted), because a soft friction constraint
needs a little slip to push back.  Static friction does not creep: an object held by
friction that could carry it does not move in the fingers.  So, as simulators commonly do
for grasps (Gazebo's grasp fix), while a closed gripper touches the same loose object with
each of its fingers (a one-finger jaw: with its finger and the part it closes against) and
the friction of those contacts, the coefficient times the normal force summed over them,
is more than the object's weight, the object is welded to the first finger where it is.
The weld lets go when the gripper opens, a finger no longer touches it, or the force it
carries grows beyond that friction (the object is pulled out, or shaken loose).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.effecters.gripper import Gripper, grasp_name
from usarsim.sim.systems.base import SYSTEMS, System, mounted

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext


class _Hold:
    """One gripper's grasp in the current model: its weld, its fingers' bodies and what it holds."""

    def __init__(self, m: mujoco.MjModel, gripper: Gripper) -> None:
        prefix = gripper.handle.prefix
        self.gripper = gripper
        self.eq = m.equality(grasp_name(prefix, gripper.name)).id
        fingers = [m.body(f"{prefix}/{f}").id for f in gripper.config.fingers]
        if len(fingers) == 1:  # a jaw closes against the part it hangs on
            fingers.append(int(m.body_parentid[fingers[0]]))
        self.fingers = fingers
        self.held = -1  # the body it holds (-1: none)


@SYSTEMS.register("grasps")
class Grasps(System):
    """Welds what each closed gripper holds by friction (see the module's description)."""

    ORDER = 60

    def __init__(self, sim: WorldContext) -> None:
        super().__init__(sim)
        self._model = None
        self._holds: list[_Hold] = []

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return bool(mounted(sim, Gripper))

    def active(self) -> bool:
        return any(h.gripper.closed for h in self._holds)

    def pre_step(self) -> None:
        sim = self.sim
        m, d = sim.model, sim.data
        if m is not self._model:  # rebuilt: ids anew, nothing welded (the next look grasps again)
            self._model = m
            self._holds = [_Hold(m, g) for g in mounted(sim, Gripper)]
        if not any(h.gripper.closed or h.held >= 0 for h in self._holds):
            return
        touching = self._touching(m, d)
        g = sim.world.gravity_m_s2
        for h in self._holds:
            if not h.gripper.closed:
                self._release(h, d)
                continue
            # the loose bodies every finger touches, and the friction their contacts give
            common: set[int] | None = None
            for f in h.fingers:
                bodies = {b for b, _ in touching.get(f, ())}
                common = bodies if common is None else common & bodies
            grip = {
                b: sum(mu_n for f in h.fingers for bb, mu_n in touching.get(f, ()) if bb == b) for b in (common or ())
            }
            if h.held >= 0:
                if h.held not in grip or self._weld_force(d, h.eq) > grip[h.held]:
                    self._release(h, d)
                continue
            if grip:
                b = max(grip, key=grip.__getitem__)
                if grip[b] > float(m.body_subtreemass[b]) * g:
                    self._weld(h, m, d, b)

    @staticmethod
    def _loose(m: mujoco.MjModel, b: int) -> bool:
        """A movable object of the world: a body of its own on a free joint."""
        return (
            int(m.body_rootid[b]) == b
            and m.body_jntnum[b] == 1
            and m.jnt_type[m.body_jntadr[b]] == mujoco.mjtJoint.mjJNT_FREE
            and mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b).startswith("movable/")
        )

    @classmethod
    def _touching(cls, m: mujoco.MjModel, d: mujoco.MjData) -> dict[int, list[tuple[int, float]]]:
        """For each body, the loose bodies it touches and, for each contact, its friction
        coefficient times its normal force (N)."""
        out: dict[int, list[tuple[int, float]]] = {}
        force = np.empty(6)
        for i in range(d.ncon):
            c = d.contact[i]
            b1, b2 = int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])
            for a, b in ((b1, b2), (b2, b1)):
                if cls._loose(m, b):
                    mujoco.mj_contactForce(m, d, i, force)
                    out.setdefault(a, []).append((b, float(c.friction[0]) * max(0.0, float(force[0]))))
        return out

    @staticmethod
    def _weld_force(d: mujoco.MjData, eq: int) -> float:
        """The force (N) the weld carries now."""
        rows = np.nonzero((d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY) & (d.efc_id == eq))[0]
        return float(np.linalg.norm(d.efc_force[rows[:3]])) if rows.size else 0.0

    @staticmethod
    def _weld(h: _Hold, m: mujoco.MjModel, d: mujoco.MjData, b: int) -> None:
        f = h.fingers[0]
        rel = d.xmat[f].reshape(3, 3).T @ (d.xpos[b] - d.xpos[f])
        inverse = np.empty(4)
        mujoco.mju_negQuat(inverse, d.xquat[f])
        relq = np.empty(4)
        mujoco.mju_mulQuat(relq, inverse, d.xquat[b])
        m.eq_obj2id[h.eq] = b
        m.eq_data[h.eq, :3] = 0.0  # the anchor: the object's origin
        m.eq_data[h.eq, 3:6] = rel  # where the object sits in the finger's frame
        m.eq_data[h.eq, 6:10] = relq
        m.eq_data[h.eq, 10] = 1.0  # torque scale
        d.eq_active[h.eq] = 1
        h.held = b

    @staticmethod
    def _release(h: _Hold, d: mujoco.MjData) -> None:
        if h.held >= 0:
            d.eq_active[h.eq] = 0
            h.held = -1
