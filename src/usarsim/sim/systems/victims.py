"""Waving victims (manual 3.2.1): their right arm swings about the shoulder."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usarsim.sim.systems.base import SYSTEMS, System

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext


@SYSTEMS.register("victims")
class WavingVictims(System):
    """Moves the waving victims' arms to their angle at the current time (kinematic: the
    arm is a mocap body, so no force needs renewing)."""

    ORDER = 10
    EVERY_STEPS = None

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return sim.entities.has_motion

    def pre_step(self) -> None:
        self.sim.entities.update(self.sim.data, self.sim.time)
