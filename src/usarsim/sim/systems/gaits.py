"""Drives that act before each stretch of physics steps (their ``STEP_EVERY``): the gaits
of walking robots set their leg joints' targets."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usarsim.sim.systems.base import SYSTEMS, System

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext


@SYSTEMS.register("gaits")
class Gaits(System):
    """The walking robots' gaits: each sets its leg joints' targets before a stretch of steps."""

    ORDER = 60

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return any(r.drive.STEP_EVERY is not None for r in sim.robots.values())

    def max_steps(self) -> int | None:
        return min(
            (r.drive.STEP_EVERY for r in self.sim.robots.values() if r.drive.STEP_EVERY is not None), default=None
        )

    def pre_step(self) -> None:
        sim = self.sim
        for r in sim.robots.values():
            if r.drive.STEP_EVERY is not None:
                r.drive.pre_step(sim, r)
