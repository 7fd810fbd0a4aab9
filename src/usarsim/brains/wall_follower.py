"""Wall follower: keep a wall on one side (right by default) at a set distance.

From two laser beams on that side, one square to the heading and one ``BEAM_GAP`` ahead of
it, the brain works out the wall's angle to its heading and its distance (the two-beam
method of the F1TENTH course's wall-following lab), projects the distance
``LOOKAHEAD`` metres ahead and turns in proportion to the error: towards the wall when
it is too far, away when too near.  A wall ahead (an inner corner) makes it turn away
from its side; no wall at all on its side (an outer corner, a doorway) makes it curve
towards that side until it finds one again.

    python -m usarsim.brains.wall_follower --port 3000 --location -6.8,4.0,-0.25 --yaw -1.5708 --side right
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from usarsim.brains.base import Brain
from usarsim.brains.runner import main_for, parser

BEAM_GAP = math.radians(40.0)  # between the square beam and the one ahead of it
LOOKAHEAD = 0.5  # m: where the distance is projected to
FRONT_RAD = math.radians(25.0)
# A P2AT's side sonars (robot file): square to the side and 50 degrees ahead of that, about
# 0.15 m nearer the wall than the laser's centre line.
SIDE_SONARS = {"right": ("F8", "F7"), "left": ("F1", "F2")}
SONAR_INSET = 0.15


class WallFollower(Brain):
    """Follow the wall on ``side`` (``"right"`` or ``"left"``) at ``distance`` metres from
    the robot's centre, at ``speed`` m/s."""

    def __init__(
        self,
        robot: Any,
        *,
        side: str = "right",
        distance: float = 0.7,
        speed: float = 0.35,
        gain: float = 1.6,
        **kw: Any,
    ):
        super().__init__(robot, **kw)
        if side not in ("right", "left"):
            raise ValueError(f"side must be right or left, got {side!r}")
        self.side = side
        self.sign = 1.0 if side == "right" else -1.0  # the side's bearing sign (clockwise positive)
        self.distance, self.speed, self.gain = distance, speed, gain
        self.wall: tuple[float, float] | None = None  # the latest (distance, angle) of the wall

    def _beam(self, bearings: np.ndarray, ranges: np.ndarray, bearing: float) -> float:
        """The range of the beam nearest ``bearing`` (the median of it and its neighbours)."""
        k = int(np.argmin(np.abs(bearings - bearing)))
        return float(np.median(ranges[max(0, k - 1) : k + 2]))

    def measure(self, scan: Any) -> tuple[float, float] | None:
        """(distance from the robot's centre to the wall on its side, the wall's angle to
        the heading: negative when the wall closes in ahead), or None without a wall in
        reach."""
        bear = self.bearings(scan)
        ranges = np.asarray(scan.ranges, float)
        a = self._beam(bear, ranges, self.sign * math.pi / 2.0)
        b = self._beam(bear, ranges, self.sign * (math.pi / 2.0 - BEAM_GAP))
        # the side sonars see what stands below the laser (boxes, crates): the nearer wins
        sonar = self.sonar()
        square, slanted = SIDE_SONARS[self.side]
        if square in sonar:
            a = min(a, sonar[square] + SONAR_INSET)
        if slanted in sonar:
            b = min(b, sonar[slanted] + SONAR_INSET)
        reach = 2.5 * self.distance + 0.5
        if a > reach or b > reach / math.cos(BEAM_GAP):
            return None
        alpha = math.atan2(b * math.cos(BEAM_GAP) - a, b * math.sin(BEAM_GAP))
        # from the laser to the wall, then from the robot's centre (the laser sits ahead of it)
        d = a * math.cos(alpha) - self.body.scanner_offset[0] * math.sin(alpha)
        return d, alpha

    def decide(self, dt: float) -> tuple[float, float]:
        scan = self.scan()
        if scan is None:
            return (0.0, 0.0)
        clr = self.clearance(scan)
        bear = self.bearings(scan)
        front = float(np.min(clr[np.abs(bear) <= FRONT_RAD]))
        sonar = self.sonar()
        ahead = [sonar[n] for n in ("F3", "F4", "F5", "F6") if n in sonar]
        if ahead:
            front = min(front, min(ahead) - 0.03)
        s = self.sign
        if front < self.distance - self.body.half_length + 0.15:
            # a wall ahead: turn away from the followed side, on the spot if it is close
            v = 0.0 if front < 0.25 else self.speed * 0.3
            return self.wheels(v, -s * 0.9)
        self.wall = self.measure(scan)
        if self.wall is None:
            # nothing on that side: curve towards it (round an outer corner, find a wall)
            return self.wheels(self.speed * 0.7, s * 0.7 * self.speed / max(self.distance, 0.3))
        d, alpha = self.wall
        ahead_d = d + LOOKAHEAD * math.sin(alpha)
        err = ahead_d - self.distance  # > 0: too far from the wall
        w = s * self.gain * err
        w = max(-1.0, min(1.0, w))
        v = self.speed * max(0.3, 1.0 - abs(err) / 0.6)
        return self.wheels(v, w)


def make(robot: Any, origin: tuple[float, float, float], args: argparse.Namespace) -> WallFollower:
    return WallFollower(
        robot, side=args.side, distance=args.distance, speed=args.speed, origin=origin, pose_source=args.pose
    )


def main(argv: list[str] | None = None) -> int:
    p = parser("Follow a wall on one side at a set distance (laser).", seconds=120.0)
    p.add_argument("--side", default="right", choices=("right", "left"), help="the wall's side (default right)")
    p.add_argument("--distance", type=float, default=0.7, help="from the robot's centre to the wall, m (default 0.7)")
    p.add_argument("--speed", type=float, default=0.35, help="forward speed, m/s (default 0.35)")
    return main_for(make, p, argv)


if __name__ == "__main__":
    raise SystemExit(main())
