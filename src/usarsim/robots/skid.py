"""Skid steering (protocol.md 5.3a): wheeled and tracked robots that turn by driving their
sides at different speeds (P2AT, P2DX, ATRVJr, Zerg, Talon, TeleMax, Kenaf...).

How they turn on the spot.  A robot pivots when its sides run in opposite directions and
every wheel (or track) scrubs sideways over the floor: the floor's pull along the treads
turns the robot, the friction across them resists.  With the same friction coefficient in
both directions the moment balance of a robot on uniformly loaded treads (the wheels at
+-L/2 along, +-B/2 across) gives a pivot rate of (B/2)^2 / ((B/2)^2 + (L/2)^2) of the
differential-drive rate (rim speed)/(B/2) for four wheels, and far less for a long
track (about a third for a teleMAX), while real skid-steered robots pivot nearly on the
differential-drive rate on a hard floor: their treads (knobby tyres, grousered rubber
tracks, track belts that ride on road wheels) slide sideways far more easily than they slip
along their rolling direction.  The model builder therefore gives a skid-steered robot's
wheels direction-dependent friction on the floor (:class:`~usarsim.robots.base.Treads`):
the surface's friction along the tread, a fraction of it across (``lateral_ratio``).

That fraction follows from the same moment balance.  A robot can turn on the spot at all
only while the friction moment of its treads across, mu_t W L / 4 (uniform ground pressure
on a tread of length L), is below what the floor's pull along them can give, mu W B / 2: mu_t
/ mu < 2 B / L (B the distance between the sides' treads).  The lateral friction here is
TREAD_STEER_MARGIN times B / L of the friction along (at most the same): an eighth of the
largest value with which the robot could pivot.  With it every shipped skid-steered robot
pivots at 82 to 98 % of the differential-drive rate on the arena floor (docs/robot-files.md
lists them), close to the ideal rate as a real skid-steered robot on a hard floor.  Only the
floor has tread contacts (a contact pair per wheel): on ramps, decks and other objects a
wheel grips alike in every direction, and a robot turns there more slowly.

How far they turn for the wheels' turning.  As its wheels scrub sideways, a skid-steered
robot turns less than its wheel speeds would turn a differential drive: its treads turn about
instantaneous centres of rotation (ICRs) further apart than the wheels, by a factor that stays
nearly the same for a robot on a given floor (Martinez et al., "Approximating kinematics for
tracked mobile robots", IJRR 24(10), 2005; Mandow et al., "Experimental kinematics for wheeled
skid-steer mobile robots", IROS 2007, for the Pioneer 3-AT), so that odometry calibrated once
(an effective track width, usarsim.sensors.motion.Odometry) holds at every speed.  Scrubbing
makes the robot shiver on its contacts (a few tenths of a millimetre, about 11 times a
second), and how it shivers (pitching, rolling, both) decides how much its wheels slip.  On
MuJoCo's default contact (0.02 s, critically damped) a P2AT falls into one way or another by
the turn's speeds, and its wheels count 1.10 to 1.22 times its turn, by no rule of the speed.
The tread's contact is a little softer and more damped (TREAD_SOLREF): over 0.3 to 1.5
rad/s asked for, in place and on arcs at up to 0.4 m/s, the factor is 1.16 to 1.20 in 98 %
of turns (1.16 to 1.21 in all), and the robot still comes to rest within a second of landing.

The wheels of a side turn together (``chained``): a track is one belt over its wheels, and
the wheeled skid-steered robots shipped (Pioneer P2AT/P3AT, ATRV-Jr, Kurt, Zerg) are
modelled as driving a side's wheels from one motor through a chain or toothed belt (the
Pioneer's chain drive).  The builder couples them with joint equality constraints (the
same rim speed for wheels of different sizes), so that a wheel pressed against a wall
cannot spin while its neighbour stalls, and the drivetrain's inertia (``drive_inertia_kg``)
is shared by the side.
"""

from __future__ import annotations

import math

import mujoco

from usarsim.config.robot import RobotConfig, Wheel
from usarsim.controls import WheelSpeeds
from usarsim.errors import ConfigError
from usarsim.robots.base import DRIVES, DriveModel, Treads, clamp

# The tread's friction across its rolling direction: this times B / L of the friction along
# it (at most the same).  An estimate (no robot's tread data are published): an eighth of
# the most with which the robot could pivot at all (the moment balance above).
TREAD_STEER_MARGIN = 0.25
# How the tread's contact with the floor gives: MuJoCo's solref (time constant, s; damping
# ratio), whose default is (0.02, 1): MuJoCo documentation, Modeling, Solver parameters.
# Estimate, chosen by measurement ("How far they turn" above): three times as compliant as the
# default (a loaded P2AT tyre sinks 0.04 mm instead of 0.014) and 2.3 times critically
# damped.  More damping evens the slip further but leaves a robot creeping for seconds after a
# bump; less leaves the over-count of a turn depending on its speed.
TREAD_SOLREF = (0.015, 2.3)
# A wheel whose lowest point is within this of the lowest wheel's touches a level floor.
ON_GROUND_M = 0.005


def chained(robot: RobotConfig) -> bool:
    """Whether the wheels of each side turn together: yes unless the robot file says
    ``chained: false`` (every shipped skid-steered robot is chained, see above)."""
    return robot.chained


def ground_wheels(robot: RobotConfig) -> list[tuple[Wheel, tuple[float, float, float]]]:
    """The driven wheels that touch a level floor when the robot stands on it with its links
    at rest, each with its axle's place on the chassis (USARSim frame)."""
    placed = []
    for w in robot.wheels:
        if not w.driven:
            continue
        if w.parent == "chassis":
            pos = w.position
        else:
            o = robot.link_origin(w.parent)
            pos = (o[0] + w.position[0], o[1] + w.position[1], o[2] + w.position[2])
        placed.append((w, pos))
    if not placed:
        return []
    low = max(p[2] + w.radius_m for w, p in placed)
    return [(w, p) for w, p in placed if p[2] + w.radius_m > low - ON_GROUND_M]


def lateral_friction_ratio(robot: RobotConfig) -> float:
    """The tread's friction across its rolling direction as a fraction of that along it:
    TREAD_STEER_MARGIN x B / L for the wheels on the ground (B: twice their mean distance
    from the centre line; L: the length they span), at most 1 (a robot on one axle)."""
    placed = ground_wheels(robot)
    if not placed:
        return 1.0
    xs = [p[0] for _, p in placed]
    span = max(xs) - min(xs)
    gauge = 2.0 * sum(abs(p[1]) for _, p in placed) / len(placed)
    if span <= 1e-9:
        return 1.0
    return min(1.0, TREAD_STEER_MARGIN * gauge / span)


@DRIVES.register("skid")
class Skid(DriveModel[WheelSpeeds, None]):
    """``DRIVE {Left} {Right}``: each side's wheels (tracks) spin at its speed, rad/s within
    the robot's MaxSpeed (percent of it when Normalized); a side not sent keeps its speed.
    On a chained side every wheel runs at the same rim speed: the speed is that of a wheel
    of the robot's WheelRadius (GEO), a smaller wheel of the track turns faster."""

    ACCEPTS = frozenset({WheelSpeeds})

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        self.left = 0.0
        self.right = 0.0
        self.chained = chained(robot)
        ref = robot.geometry.wheel_radius_m
        self._rim = {w.name: (ref / w.radius_m if self.chained and ref > 0 else 1.0) for w in robot.wheels}

    @classmethod
    def check(cls, robot: RobotConfig) -> None:
        if not (any(w.side == "left" for w in robot.wheels) and any(w.side == "right" for w in robot.wheels)):
            raise ConfigError(
                "a skid-steered robot needs at least one left and one right wheel", path=robot.path, key="wheels"
            )

    @classmethod
    def treads(cls, robot: RobotConfig) -> Treads:
        # the drivetrain's inertia at the rim: the mass a wheel carries.  Estimate: a geared
        # motor's rotor inertia times the square of its gear ratio is of that order (a
        # 1e-5 kg m^2 rotor through 50:1 gearing: 0.025 kg m^2, 1.5 kg at a 0.13 m rim, for
        # the 3.5 kg a P2AT wheel carries)
        driven = sum(1 for w in robot.wheels if w.driven)
        return Treads(
            lateral_ratio=lateral_friction_ratio(robot),
            drive_inertia_kg=robot.mass_kg / max(1, driven),
            solref=TREAD_SOLREF,
        )

    @classmethod
    def build(cls, spec: mujoco.MjSpec, chassis: mujoco.MjsBody, robot: RobotConfig, prefix: str) -> None:
        """Chain each side's driven wheels to its first one (equal rim speeds)."""
        if not chained(robot):
            return
        for side in ("left", "right"):
            wheels = [w for w in robot.wheels if w.side == side and w.driven]
            for w in wheels[1:]:
                eq = spec.add_equality()
                eq.name = f"{prefix}/{w.name}/chain"
                eq.type = mujoco.mjtEq.mjEQ_JOINT
                eq.name1 = f"{prefix}/{w.name}"
                eq.name2 = f"{prefix}/{wheels[0].name}"
                # q_w = (r_first / r_w) q_first: the same belt speed at both rims
                eq.data[0:5] = [0.0, wheels[0].radius_m / w.radius_m, 0.0, 0.0, 0.0]

    def command(self, part: WheelSpeeds, normalized: bool) -> None:
        vmax = self.robot.max_speed_rad_s
        scale = vmax / 100.0 if normalized else 1.0
        if part.left is not None and math.isfinite(part.left):
            self.left = clamp(part.left * scale, vmax)
        if part.right is not None and math.isfinite(part.right):
            self.right = clamp(part.right * scale, vmax)
        if part.left is not None or part.right is not None:
            self.wheel_speed.clear()  # a skid DRIVE takes the wheels back from joint orders

    def wheel_target(self, w: Wheel) -> float:
        return (self.left if w.side == "left" else self.right) * self._rim[w.name]

    def ordered_speed(self, w: Wheel) -> float | None:
        """A joint order on one wheel of a chained side drives the whole side (the chain):
        each wheel at the same rim speed as the ordered one."""
        own = self.wheel_speed.get(w.name)
        if own is not None or not self.chained or not self.wheel_speed:
            return own
        for other in self.robot.wheels:
            speed = self.wheel_speed.get(other.name)
            if speed is not None and other.side == w.side:
                return speed / self._rim[other.name] * self._rim[w.name]
        return None

    def on_battery_empty(self) -> None:
        self.left = self.right = 0.0
        super().on_battery_empty()
