"""The ``RFIDReleaser`` effecter, usually named ``Gun`` (protocol.md 5.4, 8): it drops RFID
tags that every robot's reader (:mod:`usarsim.sensors.rfid`) can sense."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from usarsim.effecters.base import EFFECTERS, Effecter
from usarsim.readings import ItemParams, OperationResult
from usarsim.sensors.base import ItemConfig
from usarsim.sim import frames

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView


@dataclass(frozen=True, kw_only=True)
class RfidReleaserConfig(ItemConfig):
    """An ``RFIDReleaser`` item's settings in a robot file (protocol.md 8): how many tags its magazine holds."""

    # The magazine's size was not recovered (protocol.md 8): 10 tags, an estimate.
    capacity: int = 10

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.capacity < 0:
            raise ValueError(f"capacity must be >= 0, got {self.capacity}")


@EFFECTERS.register("RFIDReleaser")
class RFIDReleaser(Effecter[RfidReleaserConfig]):
    """``SET {Type RFIDReleaser} {Name Gun} {Opcode Release}`` drops a new tag on the ground
    under the robot (RES OK), or fails when the magazine is empty."""

    ALIASES = {"Capacity": "capacity", "NumberOfTags": "capacity"}

    def reset(self, view: WorldView) -> None:
        self.left = self.config.capacity

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        if opcode.lower() != "release":
            return None
        if self.left <= 0 or view.entities is None:
            return OperationResult(ok=False)
        view.entities.release_tag(frames.from_mj_vec(self.ground_below(view)))
        self.left -= 1
        return OperationResult(ok=True)
