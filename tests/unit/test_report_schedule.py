"""The report schedule gives the reports due at each instant in the order of a heap of
(due, order of scheduling): the order the golden transcripts pin."""

from __future__ import annotations

import heapq
import itertools
from types import SimpleNamespace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usarsim.sim.reports import EPS, Report, ReportSchedule


class HeapSchedule:
    """The reference: one heap entry per report, (due, order of scheduling)."""

    def __init__(self) -> None:
        self.heap: list = []
        self.seq = itertools.count()
        self.k: dict[int, int] = {}

    def _push(self, rep: Report) -> None:
        due = rep.t0 + self.k[id(rep)] * rep.interval
        heapq.heappush(self.heap, (due, next(self.seq), rep))

    def add(self, reps: list[Report]) -> None:
        for rep in reps:
            self.k[id(rep)] = 0
            self._push(rep)

    def remove(self, robot) -> None:
        self.heap = [e for e in self.heap if e[2].robot is not robot]
        heapq.heapify(self.heap)

    def next_due(self):
        return self.heap[0][0] if self.heap else None

    def take_due(self, now: float) -> list[Report]:
        out = []
        while self.heap and self.heap[0][0] <= now + EPS:
            _, _, rep = heapq.heappop(self.heap)
            self.k[id(rep)] += 1
            while rep.t0 + self.k[id(rep)] * rep.interval <= now + EPS:
                self.k[id(rep)] += 1
            self._push(rep)
            out.append(rep)
        return out


def _robot(uid: int, sensors: list[tuple[float, str]], status: float):
    return SimpleNamespace(
        uid=uid,
        removed=False,
        reports=[],
        config=SimpleNamespace(status_interval_s=status, mission_packages=()),
        sensors=[
            SimpleNamespace(
                PERIODIC=True, PACKED=False, TYPE=t, name=f"{t}{i}", config=SimpleNamespace(scan_interval_s=iv)
            )
            for i, (iv, t) in enumerate(sensors)
        ],
    )


INTERVALS = st.sampled_from([0.05, 0.1, 0.2, 0.25, 0.3, 1.0 / 3.0, 0.7])


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.integers(0, 200),  # spawn step (4 ms steps)
            st.lists(st.tuples(INTERVALS, st.sampled_from(["Sonar", "GPS", "INS"])), max_size=5),
            INTERVALS,
            st.one_of(st.none(), st.integers(0, 400)),
        ),  # removal step
        min_size=1,
        max_size=8,
    )
)
def test_the_same_reports_in_the_same_order_as_a_heap(robots):
    new, ref = ReportSchedule(), HeapSchedule()
    spawns = sorted(
        ((at, uid, sensors, status, gone) for uid, (at, sensors, status, gone) in enumerate(robots)), key=lambda r: r[0]
    )
    twins = {}
    dt = 0.004
    for step in range(450):
        now = step * dt
        for at, uid, sensors, status, gone in spawns:
            if at == step:
                a, b = _robot(uid, sensors, status), _robot(uid, sensors, status)
                new.add_robot(a, now)
                ReportSchedule().add_robot(b, now)  # the same reports, made the same way
                ref.add(b.reports)
                twins[uid] = (a, b)
            if gone is not None and gone == step and uid in twins:
                new.remove_robot(twins[uid][0])
                ref.remove(twins[uid][1])
        assert new.next_due() == ref.next_due()
        got = [(rep.robot.uid, rep.key) for rep in new.take_due(now)]
        want = [(rep.robot.uid, rep.key) for rep in ref.take_due(now)]
        assert got == want


def test_reports_of_one_instant_reached_by_different_sums_come_in_float_order():
    # counted from 0.1, the sixth report of a 0.1 s period falls due at 0.6; counted from
    # 0.2 at 0.6000000000000001: that one comes second, though it was scheduled first
    sched = ReportSchedule()
    b = _robot(2, [(0.1, "Sonar")], 10.0)
    a = _robot(1, [(0.1, "Sonar")], 10.0)
    sched.add_robot(b, 0.15)  # on the grid from 0.2
    sched.add_robot(a, 0.05)  # from 0.1
    order = {}
    for step in range(1, 7):
        order[step] = [rep.robot.uid for rep in sched.take_due(step * 0.1) if rep.key != "STA"]
    assert order == {1: [1], 2: [2, 1], 3: [2, 1], 4: [2, 1], 5: [2, 1], 6: [1, 2]}


def test_a_removed_robots_reports_are_forgotten_and_the_others_keep_their_order():
    kept, ref = ReportSchedule(), HeapSchedule()
    pairs = [
        (
            _robot(uid, [(0.1, "Sonar"), (0.2, "GPS"), (0.3, "INS")], 0.2),
            _robot(uid, [(0.1, "Sonar"), (0.2, "GPS"), (0.3, "INS")], 0.2),
        )
        for uid in range(4)
    ]
    for i, (a, b) in enumerate(pairs):
        kept.add_robot(a, 0.05 * i)
        ReportSchedule().add_robot(b, 0.05 * i)
        ref.add(b.reports)
    for step in range(200):
        now = step * 0.004
        if step == 60:
            kept.remove_robot(pairs[1][0])
            ref.remove(pairs[1][1])
        got = [(rep.robot.uid, rep.key) for rep in kept.take_due(now)]
        assert got == [(rep.robot.uid, rep.key) for rep in ref.take_due(now)]
        if step > 60:
            assert 1 not in {uid for uid, _ in got}
    assert pairs[1][0].reports == []
    assert all(rep.robot is not pairs[1][0] for runs in kept._lists.values() for run in runs for rep in run.reports)


def test_plans_hand_on_a_sensors_item_and_a_status_report_itself_in_order():
    by_report, by_plan = ReportSchedule(), ReportSchedule()
    for uid in range(3):
        by_report.add_robot(_robot(uid, [(0.1, "Sonar"), (0.2, "GPS")], 0.2), 0.03 * uid)
        by_plan.add_robot(_robot(uid, [(0.1, "Sonar"), (0.2, "GPS")], 0.2), 0.03 * uid)
    seen_status = False
    for step in range(150):
        now = step * 0.004
        want = [rep if rep.status else rep.item for rep in by_report.take_due(now)]
        got = [x for plan in by_plan.take_due_plans(now) for x in plan]
        assert [x if x.__class__ is tuple else (x.robot.uid, x.key) for x in got] == [
            x if x.__class__ is tuple else (x.robot.uid, x.key) for x in want
        ]
        seen_status = seen_status or any(x.__class__ is not tuple for x in got)
    assert seen_status


def test_spread_shares_put_robots_spawned_in_turn_as_far_apart_as_they_can_be():
    from usarsim.sim.reports import SPREAD_SLOTS, spread_share

    assert [spread_share(k) for k in range(4)] == [0.0, 0.5, 0.25, 0.75]
    shares = [spread_share(k) for k in range(SPREAD_SLOTS)]
    assert sorted(shares) == [i / SPREAD_SLOTS for i in range(SPREAD_SLOTS)]  # each slot once
    assert spread_share(SPREAD_SLOTS) == 0.0  # then round again


def test_with_spread_phases_each_robot_reports_on_its_own_shifted_grid_on_physics_steps():
    sched = ReportSchedule("spread", dt=0.004)
    a, b, c = (_robot(i, [(0.2, "Sonar")], 0.2) for i in (1, 2, 3))
    for r in (a, b, c):
        sched.add_robot(r, 0.31)
    firsts = {r.uid: {rep.key: rep.t0 for rep in r.reports} for r in (a, b, c)}
    # robot 1: the plain grid; robot 2 half a period later; robot 3 a quarter (0.05 held to a 4 ms step: 0.048)
    assert firsts[1]["STA"] == pytest.approx(0.4)
    assert firsts[2]["STA"] == pytest.approx(0.5)
    assert firsts[3]["STA"] == pytest.approx(0.448)
    seen: dict[int, list[float]] = {1: [], 2: [], 3: []}
    while (due := sched.next_due()) is not None and due < 1.3:
        for rep in sched.take_due(due):
            if rep.key == "STA":
                seen[rep.robot.uid].append(round(due, 6))
    assert seen[1] == [0.4, 0.6, 0.8, 1.0, 1.2]
    assert seen[2] == [0.5, 0.7, 0.9, 1.1]
    assert seen[3] == [0.448, 0.648, 0.848, 1.048, 1.248]


def test_report_phases_are_named_or_refused():
    from usarsim.sim.settings import SimSettings

    with pytest.raises(ValueError, match="grid, spread"):
        ReportSchedule("staggered")
    with pytest.raises(ValueError, match="report_phases"):
        SimSettings(report_phases="staggered")
