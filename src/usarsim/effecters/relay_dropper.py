"""The ``RelayDropper`` effecter: a robot drops radio relays (breadcrumbs) where it stands, and
from then on the wireless simulation carries messages through them (docs/wireless.md,
"Relays").  DARPA's Subterranean Challenge gave its robots such relays, 6 to 12 a robot in its
virtual competition's robot configurations; a robot file gives the number (``capacity``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from usarsim.effecters.base import EFFECTERS, Effecter
from usarsim.readings import ItemParams, OperationResult
from usarsim.sensors.base import ItemConfig
from usarsim.sim import frames

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView

# A relay's antenna stands this far above the ground it was dropped on (an estimate: a
# breadcrumb is a small box with a short whip antenna)
ANTENNA_HEIGHT_M = 0.2


@dataclass(frozen=True, kw_only=True)
class RelayDropperConfig(ItemConfig):
    """A ``RelayDropper`` item's settings in a robot file: how many relays it carries."""

    capacity: int = 6  # the smaller of the Subterranean Challenge's breadcrumb counts

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.capacity < 0:
            raise ValueError(f"capacity must be >= 0, got {self.capacity}")


@EFFECTERS.register("RelayDropper")
class RelayDropper(Effecter[RelayDropperConfig]):
    """``SET {Type RelayDropper} {Name Relays} {Opcode Drop}`` drops a relay on the ground under
    the item (RES OK; named ``<robot>-Relay<k>`` on the radio), or fails when none is left."""

    ALIASES = {"Capacity": "capacity", "NumberOfRelays": "capacity"}

    def reset(self, view: WorldView) -> None:
        self.left = self.config.capacity

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        if opcode.lower() not in ("drop", "release"):
            return None
        if self.left <= 0 or view.entities is None:
            return OperationResult(ok=False)
        antenna = self.ground_below(view) + np.array([0.0, 0.0, ANTENNA_HEIGHT_M])
        view.entities.drop_relay(view.robot_name or self.robot.class_name, frames.from_mj_vec(antenna), view.time)
        self.left -= 1
        return OperationResult(ok=True)
