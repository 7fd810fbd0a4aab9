"""What the simulation reports, as protocol messages: :func:`message_for` turns each typed
value a robot's client receives (:mod:`usarsim.readings`) into its message.

* a robot status: ``STA`` (protocol.md 6.2), the aerial layout for an ``AerialVehicle``;
* a mission package's state: ``MISSTA`` (6.4);
* the outcome of a SET: ``RES`` (6.5), ``ok`` printed ``{Status OK}`` or ``{Status Failed}``;
  a camera zoom as ``{Name cam} {FOV f} {Status s}`` per camera (5.4);
* an effecter's state: ``EFF`` (6.6), a gripper ``{Status CLOSED}`` or ``{Status OPEN}``;
* any other value is a sensor reading: ``SEN`` (6.3).
"""

from __future__ import annotations

from typing import Any

from usarsim.readings import CommandResult, EffecterState, PackageState, Refusal, RobotStatus, ZoomResult

from . import messages as M

__all__ = ["effecter_status", "message_for", "status_word"]


def status_word(ok: bool) -> str:
    """An operation's RES Status (protocol.md 5.4): ``OK`` or ``Failed``."""
    return "OK" if ok else "Failed"


def effecter_status(closed: bool) -> str:
    """A gripper's EFF Status (protocol.md 6.6): ``CLOSED`` or ``OPEN``."""
    return "CLOSED" if closed else "OPEN"


def _stamped(time: float | None) -> float:
    if time is None:
        raise ValueError("a status or a result always has its simulated time")
    return time


def message_for(value: Any, time: float | None) -> M.Message:
    """The message that reports ``value`` (a reading, a status, a result) at simulated ``time``
    (None: a sensor without time stamps)."""
    v = value
    if isinstance(v, RobotStatus):
        return M.StatusMessage(time=_stamped(time), status=v)
    if isinstance(v, EffecterState):
        return M.EffecterStatus(
            time=_stamped(time), effecter_type=v.effecter_type, name=v.name, status=effecter_status(v.closed)
        )
    if isinstance(v, PackageState):
        return M.MisPkgMessage(time=_stamped(time), state=v)
    if isinstance(v, ZoomResult):
        return M.CameraZoomResult(
            time=_stamped(time),
            cameras=tuple(M.CameraZoom(n, f, status_word(ok)) for n, f, ok in v.cameras),
            camera_type=v.camera_type,
        )
    if isinstance(v, CommandResult):
        return M.Result(
            time=_stamped(time), item_type=v.item_type, name=v.name, status=status_word(v.ok), extra=v.extra
        )
    if isinstance(v, Refusal):
        return M.error_reply(v.command, v.reason)
    return M.SensorMessage(time=time, reading=v)
