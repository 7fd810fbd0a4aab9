"""Status messages, with their formats and parsers: a robot's periodic ``STA`` (protocol.md
§6.2), a mission package's ``MISSTA`` (§6.4) and an actuator's ``ASTA`` (§6.4, UDK).  Time
is printed with 2 decimals in STA and MISSTA, with 4 in ASTA as UDK wrote it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..grammar import RawMessage
from ..numbers import bool_str, f2, f4
from .common import _groups, _Reader


@dataclass(frozen=True, slots=True, kw_only=True)
class GroundVehicleStatus:
    """Periodic ``STA`` of a ground robot (§6.2).

    ``joints`` are flipper angles printed after ``RearSteer`` (TeleMax).  ``battery_s`` is the
    remaining battery life in whole seconds.  ``vehicle_type`` names the other non-aerial
    kinds (``LeggedRobot``, ``NauticalVehicle``, ``StaticPlatform``) with the same layout.
    """

    time: float
    front_steer: float = 0.0
    rear_steer: float = 0.0
    joints: tuple[tuple[str, float], ...] = ()
    light_toggle: bool = False
    light_intensity: int = 0
    battery_s: int
    view: int = -1
    vehicle_type: str = "GroundVehicle"


@dataclass(frozen=True, slots=True, kw_only=True)
class AerialVehicleStatus:
    """Periodic ``STA {Type AerialVehicle}`` of an aerial robot (§6.2)."""

    time: float
    light_toggle: bool = False
    light_intensity: int = 0
    battery_s: int
    view: int = -1


@dataclass(frozen=True, slots=True)
class LinkState:
    """One link of a ``MISSTA`` or ``ASTA`` line (§6.4): ``{Link n} {Value v} {Torque q}``, the joint's position
    (rad, or m for a prismatic joint) and the torque it applies."""

    link: int
    value: float
    torque: float


@dataclass(frozen=True, slots=True)
class MisPkgStatus:
    """``MISSTA {Time t} {Name P} {Link 1} {Value v} {Torque q} ...`` (§6.4)."""

    time: float
    name: str
    links: tuple[LinkState, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorStatus:
    """``ASTA {Time t} {Name arm} {Link 1} {Value v} {Torque q} ... [{Gripper g}]`` (§6.4,
    UDK): an actuator's links every status period; Time with 4 decimals as UDK wrote it."""

    time: float
    name: str
    links: tuple[LinkState, ...] = ()
    gripper: int | None = None


StatusMessage = GroundVehicleStatus | AerialVehicleStatus | MisPkgStatus | ActuatorStatus

# ---- formatting


def _fmt_ground_status(m: GroundVehicleStatus) -> str:
    joints = "".join(" {%s %s}" % (name, f4(angle)) for name, angle in m.joints)
    return (
        "STA {Type %s} {Time %s} {FrontSteer %s} {RearSteer %s}%s {LightToggle %s} "
        "{LightIntensity %d} {Battery %d} {View %d}\r\n"
        % (
            m.vehicle_type,
            f2(m.time),
            f4(m.front_steer),
            f4(m.rear_steer),
            joints,
            bool_str(m.light_toggle),
            m.light_intensity,
            m.battery_s,
            m.view,
        )
    )


def _fmt_aerial_status(m: AerialVehicleStatus) -> str:
    return "STA {Type AerialVehicle} {Time %s} {LightToggle %s} {LightIntensity %d} {Battery %d} {View %d}\r\n" % (
        f2(m.time),
        bool_str(m.light_toggle),
        m.light_intensity,
        m.battery_s,
        m.view,
    )


def _fmt_mispkg_status(m: MisPkgStatus) -> str:
    links = "".join(" {Link %d} {Value %s} {Torque %s}" % (k.link, f4(k.value), f4(k.torque)) for k in m.links)
    return "MISSTA {Time %s} {Name %s}%s\r\n" % (f2(m.time), m.name, links)


def _fmt_actuator_status(m: ActuatorStatus) -> str:
    links = "".join(" {Link %d} {Value %s} {Torque %s}" % (k.link, f4(k.value), f4(k.torque)) for k in m.links)
    gripper = "" if m.gripper is None else " {Gripper %d}" % m.gripper
    return "ASTA {Time %s} {Name %s}%s%s\r\n" % (f4(m.time), m.name, links, gripper)


# ---- parsing

_STA_KEYS = frozenset({"type", "time", "frontsteer", "rearsteer", "lighttoggle", "lightintensity", "battery", "view"})


def _parse_sta(r: _Reader) -> GroundVehicleStatus | AerialVehicleStatus:
    # Type, Time and Battery are required; UDK lines may lack the others (defaults used).
    vehicle_type = r.text("Type")
    time = r.req_float("Time")
    battery = r.req_int("Battery")
    light = r.bool(r.seg("LightToggle")) if r.raw.has("LightToggle") else False
    intensity = r.req_int("LightIntensity") if r.raw.has("LightIntensity") else 0
    view = r.req_int("View") if r.raw.has("View") else -1
    if vehicle_type == "AerialVehicle":
        return AerialVehicleStatus(
            time=time, light_toggle=light, light_intensity=intensity, battery_s=battery, view=view
        )
    joints = tuple((s.key, r.number(s)) for s in r.raw.segments if s.key.lower() not in _STA_KEYS)
    return GroundVehicleStatus(
        vehicle_type=vehicle_type,
        time=time,
        front_steer=r.opt_float("FrontSteer") or 0.0,
        rear_steer=r.opt_float("RearSteer") or 0.0,
        joints=joints,
        light_toggle=light,
        light_intensity=intensity,
        battery_s=battery,
        view=view,
    )


def _parse_asta(r: _Reader) -> ActuatorStatus:
    links = []
    for group in _groups(r.raw.segments, "Link"):
        lr = _Reader(RawMessage(r.raw.type, tuple(s for s in group if s.key.lower() != "gripper")), r.what)
        links.append(
            LinkState(link=lr.req_int("Link"), value=lr.req_float("Value"), torque=lr.opt_float("Torque") or 0.0)
        )
    gripper = r.raw.get("Gripper")
    return ActuatorStatus(
        time=r.req_float("Time"),
        name=r.text("Name"),
        links=tuple(links),
        gripper=None if gripper is None else r.req_int("Gripper"),
    )


def _parse_missta(r: _Reader) -> MisPkgStatus:
    links = []
    for group in _groups(r.raw.segments, "Link"):
        lr = _Reader(RawMessage(r.raw.type, tuple(group)), r.what)
        links.append(
            LinkState(
                link=lr.req_int("Link"),
                value=lr.req_float("Value"),
                torque=lr.req_float("Torque"),
            )
        )
    return MisPkgStatus(time=r.req_float("Time"), name=r.text("Name"), links=tuple(links))


FORMATTERS: dict[type, Callable[[Any], str]] = {
    GroundVehicleStatus: _fmt_ground_status,
    AerialVehicleStatus: _fmt_aerial_status,
    MisPkgStatus: _fmt_mispkg_status,
    ActuatorStatus: _fmt_actuator_status,
}

PARSERS: dict[str, Callable[[_Reader], StatusMessage]] = {
    "STA": _parse_sta,
    "MISSTA": _parse_missta,
    "ASTA": _parse_asta,
}
