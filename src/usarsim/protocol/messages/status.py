"""Status messages, with their formats and parsers: a robot's periodic ``STA`` (protocol.md
§6.2), a mission package's ``MISSTA`` (§6.4) and an actuator's ``ASTA`` (§6.4, UDK).  Time
is printed with 2 decimals in STA and MISSTA, with 4 in ASTA as UDK wrote it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.readings import RobotStatus

from .common import _Reader
from .declare import BOOL, F2, F4, INT, TEXT, Key, Layout, Pairs, Variants, group, key, message


@dataclass(frozen=True, slots=True)
class StatusMessage:
    """A robot's periodic ``STA`` (§6.2): its time (2 decimals) and its status then, a
    :class:`usarsim.readings.RobotStatus` (the payload, as a SEN line's is its reading).

    A ground robot's line (``{Type GroundVehicle}``, and the other non-aerial kinds,
    ``LeggedRobot``, ``NauticalVehicle``, ``StaticPlatform``, with the same layout) has its
    steer angles and its joints (flipper angles, printed after ``RearSteer``); an aerial
    robot's (``{Type AerialVehicle}``) has neither.  ``battery_s`` is the remaining battery
    life in whole seconds.
    """

    time: float
    status: RobotStatus


@dataclass(frozen=True, slots=True)
class LinkState:
    """One link of a ``MISSTA`` or ``ASTA`` line (§6.4): ``{Link n} {Value v} {Torque q}``, the joint's position
    (rad, or m for a prismatic joint) and the torque it applies."""

    link: int = key("Link", INT)
    value: float = key("Value", F4)
    torque: float = key("Torque", F4)


@dataclass(frozen=True, slots=True)
class MisPkgStatus:
    """``MISSTA {Time t} {Name P} {Link 1} {Value v} {Torque q} ...`` (§6.4)."""

    time: float = key("Time", F2)
    name: str = key("Name", TEXT)
    links: tuple[LinkState, ...] = group(LinkState)


@dataclass(frozen=True, slots=True)
class ActuatorStatus:
    """``ASTA {Time t} {Name arm} {Link 1} {Value v} {Torque q} ... [{Gripper g}]`` (§6.4,
    UDK): an actuator's links every status period; Time with 4 decimals as UDK wrote it."""

    time: float = key("Time", F4)
    name: str = key("Name", TEXT)
    links: tuple[LinkState, ...] = group(LinkState, torque=0.0)  # UDK lines may lack a link's Torque
    gripper: int | None = key("Gripper", INT, default=None, optional=True)


StatusMessages = StatusMessage | MisPkgStatus | ActuatorStatus

# ---- formatting and parsing, from the declarations above

_LIGHTS_AND_BATTERY = {
    "status.light_toggle": Key("LightToggle", BOOL, absent=False, has_absent=True),
    "status.light_intensity": Key("LightIntensity", INT, absent=0, has_absent=True),
    "status.battery_s": Key("Battery", INT),
    "status.view": Key("View", INT, absent=-1, has_absent=True),
}
_GROUND = Layout(
    StatusMessage,
    "STA",
    read_first=("status.vehicle_type", "time", "status.battery_s", "status.light_toggle", "status.light_intensity")
    + ("status.view", "status.joints"),
    keys={
        "status.vehicle_type": Key("Type", TEXT),
        "time": Key("Time", F2),
        "status.front_steer": Key("FrontSteer", F4, absent=0.0, has_absent=True),
        "status.rear_steer": Key("RearSteer", F4, absent=0.0, has_absent=True),
        "status.joints": Pairs(F4),
        **_LIGHTS_AND_BATTERY,
    },
    nested={"status": RobotStatus},
)
_AERIAL = Layout(
    StatusMessage,
    "STA",
    fixed=(("Type", "AerialVehicle"),),
    read_first=("time", "status.battery_s"),
    keys={"time": Key("Time", F2), **_LIGHTS_AND_BATTERY},
    constants={"status.vehicle_type": "AerialVehicle"},
    nested={"status": RobotStatus},
)
_STA = Variants(
    StatusMessage,
    ((lambda m: m.status.vehicle_type == "AerialVehicle", _AERIAL), (None, _GROUND)),
    # Type, Time and Battery are required; UDK lines may lack the others (defaults used)
    lambda r: (_AERIAL if r.text("Type") == "AerialVehicle" else _GROUND).parse(r),
)
_MISSTA = message(MisPkgStatus, "MISSTA", read_first=("links",))
_ASTA = message(ActuatorStatus, "ASTA", read_first=("links",))


FORMATTERS: dict[type, Callable[[Any], str]] = {
    StatusMessage: _STA.format,
    MisPkgStatus: _MISSTA.format,
    ActuatorStatus: _ASTA.format,
}

PARSERS: dict[str, Callable[[_Reader], StatusMessages]] = {
    "STA": _STA.parse,
    "MISSTA": _MISSTA.parse,
    "ASTA": _ASTA.parse,
}
