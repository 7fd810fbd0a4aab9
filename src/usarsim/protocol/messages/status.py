"""Status messages, with their formats and parsers: a robot's periodic ``STA`` (protocol.md
§6.2), a mission package's ``MISSTA`` (§6.4) and an actuator's ``ASTA`` (§6.4, UDK).  Time
is printed with 2 decimals in STA and MISSTA, with 4 in ASTA as UDK wrote it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .common import _Reader
from .declare import BOOL, F2, F4, INT, TEXT, group, key, message, pairs


@dataclass(frozen=True, slots=True, kw_only=True)
class GroundVehicleStatus:
    """Periodic ``STA`` of a ground robot (§6.2).

    ``joints`` are flipper angles printed after ``RearSteer`` (TeleMax).  ``battery_s`` is the
    remaining battery life in whole seconds.  ``vehicle_type`` names the other non-aerial
    kinds (``LeggedRobot``, ``NauticalVehicle``, ``StaticPlatform``) with the same layout.
    """

    vehicle_type: str = key("Type", TEXT, default="GroundVehicle")
    time: float = key("Time", F2)
    front_steer: float = key("FrontSteer", F4, default=0.0, absent=0.0)
    rear_steer: float = key("RearSteer", F4, default=0.0, absent=0.0)
    joints: tuple[tuple[str, float], ...] = pairs(F4)
    light_toggle: bool = key("LightToggle", BOOL, default=False, absent=False)
    light_intensity: int = key("LightIntensity", INT, default=0, absent=0)
    battery_s: int = key("Battery", INT)
    view: int = key("View", INT, default=-1, absent=-1)


@dataclass(frozen=True, slots=True, kw_only=True)
class AerialVehicleStatus:
    """Periodic ``STA {Type AerialVehicle}`` of an aerial robot (§6.2)."""

    time: float = key("Time", F2)
    light_toggle: bool = key("LightToggle", BOOL, default=False, absent=False)
    light_intensity: int = key("LightIntensity", INT, default=0, absent=0)
    battery_s: int = key("Battery", INT)
    view: int = key("View", INT, default=-1, absent=-1)


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


StatusMessage = GroundVehicleStatus | AerialVehicleStatus | MisPkgStatus | ActuatorStatus

# ---- formatting and parsing, from the declarations above

_GROUND = message(
    GroundVehicleStatus,
    "STA",
    read_first=("vehicle_type", "time", "battery_s", "light_toggle", "light_intensity", "view", "joints"),
)
_AERIAL = message(AerialVehicleStatus, "STA", fixed=(("Type", "AerialVehicle"),), read_first=("time", "battery_s"))
_MISSTA = message(MisPkgStatus, "MISSTA", read_first=("links",))
_ASTA = message(ActuatorStatus, "ASTA", read_first=("links",))


def _parse_sta(r: _Reader) -> GroundVehicleStatus | AerialVehicleStatus:
    # Type, Time and Battery are required; UDK lines may lack the others (defaults used).
    layout = _AERIAL if r.text("Type") == "AerialVehicle" else _GROUND
    status: GroundVehicleStatus | AerialVehicleStatus = layout.parse(r)
    return status


FORMATTERS: dict[type, Callable[[Any], str]] = {
    GroundVehicleStatus: _GROUND.format,
    AerialVehicleStatus: _AERIAL.format,
    MisPkgStatus: _MISSTA.format,
    ActuatorStatus: _ASTA.format,
}

PARSERS: dict[str, Callable[[_Reader], StatusMessage]] = {
    "STA": _parse_sta,
    "MISSTA": _MISSTA.parse,
    "ASTA": _ASTA.parse,
}
