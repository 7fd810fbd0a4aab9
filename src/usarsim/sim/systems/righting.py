"""Self-righting (DRIVE {Flip True}, protocol.md 5.3 and 8): an overturned robot is rolled
back onto its wheels.

UT2004's KRobot applied FlipTorque for FlipTime = 3 s to an overturned robot.  The torque
here rolls the robot about the axis that brings its top up, sized to lift its weight at
half its width or height, twice over (UT's FlipTorque 350 was in engine units), until it
is within 25 degrees of upright.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

import numpy as np

from usarsim.sim.constants import UP
from usarsim.sim.systems.base import SYSTEMS, System

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext
    from usarsim.sim.robot import SimRobot

log = logging.getLogger("usarsim.sim")

FLIP_TIME_S = 3.0
FLIP_MARGIN = 2.0
OVERTURNED_COS = math.cos(math.radians(60.0))  # more than 60 degrees from upright


def start_righting(sim: WorldContext, r: SimRobot) -> bool:
    """Start righting an overturned robot; False (ignored) when it is upright or has no power."""
    if r.battery_empty:
        return False
    up_z = float(sim.data.xmat[r.handle.body_id][8])  # world z of the body's up axis
    if up_z > OVERTURNED_COS:
        return False
    r.flip_until = sim.time + FLIP_TIME_S
    for system in sim.systems:
        if isinstance(system, Righting):
            system.righting[r.uid] = r
    log.info("robot '%s' (id %d): self-righting for %.0f s", r.name, r.uid, FLIP_TIME_S)
    return True


@SYSTEMS.register("righting")
class Righting(System):
    """Rolls each robot being righted about its own forward axis (sideways is the easy way
    over) towards upright: a torque growing with its tilt, damped by its roll rate so that
    it does not roll on past upright; exactly upside down it rolls to its right."""

    ORDER = 20

    def __init__(self, sim: WorldContext) -> None:
        super().__init__(sim)
        # the robots being righted, by id (asked twice every stretch of steps: with hundreds
        # of robots, looking at each of them then cost more than the rest of the stretch's
        # bookkeeping)
        self.righting: dict[int, SimRobot] = {}

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return bool(sim.robots)

    def active(self) -> bool:
        return bool(self.righting)

    def pre_step(self) -> None:
        if not self.righting:
            return
        sim = self.sim
        d = sim.data
        for uid, r in list(self.righting.items()):
            if r.flip_until < 0 or sim.robots.get(uid) is not r:  # done, or removed
                del self.righting[uid]
                continue
            b = r.handle.body_id
            rot = d.xmat[b].reshape(3, 3)
            up, forward = rot[:, 2], rot[:, 0]
            sense = float(np.cross(up, UP) @ forward)
            tilt = math.atan2(abs(sense), float(up[2]))  # angle from upright, 0..pi
            roll_rate = float(d.cvel[b][:3] @ forward)
            if sim.time >= r.flip_until or (tilt < math.radians(25.0) and abs(roll_rate) < 0.5):
                r.flip_until = -1.0
                d.xfrc_applied[b, 3:] = 0.0
                del self.righting[uid]
                continue
            sign = 1.0 if sense >= -1e-3 else -1.0
            dims = r.config.geometry.dimensions
            limit = FLIP_MARGIN * r.config.mass_kg * sim.world.gravity_m_s2 * max(dims[1], dims[2]) / 2.0
            inertia = r.config.mass_kg * (dims[1] ** 2 + dims[2] ** 2) / 12.0
            k = limit / (math.pi / 2.0)
            damping = 2.0 * math.sqrt(k * inertia)
            torque = max(-limit, min(limit, sign * k * tilt - damping * roll_rate))
            d.xfrc_applied[b, 3:] = forward * torque
