"""What a client reads of a message: the message object it parses from the line the server
prints for it, made without printing the line where that is quick to do exactly.

:func:`as_received` serves the in-process direct path (:mod:`usarsim.client.direct`), whose
clients must see exactly what a client of the control port sees: each number at the precision
its key is printed with (a negative zero printed as a zero, an angle normalised into [0, 2 pi)
as UT printed it), the fields a line does not carry at the values a reader gives them.  A rule
covers the messages a robot reports many times a second (STEPPED, STA, MISSTA and the SEN
lines of the common sensors); for any other message, and for any value a rule cannot be sure
of (a name with spaces or braces, a number that is not finite), it returns None and the caller
prints the line and reads it back.  Every rule is checked against printing and reading back
(tests/fast/test_protocol_received.py).

Python's ``round(x, n)`` is correctly rounded, as ``%.nf`` is, so it gives the float a reader
parses from the printed digits.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from usarsim.readings import (
    EncoderItem,
    EncoderReading,
    GpsReading,
    OdometryReading,
    PackageLink,
    PackageState,
    PoseReading,
    RangeItem,
    RangeReading,
    RangeScanReading,
    RfidReading,
    RobotStatus,
    TouchItem,
    TouchReading,
    VictimReading,
)

from . import messages as M
from .numbers import TAU, t4

__all__ = ["as_received"]


class _Unsure(Exception):
    """A value the quick rules cannot be sure to read as a client would: print and read back."""


def as_received(msg: Any) -> list[Any] | None:
    """The messages a client parses from the line(s) printed for ``msg``, or None when no
    quick rule covers it (print it and read it back)."""
    rule = _RULES.get(type(msg))
    if rule is None:
        return None
    try:
        return [rule(msg)]
    except _Unsure:
        return None


# Values ----------------------------------------------------------------------------------

_PLAIN: dict[str, bool] = {}
_PLAIN_LIMIT = 4096


def _text(s: Any) -> str:
    """A name or a word as read back: only one of printable ASCII without spaces or braces is
    sure to be (the cache holds the answers for the few names a world has)."""
    ok = _PLAIN.get(s)
    if ok is None:
        ok = isinstance(s, str) and s != "" and s.isascii() and s.isprintable() and not any(c in s for c in " {}")
        if len(_PLAIN) < _PLAIN_LIMIT:
            _PLAIN[s] = ok
    if not ok:
        raise _Unsure
    return str(s)


def _r4(x: float) -> float:
    """``%.4f`` read back (``-0.0000`` reads as 0.0)."""
    if x - x != 0.0:  # inf or nan: printed as Python prints it
        raise _Unsure
    return round(x, 4) + 0.0


def _r2(x: float) -> float:
    if x - x != 0.0:
        raise _Unsure
    return round(x, 2) + 0.0


def _angle4(x: float) -> float:
    """An angle printed normalised into [0, 2 pi) at 4 decimals, read back."""
    if x - x != 0.0:
        raise _Unsure
    a = round(x % TAU, 4) + 0.0
    return 0.0 if a == _FULL_TURN else a


_FULL_TURN = round(TAU, 4)  # 6.2832, printed as 0.0000


def _int(x: Any) -> int:
    """``%d`` read back."""
    if not -(2**31) <= x < 2**31:  # and not nan: a reader's integers are of a few digits
        raise _Unsure
    return int(x)


def _vec4(v: Sequence[float]) -> tuple[float, ...]:
    return tuple([_r4(x) for x in v])


def _vec3(v: Sequence[float], read: Callable[[float], float]) -> tuple[float, float, float]:
    """A location or orientation read back: a reader takes three numbers, no more or less."""
    if len(v) != 3:
        raise _Unsure
    return (read(v[0]), read(v[1]), read(v[2]))


_T4: dict[float, float] = {}


def _t4(x: float) -> float:
    """Truncated to 4 decimals (a scanner's resolution and field of view), read back: the few
    values a world's scanners have, cached."""
    out = _T4.get(x)
    if out is None:
        if x - x != 0.0:
            raise _Unsure
        out = float(t4(x))
        if len(_T4) < _PLAIN_LIMIT:
            _T4[x] = out
    return out


def _ranges4(v: Sequence[float]) -> tuple[float, ...]:
    """A sweep's ranges at 4 decimals, read back.  NumPy rounds the scaled values to the
    nearest integer; that is the correctly rounded one except where the scaling itself may have
    crossed a half (below 1e5 m the scaled value is off by less than 1e-7), and those few are
    rounded by Python.  ``n / 10000`` is the float nearest
    the decimal, as IEEE division is correctly rounded."""
    if len(v) < 24:
        return _vec4(v)
    import numpy as np

    a = np.asarray(v, dtype=float)
    if not np.isfinite(a).all() or np.abs(a).max() >= 1e5:
        raise _Unsure
    s = a * 10000.0
    q = np.rint(s) / 10000.0 + 0.0
    near_half = np.abs(s - np.floor(s) - 0.5) < 1e-5
    if near_half.any():
        for i in np.flatnonzero(near_half):
            q[i] = round(float(a[i]), 4) + 0.0
    return tuple(q.tolist())


# Readings -------------------------------------------------------------------------------


def _kind(sensor_type: str, known: frozenset[str]) -> str:
    """A reading's {Type}, which must be one its layout is read back by."""
    if sensor_type.lower() not in known:
        raise _Unsure
    return _text(sensor_type)


_SCANNERS = frozenset({"rangescanner", "irscanner"})
_POSES = frozenset({"groundtruth", "ins"})
_RANGERS = frozenset({"sonar", "ir", "rangesensor"})


def _scan(r: RangeScanReading) -> RangeScanReading:
    return RangeScanReading(
        _kind(r.sensor_type, _SCANNERS), _text(r.name), _t4(r.resolution_rad), _t4(r.fov_rad), _ranges4(r.ranges_m)
    )


def _pose(r: PoseReading) -> PoseReading:
    return PoseReading(
        _kind(r.sensor_type, _POSES), _text(r.name), _vec3(r.location, _r4), _vec3(r.orientation, _angle4)
    )


def _range(r: RangeReading) -> RangeReading:
    return RangeReading(
        _kind(r.sensor_type, _RANGERS), tuple([RangeItem(_text(i.name), _r4(i.range_m)) for i in r.items])
    )


def _encoder(r: EncoderReading) -> EncoderReading:
    return EncoderReading(tuple([EncoderItem(_text(i.name), _int(i.tick)) for i in r.items]))


def _touch(r: TouchReading) -> TouchReading:
    return TouchReading(tuple([TouchItem(_text(i.name), bool(i.touching)) for i in r.items]))


def _odometry(r: OdometryReading) -> OdometryReading:
    return OdometryReading(_text(r.name), _r4(r.x_m), _r4(r.y_m), _r4(r.theta_rad))


def _coordinate(c: tuple[int, float, str]) -> tuple[int, float, str]:
    if c[2] not in ("N", "S", "E", "W"):
        raise _Unsure
    return (_int(c[0]), _r4(c[1]), c[2])


def _gps(r: GpsReading) -> GpsReading:
    fix = _int(r.fix) != 0
    if r.fix and r.latitude is not None and r.longitude is not None:
        return GpsReading(_text(r.name), fix, _int(r.satellites), _coordinate(r.latitude), _coordinate(r.longitude))
    return GpsReading(_text(r.name), fix, _int(r.satellites))


def _rfid(r: RfidReading) -> RfidReading:
    if r.tags:
        raise _Unsure  # tags: printed and read back
    return RfidReading(_text(r.name), ())


def _victim(r: VictimReading) -> VictimReading:
    if r.parts:
        raise _Unsure  # parts: printed and read back
    return VictimReading("VictSensor", ())  # {Status NoVictims} carries no Name


_READINGS: dict[type, Callable[[Any], Any]] = {
    RangeScanReading: _scan,
    PoseReading: _pose,
    RangeReading: _range,
    EncoderReading: _encoder,
    TouchReading: _touch,
    OdometryReading: _odometry,
    GpsReading: _gps,
    RfidReading: _rfid,
    VictimReading: _victim,
}


# Messages -------------------------------------------------------------------------------


def _sensor(m: M.SensorMessage) -> M.SensorMessage:
    rule = _READINGS.get(type(m.reading))
    if rule is None:
        raise _Unsure
    return M.SensorMessage(time=None if m.time is None else _r4(m.time), reading=rule(m.reading))


def _status(m: M.StatusMessage) -> M.StatusMessage:
    s = m.status
    battery, light, intensity, view = _int(s.battery_s), bool(s.light_toggle), _int(s.light_intensity), _int(s.view)
    if s.vehicle_type == "AerialVehicle":  # no steer angles or joints on its line
        status = RobotStatus("AerialVehicle", battery, light_toggle=light, light_intensity=intensity, view=view)
    else:
        status = RobotStatus(
            _text(s.vehicle_type),
            battery,
            _r4(s.front_steer),
            _r4(s.rear_steer),
            tuple([(_text(k), _r4(v)) for k, v in s.joints]),
            light,
            intensity,
            view,
        )
    return M.StatusMessage(time=_r2(m.time), status=status)


def _mispkg(m: M.MisPkgMessage) -> M.MisPkgMessage:
    st = m.state
    links = tuple([PackageLink(_int(k.link), _r4(k.value), _r4(k.torque)) for k in st.links])
    return M.MisPkgMessage(time=_r2(m.time), state=PackageState(_text(st.name), links))


def _stepped(m: M.Stepped) -> M.Stepped:
    return M.Stepped(time=_r4(m.time))


_RULES: dict[type, Callable[[Any], Any]] = {
    M.SensorMessage: _sensor,
    M.StatusMessage: _status,
    M.MisPkgMessage: _mispkg,
    M.Stepped: _stepped,
}


def covered(msg: Any) -> bool:
    """Whether a quick rule covers ``msg`` (for the tests: the rest is printed and read back)."""
    return type(msg) in _RULES and (not isinstance(msg, M.SensorMessage) or type(msg.reading) in _READINGS)
