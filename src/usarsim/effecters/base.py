"""The effecter plugin base and registry (design.md 4; protocol.md 5.4, 6.6, 8).

An effecter is a mounted item that acts on the world when a client operates it with
``SET {Type T} {Name N} {Opcode op} {Params p}``: it gets the typed parameters, acts, and
answers with an :class:`~usarsim.readings.OperationResult` (the RES line); after an
operation it may report its state (:class:`~usarsim.readings.EffecterState`, an EFF line).
It sends no SEN line.  Robot files list effecters with the other items, under ``sensors:``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from usarsim.sensors.base import ITEMS, Item, ItemConfig

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView

__all__ = ["EFFECTERS", "Effecter"]


EC = TypeVar("EC", bound=ItemConfig)


class Effecter(Item[EC]):
    """Base class of every effecter plugin."""

    PERIODIC = False

    def ground_below(self, view: WorldView) -> np.ndarray:
        """The point of the ground (or whatever lies below) straight under the item, within 10 m,
        MuJoCo frame; the item's own place when nothing is that near (what a dropper drops on)."""
        pos, _ = self.handle.sensor_frame(view.data, self.item.location, self.item.orientation, self.item.mount)
        down = np.array([[0.0, 0.0, -1.0]])
        dist, _, _ = view.caster.cast(pos, down, 10.0, self.handle.body_id)
        ground: np.ndarray = pos + down[0] * (float(dist[0]) if math.isfinite(dist[0]) else 0.0)
        return ground


EFFECTERS = ITEMS.new("effecter")
