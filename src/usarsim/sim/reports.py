"""When each robot reports: STA and MISSTA every status period, each sensor at its own
ScanInterval of simulated time (packed sensors of one type together, in one SEN line).

Every report falls on the world's grid of its period (multiples of it in simulated time,
from the first one at or after the spawn): the reports of all robots fall on the same
instants, so that the physics runs in long stretches between them.
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from usarsim.sensors import Sensor

if TYPE_CHECKING:
    from usarsim.sim.robot import SimRobot

EPS = 1e-9


@dataclass(eq=False)
class Report:
    """A scheduled report: the robot's status (STA), a mission package's state (MISSTA),
    one sensor, or all packed sensors of a type on the robot."""

    robot: SimRobot
    sensors: list[Sensor]
    interval: float
    t0: float
    key: str
    status: bool = False
    package: object = None  # a MissionPackage: MISSTA
    k: int = 0

    @property
    def due(self) -> float:
        return self.t0 + self.k * self.interval


class ReportSchedule:
    """The reports of every robot, soonest first."""

    def __init__(self) -> None:
        self._heap: list[tuple[float, int, Report]] = []
        self._seq = itertools.count()

    def next_due(self) -> float | None:
        return self._heap[0][0] if self._heap else None

    def add_robot(self, r: SimRobot, now: float) -> None:
        """Every report of ``r`` on its own period, from the first grid instant at or after
        ``now``."""

        def on_grid(interval: float) -> float:
            return math.ceil(now / interval - 1e-6) * interval

        period = r.config.status_interval_s
        reports = [Report(r, [], period, on_grid(period), "STA", status=True)]
        for pkg in r.config.mission_packages:
            reports.append(Report(r, [], period, on_grid(period), f"MISSTA:{pkg.name}", package=pkg))
        packed: dict[str, Report] = {}
        for s in r.sensors:
            if not s.PERIODIC:
                continue
            if s.PACKED:
                rep = packed.get(s.TYPE)
                if rep is None:
                    rep = Report(r, [], s.config.scan_interval_s, on_grid(s.config.scan_interval_s), f"SEN:{s.TYPE}")
                    packed[s.TYPE] = rep
                    reports.append(rep)
                rep.sensors.append(s)
            else:
                reports.append(Report(r, [s], s.config.scan_interval_s, on_grid(s.config.scan_interval_s),
                                      f"SEN:{s.TYPE}:{s.name}"))
        r.reports = reports
        for rep in reports:
            heapq.heappush(self._heap, (rep.due, next(self._seq), rep))

    def take_due(self, now: float) -> list[Report]:
        """The reports due at ``now`` (of robots still there), in order; each is scheduled
        again at the first multiple of its interval after ``now``."""
        heap = self._heap
        out = []
        while heap and heap[0][0] <= now + EPS:
            _, _, rep = heapq.heappop(heap)
            if rep.robot.removed:
                continue
            rep.k += 1
            while rep.due <= now + EPS:
                rep.k += 1
            heapq.heappush(heap, (rep.due, next(self._seq), rep))
            out.append(rep)
        return out
