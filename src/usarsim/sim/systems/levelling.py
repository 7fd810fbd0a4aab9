"""Hovering robots keep level (their drive says ``HOVERS``: aerial robots): a restoring
torque towards upright; their roll and pitch rates are damped by their servos."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from usarsim.sim.constants import UP
from usarsim.sim.systems.base import SYSTEMS, System

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext

# N m per rad of tilt per kg: hovering robots right themselves (and a vessel's hull, by
# its weight hanging below its buoyancy, in roll: systems.water).
AERIAL_LEVEL_STIFFNESS = 20.0


@SYSTEMS.register("levelling")
class Levelling(System):
    """Hovering robots keep level: a restoring torque towards upright, before each stretch."""

    ORDER = 30

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return any(r.drive.HOVERS for r in sim.robots.values())

    def pre_step(self) -> None:
        d = self.sim.data
        for r in self.sim.robots.values():
            if not r.drive.HOVERS:
                continue
            b = r.handle.body_id
            up = d.xmat[b].reshape(3, 3)[:, 2]
            d.xfrc_applied[b, 3:] = np.cross(up, UP) * (AERIAL_LEVEL_STIFFNESS * r.config.mass_kg)
