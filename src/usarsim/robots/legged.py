"""Walking robots (drive ``legged``): the AIBO (ERS) trots, the QRIO walks.

A gait engine (the world system :class:`Gaits`) sets the leg joints' angles every
GAIT_STEPS physics steps: each foot stands
for ``duty`` of a period, staying where it was put while the body moves over it, then
swings forward, lifted, to where it will stand; a biped sways over its standing foot.
DRIVE {LinearVelocity} {LateralVelocity} {RotationalVelocity} (protocol.md 5.3d) sets the
walking speeds; {Left} {Right} (5.3a) are taken as a skid-steered robot's sides: their
mean the forward speed, their difference the turn rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import mujoco

from usarsim.config.reader import FieldDefaults, Section, did_you_mean
from usarsim.config.robot import Link, RobotConfig
from usarsim.controls import Velocities, WheelSpeeds
from usarsim.errors import ConfigError
from usarsim.robots.base import DRIVES, DriveModel, clamp
from usarsim.sim import joints
from usarsim.sim.systems.base import SYSTEMS, System

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext
    from usarsim.sim.robot import SimRobot

GAIT_STEPS = 5  # a walking robot's joint targets are renewed every 5 physics steps (20 ms)


@dataclass(frozen=True, kw_only=True)
class Leg:
    """One leg of a walking robot: its hip pitch, hip roll and knee links, the lengths of
    its upper and lower segments, and its phase in the gait (0..1).  A biped's leg also
    has a hip yaw (it turns the foot) and ankle pitch and roll links (they keep the sole
    flat); its chain then runs yaw, roll, pitch, knee, ankle pitch, ankle roll, and
    ``knee_forward`` bends its knee forward, as a person's does."""

    hip_pitch: str
    hip_roll: str
    knee: str
    upper_m: float
    lower_m: float
    phase: float = 0.0
    hip_yaw: str | None = None
    ankle_pitch: str | None = None
    ankle_roll: str | None = None
    knee_forward: bool = False

    @property
    def joints(self) -> tuple[str, ...]:
        return tuple(
            j
            for j in (self.hip_yaw, self.hip_roll, self.hip_pitch, self.knee, self.ankle_pitch, self.ankle_roll)
            if j is not None
        )


@dataclass(frozen=True, kw_only=True)
class Gait:
    """A walking robot's gait (DRIVE {LinearVelocity} {LateralVelocity} {RotationalVelocity}):
    the robot file's ``gait`` section."""

    legs: tuple[Leg, ...]
    stand_height_m: float  # hip to foot, standing
    step_height_m: float = 0.02
    period_s: float = 0.5
    max_linear_m_s: float = 0.2
    max_lateral_m_s: float = 0.1
    max_yaw_rate_rad_s: float = 0.8
    # fraction of a period each foot stands: 0.5 trots; above it every step begins and
    # ends with both feet down (a biped's double support)
    duty: float = 0.5
    sway_m: float = 0.0  # how far the body shifts sideways over the standing foot


def read_gait(gs: Section, links: set[str]) -> Gait:
    """A robot file's ``gait`` section; every leg joint it names is one of ``links``."""
    ld = FieldDefaults(Leg)
    legs = []
    for ls in gs.entries("legs", required=True):
        leg = Leg(
            hip_pitch=ls.str("hip_pitch"),
            hip_roll=ls.str("hip_roll"),
            knee=ls.str("knee"),
            upper_m=ls.float("upper_m", min=0.001),
            lower_m=ls.float("lower_m", min=0.001),
            phase=ls.float("phase", ld.phase, min=0.0, max=1.0),
            hip_yaw=ls.str("hip_yaw", ld.hip_yaw),
            ankle_pitch=ls.str("ankle_pitch", ld.ankle_pitch),
            ankle_roll=ls.str("ankle_roll", ld.ankle_roll),
            knee_forward=ls.bool("knee_forward", ld.knee_forward),
        )
        for j in leg.joints:
            if j not in links:
                raise ConfigError(f"unknown leg joint '{j}'{did_you_mean(j, links)}", path=gs.path, key=gs.key)
        legs.append(leg)
    d = FieldDefaults(Gait)
    out = Gait(
        legs=tuple(legs),
        stand_height_m=gs.float("stand_height_m", min=0.001),
        step_height_m=gs.float("step_height_m", d.step_height_m, min=0.0),
        period_s=gs.float("period_s", d.period_s, min=0.05),
        max_linear_m_s=gs.float("max_linear_m_s", d.max_linear_m_s, min=0.0, min_exclusive=True),
        max_lateral_m_s=gs.float("max_lateral_m_s", d.max_lateral_m_s, min=0.0, min_exclusive=True),
        max_yaw_rate_rad_s=gs.float("max_yaw_rate_rad_s", d.max_yaw_rate_rad_s, min=0.0, min_exclusive=True),
        duty=gs.float("duty", d.duty, min=0.5, max=0.95),
        sway_m=gs.float("sway_m", d.sway_m, min=0.0),
    )
    gs.finish()
    two_legs_apart = len(out.legs) == 2 and abs(abs(out.legs[0].phase - out.legs[1].phase) - 0.5) <= 1e-6
    if out.sway_m > 0.0 and not two_legs_apart:
        raise gs.error("sway_m", "only a biped sways: two legs half a period apart (phase 0 and 0.5)")
    return out


def leg_ik(
    fx: float, fy: float, fz: float, upper: float, lower: float, knee_forward: bool = False
) -> tuple[float, float, float]:
    """Hip pitch, hip roll and knee angles that put a foot at (fx, fy, fz) from its hip
    (USARSim frame: forward, right, down), for a leg of two segments whose knee bends
    backwards (or forwards, as a person's, with ``knee_forward``).  Positive pitch swings
    the leg forward, positive roll swings it left, a positive knee folds the lower leg
    forward.  The roll turns the plane in which pitch and knee move."""
    roll = -math.atan2(fy, fz)
    down = math.hypot(fy, fz)
    d = min(max(math.hypot(fx, down), abs(upper - lower) + 1e-6), (upper + lower) * 0.999)
    inner = math.acos(max(-1.0, min(1.0, (upper**2 + lower**2 - d**2) / (2 * upper * lower))))
    beta = math.acos(max(-1.0, min(1.0, (upper**2 + d**2 - lower**2) / (2 * upper * d))))
    if knee_forward:
        return math.atan2(fx, down) + beta, roll, inner - math.pi
    return math.atan2(fx, down) - beta, roll, math.pi - inner


def _smooth(x: float) -> float:
    """0 to 1 over x in [0, 1], with zero slope at both ends."""
    return 0.5 - 0.5 * math.cos(math.pi * min(1.0, max(0.0, x)))


@DRIVES.register("legged")
class Legged(DriveModel[Velocities | WheelSpeeds, Gait]):
    """The gait of a walking robot, and the velocities it walks at."""

    ACCEPTS = frozenset({Velocities, WheelSpeeds})
    SET_DOWN_ALWAYS = True
    SETTINGS = "gait"
    SETTINGS_REQUIRED = True

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        self.gait: Gait = self.settings
        self.walk = {"linear": 0.0, "lateral": 0.0, "rotational": 0.0}
        self.sides = [0.0, 0.0]  # the last {Left} {Right}, rad/s (or percent)
        # the gait's clock; how far it has set off (0 standing, 1 walking; it fades in over
        # ``gait_rise`` seconds and out over half a period); whether its speed follows the
        # command before that (a gait that starts on all its feet); the velocities it walks
        # at (they follow the command within half a period); each foot's place (forward,
        # right, yaw) from under its hip and where its swing began; the time the gait was
        # last set
        self.gait_clock = 0.0
        self.gait_amp = 0.0
        self.gait_rise = 0.0
        self.gait_walks_at_once = False
        self.gait_vel: tuple[float, ...] = (0.0, 0.0, 0.0)
        self.gait_last = 0.0
        self.feet: list[list[float]] = []
        self.swing_from: list[list[float] | None] = []

    def _leg_link(self, name: str) -> Link:
        link = self.robot.link(name)
        if link is None:
            raise ConfigError(
                f"the gait names a leg joint the robot has no link of: {name}", path=self.robot.path, key="gait"
            )
        return link

    @classmethod
    def read_settings(cls, section: Section, robot: RobotConfig) -> Gait:
        return read_gait(section, {ln.name for ln in robot.links})

    @classmethod
    def lowest_point_m(cls, robot: RobotConfig) -> float:
        """Standing on its legs: hip, leg and foot (a ball or a sole), or its body if lower."""
        low = [robot.body_lowest_point_m]
        gait = cls.settings_of(robot)
        for leg in gait.legs:
            # a leg's joints are links of the robot (checked when the gait is read)
            if leg.ankle_pitch is None:
                knee = cast(Link, robot.link(leg.knee))
                foot = max((p.radius_m for p in knee.shapes if p.shape == "sphere"), default=0.0)
            else:
                sole = cast(Link, robot.link(leg.ankle_roll or leg.ankle_pitch))
                foot = max((p.center[2] + p.size[2] / 2.0 for p in sole.shapes if p.shape == "box"), default=0.0)
            low.append(robot.link_origin(leg.hip_pitch)[2] + gait.stand_height_m + foot)
        return max(low)

    def command(self, part: Velocities | WheelSpeeds, normalized: bool) -> None:
        g = self.gait
        if isinstance(part, WheelSpeeds):
            # a side's speed as a fraction of the robot's MaxSpeed (or of 100 %): the mean of
            # the two sides walks forward, their difference turns (left faster: right turn)
            for i, v in enumerate((part.left, part.right)):
                if v is not None and math.isfinite(v):
                    self.sides[i] = v
            top = 100.0 if normalized else self.robot.max_speed_rad_s
            fwd = (self.sides[0] + self.sides[1]) / 2.0 / top
            turn = (self.sides[0] - self.sides[1]) / 2.0 / top
            self.walk["linear"] = clamp(fwd * g.max_linear_m_s, g.max_linear_m_s)
            self.walk["rotational"] = clamp(turn * g.max_yaw_rate_rad_s, g.max_yaw_rate_rad_s)
            return
        for key, value, top in (
            ("linear", part.linear, g.max_linear_m_s),
            ("lateral", part.lateral, g.max_lateral_m_s),
            ("rotational", part.rotational, g.max_yaw_rate_rad_s),
        ):
            if value is not None and math.isfinite(value):
                self.walk[key] = clamp(value * top / 100.0 if normalized else value, top)

    def pre_step(self, sim: WorldContext, r: SimRobot) -> None:
        """Set the leg joints of a walking robot for this instant of its gait.  Each foot
        stands for ``duty`` of a period, staying where it was put while the body moves
        over it (the commanded speed, side speed and turn rate carry the body), then swings
        forward, lifted, to where it will stand evenly about its hip at the current speed:
        a trot for four legs at duty 0.5 (diagonal legs together), a walk for two legs
        above it, with both feet down at the start and end of every step while the body
        sways over the foot that will stand alone.  Hip yaw joints turn the feet with the
        ground, ankles keep the soles flat.  The walking speed follows the command within
        half a period.  Setting off from rest, a gait whose feet all stand at its start (duty
        above 0.5: a biped's double support) sways over its first standing foot while the
        other is still down, (duty - 0.5) / 2 of a period, lifts that one with a full step
        and speeds up from the first instant; a gait that lifts feet at once (a trot) fades
        its steps in over half a period before it speeds up.  It comes to rest over half a
        period.  At rest its feet are back under its hips and its joints are left to joint
        commands."""
        g = self.gait
        if r.battery_empty:
            return
        cmd = (self.walk["linear"], self.walk["lateral"], self.walk["rotational"])
        moving = any(abs(c) > 1e-6 for c in cmd)
        if not moving and self.gait_amp <= 0.0:
            return  # standing: its joints are the client's (DRIVE Name groups, MULTIDRIVE)
        n = len(g.legs)
        dt = max(0.0, sim.time - self.gait_last)
        self.gait_last = sim.time
        half = 0.5 * g.period_s
        if self.gait_amp <= 0.0:  # setting off: both feet down, the body between them
            self.gait_clock = (g.duty - 0.5) / 2.0 * g.period_s
            self.gait_amp, dt = 1e-9, 0.0
            self.gait_vel = (0.0, 0.0, 0.0)
            self.feet = [[0.0, 0.0, 0.0] for _ in range(n)]
            self.swing_from = [None] * n
            # every foot stands until the first lifts, (duty - 0.5) / 2 of a period from
            # now: the sway is built by then, and the first step is a whole one; a trot
            # lifts feet at once and fades its steps in over half a period
            self.gait_walks_at_once = g.duty > 0.5
            self.gait_rise = self.gait_clock if self.gait_walks_at_once else half
        else:
            self.gait_clock += dt
        tops = (g.max_linear_m_s, g.max_lateral_m_s, g.max_yaw_rate_rad_s)
        if self.gait_amp >= 1.0 or self.gait_walks_at_once:  # the speed follows the command
            self.gait_vel = tuple(
                cur + max(-top * dt / half, min(top * dt / half, c - cur))
                for cur, c, top in zip(self.gait_vel, cmd if moving else (0.0, 0.0, 0.0), tops)
            )
        at_rest = not any(self.gait_vel) and all(abs(x) < 1e-4 for f in self.feet for x in f)
        if moving or not at_rest:  # (stopped while setting off, it still steps its feet back under it)
            self.gait_amp = min(1.0, self.gait_amp + dt / self.gait_rise)
        else:  # coming to rest over half a period; a command meanwhile fades it in over as long
            self.gait_amp = max(0.0, self.gait_amp - dt / half)
            self.gait_rise, self.gait_walks_at_once = half, False
        # the feet: standing ones stay on the ground as the body moves, swinging ones go
        # to where they will stand
        stance_t = g.duty * g.period_s
        v, lat, w = self.gait_vel
        reach = 0.4 * (g.legs[0].upper_m + g.legs[0].lower_m)
        for i, leg in enumerate(g.legs):
            hip = self.robot.link_origin(leg.hip_pitch)
            ground = (v - w * hip[1], lat + w * hip[0], w)  # how the ground moves past the hip
            p = (self.gait_clock / g.period_s + leg.phase) % 1.0
            f = self.feet[i]
            if p < g.duty or self.gait_amp < 1.0:
                if self.swing_from[i] is not None and self.gait_amp >= 1.0:  # it landed p x period ago
                    for j in range(3):
                        f[j] = ground[j] * (stance_t / 2.0 - p * g.period_s)
                else:
                    for j in range(3):
                        f[j] -= ground[j] * dt
                self.swing_from[i] = None
            else:
                start = self.swing_from[i]
                if start is None:  # it stood until (p - duty) x period ago
                    stood = max(0.0, dt - (p - g.duty) * g.period_s)
                    start = self.swing_from[i] = [x - gx * stood for x, gx in zip(f, ground)]
                s_ = _smooth((p - g.duty) / (1.0 - g.duty))
                for j in range(3):
                    f[j] = start[j] + (ground[j] * stance_t / 2.0 - start[j]) * s_
            f[0] = max(-reach, min(reach, f[0]))
            f[1] = max(-reach, min(reach, f[1]))
            f[2] = max(-0.8, min(0.8, f[2]))
        if self.gait_amp <= 0.0:
            self.feet = [[0.0, 0.0, 0.0] for _ in range(n)]
        for name, value in self._leg_targets(self.gait_clock, self.gait_amp):
            r.joints[name] = (0, value)
            joints.apply(sim.model, sim.data, r, self._leg_link(name))

    def _leg_targets(self, t: float, amp: float) -> list[tuple[str, float]]:
        """The angle of every leg joint of a walking robot at time ``t`` of its gait, its
        feet where ``self.feet`` puts them, its sway and steps scaled by ``amp`` (0: standing,
        every foot under its hip)."""
        g = self.gait
        # a swaying robot sways first and steps once it sways fully
        step_amp = max(0.0, 2.0 * amp - 1.0) if g.sway_m > 0.0 else amp
        phases = [(t / g.period_s + leg.phase) % 1.0 for leg in g.legs]
        # a biped's body sways sideways (right positive) as a sine of the gait, furthest
        # over the standing foot in the middle of the other foot's swing: the smooth sway
        # keeps the point where the feet carry the weight inside the standing sole
        shift = 0.0
        if amp > 0.0 and g.sway_m > 0.0:
            side = self.robot.link_origin(g.legs[0].hip_pitch)[1]
            shift = -math.copysign(g.sway_m * min(1.0, 2.0 * amp), side) * math.cos(
                2.0 * math.pi * (phases[0] - (g.duty + 1.0) / 2.0)
            )
        targets = []
        for i, (leg, p) in enumerate(zip(g.legs, phases)):
            fx, fy, yaw = self.feet[i] if amp > 0.0 and self.feet else (0.0, 0.0, 0.0)
            fy -= shift
            fz = g.stand_height_m
            if amp > 0.0 and p >= g.duty:  # swinging: lifted
                fz -= g.step_height_m * step_amp * math.sin(math.pi * (p - g.duty) / (1.0 - g.duty))
            if leg.hip_yaw is not None:
                fx, fy = math.cos(yaw) * fx + math.sin(yaw) * fy, -math.sin(yaw) * fx + math.cos(yaw) * fy
            pitch, roll, knee = leg_ik(fx, fy, fz, leg.upper_m, leg.lower_m, leg.knee_forward)
            targets += [(leg.hip_pitch, pitch), (leg.hip_roll, roll), (leg.knee, knee)]
            if leg.hip_yaw is not None:
                targets.append((leg.hip_yaw, yaw))
            if leg.ankle_pitch is not None:
                targets.append((leg.ankle_pitch, -(pitch + knee)))
            if leg.ankle_roll is not None:
                targets.append((leg.ankle_roll, -roll))
        return targets

    def on_spawn(self, sim: WorldContext, r: SimRobot) -> None:
        """A walking robot is built standing: its leg joints start at their standing angles."""
        m, d = sim.model, sim.data
        for name, value in self._leg_targets(0.0, 0.0):
            r.joints[name] = (0, value)
            d.qpos[r.handle.joint_qpos[name]] = value
            d.act[int(m.actuator_actadr[r.handle.actuator[name]])] = value
            joints.apply(sim.model, sim.data, r, self._leg_link(name))
        mujoco.mj_forward(m, d)


@SYSTEMS.register("gaits")
class Gaits(System):
    """The walking robots' gaits: each sets its leg joints' targets before a stretch of at
    most GAIT_STEPS physics steps."""

    ORDER = 60
    EVERY_STEPS = GAIT_STEPS

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        return any(isinstance(r.drive, Legged) for r in sim.robots.values())

    def pre_step(self) -> None:
        sim = self.sim
        for r in sim.robots.values():
            if isinstance(r.drive, Legged):
                r.drive.pre_step(sim, r)
