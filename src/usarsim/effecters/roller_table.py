"""The ``RollerTable`` effecter (protocol.md 5.4, 8): a conveyor on the robot's back.
Operated with SET; it answers RES.  What lies on it is carried by a world system
(:mod:`usarsim.effecters.rollers`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from usarsim.effecters.base import EFFECTERS, Effecter
from usarsim.readings import FieldValue, ItemParams, OperationResult
from usarsim.sensors.base import ItemConfig

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView

ROLLER_FRICTION = 0.05  # the table's top between its rollers' pushes


@dataclass(frozen=True, kw_only=True)
class RollerTableConfig(ItemConfig):
    """A ``RollerTable`` item's settings in a robot file (protocol.md 8): which chassis piece is the table's top, the
    rollers' top speed in m/s and their grip on a load."""

    # Our design (no USARSim source describes its roller table, protocol.md 8): a chassis
    # piece of the robot is the table's top, and what lies on it is carried along the
    # robot's X axis at up to 0.3 m/s, gripped with friction 1.
    surface: int = 0  # index of the chassis piece that is the table's top
    max_speed_m_s: float = 0.3
    grip: float = 1.0  # friction coefficient between the rollers and a load

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.surface < 0 or self.max_speed_m_s <= 0 or self.grip < 0:
            raise ValueError("need surface >= 0, max_speed_m_s > 0 and grip >= 0")


@EFFECTERS.register("RollerTable")
class RollerTable(Effecter[RollerTableConfig]):
    """A conveyor on the robot: ``SET {Type RollerTable} {Name r} {Opcode Roll} {Params v}``
    (m/s along the robot's X, negative backwards, 0 or ``{Opcode Stop}`` stops) makes the
    rollers carry whatever lies on the table's top: each load is pushed towards that speed
    relative to the robot with up to grip x its weight."""

    ALIASES = {"Surface": "surface", "MaxSpeed": "max_speed_m_s", "Grip": "grip"}

    def configure(self, view: WorldView) -> None:
        if self.config.surface >= len(self.robot.chassis):
            raise ValueError(f"roller table {self.name}: the robot has no chassis piece {self.config.surface}")
        self.geom = view.model.geom(f"{self.handle.prefix}/chassis{self.config.surface}").id
        # rollers turn freely: the top itself hardly holds a load; the rollers' grip does
        view.model.geom_friction[self.geom, 0] = ROLLER_FRICTION
        view.model.geom_priority[self.geom] = 2

    def reset(self, view: WorldView) -> None:
        self.speed = 0.0

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        op = opcode.lower()
        if op == "stop":
            self.speed = 0.0
            return OperationResult(ok=True)
        if op not in ("roll", "speed", "move"):
            return None
        if not params.values:
            return OperationResult(ok=False)
        v = params.values[0]
        self.speed = max(-self.config.max_speed_m_s, min(self.config.max_speed_m_s, v))
        return OperationResult(ok=True)

    def conf_fields(self) -> tuple[tuple[str, FieldValue], ...]:
        return (("MaxSpeed", self.config.max_speed_m_s),)
