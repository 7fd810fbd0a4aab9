"""How a running simulation uses the interpreter: its garbage collector and its lock.

The simulation thread is the critical path of a server: it runs the physics (MuJoCo
releases the interpreter lock while it steps) and, between two stretches of it, the Python
that schedules reports and hands instants to the measuring thread.  Each time it comes out
of MuJoCo it needs the lock back, which the measuring thread or the server may be holding.
Two things kept it waiting (256 P2ATs on a 2-core machine, 2026-11-25):

* *Full collections.*  A world of hundreds of robots is millions of Python objects that
  live as long as the model does.  Readings in flight to the clients outlive the younger
  generations of CPython's collector and are promoted to the oldest, and every tenth
  collection of the middle generation then ran a full collection, which walks the whole
  heap holding the lock: eight in ten simulated seconds, 60 to 80 ms each.  So once the
  model stands still after a change (a spawn, a removal, a rebuild) the simulation thread
  collects the young generations and moves everything left to the collector's permanent
  generation (``gc.freeze``), which later collections do not walk: the full collections of
  the same run took 2 to 4 ms each, and the simulation thread waited for the lock after its physics
  calls 0.2 to 0.35 s of ten simulated seconds instead of 0.65 to 0.85 s.  Frozen objects
  that are, or later become, cyclic garbage are not collected while frozen; so a removal,
  whose robot's objects may be such garbage, thaws the heap, and the next freeze collects in
  full first; the heap is thawed when the runner stops.  Robots come and go in bursts (a
  team connecting, a controller reconnecting in a loop), so "still" means for half a second
  of wall time: a burst costs no collection per robot.
* *The switch interval.*  A thread that wants the lock waits up to the interpreter's
  switch interval (5 ms by default) before the holder is asked to let go.  While a
  simulation runs it is :data:`SWITCH_INTERVAL_S`: four pairs of 256-robot bench runs
  alternately gave a ratio to bare ``mj_step`` of 0.93 to 0.97 with 0.5 ms and 0.90 to 0.93
  with 5 ms; with 16 and 64 robots it made no difference that three pairs could show.
"""

from __future__ import annotations

import gc
import logging
import sys
import threading
import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from usarsim.sim.simulation import Simulation

log = logging.getLogger("usarsim.sim")

# The interpreter's switch interval while a simulation thread runs (see above).
SWITCH_INTERVAL_S = 0.0005

_lock = threading.Lock()
_running = 0  # simulation threads running in this process
_saved_interval: float | None = None  # the switch interval before the first of them


class InterpreterTuning:
    """The collector and switch interval of the process while one simulation thread runs
    (see the module's description): :meth:`start` as it starts, :meth:`after_change`
    after anything that may have changed the model, :meth:`tick` often (cheap), and
    :meth:`stop` as it ends.  The heap is frozen once the model has stood still for
    :attr:`SETTLE_S` of wall time, so that robots coming and going in quick succession cost
    no collection each."""

    SETTLE_S = 0.5

    def __init__(self) -> None:
        self._model: object = None
        self._uids: frozenset[int] = frozenset()
        self._changed_at: float | None = None  # when the model last changed, not frozen since
        self._removed = False  # a robot removed since the heap was last frozen
        self.frozen = False
        self._started = False

    def start(self, sim: Simulation) -> None:
        global _running, _saved_interval
        with _lock:
            if _running == 0:
                _saved_interval = sys.getswitchinterval()
                sys.setswitchinterval(SWITCH_INTERVAL_S)
            _running += 1
        self._started = True
        self.after_change(sim)

    def after_change(self, sim: Simulation) -> None:
        """Note a change of the model, if there was one (cheap otherwise); a removal thaws
        the heap at once (the removed robot's objects may be garbage in cycles)."""
        if sim.model is self._model:
            return
        uids = frozenset(sim.robots)
        if not self._uids <= uids:
            self._removed = True
            if self.frozen:
                gc.unfreeze()
                self.frozen = False
        self._model, self._uids, self._changed_at = sim.model, uids, time.monotonic()

    def tick(self) -> None:
        """Freeze the heap if the model has stood still for SETTLE_S since it changed: a full
        collection first if a robot was removed meanwhile, else of the young generations
        only (a full one walks the whole process)."""
        if self._changed_at is None or time.monotonic() - self._changed_at < self.SETTLE_S:
            return
        t0 = time.perf_counter()
        full = self._removed
        collected = gc.collect() if full else gc.collect(1)
        gc.freeze()
        self.frozen, self._removed, self._changed_at = True, False, None
        log.debug(
            "heap frozen (%s collection first): %d objects, %d collected, %.1f ms",
            "a full" if full else "a young",
            gc.get_freeze_count(),
            collected,
            (time.perf_counter() - t0) * 1e3,
        )

    def stop(self) -> None:
        """Thaw the heap, and give the switch interval back when no other simulation thread
        of the process runs."""
        global _running
        if self.frozen:
            gc.unfreeze()
            self.frozen = False
        self._model, self._changed_at = None, None
        if self._started:
            self._started = False
            with _lock:
                _running -= 1
                if _running == 0 and _saved_interval is not None:
                    sys.setswitchinterval(_saved_interval)
