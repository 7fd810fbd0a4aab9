"""What every brain shares: the robot's pose and laser in the form a controller wants them,
wheel speeds from a forward speed and a turn rate, and sending DRIVE only when it changes.

A brain is given a :class:`usarsim.client.Robot` and is stepped once per control period:
``brain.step(dt)`` reads the robot's latest readings (the client keeps them up to date
while :meth:`World.step` or :meth:`World.wait` runs), decides, sends its DRIVE and returns
the wheel speeds ``(left, right)`` in rad/s.  The same brain therefore runs in real time
(``world.wait(dt)`` between steps) or in lock-step (``world.step(dt)``), and a program, or
an environment wrapping the simulator, can step it alongside anything else.

Frames are USARSim's: X forward, Y right, Z down, yaw positive clockwise seen from above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from usarsim.readings import RangeReading, TouchReading


def wrap(a: float) -> float:
    """An angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


def compose(a: tuple[float, float, float], b: tuple[float, float, float]) -> tuple[float, float, float]:
    """Pose ``b`` given in the frame of pose ``a``, in a's parent frame ((x, y, yaw))."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + b[0] * c - b[1] * s, a[1] + b[0] * s + b[1] * c, wrap(a[2] + b[2]))


def inverse(a: tuple[float, float, float]) -> tuple[float, float, float]:
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-a[0] * c - a[1] * s, a[0] * s - a[1] * c, wrap(-a[2]))


@dataclass(frozen=True)
class Body:
    """What a brain needs to know of its robot's build.  The defaults are a P2AT's (its
    robot file, whose Odometry TrackWidth is the calibrated track width)."""

    wheel_radius: float = 0.13  # m
    track_width: float = 0.552  # m: the effective track of a skid-steered robot (turns slip)
    max_wheel_speed: float = 5.385  # rad/s
    half_length: float = 0.262  # m: chassis origin to the front (and back) of the robot
    half_width: float = 0.249  # m: chassis origin to its side
    scanner_offset: tuple[float, float] = (0.144, 0.0)  # the laser's X, Y on the robot (m)
    victim_sensor_offset: tuple[float, float] = (0.206, 0.0)  # the VictSensor's, pan and tilt at 0

    @property
    def radius(self) -> float:
        return math.hypot(self.half_length, self.half_width)


P2AT = Body()
STALL_S = 1.5  # driven this long without moving: stalled
TILT_BASELINE_S = 20.0  # s: how slowly the level the robot leans from follows its INS


class Brain:
    """Base of the brains: subclasses implement :meth:`decide`.

    ``pose_source`` says where the brain's pose comes from: ``"odometry"`` (dead reckoning,
    composed with ``origin``, the world pose the robot started from: then the brain's map
    is in world coordinates; with ``gyro``, its turns are the INS's when the robot has one),
    ``"ins"`` (the INS sensor, world frame) or ``"truth"`` (the
    GroundTruth sensor: exact, for debugging; competitions took it off the robots).  With
    odometry, ``calibrate`` sets the Odometry sensor's TrackWidth to the body's effective
    track width first, so that it counts turns right."""

    def __init__(
        self,
        robot: Any,
        *,
        body: Body = P2AT,
        origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
        pose_source: str = "odometry",
        calibrate: bool = True,
        gyro: bool = True,
    ):
        if pose_source not in ("odometry", "ins", "truth"):
            raise ValueError(f"pose_source must be odometry, ins or truth, got {pose_source!r}")
        self.robot = robot
        self.body = body
        # three values in, three out
        self.origin = cast("tuple[float, float, float]", tuple(float(v) for v in origin))
        self.pose_source = pose_source
        self.done = False  # set when the brain has finished its task
        self.time = 0.0  # control time: the sum of the dt given to step()
        self.command = (0.0, 0.0)
        self._sent: tuple[float, float] | None = None
        self._level: tuple[float, ...] | None = None  # the INS's roll and pitch when level
        self.gyro = gyro
        self._reckoned: tuple[float, float, float] | None = None  # dead reckoning (pose source odometry)
        self._last_odo: tuple[float, float, float] | None = None
        self._last_yaw: float | None = None  # the INS's yaw at the last step
        self.escapes = 0  # times it backed off something it ran into
        self._escape: list[tuple[float, float, float]] = []  # (seconds, v, w) still to do
        self._history: list[tuple[float, tuple[float, float, float], bool]] = []  # (time, pose, driving)
        if calibrate and pose_source == "odometry":
            # the odometry's turns with the effective track width (docs/robot-files.md)
            robot.set("Odometry", "Odometry", "TrackWidth", body.track_width)

    # the control loop --------------------------------------------------------------------
    def step(self, dt: float) -> tuple[float, float]:
        """One control period: decide and send the wheel speeds (rad/s) if they changed."""
        self.time += dt
        if self.done:
            left, right = 0.0, 0.0
        else:
            self._dead_reckon()
            self._follow_level(dt)
            self._watch()
            if not self._escape and (self.touching() or self.stalled()):
                self.start_escape()
            left, right = self._escaping(dt) if self._escape else self.decide(dt)
        left, right = self.limit(left, right)
        self.command = (left, right)
        rounded = (round(left, 3), round(right, 3))
        if rounded != self._sent:
            self.robot.drive(left=rounded[0], right=rounded[1])
            self._sent = rounded
        return self.command

    def decide(self, dt: float) -> tuple[float, float]:
        raise NotImplementedError

    # running into things -----------------------------------------------------------------
    def _watch(self) -> None:
        pose = self.pose()
        if pose is None:
            return
        driving = max(abs(self.command[0]), abs(self.command[1])) > 0.5 and not self._escape
        # where it is by its INS when it has one: inertial, so it does not move on with wheels
        # that spin (a robot hung up on a box the laser passes over, its odometry running on)
        ins = self._ins()
        if ins is not None:
            pose = (ins.location[0], ins.location[1], ins.orientation[2])
        self._history.append((self.time, pose, driving))
        while self._history and self.time - self._history[0][0] > STALL_S + 0.5:
            self._history.pop(0)

    def stalled(self) -> bool:
        """True when the wheels have been driven for STALL_S seconds and the robot has
        neither moved nor turned (by its INS, else its pose): it is pushing against something
        (a P2AT's motors stall at a wall), or hung up on something with its wheels spinning."""
        recent = [h for h in self._history if self.time - h[0] <= STALL_S]
        if not recent or self.time - recent[0][0] < STALL_S - 0.15 or not all(h[2] for h in recent):
            return False
        (x0, y0, a0), (x1, y1, a1) = recent[0][1], recent[-1][1]
        return math.hypot(x1 - x0, y1 - y0) < 0.04 and abs(wrap(a1 - a0)) < 0.06

    def start_escape(self, turn: float | None = None) -> None:
        """Back off for a moment, then turn on the spot (``turn`` +1 right, -1 left;
        default: towards the side the laser shows more room on)."""
        if turn is None:
            turn = 1.0
            scan = self.scan()
            if scan is not None:
                clr = np.minimum(self.clearance(scan), 3.0)
                bear = self.bearings(scan)
                right, left = clr[bear > 0.3], clr[bear < -0.3]
                turn = 1.0 if (right.mean() if right.size else 0.0) >= (left.mean() if left.size else 0.0) else -1.0
        self.escapes += 1
        self._escape = [(0.8, -0.2, 0.0), (1.0, 0.0, turn * 0.8)]
        self._history.clear()

    def _escaping(self, dt: float) -> tuple[float, float]:
        seconds, v, w = self._escape[0]
        seconds -= dt
        if seconds <= 1e-9:
            self._escape.pop(0)
        else:
            self._escape[0] = (seconds, v, w)
        return self.wheels(v, w)

    def stop(self) -> None:
        """Wheels to zero."""
        self.robot.drive(left=0.0, right=0.0)
        self._sent = (0.0, 0.0)
        self.command = (0.0, 0.0)

    # motion ------------------------------------------------------------------------------
    def wheels(self, v: float, w: float) -> tuple[float, float]:
        """Wheel speeds (rad/s) for ``v`` m/s forward and ``w`` rad/s of turn (clockwise,
        to the right, positive), scaled down together when a wheel would exceed its top
        speed (the turn is kept)."""
        b = self.body
        left = (v + w * b.track_width / 2.0) / b.wheel_radius
        right = (v - w * b.track_width / 2.0) / b.wheel_radius
        return self.limit(left, right)

    def limit(self, left: float, right: float) -> tuple[float, float]:
        top = max(abs(left), abs(right))
        if top > self.body.max_wheel_speed:
            k = self.body.max_wheel_speed / top
            left, right = left * k, right * k
        return float(left), float(right)

    # what the robot knows ----------------------------------------------------------------
    def pose(self) -> tuple[float, float, float] | None:
        """(x, y, yaw) in the brain's frame (see ``pose_source``), or None before the first
        reading."""
        if self.pose_source == "truth":
            gt = self.robot.ground_truth()
            return None if gt is None else (gt[0][0], gt[0][1], wrap(gt[1][2]))
        if self.pose_source == "ins":
            for r in self.robot.readings.values():
                if getattr(r, "sensor_type", None) == "INS":
                    return (r.location[0], r.location[1], wrap(r.orientation[2]))
            return None
        if self._reckoned is None:
            self._dead_reckon()
        return self._reckoned

    def _dead_reckon(self) -> None:
        """Odometry: the distance the wheels rolled, along the heading.  With ``gyro`` and
        an INS, the heading turns as the INS's does (it follows the body, whose turns the
        wheels, slipping, miscount, above all as the robot lurches over a box); otherwise
        as the odometry's."""
        if self.pose_source != "odometry":
            return
        odo = self.robot.odometry()
        if odo is None:
            return
        ins = next((r for r in self.robot.readings.values() if getattr(r, "sensor_type", None) == "INS"), None)
        yaw = ins.orientation[2] if ins is not None and self.gyro else None
        if self._reckoned is None or self._last_odo is None:
            self._reckoned = compose(self.origin, odo)
        else:
            (x0, y0, a0), (x1, y1, a1) = self._last_odo, odo
            ds = (x1 - x0) * math.cos(a0) + (y1 - y0) * math.sin(a0)  # along the heading it had
            turn = wrap(yaw - self._last_yaw) if yaw is not None and self._last_yaw is not None else wrap(a1 - a0)
            x, y, a = self._reckoned
            mid = a + turn / 2.0
            self._reckoned = (x + ds * math.cos(mid), y + ds * math.sin(mid), wrap(a + turn))
        self._last_odo, self._last_yaw = odo, yaw

    def tilt(self) -> float:
        """How far the robot leans now (the larger of |roll| and |pitch|, radians) by its
        INS, or 0 without one: measured from the INS's slow-moving average of them (a time
        constant of ``TILT_BASELINE_S``, updated once a step), as the INS's integrated roll
        and pitch drift a little each time the robot leans and comes back."""
        now = self._ins_level()
        if now is None or self._level is None:
            return 0.0
        return max(abs(wrap(n - b)) for n, b in zip(now, self._level))

    def _ins(self) -> Any:
        """The INS's latest reading, or None."""
        return next((r for r in self.robot.readings.values() if getattr(r, "sensor_type", None) == "INS"), None)

    def _ins_level(self) -> tuple[float, float] | None:
        ins = self._ins()
        return None if ins is None else (wrap(ins.orientation[0]), wrap(ins.orientation[1]))

    def _follow_level(self, dt: float) -> None:
        now = self._ins_level()
        if now is None:
            return
        if self._level is None:
            self._level = now
        k = min(1.0, dt / TILT_BASELINE_S)
        self._level = tuple(b + wrap(n - b) * k for b, n in zip(self._level, now))

    def scan(self) -> Any:
        """The latest laser sweep (:class:`usarsim.client.Scan`) or None."""
        return self.robot.scan()

    def bearings(self, scan: Any) -> np.ndarray:
        """The scan's beam directions as USARSim yaw offsets: clockwise (to the right) positive."""
        return -np.asarray(scan.angles, dtype=float)

    def clearance(self, scan: Any) -> np.ndarray:
        """For every beam, how far the robot could go along it before its body touches what
        the beam hit: the range less the distance from the laser to the edge of the robot's
        footprint in that direction (metres; negative: already touching)."""
        b = self.body
        bear = self.bearings(scan)
        c, s = np.cos(bear), np.sin(bear)
        sx, sy = b.scanner_offset
        # distance from the laser to the rectangle's edge along each beam
        with np.errstate(divide="ignore"):
            tx = np.where(c > 1e-9, (b.half_length - sx) / c, np.where(c < -1e-9, (-b.half_length - sx) / c, np.inf))
            ty = np.where(s > 1e-9, (b.half_width - sy) / s, np.where(s < -1e-9, (-b.half_width - sy) / s, np.inf))
        inside = np.minimum(tx, ty)
        return np.asarray(scan.ranges, dtype=float) - inside

    def sonar(self) -> dict[str, float]:
        """The latest sonar ranges by sensor name (empty without sonars)."""
        out: dict[str, float] = {}
        for r in self.robot.readings.values():
            if isinstance(r, RangeReading) and r.sensor_type == "Sonar":
                out.update((item.name, item.range_m) for item in r.items)
        return out

    def touching(self) -> bool:
        """True while a Touch sensor of the robot reads True."""
        for r in self.robot.readings.values():
            if isinstance(r, TouchReading):
                return any(item.touching for item in r.items)
        return False
