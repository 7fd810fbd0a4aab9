"""The ``Gripper`` effecter (manual section 11, protocol.md 5.4, 6.6, 8): its fingers are
links of the robot.  Operated with SET; it answers RES, then reports its state in an EFF
line."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco

from usarsim.effecters.base import EFFECTERS, Effecter
from usarsim.readings import EffecterState, ItemParams, OperationResult
from usarsim.sensors.base import ItemConfig

if TYPE_CHECKING:
    from usarsim.sim.view import WorldView


def grasp_name(prefix: str, gripper: str) -> str:
    """The weld of the robot ``prefix``'s gripper ``gripper`` (:mod:`usarsim.effecters.grasps`)."""
    return f"{prefix}/grasp/{gripper}"


@dataclass(frozen=True, kw_only=True)
class GripperConfig(ItemConfig):
    """A ``Gripper`` item's settings in a robot file (protocol.md 8): its finger links and the joint values, metres
    or radians, that open and close them."""

    fingers: tuple[str, ...] = ()  # link names of the fingers (prismatic or revolute joints)
    open_value: float = 0.04  # joint value of an open finger (m or rad)
    closed_value: float = -0.02  # beyond touching: the fingers squeeze with their MaxTorque

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.fingers:
            raise ValueError("a Gripper needs its fingers: the names of its finger links")


@EFFECTERS.register("Gripper")
class Gripper(Effecter[GripperConfig]):
    """``SET {Type Gripper} {Name g} {Opcode Open|Close}`` (or ``{Opcode Grip} {Params 1|0}``,
    1 closing) drives every finger to its open or closed value; a closed gripper holds an
    object with the fingers' force (their links' MaxTorque).  RES OK, then ``EFF {Status
    OPEN|CLOSED}``."""

    ALIASES = {"Fingers": "fingers", "Open": "open_value", "Closed": "closed_value"}

    def build(self, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, prefix: str) -> None:
        """The weld that holds what the gripper grasps (:mod:`usarsim.effecters.grasps`): from
        its first finger to the world, off until it closes on something."""
        eq = spec.add_equality()
        eq.name = grasp_name(prefix, self.name)
        eq.type = mujoco.mjtEq.mjEQ_WELD
        eq.objtype = mujoco.mjtObj.mjOBJ_BODY
        eq.name1 = f"{prefix}/{self.config.fingers[0]}"
        eq.name2 = "world"
        eq.active = False

    def configure(self, view: WorldView) -> None:
        names = {ln.name for ln in self.robot.links}
        missing = [f for f in self.config.fingers if f not in names]
        if missing:
            raise ValueError(f"gripper {self.name}: unknown finger links {missing}")

    def reset(self, view: WorldView) -> None:
        self.closed = False

    def operate(self, view: WorldView, opcode: str, params: ItemParams) -> OperationResult | None:
        op = opcode.lower()
        if op == "grip":
            if not params.values:
                return OperationResult(ok=False)
            op = "close" if int(params.values[0]) else "open"
        if op not in ("open", "close") or view.drive_joint is None:
            return None
        value = self.config.closed_value if op == "close" else self.config.open_value
        ok = all(view.drive_joint(f, value, 0) for f in self.config.fingers)
        if ok:
            self.closed = op == "close"
        return OperationResult(ok=ok)

    def state(self) -> EffecterState:
        return EffecterState(self.TYPE, self.name, closed=self.closed)
