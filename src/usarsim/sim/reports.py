"""When each robot reports: STA and MISSTA every status period, each sensor at its own
ScanInterval of simulated time (packed sensors of one type together, in one SEN line).

Every report falls on the world's grid of its period (multiples of it in simulated time,
from the first one at or after the spawn): the reports of all robots fall on the same
instants, so that the physics runs in long stretches between them.

With the phases spread (``serve --report-phases spread``), each robot's grid is shifted by a
share of the period of its own, as USARSim's sensor timers were by the robots' spawns: the k-th
robot spawned reports at ``phase + n * period`` with ``phase`` = :func:`spread_share` (k) of the
period, on a physics step.  The readings of many robots then come in small groups instead of
one burst an instant (what a client that turns every line into something else, as the ROS 2
bridge does, waits on), for more simulation CPU (the physics stops more often: about a third
more with 16 P2ATs in real time).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from usarsim.sim.settings import REPORT_PHASES

if TYPE_CHECKING:
    from usarsim.sensors.base import Sensor
    from usarsim.sim.robot import SimRobot

EPS = 1e-9
SPREAD_SLOTS = 8  # report phases a period is shared into with the phases spread (a power of two)


def spread_share(k: int) -> float:
    """The k-th robot's share of a period with the phases spread: ``k`` modulo
    :data:`SPREAD_SLOTS`, its bits reversed, so that robots spawned one after another fall
    as far apart as they can (0, 1/2, 1/4, 3/4, 1/8, ...)."""
    bits = SPREAD_SLOTS.bit_length() - 1
    i = k % SPREAD_SLOTS
    return int(format(i, f"0{bits}b")[::-1], 2) / SPREAD_SLOTS


@dataclass(eq=False)
class Report:
    """A scheduled report: the robot's status (STA), a mission package's state (MISSTA),
    one sensor, or all packed sensors of a type on the robot.  It falls due at
    ``t0 + k * interval`` for k = 0, 1, 2..."""

    robot: SimRobot
    sensors: list[Sensor]
    interval: float
    t0: float
    key: str
    status: bool = False
    package: object = None  # a MissionPackage: MISSTA
    item: tuple = ()  # what the measuring thread is given: (robot id, sensors, key)
    muted: bool = False  # a sensor report nobody reads: it falls due, and is not measured

    def __post_init__(self) -> None:
        self.item = (self.robot.uid, self.sensors, self.key)


class _Cohort:
    """Reports that fall due together: the same first instant and period (so the same
    instants, to the bit), in the order they were scheduled; ``k``: the next is the k-th.
    Its list of reports is replaced, never changed in place."""

    __slots__ = ("t0", "interval", "k", "reports", "_plan")

    def __init__(self, t0: float, interval: float, reports: list[Report]):
        self.t0, self.interval, self.k = t0, interval, 0
        self.set_reports(reports)

    def set_reports(self, reports: list[Report]) -> None:
        self.reports = reports
        self._plan: list | None = None

    @property
    def due(self) -> float:
        return self.t0 + self.k * self.interval

    def plan(self) -> list:
        """Its reports as the simulation hands them on: the measuring thread's
        (robot id, sensors, key) for a sensor's, the Report itself for a status or a
        mission package's (usarsim.sim.status); kept until its reports change."""
        if self._plan is None:
            self._plan = [
                rep if rep.status or rep.package is not None else rep.item for rep in self.reports if not rep.muted
            ]
        return self._plan


class ReportSchedule:
    """The reports of every robot, soonest first, and those due at one instant in the order
    they were last scheduled.

    Reports are kept by the instant they fall due (the float itself: two reports of one
    instant reached by different sums may differ in the last bit, and the earlier comes
    first), in the order they were scheduled, as runs of reports of one cohort (the same
    first instant and period, see :class:`_Cohort`).  That is the order of a heap of (due,
    order of scheduling), without a heap operation per report: with 256 P2ATs some 19,000
    reports a simulated second fall due, in a few runs an instant.
    """

    def __init__(self, phases: str = "grid", dt: float = 0.0) -> None:
        if phases not in REPORT_PHASES:
            raise ValueError(f"report phases are one of {', '.join(REPORT_PHASES)}, got {phases!r}")
        self._lists: dict[float, list[_Cohort]] = {}
        self._next: float | None = None  # the soonest instant a list is kept for
        self._spread = phases == "spread"
        self._dt = dt  # phases fall on physics steps
        self._added = 0  # robots added so far (the k of spread_share)

    def next_due(self) -> float | None:
        return self._next

    def _schedule(self, run: _Cohort) -> None:
        due = run.due
        runs = self._lists.get(due)
        if runs is None:
            self._lists[due] = [run]
            if self._next is None or due < self._next:
                self._next = due
            return
        last = runs[-1]
        if last.t0 == run.t0 and last.interval == run.interval:  # the same cohort: one run
            last.set_reports(last.reports + run.reports)
        else:
            runs.append(run)

    def add_robot(self, r: SimRobot, now: float) -> None:
        """Every report of ``r`` on its own period, from the first grid instant at or after
        ``now`` (the grid shifted by the robot's phase when the phases are spread)."""
        share = spread_share(self._added) if self._spread else 0.0
        self._added += 1

        def on_grid(interval: float) -> float:
            if not share:
                return math.ceil(now / interval - 1e-6) * interval
            phase = share * interval
            if self._dt > 0:
                phase = round(phase / self._dt) * self._dt
            return math.ceil((now - phase) / interval - 1e-6) * interval + phase

        period = r.config.status_interval_s
        reports = [Report(r, [], period, on_grid(period), "STA", status=True)]
        for pkg in r.config.mission_packages:
            reports.append(Report(r, [], period, on_grid(period), f"MISSTA:{pkg.name}", package=pkg))
        packed: dict[str, Report] = {}
        for item in r.sensors:
            if not item.PERIODIC:
                continue
            s = cast("Sensor[Any]", item)  # the items that send SEN lines at their period are sensors
            if s.PACKED:
                rep = packed.get(s.TYPE)
                if rep is None:
                    rep = Report(r, [], s.config.scan_interval_s, on_grid(s.config.scan_interval_s), f"SEN:{s.TYPE}")
                    packed[s.TYPE] = rep
                    reports.append(rep)
                rep.sensors.append(s)
            else:
                reports.append(
                    Report(
                        r, [s], s.config.scan_interval_s, on_grid(s.config.scan_interval_s), f"SEN:{s.TYPE}:{s.name}"
                    )
                )
        r.reports = reports
        for rep in reports:
            self._schedule(_Cohort(rep.t0, rep.interval, [rep]))

    def remove_robot(self, r: SimRobot) -> None:
        """Forget every report of ``r`` (removed): nothing here keeps it alive."""
        for due in list(self._lists):
            runs = []
            for run in self._lists[due]:
                run.set_reports([rep for rep in run.reports if rep.robot is not r])
                if run.reports:
                    runs.append(run)
            if runs:
                self._lists[due] = runs
            else:
                del self._lists[due]
        self._next = min(self._lists) if self._lists else None
        r.reports = []

    def read_only(self, r: SimRobot, wanted: frozenset[str] | None) -> None:
        """Measure only the sensors of ``r`` whose type or name is in ``wanted`` (None: every
        one).  The others' reports still fall due at their instants, so that the physics runs
        in the same stretches and every reading taken is the same, bit for bit; they are not
        measured (each sensor's noise comes from a generator of its own)."""
        for rep in r.reports:
            if rep.sensors:
                rep.muted = wanted is not None and not any(s.TYPE in wanted or s.name in wanted for s in rep.sensors)
        for runs in self._lists.values():
            for run in runs:
                run.set_reports(run.reports)  # its plan made again

    def take_due(self, now: float) -> list[Report]:
        """The reports due at ``now``, in order; each is scheduled
        again at the first multiple of its interval after ``now``."""
        return [rep for reports, _ in self._take(now) for rep in reports]

    def take_due_plans(self, now: float) -> list[list]:
        """:meth:`take_due` as the plans of its runs (:meth:`_Cohort.plan`), in order."""
        return [plan for _, plan in self._take(now)]

    def _take(self, now: float) -> list[tuple[list[Report], list]]:
        """The reports and the plan of each run due at ``now``, as it fell due (a run
        scheduled again may be joined by another of its cohort: it then gets a new list)."""
        out: list[tuple[list[Report], list]] = []
        lists = self._lists
        limit = now + EPS
        while self._next is not None and self._next <= limit:
            for run in lists.pop(self._next):  # a removed robot's are gone already (remove_robot)
                out.append((run.reports, run.plan()))
                run.k += 1
                while run.t0 + run.k * run.interval <= limit:
                    run.k += 1
                self._schedule(run)
            self._next = min(lists) if lists else None
        return out
