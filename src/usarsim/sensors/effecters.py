"""Effecters that are items of a robot file (manual section 11, protocol.md 5.4, 6.6, 8):
the ``Gripper``, whose fingers are links of the robot, and the ``RollerTable``, a conveyor
on its back.  Operated with SET; they answer RES, and the gripper reports its state in an
EFF line."""

from __future__ import annotations

from dataclasses import dataclass

from usarsim.sensors.base import SENSORS, Sensor, SensorConfig


@dataclass(frozen=True, kw_only=True)
class GripperConfig(SensorConfig):
    fingers: tuple = ()  # link names of the fingers (prismatic or revolute joints)
    open_value: float = 0.04  # joint value of an open finger (m or rad)
    closed_value: float = -0.02  # beyond touching: the fingers squeeze with their MaxTorque

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.fingers:
            raise ValueError("a Gripper needs its fingers: the names of its finger links")


@SENSORS.register("Gripper")
class Gripper(Sensor):
    """``SET {Type Gripper} {Name g} {Opcode Open|Close}`` (or ``{Opcode Grip} {Params 1|0}``,
    1 closing) drives every finger to its open or closed value; a closed gripper holds an
    object with the fingers' force (their links' MaxTorque).  RES OK, then ``EFF {Status
    OPEN|CLOSED}``."""

    PERIODIC = False
    Config = GripperConfig
    ALIASES = {"Fingers": "fingers", "Open": "open_value", "Closed": "closed_value"}

    def configure(self, view) -> None:
        names = {ln.name for ln in self.robot.links}
        missing = [f for f in self.config.fingers if f not in names]
        if missing:
            raise ValueError(f"gripper {self.name}: unknown finger links {missing}")

    def reset(self, view) -> None:
        self.closed = False

    def operate(self, view, opcode, params):
        op = opcode.lower()
        if op == "grip":
            try:
                op = "close" if int(float(str(params).split()[0])) else "open"
            except (ValueError, IndexError):
                return "Failed"
        if op not in ("open", "close") or view.drive_joint is None:
            return None
        value = self.config.closed_value if op == "close" else self.config.open_value
        ok = all(view.drive_joint(f, value, 0) for f in self.config.fingers)
        if ok:
            self.closed = op == "close"
        return "OK" if ok else "Failed"

    def effecter_state(self) -> str:
        return "CLOSED" if self.closed else "OPEN"

    def conf_fields(self):
        return ()


ROLLER_FRICTION = 0.05  # the table's top between its rollers' pushes


@dataclass(frozen=True, kw_only=True)
class RollerTableConfig(SensorConfig):
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


@SENSORS.register("RollerTable")
class RollerTable(Sensor):
    """A conveyor on the robot: ``SET {Type RollerTable} {Name r} {Opcode Roll} {Params v}``
    (m/s along the robot's X, negative backwards, 0 or ``{Opcode Stop}`` stops) makes the
    rollers carry whatever lies on the table's top: each load is pushed towards that speed
    relative to the robot with up to grip x its weight."""

    PERIODIC = False
    Config = RollerTableConfig
    ALIASES = {"Surface": "surface", "MaxSpeed": "max_speed_m_s", "Grip": "grip"}

    def configure(self, view) -> None:
        if self.config.surface >= len(self.robot.chassis):
            raise ValueError(f"roller table {self.name}: the robot has no chassis piece {self.config.surface}")
        self.geom = view.model.geom(f"{self.handle.prefix}/chassis{self.config.surface}").id
        # rollers turn freely: the top itself hardly holds a load; the rollers' grip does
        view.model.geom_friction[self.geom, 0] = ROLLER_FRICTION
        view.model.geom_priority[self.geom] = 2

    def reset(self, view) -> None:
        self.speed = 0.0

    def operate(self, view, opcode, params):
        op = opcode.lower()
        if op == "stop":
            self.speed = 0.0
            return "OK"
        if op not in ("roll", "speed", "move"):
            return None
        try:
            v = float(str(params).replace(",", " ").split()[0])
        except (ValueError, IndexError):
            return "Failed"
        if v != v or abs(v) == float("inf"):
            return "Failed"
        self.speed = max(-self.config.max_speed_m_s, min(self.config.max_speed_m_s, v))
        return "OK"

    def conf_fields(self):
        return (("MaxSpeed", self.config.max_speed_m_s),)
