"""Status messages, with their formats and parsers: a robot's periodic ``STA`` (protocol.md
§6.2), a mission package's ``MISSTA`` (§6.4) and an actuator's ``ASTA`` (§6.4, UDK).  Time
is printed with 2 decimals in STA and MISSTA, with 4 in ASTA as UDK wrote it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.readings import PackageLink, PackageState, RobotStatus

from .common import _Reader
from .declare import Key, Layout, Pairs, Variants, group, items, key, key_spec, message
from .kinds import BOOL, F2, F4, INT, TEXT


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


# a link of a MISSTA or ASTA line (§6.4): {Link n} {Value v} {Torque q}
LINK = {"link": Key("Link", INT), "value": Key("Value", F4), "torque": Key("Torque", F4)}


@dataclass(frozen=True, slots=True)
class MisPkgMessage:
    """``MISSTA {Time t} {Name P} {Link 1} {Value v} {Torque q} ...`` (§6.4): its time and the
    mission package's state then (a :class:`usarsim.readings.PackageState`, the payload)."""

    time: float
    state: PackageState


@dataclass(frozen=True, slots=True)
class ActuatorStatus:
    """``ASTA {Time t} {Name arm} {Link 1} {Value v} {Torque q} ... [{Gripper g}]`` (§6.4,
    UDK): an actuator's links every status period; Time with 4 decimals as UDK wrote it."""

    time: float = key("Time", F4)
    name: str = key("Name", TEXT)
    links: tuple[PackageLink, ...] = group(PackageLink, LINK, torque=0.0)  # UDK lines may lack a link's Torque
    gripper: int | None = key("Gripper", INT, default=None, optional=True)


StatusMessages = StatusMessage | MisPkgMessage | ActuatorStatus

# ---- formatting and parsing, from the declarations above

_LIGHTS_AND_BATTERY = {
    "status.light_toggle": key_spec("LightToggle", BOOL, absent=False),
    "status.light_intensity": key_spec("LightIntensity", INT, absent=0),
    "status.battery_s": Key("Battery", INT),
    "status.view": key_spec("View", INT, absent=-1),
}
_GROUND = Layout(
    StatusMessage,
    "STA",
    read_first=("status.vehicle_type", "time", "status.battery_s", "status.light_toggle", "status.light_intensity")
    + ("status.view", "status.joints"),
    keys={
        "status.vehicle_type": Key("Type", TEXT),
        "time": Key("Time", F2),
        "status.front_steer": key_spec("FrontSteer", F4, absent=0.0),
        "status.rear_steer": key_spec("RearSteer", F4, absent=0.0),
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
_MISSTA = Layout(
    MisPkgMessage,
    "MISSTA",
    read_first=("state.links",),
    keys={"time": Key("Time", F2), "state.name": Key("Name", TEXT), "state.links": items(PackageLink, **LINK)},
    nested={"state": PackageState},
)
_ASTA = message(ActuatorStatus, "ASTA", read_first=("links",))


FORMATTERS: dict[type, Callable[[Any], str]] = {
    StatusMessage: _STA.format,
    MisPkgMessage: _MISSTA.format,
    ActuatorStatus: _ASTA.format,
}

PARSERS: dict[str, Callable[[_Reader], StatusMessages]] = {
    "STA": _STA.parse,
    "MISSTA": _MISSTA.parse,
    "ASTA": _ASTA.parse,
}
