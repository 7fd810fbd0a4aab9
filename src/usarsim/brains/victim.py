"""Victim approacher: explore until the victim sensor sees someone, then go to them.

It explores as the frontier explorer does (:mod:`usarsim.brains.frontier`) while it reads
the VictSensor: every body part the sensor reports is placed in the world (the sensor's
mount on the robot, the robot's pose) and grouped with the parts seen within
``GROUP_M`` of it.  A group becomes a victim once the sensor has reported it in at least
two readings and as at least two different body parts: the arenas' false alarms (a doll's
head, a glove) show one part only.  The victim's position is where its pelvis was seen (the
middle of the body), or while no pelvis was, the middle of the parts seen.  The brain then
logs the victim's estimated world position, plans a path to the floor beside it on its map and follows it, refining the
estimate as readings come; within ``reach`` metres of it the brain is done and reports
where the victim is.

    python -m usarsim.brains.victim --port 3000 --start PlayerStart1 --bounds -6,-7.2,6,7.2
"""

from __future__ import annotations

import argparse
import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from usarsim.brains.base import compose
from usarsim.brains.frontier import FrontierExplorer
from usarsim.brains.grid import Bounds, path_to
from usarsim.brains.runner import main_for, parser
from usarsim.client.core import report_line
from usarsim.readings import VictimReading

log = logging.getLogger("usarsim.brains.victim")

GROUP_M = 0.8  # parts this near each other belong to one victim


@dataclass
class Sighting:
    """Body parts seen near one place: where (their mean, world frame), which parts, in
    how many readings."""

    points: list[tuple[float, float]] = field(default_factory=list)
    pelvis: list[tuple[float, float]] = field(default_factory=list)
    parts: set[str] = field(default_factory=set)
    readings: int = 0
    last: float = 0.0

    @property
    def position(self) -> tuple[float, float]:
        """Where the pelvis was seen (a victim's position, the middle of its body), else the
        middle of the parts seen."""
        p = np.asarray(self.pelvis[-30:] if self.pelvis else self.points[-60:])
        return float(p[:, 0].mean()), float(p[:, 1].mean())

    @property
    def confirmed(self) -> bool:
        return self.readings >= 2 and len(self.parts) >= 2


class VictimApproacher(FrontierExplorer):
    """Find a victim and stop within ``reach`` metres of it.  ``found`` is the victim's
    estimated world position (x, y) once confirmed; ``done`` once the robot is beside it."""

    def __init__(self, robot: Any, *, reach: float = 1.0, **kw: Any):
        super().__init__(robot, **kw)
        self.reach = reach
        self.sightings: list[Sighting] = []
        self.found: tuple[float, float] | None = None
        self.target: Sighting | None = None
        self._last_reading: Any = None
        self._approach_plan = -math.inf

    @property
    def victims_found(self) -> list[tuple[str, float, float]]:
        """The victims confirmed so far, (name, x, y) in the world frame: what the team's map
        lists (usarsim.brains.teammap)."""
        confirmed = [s for s in self.sightings if s.confirmed]
        return [(f"V{i + 1}", *s.position) for i, s in enumerate(confirmed)]

    def look(self, pose: tuple[float, float, float]) -> None:
        """Place the parts of a new VictSensor reading in the world and group them."""
        reading = next((r for r in self.robot.readings.values() if isinstance(r, VictimReading)), None)
        if reading is None or reading is self._last_reading:
            return
        self._last_reading = reading
        sx, sy = self.body.victim_sensor_offset
        sensor = compose(pose, (sx, sy, 0.0))
        touched: set[int] = set()
        for part in reading.parts:
            wx, wy, _ = compose(sensor, (part.location[0], part.location[1], 0.0))
            best = None
            for k, s in enumerate(self.sightings):
                if math.dist(s.position, (wx, wy)) < GROUP_M:
                    best = k
                    break
            if best is None:
                self.sightings.append(Sighting())
                best = len(self.sightings) - 1
            s = self.sightings[best]
            s.points.append((wx, wy))
            if part.part_name.lower() == "pelvis":
                s.pelvis.append((wx, wy))
            s.parts.add(part.part_name)
            s.last = self.time
            touched.add(best)
        for k in touched:
            self.sightings[k].readings += 1
        if self.target is None:
            for s in self.sightings:
                if s.confirmed:
                    self.target = s
                    x, y = s.position
                    log.info(
                        "t=%.1f victim seen: estimated at %.2f, %.2f (%s)", self.time, x, y, ", ".join(sorted(s.parts))
                    )
                    self.path = []
                    break

    def approach(self, pose: tuple[float, float, float]) -> None:
        """A path to the floor beside the victim (the reachable cell within ``reach`` of it
        that is cheapest to get to)."""
        self._approach_plan = self.time
        if self.target is None:
            return
        vx, vy = self.target.position
        grid = self.fused()
        dist, parent = self.planner.search(grid, pose[:2])
        ii, jj = np.mgrid[0 : grid.shape[0], 0 : grid.shape[1]]
        cx, cy = grid.center(ii, jj)
        gap = np.hypot(cx - vx, cy - vy)
        ok = np.isfinite(dist) & (gap < self.reach - 0.15) & (gap > 0.4)
        if not ok.any():  # nothing known beside it yet: head for it through what is known
            ok = np.isfinite(dist)
            cost = gap * 10.0 + dist
        else:
            cost = dist
        cost = np.where(ok, cost, np.inf)
        k = np.unravel_index(int(np.argmin(cost)), cost.shape)
        self.goal = grid.center(*k)
        self.path = path_to(grid, parent, (int(k[0]), int(k[1])))

    def decide(self, dt: float) -> tuple[float, float]:
        pose = self.sense()
        if pose is None:
            return (0.0, 0.0)
        self.look(pose)
        if self.target is None:
            return super().decide(dt)
        vx, vy = self.target.position
        if math.dist(pose[:2], (vx, vy)) <= self.reach:
            self.found = (vx, vy)
            self.done = True
            log.info("t=%.1f beside the victim: estimated at %.2f, %.2f", self.time, vx, vy)
            # for the score (REPORT, an extension: a server without it ignores the line)
            self.robot.send(report_line((vx, vy, 0.0), "Victim1"))
            return (0.0, 0.0)
        if not self.path or self.time - self._approach_plan >= self.replan_s:
            self.approach(pose)
        if not self.path:
            return self.wheels(0.0, 0.6)
        v, w = self.follow(pose)
        return self.wheels(v, w)


def make(robot: Any, origin: tuple[float, float, float], args: argparse.Namespace) -> VictimApproacher:
    bounds = Bounds.parse(args.bounds) if args.bounds else None
    return VictimApproacher(robot, bounds=bounds, reach=args.reach, origin=origin, pose_source=args.pose)


def report(brain: VictimApproacher) -> None:
    if brain.found is not None:
        print(
            f"victim at {brain.found[0]:.2f}, {brain.found[1]:.2f} (world frame, metres); "
            f"the robot stands within {brain.reach:g} m of it",
            flush=True,
        )
    elif brain.target is not None:
        x, y = brain.target.position
        print(f"victim seen at {x:.2f}, {y:.2f} but not reached in time", flush=True)
    else:
        print("no victim found", flush=True)


def main(argv: list[str] | None = None) -> int:
    p = parser("Explore until the victim sensor sees a victim, then drive to it and report where it is.", seconds=600.0)
    p.add_argument(
        "--bounds",
        default=None,
        help="the area to search, xmin,ymin,xmax,ymax in the world frame (default: 30 m square around "
        "the start; DM-USAR_yellow's arena: -6,-7.2,6,7.2)",
    )
    p.add_argument("--reach", type=float, default=1.0, help="stop this near the victim, m (default 1.0)")
    return main_for(make, p, argv, report=report)


if __name__ == "__main__":
    raise SystemExit(main())
