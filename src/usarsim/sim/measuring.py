"""Sensor readings taken on a thread of their own, while the physics runs on.

At a report instant the simulation thread copies the world's state (``mj_copyData``) into
one of a few spare ``MjData`` and hands the instant's reports to the measuring thread,
which reads every due sensor from that copy, exactly as the simulation thread would have
read them at that instant, and makes the robots' statuses from it and from what the
simulation thread took of the rest then (:mod:`usarsim.sim.status`), while the simulation
thread steps the physics on (MuJoCo releases the interpreter lock while it steps, and the
ray-cast kernel while it casts).
Readings are the same, bit for bit, and come out in the same order: one thread measures,
in the order the instants came, and each sensor's own state (its noise, its scan
accumulators) is only ever touched by it.  The simulation keeps everything it outputs
after an instant behind that instant's readings (:class:`OrderedOutbox`).

What the measuring thread reads besides its copy (the model, the world's entities, the
sensors' configuration) changes only in requests that are not marked ``concurrent``
(spawns, removals, SET on items...), and the simulation waits for every reading to be
taken before it runs those (:meth:`Simulation.settle`).

``SimSettings(sensor_thread=False)`` (``serve --sensors-inline``) measures on the simulation
thread instead.
"""

from __future__ import annotations

import os
import threading
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TYPE_CHECKING, Union

import mujoco

from usarsim.sim.outputs import Output
from usarsim.sim.status import Standing, status_output
from usarsim.sim.view import WorldView

if TYPE_CHECKING:
    from usarsim.sensors import Sensor
    from usarsim.sim.raycaster import RayCaster
    from usarsim.sim.reports import Report

# Copies of the world in use at once: instants measured, or waiting to be, while the
# physics runs on; the simulation waits for the oldest when all are taken.
SLOTS = 3
# The measuring thread runs this much nicer than the simulation thread (Linux: a thread's
# own nice value).  The simulation thread is the critical path: when the measuring thread,
# the server's event loop and the clients want more processors than there are, the kernel
# then gives the simulation thread the larger share instead of an equal one.
MEASURING_NICE = 5


def measure_report(uid: int, sensors: list[Sensor], key: str, view: WorldView) -> Output | None:
    """One report of a robot's sensors (one sensor, or a packed group of one type) from
    ``view``; None when there is nothing to report this time."""
    first = sensors[0]
    if first.PACKED:
        cls = type(first)
        value = cls.combine(cls.measure_group(sensors, view))
    else:
        value = first.measure(view)
    if value is None:  # nothing to report this tick (e.g. a sensor that accumulates scans)
        return None
    t = view.time if first.config.with_time_stamp else None
    return Output(uid, t, value, key)


# What an instant's job holds, in the order they fall due: sensor reports to measure
# (robot id, sensors, key), and status and mission package reports (usarsim.sim.status).
Due = Union["Report", tuple[int, list, str]]


def measure_all(items: list[Due], view: WorldView, standing: Standing) -> list[Output]:
    """An instant's outputs in order, measured from ``view`` and ``standing`` (of the instant)."""
    out = []
    for item in items:
        if item.__class__ is tuple:
            o = measure_report(item[0], item[1], item[2], view)
            if o is not None:
                out.append(o)
        else:
            out.append(status_output(item, view.data, standing, view.time))  # type: ignore[arg-type]  # not a tuple: a Report
    return out


def _be_nicer() -> None:
    """Make the calling thread MEASURING_NICE nicer than it is (where the system can)."""
    if MEASURING_NICE <= 0 or not hasattr(os, "setpriority"):
        return
    try:
        tid = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, tid, os.getpriority(os.PRIO_PROCESS, tid) + MEASURING_NICE)
    except OSError:  # not allowed here: the thread keeps its share
        pass


class _Slot:
    __slots__ = ("data", "caster", "future")

    def __init__(self, model: mujoco.MjModel, caster: RayCaster):
        self.data = mujoco.MjData(model)
        self.caster = caster.bound_to(self.data)
        self.future: Future | None = None


class Measurer:
    """The measuring thread and its copies of the world (made again for a new model)."""

    def __init__(self) -> None:
        self._executor = ThreadPoolExecutor(1, thread_name_prefix="usarsim-sensors", initializer=_be_nicer)
        self._model: mujoco.MjModel | None = None
        self._slots: list[_Slot] = []
        self._next = 0

    def submit(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        caster: RayCaster,
        time: float,
        world,
        entities,
        items: list[Due],
        standing: Standing,
    ) -> Future:
        """Measure ``items`` at simulated ``time`` from a copy of ``data`` taken now (and
        ``standing``, taken now)."""
        if model is not self._model:
            self._model, self._slots, self._next = model, [], 0
        if len(self._slots) < SLOTS:
            self._slots.append(_Slot(model, caster))
        slot = self._slots[self._next % len(self._slots)]
        self._next += 1
        if slot.future is not None:
            slot.future.result()  # the copy is free once its instant is measured
        mujoco.mj_copyData(slot.data, model, data)
        view = WorldView(model, slot.data, time, slot.caster, world, entities)
        slot.future = self._executor.submit(measure_all, items, view, standing)
        return slot.future

    def call(self, fn) -> Future:
        """Run ``fn()`` on the measuring thread, after what was submitted before (profiling)."""
        return self._executor.submit(fn)

    def close(self) -> None:
        self._executor.shutdown(wait=True, cancel_futures=True)
        self._slots = []
        self._model = None


class OrderedOutbox:
    """The simulation's outputs in order: lists of ready outputs and instants being
    measured (futures of lists), taken from the front as far as they are ready."""

    def __init__(self) -> None:
        self.open: list[Output] = []  # what the simulation thread appends to now
        self._queue: deque = deque()

    def append(self, o: Output) -> None:
        self.open.append(o)

    def insert(self, i: int, o: Output) -> None:
        self.open.insert(i, o)

    def __len__(self) -> int:
        return len(self.open)

    def push(self, future: Future) -> None:
        """An instant's readings: everything appended from now on comes after them."""
        if self.open:
            self._queue.append(self.open)
            self.open = []
        self._queue.append(future)

    @property
    def waiting(self) -> bool:
        return bool(self._queue)

    def take(self, wait: bool = False) -> list[Output]:
        """Every output ready from the front (with ``wait``, every output)."""
        if self.open:
            self._queue.append(self.open)
            self.open = []
        out: list[Output] = []
        q = self._queue
        while q:
            head = q[0]
            if isinstance(head, list):
                out.extend(head)
            elif wait or head.done():
                taken = head.result()
                out.extend(taken)
                # The future stays in its slot until the slot is used again; emptied, it
                # keeps no reading alive, so the readings are freed by whoever drops them
                # last (the server, once written), not by the simulation thread when it
                # reuses the slot (a thousand readings an instant with 256 robots: 1 ms).
                taken.clear()
            else:
                break
            q.popleft()
        return out

    def settle(self) -> None:
        """Wait until every instant handed over has been measured (its outputs stay queued)."""
        for item in self._queue:
            if not isinstance(item, list):
                item.result()
