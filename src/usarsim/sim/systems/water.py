"""Water (a world's ``water`` volumes): buoyancy, drag and the vessel's own propulsion for
every robot in water; robots not built for water lose their battery there (as in UT2004)."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.sim import frames
from usarsim.sim.constants import LEVEL_STIFFNESS, UP
from usarsim.sim.context import Vessel
from usarsim.sim.systems.base import SYSTEMS, System

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext

log = logging.getLogger("usarsim.sim")

HULL_CROSS_DRAG = 10.0  # a vessel's drag across its hull, relative to along it
HULL_PITCH_RIGHTING = 0.05  # its pitch righting, relative to its roll righting


@SYSTEMS.register("water")
class Water(System):
    """Buoyancy, drag and a vessel's propulsion for every robot in the world's water."""

    ORDER = 40

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return bool(sim.world.water and sim.robots)

    def pre_step(self) -> None:
        sim = self.sim
        d = sim.data
        g = sim.world.gravity_m_s2
        for r in sim.robots.values():
            b = r.handle.body_id
            loc = frames.from_mj_vec(d.xipos[b])  # centre of mass, USARSim frame
            depth = max((wv.depth_of(loc), wv) for wv in sim.world.water)
            height = r.config.geometry.dimensions[2]
            frac = min(max((depth[0] + height / 2.0) / height, 0.0), 1.0)
            was = r.in_water
            r.in_water = frac > 0.0
            if not r.in_water:
                if was:
                    d.xfrc_applied[b] = 0.0
                continue
            drive = r.drive
            if not isinstance(drive, Vessel):  # a robot not built for water
                if depth[0] > 0.0 and not r.battery_empty:
                    r.battery_used_s = r.config.battery_s
                    log.info("robot '%s' (id %d) went under water: its battery is gone", r.name, r.uid)
                continue
            n = drive.vessel
            rot = d.xmat[b].reshape(3, 3)
            vel = np.empty(6)
            mujoco.mj_objectVelocity(sim.model, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)  # world frame
            ang, lin = vel[:3], vel[3:]
            force = np.array([0.0, 0.0, depth[1].density_kg_m3 * g * n.volume_m3 * frac])
            # a hull slips through the water lengthwise and hardly at all sideways or
            # up and down (its fins): drag ten times larger across than along it
            v_body = rot.T @ lin
            force -= rot @ (v_body * np.array([1.0, HULL_CROSS_DRAG, HULL_CROSS_DRAG])) * (n.drag_n_per_m_s * frac)
            torque = -n.angular_drag * ang * frac
            if not r.battery_empty:
                thrust, turns = drive.propulsion(rot, lin, frac)
                force += thrust
                for t in turns:
                    torque += t
            # the hull rights itself (its weight hangs below its buoyancy): firmly in roll,
            # gently in pitch, which the stern planes overcome
            up = rot[:, 2]
            tilt = np.cross(up, UP)
            righting = LEVEL_STIFFNESS * r.config.mass_kg
            torque += rot[:, 0] * (float(tilt @ rot[:, 0]) * righting)
            torque += rot[:, 1] * (float(tilt @ rot[:, 1]) * righting * HULL_PITCH_RIGHTING)
            d.xfrc_applied[b, :3] = force
            d.xfrc_applied[b, 3:] = torque
