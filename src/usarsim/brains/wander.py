"""Wander: drive about without touching anything, the first brain of Pyro's tutorials
(manual 13.2) grown a little.

It drives forward while the laser (and the front sonars, which see boxes below the laser)
show room ahead, steering away from the nearer side; when something comes within
``near`` metres of its front it turns on the spot towards the side with more room until
the way ahead is clear for ``clear`` metres, and now and then it picks a new gentle
curve (from its own seeded random generator) so that it does not trace the same loop
for ever.  If its bumper (Touch) closes, or its wheels turn without the robot moving, it
backs off and turns (as every brain does: :meth:`Brain.start_escape`).

    python -m usarsim.brains.wander --port 3000 --start PlayerStart1 --seconds 120
"""

from __future__ import annotations

import argparse
import logging
import math
from typing import Any

import numpy as np

from usarsim.brains.base import Brain
from usarsim.brains.runner import main_for, parser

log = logging.getLogger("usarsim.brains.wander")

FRONT_RAD = math.radians(35.0)  # "ahead": the beams within this of the heading
SIDE_RAD = (math.radians(35.0), math.radians(100.0))  # the sides: between these off the heading


class Wander(Brain):
    """Obstacle-avoiding wander (see the module's description).  ``speed`` m/s at most
    forward, ``turn_rate`` rad/s on the spot."""

    def __init__(
        self,
        robot: Any,
        *,
        speed: float = 0.45,
        turn_rate: float = 0.9,
        near: float = 0.45,
        clear: float = 0.9,
        seed: int = 0,
        **kw: Any,
    ):
        super().__init__(robot, **kw)
        self.speed, self.turn_rate, self.near, self.clear = speed, turn_rate, near, clear
        self.rng = np.random.default_rng(seed)
        self.mode = "forward"
        self.turn_dir = 1.0
        self.mode_time = 0.0
        self.curve = 0.0  # the gentle turn rate it drifts with (rad/s)
        self.curve_left = 0.0
        self.distance = 0.0  # metres driven (by the brain's pose)
        self._last_xy: tuple[float, float] | None = None

    def room(self) -> tuple[float, float, float] | None:
        """Clearance (m) ahead, to the left and to the right, or None before a scan."""
        scan = self.scan()
        if scan is None:
            return None
        clr = self.clearance(scan)
        bear = self.bearings(scan)
        front = float(np.min(clr[np.abs(bear) <= FRONT_RAD]))
        right = (bear > SIDE_RAD[0]) & (bear <= SIDE_RAD[1])
        left = (bear < -SIDE_RAD[0]) & (bear >= -SIDE_RAD[1])
        sonar = self.sonar()
        ahead = [sonar[n] for n in ("F3", "F4", "F5", "F6") if n in sonar]
        if ahead:
            front = min(front, min(ahead) - 0.03)  # the sonars sit at the front edge
        return front, float(np.mean(np.minimum(clr[left], 3.0))), float(np.mean(np.minimum(clr[right], 3.0)))

    def _odometer(self) -> None:
        pose = self.pose()
        if pose is None:
            return
        xy = (pose[0], pose[1])
        if self._last_xy is not None:
            self.distance += math.dist(xy, self._last_xy)
        self._last_xy = xy

    def set_mode(self, mode: str) -> None:
        if mode != self.mode:
            log.info("t=%.1f %s -> %s", self.time, self.mode, mode)
        self.mode = mode
        self.mode_time = 0.0

    def decide(self, dt: float) -> tuple[float, float]:
        self.mode_time += dt
        self._odometer()
        room = self.room()
        if room is None:
            return (0.0, 0.0)
        front, left, right = room
        if self.mode == "turn":
            if front > self.clear and self.mode_time > 0.4:
                self.set_mode("forward")
            elif self.mode_time > 8.0:  # no way out this way: back off and try the other
                self.turn_dir = -self.turn_dir
                self.start_escape(self.turn_dir)
                self.set_mode("turn")
                return self.wheels(-0.2, 0.0)
            else:
                return self.wheels(0.0, self.turn_dir * self.turn_rate)
        # forward
        if front < self.near:
            self.turn_dir = 1.0 if right > left else -1.0
            if abs(right - left) < 0.1:
                self.turn_dir = 1.0 if self.rng.random() < 0.5 else -1.0
            self.set_mode("turn")
            return self.wheels(0.0, self.turn_dir * self.turn_rate)
        self.curve_left -= dt
        if self.curve_left <= 0:
            self.curve = float(self.rng.uniform(-0.25, 0.25))
            self.curve_left = float(self.rng.uniform(2.0, 6.0))
        v = self.speed * min(1.0, 0.25 + (front - self.near) / 1.2)
        # away from the nearer side (more so when it is near), plus the drift
        w = self.curve + 0.6 * (right - left) / max(0.5, min(left, right) + 0.5)
        w = max(-0.8, min(0.8, w))
        return self.wheels(v, w)


def make(robot: Any, origin: tuple[float, float, float], args: argparse.Namespace) -> Wander:
    return Wander(robot, speed=args.speed, seed=args.seed, origin=origin, pose_source=args.pose)


def main(argv: list[str] | None = None) -> int:
    p = parser("Wander about, avoiding obstacles (laser and sonar).", seconds=120.0)
    p.add_argument("--speed", type=float, default=0.45, help="top forward speed, m/s (default 0.45)")
    p.add_argument("--seed", type=int, default=0, help="seed of its random turns (default 0)")
    return main_for(make, p, argv, report=lambda b: print(f"drove {b.distance:.1f} m"))


if __name__ == "__main__":
    raise SystemExit(main())
