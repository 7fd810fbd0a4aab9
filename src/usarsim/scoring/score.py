"""The score of a run, from the simulator's ground truth (docs/scoring.md), modelled on the
RoboCup Rescue virtual-robot competitions: victims found and reported, floor explored,
distance travelled, collisions, robots lost, radio contact, and one combined score.

:class:`Scorer` is fed what the simulation hands its observers, in order: frames of the world
(:class:`usarsim.sim.types.WorldFrame`, poses every 0.1 simulated seconds, radio links every
second, the push of each robot against static solids) and the outputs the robots' clients get
(victim-sensor readings, laser sweeps, REPORT answers).  It does no I/O; :meth:`result` gives
the score as a JSON-ready dict at any time.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from typing import cast

import numpy as np

from usarsim.config.world import WorldConfig
from usarsim.coverage import CoverageGrid
from usarsim.readings import CommandResult, RangeScanReading, VictimReading
from usarsim.sim.types import LinkTraffic, Output, WorldFrame, euler_to_mat

# Floor explored: cells of this size over the world's floor, marked along every laser beam
# from the scanner to what it hit, up to SCAN_RANGE_M (the reach at which a laser's map of a
# room is still worth having; our choice, the same as usarsim/Explore-v0's sensing range).
CELL_M = 0.1
SCAN_RANGE_M = 8.0
# A reported victim counts when the report lies within this distance (horizontal, metres) of
# a victim not yet counted (our choice: about a body's half-length plus a map's error).
REPORT_RADIUS_M = 1.0
# A collision: a push against a static solid (a wall, a box, a near-vertical face) of more than
# this force (newtons) after none; a P2AT (14 kg) driving into a wall pushes with well over
# 100 N (its wheels' grip), one resting against a wall with almost none.
COLLISION_FORCE_N = 30.0
# Lost: battery empty, upside down (flipped), or stuck: moved less than STUCK_DISTANCE_M over the
# last STUCK_WINDOW_S simulated seconds of the run (counted only for a robot there that long).
STUCK_DISTANCE_M = 0.25
STUCK_WINDOW_S = 60.0
# A move between two frames shorter than this is the physics' jitter, not travel.
JITTER_M = 0.0005


@dataclass(frozen=True)
class Weights:
    """The combined score's weights (docs/scoring.md): points per victim, per square metre
    explored, per collision, per robot lost, per false report, and for radio contact all the
    time (times the team's share of time in contact)."""

    victim: float = 50.0
    area_m2: float = 1.0
    collision: float = -5.0
    robot_lost: float = -20.0
    false_report: float = -10.0
    radio_contact: float = 10.0


@dataclass
class RobotScore:
    """What the score keeps of one robot (docs/scoring.md): victims it found, distance travelled (m), collisions, why
    it was lost, its samples in radio contact, the floor cells its lasers explored, and the recent poses and battery
    it is judged lost by."""

    name: str
    class_name: str
    victims_found: set[str] = field(default_factory=set)
    distance_m: float = 0.0
    collisions: int = 0
    pushing: bool = False  # against a static solid at the last frame
    lost: str | None = None
    contact_samples: int = 0
    samples: int = 0
    area_cells: set[int] = field(default_factory=set)
    first_time: float = 0.0
    track: deque = field(default_factory=lambda: deque())  # (time, x, y) over the stuck window
    poses: deque = field(default_factory=lambda: deque(maxlen=64))  # (time, x, y, yaw) of recent frames
    battery_s: float = 0.0
    flipped: bool = False


class Scorer:
    """The score of a run, kept from the world frames and the robots' outputs fed to it in order (:meth:`frame`,
    :meth:`outputs`); :meth:`result` gives it as a JSON-ready dict at any time."""

    def __init__(
        self,
        world: WorldConfig,
        *,
        seed: int = 0,
        weights: Weights | None = None,
        mounts: dict[str, dict[str, tuple]] | None = None,
    ):
        self.world = world
        self.seed = seed
        self.weights = weights or Weights()
        fl = world.floor
        bounds = (
            fl.center[0] - fl.size[0] / 2,
            fl.center[1] - fl.size[1] / 2,
            fl.center[0] + fl.size[0] / 2,
            fl.center[1] + fl.size[1] / 2,
        )
        self.grid = CoverageGrid(bounds, CELL_M)
        self.robots: dict[str, RobotScore] = {}
        self._names: dict[int, str] = {}
        self.mounts: dict[str, dict[str, tuple]] = mounts if mounts is not None else {}  # class -> item -> mount
        self.time = 0.0
        self.reports: list[tuple[str, tuple[float, float, float], str | None]] = []  # (robot, where, victim)
        self._reported: set[str] = set()
        self.false_reports = 0
        self._victims = [(v.name, v.location) for v in world.victims]
        self._waiting: dict[int, list[Output]] = {}
        self.traffic: dict[tuple[str, str], LinkTraffic] = {}  # what the radio channel carried, by link

    # Feeding ---------------------------------------------------------------------------
    def frame(self, f: WorldFrame) -> None:
        self.time = max(self.time, f.time)
        present = set()
        for r in f.robots:
            present.add(r.name)
            self._names[r.uid] = r.name
            s = self.robots.get(r.name)
            if s is None:
                s = self.robots[r.name] = RobotScore(r.name, r.config.class_name, first_time=f.time)
            x, y = r.location[0], r.location[1]
            if s.poses:
                _, px, py, _ = s.poses[-1]
                step = math.hypot(x - px, y - py)
                if step > JITTER_M:
                    s.distance_m += step
            s.poses.append((f.time, x, y, r.rotation[2]))
            s.track.append((f.time, x, y))
            while s.track and s.track[0][0] < f.time - STUCK_WINDOW_S - 1e-9:
                s.track.popleft()
            pushing = r.wall_force_n > COLLISION_FORCE_N
            if pushing and not s.pushing:
                s.collisions += 1
            s.pushing = pushing
            s.battery_s = r.battery_s
            rot = euler_to_mat(*r.rotation)
            s.flipped = rot[2][2] < 0.0  # the robot's own down axis points up
            for o in self._waiting.pop(r.uid, ()):
                self.output(o)
        if f.traffic is not None:
            self.traffic = {(t.src, t.dst): t for t in f.traffic}  # counts since the start: the latest
        if f.links is not None:
            up: set[str] = set()
            for ln in f.links:
                if ln.holds:
                    up.add(ln.a)
                    up.add(ln.b)
            for name in present:
                s = self.robots[name]
                s.samples += 1
                if name.lower() in up:
                    s.contact_samples += 1

    def outputs(self, outs: list[Output]) -> None:
        for o in outs:
            self.output(o)

    def output(self, o: Output) -> None:
        v = o.value
        if not isinstance(v, (VictimReading, RangeScanReading, CommandResult)):
            return
        name = self._names.get(o.uid)
        if name is None:  # spawned since the last frame: waits for it
            self._waiting.setdefault(o.uid, []).append(o)
            return
        s = self.robots[name]
        if isinstance(v, VictimReading):
            s.victims_found.update(p.victim for p in v.parts if p.victim)
        elif isinstance(v, RangeScanReading):
            self._scan(s, v, o.time if o.time is not None else self.time)
        elif v.item_type == "Victim":
            where = dict(v.extra).get("Location")
            if isinstance(where, str):
                where = tuple(float(c) for c in where.split(","))
            if where is not None:
                # a REPORT's location (usarsim.sim.facade): its three floats, or their text
                self._report(name, cast(tuple[float, float, float], tuple(cast(Iterable[float], where))))

    def _scan(self, s: RobotScore, v: RangeScanReading, t: float) -> None:
        pose = _pose_at(s.poses, t)
        if pose is None:
            return
        _, x, y, yaw = pose
        mx, my, myaw = self.mounts.get(s.class_name, {}).get(v.name, (0.0, 0.0, 0.0))
        c, sn = math.cos(yaw), math.sin(yaw)
        origin = (x + c * mx - sn * my, y + sn * mx + c * my)
        ranges = np.minimum(np.asarray(v.ranges_m, dtype=float), SCAN_RANGE_M)
        n = len(ranges)
        if n == 0:
            return
        half = (n - 1) * v.resolution_rad / 2.0
        # USARSim's first beam is the rightmost; headings clockwise from X (the USARSim yaw)
        headings = yaw + myaw + np.linspace(half, -half, n)
        new = self.grid.mark_beams(origin, headings, ranges)
        s.area_cells.update(new.tolist())

    def _report(self, robot: str, where: tuple[float, float, float]) -> None:
        best, best_d = None, REPORT_RADIUS_M
        for name, loc in self._victims:
            if name in self._reported:
                continue
            d = math.hypot(where[0] - loc[0], where[1] - loc[1])
            if d <= best_d:
                best, best_d = name, d
        if best is None:
            self.false_reports += 1
        else:
            self._reported.add(best)
        self.reports.append((robot, where, best))

    # The score -------------------------------------------------------------------------
    def _lost(self, s: RobotScore) -> str | None:
        if s.battery_s <= 0.0:
            return "battery"
        if s.flipped:
            return "flipped"
        if s.track and self.time - s.first_time >= STUCK_WINDOW_S - 1e-9:
            xs = [p[1] for p in s.track]
            ys = [p[2] for p in s.track]
            if max(math.hypot(x - xs[-1], y - ys[-1]) for x, y in zip(xs, ys, strict=True)) < STUCK_DISTANCE_M:
                return "stuck"
        return None

    def result(self) -> dict:
        w = self.weights
        robots = {}
        found: set[str] = set()
        distance = 0.0
        collisions = 0
        lost = 0
        shares = []
        cell_area = self.grid.cell_area_m2
        for name, s in self.robots.items():
            why = self._lost(s)
            share = s.contact_samples / s.samples if s.samples else 0.0
            robots[name] = {
                "class": s.class_name,
                "victims_found": sorted(s.victims_found),
                "area_m2": round(len(s.area_cells) * cell_area, 3),
                "distance_m": round(s.distance_m, 3),
                "collisions": s.collisions,
                "lost": why,
                "radio_contact_share": round(share, 4),
            }
            found |= s.victims_found
            distance += s.distance_m
            collisions += s.collisions
            lost += why is not None
            shares.append(share)
        area = self.grid.seen_m2
        team_share = float(np.mean(shares)) if shares else 0.0
        traffic = list(self.traffic.values())
        counted = len(self._reported) if self.reports else len(found)
        score = (
            w.victim * counted
            + w.area_m2 * area
            + w.collision * collisions
            + w.robot_lost * lost
            + w.false_report * self.false_reports
            + w.radio_contact * team_share
        )
        return {
            "world": self.world.name,
            "seed": self.seed,
            "time_s": round(self.time, 3),
            "weights": asdict(w),
            "team": {
                "score": round(score, 3),
                "victims_found": len(found),
                "victims_reported": len(self._reported),
                "false_reports": self.false_reports,
                "area_m2": round(area, 3),
                "distance_m": round(distance, 3),
                "collisions": collisions,
                "robots_lost": lost,
                "radio_contact_share": round(team_share, 4),
                "messages_delivered": sum(t.delivered for t in traffic),
                "messages_lost": sum(t.dropped for t in traffic),
            },
            "robots": robots,
            "radio": {
                f"{t.src}>{t.dst}": {
                    "delivered": t.delivered,
                    "delivered_bytes": t.delivered_bytes,
                    "dropped": {"range": t.dropped_range, "loss": t.dropped_loss, "capacity": t.dropped_capacity},
                    "dropped_bytes": t.dropped_bytes,
                    "mean_delay_s": round(t.mean_delay_s, 6),
                }
                for t in sorted(traffic, key=lambda t: (t.src, t.dst))
            },
        }

    def line(self) -> str:
        """One line of the score now (``usarsim serve --score``)."""
        r = self.result()
        t = r["team"]
        return (
            f"score t={r['time_s']:.1f} s: {t['score']:.1f} (victims {t['victims_found']} found, "
            f"{t['victims_reported']} reported, {t['false_reports']} false; area {t['area_m2']:.1f} m2; "
            f"distance {t['distance_m']:.1f} m; collisions {t['collisions']}; robots lost {t['robots_lost']}; "
            f"radio contact {100 * t['radio_contact_share']:.0f} %"
            + (
                f"; messages lost {t['messages_lost']} of {t['messages_delivered'] + t['messages_lost']})"
                if self.traffic
                else ")"
            )
        )


def _pose_at(poses: deque, t: float) -> tuple | None:
    """The frame pose nearest ``t`` (frames come every 0.1 s; reports fall on the same grid)."""
    if not poses:
        return None
    return min(poses, key=lambda p: abs(p[0] - t))


def laser_mounts(descriptions) -> dict[str, tuple[float, float, float]]:
    """Item name -> (x, y, yaw) of each mounted item on the robot (its GEO mount, USARSim frame)."""
    return {d.name: (float(d.location[0]), float(d.location[1]), float(d.orientation[2])) for d in descriptions}
