"""The effecter plugin base and registry (design.md 4; protocol.md 5.4, 6.6, 8).

An effecter is a mounted item that acts on the world when a client operates it with
``SET {Type T} {Name N} {Opcode op} {Params p}``: it gets the typed parameters, acts, and
answers with an :class:`~usarsim.readings.OperationResult` (the RES line); after an
operation it may report its state (:class:`~usarsim.readings.EffecterState`, an EFF line).
It sends no SEN line.  Robot files list effecters with the other items, under ``sensors:``.
"""

from __future__ import annotations

from typing import TypeVar

from usarsim.sensors.base import ITEMS, Item, ItemConfig

__all__ = ["EFFECTERS", "Effecter"]


EC = TypeVar("EC", bound=ItemConfig)


class Effecter(Item[EC]):
    """Base class of every effecter plugin."""

    PERIODIC = False


EFFECTERS = ITEMS.new("effecter")
