"""Frontier explorer: map the unknown with the laser and go where the map ends.

Every laser sweep goes into a log-odds occupancy grid (:mod:`usarsim.brains.grid`) at the
pose the brain believes it has (odometry composed with its start pose, by default).
About once a second, and whenever it reaches its goal, it plans: frontier cells (known free
cells beside unknown ones, in groups of at least ``min_frontier``) inside the area it was
asked to explore are candidate goals; Dijkstra's algorithm over the free cells, kept
away from obstacles by the robot's half-width and a little more, gives the path cost to
each; the goal is the frontier with the lowest path cost, plus a little for the turn it
needs, less a little for staying with the goal it had (so that it does not dither).  It
follows the path by pure pursuit (a point ``LOOKAHEAD`` metres along it), turning on the
spot when that point is far off its heading.  A goal it makes no progress towards for
``GIVE_UP_S`` seconds is put aside for a while.  When no frontier is left that it can
reach (after turning on the spot for ``NO_GOAL_S`` seconds to look around), it is done.

With odometry (the default pose source) every sweep is first fitted to the map made so far
(:class:`usarsim.brains.grid.ScanMatcher`), which corrects the odometry's drift: its
wheels slip in turns on the spot and over boxes.  Sweeps taken while the robot leans
(its INS says so: on a ramp, over a box) are left out of the map.

Obstacles the laser cannot see (a box below its beam) are found by running into them:
the bumper or a stall marks the cell ahead as occupied before the robot backs off.

In a team (:mod:`usarsim.brains.team`) each explorer also keeps the latest map each
team-mate sent; the map it plans on is its own where it has seen for itself and the sum
of theirs elsewhere, and it keeps away from the goals they announced.

    python -m usarsim.brains.frontier --port 3000 --start PlayerStart1 --bounds -6,-7.2,6,7.2 --seconds 300
"""

from __future__ import annotations

import argparse
import logging
import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from usarsim.brains.base import Brain, compose, inverse, wrap
from usarsim.brains.grid import (
    FREE_BELOW,
    L_MAX,
    L_MIN,
    OCC_ABOVE,
    Bounds,
    OccupancyGrid,
    Planner,
    ScanMatcher,
    frontier_clusters,
    path_to,
    warm_up,
)
from usarsim.brains.runner import main_for, numbers_first, parser

log = logging.getLogger("usarsim.brains.frontier")

LOOKAHEAD = 0.6  # m along the path: the point pure pursuit steers to
TURN_IN_PLACE = 0.7  # rad: beyond this off the heading, turn on the spot
GIVE_UP_S = 12.0  # s without getting 0.3 m nearer the goal: put it aside
ASIDE_S = 60.0  # ... for this long
REACHED = 0.35  # m: a goal this near is reached
NO_GOAL_S = 8.0  # s without a frontier it can reach (turning to look around): done
# The front sonars (a P2AT's F3-F6, robot file) and how near they must see something the laser
# does not for it to be a low obstacle in the way (m, from the sonars at the front edge)
FRONT_SONARS = ("F3", "F4", "F5", "F6")
LOW_OBSTACLE_M = 0.25
MAX_TILT = math.radians(3.0)  # a sweep taken leaning more than this (on a ramp, a box) is not mapped
PEER_RADIUS = 0.5  # m: beams ending this near a team-mate hit the team-mate


@dataclass
class Peer:
    """What a team-mate last sent: its map (log-odds), its position and its goal."""

    logodds: np.ndarray
    position: tuple[float, float] | None
    goal: tuple[float, float] | None
    time: float


class FrontierExplorer(Brain):
    """Explore ``bounds`` (a :class:`Bounds` in the brain's frame; default a square of
    ``2 * reach`` metres around where it starts) with a grid of ``resolution`` metres."""

    def __init__(
        self,
        robot: Any,
        *,
        bounds: Bounds | None = None,
        reach: float = 15.0,
        resolution: float = 0.1,
        speed: float = 0.5,
        replan_s: float = 1.0,
        free_limit: float = 6.0,
        min_frontier: int = 4,
        turn_weight: float = 0.4,
        keep_weight: float = 0.8,
        team_spread: float = 3.0,
        match_scans: bool | None = None,
        **kw: Any,
    ):
        super().__init__(robot, **kw)
        # odometry drifts (wheels slip in turns and over boxes): fit each sweep to the map
        self.matcher = (
            ScanMatcher() if (self.pose_source == "odometry" if match_scans is None else match_scans) else None
        )
        self.correction = (0.0, 0.0, 0.0)  # corrected pose = correction o the pose source's
        self.matched = 0
        self._lost = False  # the pose may be far off: the next match searches wide
        self._unmatched = 0
        ox, oy = self.origin[0], self.origin[1]
        self.bounds = bounds or Bounds.around(ox, oy, reach)
        # the map covers the area to explore and where the robot starts, with a margin
        margin = 1.5
        mb = Bounds(
            min(self.bounds.xmin, ox) - margin,
            min(self.bounds.ymin, oy) - margin,
            max(self.bounds.xmax, ox) + margin,
            max(self.bounds.ymax, oy) + margin,
        )
        self.own = OccupancyGrid(mb, resolution)
        self.map = self.own
        ii, jj = np.mgrid[0 : self.own.shape[0], 0 : self.own.shape[1]]
        cx, cy = self.own.center(ii, jj)
        self.region = (
            (cx > self.bounds.xmin) & (cx < self.bounds.xmax) & (cy > self.bounds.ymin) & (cy < self.bounds.ymax)
        )
        self.planner = Planner()
        self.speed, self.replan_s, self.free_limit = speed, replan_s, free_limit
        self.min_frontier, self.turn_weight, self.keep_weight, self.team_spread = (
            min_frontier,
            turn_weight,
            keep_weight,
            team_spread,
        )
        self.path: list[tuple[float, float]] = []
        self.goal: tuple[float, float] | None = None
        self.trail: list[tuple[float, float]] = []  # where it has been (brain's frame)
        self.peers: dict[str, Peer] = {}
        self.plans = 0
        self.frontiers_left = -1
        self._aside: list[tuple[float, float, float]] = []  # (x, y, until)
        self._last_plan = -math.inf
        self._last_scan: float | None = None
        self._best = (math.inf, 0.0)  # (nearest to the goal so far, when)
        self._fused = True
        self._stuck_since: float | None = None  # since when no frontier could be reached
        warm_up()

    # the map ---------------------------------------------------------------------------
    def pose(self) -> tuple[float, float, float] | None:
        raw = super().pose()
        return None if raw is None else compose(self.correction, raw)

    def sense(self) -> tuple[float, float, float] | None:
        """Put a new sweep into the map; the pose (or None before the first readings)."""
        pose = self.pose()
        scan = self.scan()
        if pose is None or scan is None:
            return pose
        if scan.time != self._last_scan and self.tilt() >= MAX_TILT:
            self._lost = True  # the wheels slip as it lurches: search wide once level again
        if scan.time != self._last_scan and self.tilt() < MAX_TILT:
            self._last_scan = scan.time
            max_range = scan.max_range or float(np.max(scan.ranges))
            bearings = self.bearings(scan)
            ranges = scan.ranges
            sx, sy = self.body.scanner_offset
            mates = self._beside_peers(pose, ranges, bearings)
            if mates.any():
                ranges, bearings = ranges[~mates], bearings[~mates]
            if self.matcher is not None:
                hit = (ranges < max_range * 0.995) & (ranges < self.free_limit)
                r, b = ranges[hit], bearings[hit]
                points = np.column_stack((sx + r * np.cos(b), sy + r * np.sin(b)))
                if len(self.trail) % 5 == 0 or self.matcher.field is None:
                    self.matcher.refresh(self.own)
                better = self.matcher.match(self.own, pose, points, wide=False)
                if better is None:
                    self._unmatched += 1
                    self._lost = self._lost or self._unmatched >= 5
                else:
                    self._lost, self._unmatched = False, 0
                    self.matched += 1
                    # not None: self.pose() above was not, and it is None only when this is
                    raw = cast("tuple[float, float, float]", super().pose())
                    self.correction = compose(better, inverse(raw))
                    pose = better
            x, y, a = pose
            c, s = math.cos(a), math.sin(a)
            origin = (x + sx * c - sy * s, y + sx * s + sy * c)
            self.own.integrate(origin, a + bearings, ranges, max_range, self.free_limit)
            self.own.clear_disk(x, y, self.body.half_width)
            self._fused = False
            if not self.trail or math.dist(self.trail[-1], (x, y)) > 0.1:
                self.trail.append((x, y))
        return pose

    def fused(self) -> OccupancyGrid:
        """The map it plans on: its own where it has seen for itself, elsewhere what its
        team-mates sent (their log-odds added up).  Their maps were made at poses of their
        own, never quite the same as this robot's: where both saw a place, its own view of
        it wins, so that a wall a team-mate drew a little aside does not close a doorway."""
        if not self.peers:
            return self.own
        if not self._fused:
            theirs = np.zeros_like(self.own.logodds)
            for p in self.peers.values():
                theirs += p.logodds
            own = self.own.logodds
            known = (own < FREE_BELOW) | (own > OCC_ABOVE)
            if self.map is self.own:
                self.map = OccupancyGrid(self.own.bounds, self.own.resolution)
            self.map.logodds = np.where(known, own, np.clip(theirs, L_MIN, L_MAX)).astype(np.float32)
            self._fused = True
        return self.map

    def receive(
        self,
        name: str,
        logodds: np.ndarray | None,
        position: tuple[float, float] | None,
        goal: tuple[float, float] | None,
    ) -> None:
        """A team-mate's latest map (None: only its position and goal), position and goal."""
        old = self.peers.get(name)
        if logodds is None:
            if old is None:
                logodds = np.zeros_like(self.own.logodds)
            else:
                logodds = old.logodds
        else:
            self._fused = False
        self.peers[name] = Peer(logodds, position, goal, self.time)

    def _beside_peers(self, pose: tuple[float, float, float], ranges: np.ndarray, bearings: np.ndarray) -> np.ndarray:
        """The beams that end on a team-mate (within ``PEER_RADIUS`` of where it last said it
        was): they are left out of the map and of the scan matching."""
        out = np.zeros(ranges.shape, bool)
        fresh = [p.position for p in self.peers.values() if p.position is not None and self.time - p.time < 2.0]
        if not fresh:
            return out
        x, y, a = pose
        sx, sy = self.body.scanner_offset
        c, s = math.cos(a), math.sin(a)
        ox, oy = x + sx * c - sy * s, y + sx * s + sy * c
        ex, ey = ox + ranges * np.cos(a + bearings), oy + ranges * np.sin(a + bearings)
        for px, py in fresh:
            out |= np.hypot(ex - px, ey - py) < PEER_RADIUS
        return out

    def start_escape(self, turn: float | None = None) -> None:
        # what it ran into is an obstacle, even if the laser did not see it (below its beam)
        pose = self.pose()
        if pose is not None and self.command[0] + self.command[1] > 0.5:
            x, y, a = pose
            ahead = self.body.half_length + 0.08
            self.own.mark_occupied(x + ahead * math.cos(a), y + ahead * math.sin(a), 0.1)
            self._fused = False
        super().start_escape(turn)
        self._last_plan = -math.inf  # plan again once free
        self._lost = True

    # planning --------------------------------------------------------------------------
    def plan(self, pose: tuple[float, float, float]) -> None:
        self.plans += 1
        self._last_plan = self.time
        grid = self.fused()
        x, y, a = pose
        labels, _ = frontier_clusters(grid, self.min_frontier)
        dist, parent = self.planner.search(grid, (x, y))
        candidates = (labels > 0) & self.region
        self._aside = [g for g in self._aside if g[2] > self.time]
        outside = 0.0
        if not (candidates & np.isfinite(dist)).any() and np.count_nonzero(
            ~grid.unknown & self.region
        ) < 0.2 * np.count_nonzero(self.region):
            # it has hardly seen the area yet (it starts far from it) and can reach none of its
            # frontiers: make for the frontiers nearest to the area
            candidates = labels > 0
            outside = 3.0
        ii, jj = np.nonzero(candidates)
        self.frontiers_left = int(ii.size)
        if ii.size == 0:
            self.path, self.goal = [], None
            return
        d = dist[ii, jj]
        ok = np.isfinite(d)
        if not ok.any():
            self.path, self.goal = [], None
            return
        ii, jj, d = ii[ok], jj[ok], d[ok]
        cx, cy = grid.center(ii, jj)
        score = d + self.turn_weight * np.abs(np.vectorize(wrap)(np.arctan2(cy - y, cx - x) - a))
        if outside:
            b = self.bounds
            score += outside * np.hypot(
                np.maximum(0.0, np.maximum(b.xmin - cx, cx - b.xmax)),
                np.maximum(0.0, np.maximum(b.ymin - cy, cy - b.ymax)),
            )
        if self.goal is not None:
            score -= self.keep_weight * (np.hypot(cx - self.goal[0], cy - self.goal[1]) < 0.6)
        for gx, gy, _ in self._aside:
            score += 100.0 * (np.hypot(cx - gx, cy - gy) < 0.8)
        for peer in self.peers.values():
            if peer.goal is not None:  # leave a team-mate's goal (and what it will see there) to it
                near = np.hypot(cx - peer.goal[0], cy - peer.goal[1])
                score += np.maximum(0.0, self.team_spread - near) * 2.0
        k = int(np.argmin(score))
        goal = (float(cx[k]), float(cy[k]))
        if self.goal is None or math.dist(goal, self.goal) > 0.6:
            self._best = (math.inf, self.time)
        self.goal = goal
        self.path = path_to(grid, parent, (int(ii[k]), int(jj[k])))

    # driving ---------------------------------------------------------------------------
    def follow(self, pose: tuple[float, float, float]) -> tuple[float, float]:
        """Pure pursuit along the path; (v, w)."""
        x, y, a = pose
        pts = np.asarray(self.path)
        d = np.hypot(pts[:, 0] - x, pts[:, 1] - y)
        near = int(np.argmin(d))
        ahead = np.nonzero(d[near:] >= LOOKAHEAD)[0]
        tx, ty = pts[near + int(ahead[0])] if ahead.size else pts[-1]
        err = wrap(math.atan2(ty - y, tx - x) - a)
        if abs(err) > TURN_IN_PLACE:
            return 0.0, math.copysign(0.9, err)
        v = self.speed * max(0.25, 1.0 - abs(err) / (TURN_IN_PLACE + 0.3))
        return v, max(-1.0, min(1.0, 2.0 * err))

    def decide(self, dt: float) -> tuple[float, float]:
        pose = self.sense()
        if pose is None:
            return (0.0, 0.0)
        x, y, _ = pose
        if self.goal is not None:
            g = math.dist((x, y), self.goal)
            if g < self._best[0] - 0.3:
                self._best = (g, self.time)
            elif self.time - self._best[1] > GIVE_UP_S:
                log.info("t=%.1f putting goal %.1f,%.1f aside", self.time, *self.goal)
                self._aside.append((self.goal[0], self.goal[1], self.time + ASIDE_S))
                self.goal, self.path = None, []
            elif g < REACHED:
                self.path = []
        if not self.path or self.time - self._last_plan >= self.replan_s:
            self.plan(pose)
            if not self.path:
                if self._stuck_since is None:
                    self._stuck_since = self.time
                if self.time - self._stuck_since > NO_GOAL_S:
                    log.info("t=%.1f no frontier left that it can reach: done", self.time)
                    self.done = True
                    return (0.0, 0.0)
                return self.wheels(0.0, 0.6)  # look around: the laser sees only ahead
            self._stuck_since = None
        v, w = self.follow(pose)
        scan = self.scan()
        if scan is not None and v > 0:
            clr = self.clearance(scan)
            front = float(np.min(clr[np.abs(self.bearings(scan)) < math.radians(30.0)]))
            sonar = self.sonar()
            low = min((sonar[n] for n in FRONT_SONARS if n in sonar), default=math.inf)
            if low < LOW_OBSTACLE_M and front > low + 0.3:
                # the front sonars see something the laser passes over (a low box): it goes
                # into the map, and the path goes round it
                _, _, a = pose
                ahead = self.body.half_length + low + 0.05
                self.own.mark_occupied(x + ahead * math.cos(a), y + ahead * math.sin(a), 0.15)
                self._fused = False
                self._last_plan = -math.inf
                v = 0.0
            elif front < 0.15:
                v = 0.0
            elif front < 0.4:
                v = min(v, 0.15)
        return self.wheels(v, w)


def make(robot: Any, origin: tuple[float, float, float], args: argparse.Namespace) -> FrontierExplorer:
    bounds = Bounds.parse(args.bounds) if args.bounds else None
    return FrontierExplorer(robot, bounds=bounds, speed=args.speed, origin=origin, pose_source=args.pose)


def report(brain: FrontierExplorer, png: str | None = None) -> None:
    known = np.count_nonzero(~brain.own.unknown & brain.region) * brain.own.resolution**2
    print(
        f"mapped {known:.1f} m2 of the area to explore; {brain.plans} plans; "
        f"{'done' if brain.done else f'{brain.frontiers_left} frontier cells left'}"
    )
    if png:
        brain.own.to_png(png, path_xy=brain.trail)
        print(f"map saved to {png}")


def main(argv: list[str] | None = None) -> int:
    p = parser("Explore: map with the laser, drive to the nearest frontier.", seconds=300.0)
    p.add_argument(
        "--bounds",
        default=None,
        help="the area to explore, xmin,ymin,xmax,ymax in the world frame (metres); default: 30 m "
        "square around the start (DM-USAR_yellow's arena: -6,-7.2,6,7.2)",
    )
    p.add_argument("--speed", type=float, default=0.5, help="top forward speed, m/s (default 0.5)")
    p.add_argument("--map", default=None, help="save the map as a PNG picture here at the end")
    args = p.parse_known_args(numbers_first(argv))[0]
    return main_for(make, p, argv, report=lambda b: report(b, args.map))


if __name__ == "__main__":
    raise SystemExit(main())
