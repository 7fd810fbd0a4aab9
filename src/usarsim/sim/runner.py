"""The simulation thread: applies client requests, advances the simulated clock in
one of three modes and hands outputs to the server.

Modes (``--speed``/``--lockstep``):

* real time: simulated time paced to the wall clock (``speed`` 1);
* accelerated: ``speed`` > 1 runs that many times faster; ``speed`` None (``max``)
  runs as fast as it can;
* lock-step: the world stands still until a STEP request; then exactly that much
  simulated time is run, every output due in it is delivered, and the STEP's
  ``on_done`` callback is called.  Spawns, removals, queries and the requests a client
  waits for a reply to (a SET on an item, a REPORT) happen at once, at the current simulated
  time; the commands without a reply (DRIVE, joint orders) wait for the start of the next
  STEP, in arrival order.

In lock-step a short STEP asked for while the simulation thread has nothing to do runs at
once on the thread that asked (the server's event loop), and the requests that wait for the
next STEP are kept without waking the simulation thread: a controller's STEP/STEPPED round
trip then wakes no thread of ours.  With the event loop polling its sockets meanwhile
(:mod:`usarsim.server.polling`) that took round trips of 4 ms with no robot from 8,700 to
13,000 a second on a 2-core machine; either alone gave nothing measurable.  Whoever runs the
simulation holds the runner's lock, so that it is only ever run by one thread at a time, in
the order asked.
"""

from __future__ import annotations

import logging
import math
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from usarsim.errors import SimulationStopped, UsarsimError
from usarsim.sim.interpreter import InterpreterTuning
from usarsim.sim.simulation import Output, Simulation

log = logging.getLogger("usarsim.sim")

# A STEP whose time is a whole number of physics steps up to this fraction of a step runs
# exactly that many (0.6 s / 4 ms is 149.99999999999997 in floating point).
STEP_EPS = 1e-6


@dataclass
class Request:
    """A unit of work for the simulation thread.

    ``action(sim)`` runs on the simulation thread; ``immediate`` requests (spawn,
    remove, queries) run at once even in lock-step mode; ``on_done(result, error)`` is
    called on the simulation thread afterwards; ``concurrent`` ones need not wait for the
    sensor readings being taken.
    """

    action: Callable[[Simulation], Any]
    immediate: bool = False
    on_done: Callable[[Any, BaseException | None], None] | None = None
    # runs while sensor readings are still being taken on the measuring thread: it changes
    # nothing a sensor reads besides the live state (drive commands, queries); the others
    # wait for every reading first (usarsim.sim.measuring)
    concurrent: bool = False


@dataclass
class StepRequest:
    """A lock-step ``STEP {Time s}`` for the simulation thread (protocol.md 18): the simulated seconds to run, then
    ``on_done(time)`` with the new simulated time, which the STEPPED reply carries."""

    seconds: float
    on_done: Callable[[float], None]
    # called instead of ``on_done`` with the error when the STEP will not run (the simulation
    # has stopped, or stopped on an error while running it)
    on_refused: Callable[[BaseException], None] | None = None


@dataclass
class _Stop:
    done: threading.Event = field(default_factory=threading.Event)


class SimulationRunner:
    """Owns the simulation thread.  ``deliver(outputs)`` is called from that thread
    with each batch of outputs, in order; the server makes it thread-safe."""

    CHUNK_S = 0.02  # most simulated time run between two looks at the request queue
    # As fast as it goes (speed None), a chunk is sized in wall time instead: the simulation
    # looks at its requests and hands its outputs over about every FAST_LOOK_WALL_S of wall
    # time (the 20 ms a 0.02 s chunk lasts with 256 robots), in chunks of CHUNK_S to
    # FAST_CHUNK_MAX_S of simulated time.  Sixteen P2ATs run some 18 times faster than real
    # time, so a 0.02 s chunk lasted about a millisecond, and waking the server for each cost a
    # tenth of the real-time factor (2-core machine, three pairs of runs alternately: ratio to
    # bare mj_step 0.70-0.73 with 0.02 s chunks, 0.78-0.86 with 0.1 s; 64 robots, two pairs:
    # 0.80-0.89 looking every 5 ms, 0.91-0.92 every 20 ms).
    FAST_LOOK_WALL_S = 0.02
    FAST_CHUNK_MAX_S = 0.1
    MAX_LAG_S = 0.1  # real-time modes: most wall time the simulated clock may trail by
    # Lock-step: a STEP runs on the thread that asks for it when it is expected to last at
    # most this long (wall seconds; from how long the STEPs of the current model took), so
    # that the event loop is never held up for longer than this by a STEP.
    INLINE_STEP_WALL_S = 0.005

    def __init__(
        self,
        sim: Simulation,
        deliver: Callable[[list[Output]], None],
        *,
        speed: float | None = 1.0,
        lockstep: bool = False,
    ):
        self.sim = sim
        self.deliver = deliver
        self.speed = speed
        self.lockstep = lockstep
        self.queue: queue.SimpleQueue = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._run, name="usarsim-sim", daemon=True)
        self._pending: list[Request] = []
        self.error: BaseException | None = None
        self._lag_lost = 0.0
        self._lag_logged: float | None = None  # when the lag warning was last given
        self._owed = 0.0  # lock-step: simulated time asked for and not yet run (< one step)
        self._stopping = threading.Event()  # set by stop(): queued requests are dropped
        # Lock-step: held by the thread that runs the simulation; the requests queued and
        # those handled (equal: the simulation thread has nothing to do, none in its hands).
        self._lock = threading.Lock()
        self._count_lock = threading.Lock()
        self._queued = 0
        self._handled = 0
        # lock-step: wall seconds a simulated second of STEP took with this model (None: not yet known)
        self._wall_per_s: float | None = None
        self._rate_model: object = None
        self._running = False  # the simulation thread is running
        # set (under _closing_lock) once the thread no longer takes requests: later ones are
        # answered at once, those still queued are answered as it ends (see _close)
        self._closing_lock = threading.Lock()
        self._closed = False
        self._interpreter = InterpreterTuning()  # collector and switch interval (sim/interpreter.py)
        # called with the error, on the simulation thread as it ends, when it stopped on one
        self.on_failure: Callable[[BaseException], None] | None = None

    # Thread-safe API ---------------------------------------------------------------
    def submit(self, req: Request | StepRequest) -> None:
        """Queue ``req`` for the simulation thread.  A request that will never run (the
        simulation has stopped or is stopping) is answered at once with
        :class:`~usarsim.errors.SimulationStopped`, so that nobody waits for it."""
        with self._closing_lock:  # held to the end: the thread cannot close between the look and the put
            if not self._closed:
                self._put(req)
                return
        self._refuse(req)  # outside the lock: its answer may ask the runner again

    def _put(self, req: Request | StepRequest) -> None:
        if not self.lockstep:
            self.queue.put(req)
            return
        with self._count_lock:
            if isinstance(req, Request) and not req.immediate and self._queued == self._handled:
                # nothing queued ahead of it: it waits for the next STEP without waking anyone
                self._pending.append(req)
                return
            self._queued += 1
            self.queue.put(req)

    def step(
        self,
        seconds: float,
        on_done: Callable[[float], None],
        on_refused: Callable[[BaseException], None] | None = None,
    ) -> None:
        """Lock-step: run ``seconds`` of simulated time, then ``on_done(time)``; or, when it
        will not run (the simulation has stopped), ``on_refused(error)``.  A STEP expected to
        be short runs at once on the calling thread when the simulation thread has nothing
        to do (see the module's description); any other is queued."""
        if self.lockstep and self._running and not self._stopping.is_set() and self._lock.acquire(blocking=False):
            try:
                with self._count_lock:
                    idle = self._queued == self._handled
                rate = self._wall_per_s if self._rate_model is self.sim.model else None
                if idle and rate is not None and seconds * rate <= self.INLINE_STEP_WALL_S:
                    try:
                        self._step(seconds, on_done)
                    except BaseException as exc:  # as on the simulation thread: the simulation stops
                        self.error = exc
                        log.exception("the simulation stopped on an unexpected error")
                        self._stopping.set()
                        self.queue.put(_Stop())
                        self._refuse(StepRequest(seconds, on_done, on_refused))
                    return
            finally:
                self._lock.release()
        self.submit(StepRequest(seconds, on_done, on_refused))

    def start(self) -> None:
        self._thread.start()

    # Waiting for the thread at stop: it finishes at most one chunk of physics (CHUNK_S) or one
    # request; a model build of hundreds of robots takes a few seconds on a slow machine.
    STOP_TIMEOUT_S = 120.0

    def stop(self, timeout: float | None = None) -> None:
        """Stop the simulation thread and wait until it has ended.

        Requests still queued (the removals of every robot whose client the server just
        closed, say) are not run: rebuilding the model once per removed robot is work nobody
        will see.  Each is answered with :class:`~usarsim.errors.SimulationStopped` instead,
        as is any asked for later, so that nobody waits for them (a STEP's client is gone
        with the server).  The thread must have ended before the interpreter finalises:
        a daemon thread still inside MuJoCo (a model compiling) when Python exits is unwound
        by force through native frames, and the process dies with a segmentation fault after
        its work is done."""
        self._stopping.set()
        self.queue.put(_Stop())
        if not self._thread.is_alive():
            self._close()  # never started: what was asked of it is answered all the same
            return
        self._thread.join(self.STOP_TIMEOUT_S if timeout is None else timeout)
        if self._thread.is_alive():
            log.error(
                "the simulation thread did not stop within %.0f s", self.STOP_TIMEOUT_S if timeout is None else timeout
            )

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    # Thread body -------------------------------------------------------------------
    def _run(self) -> None:
        try:
            self.sim.measure_on_thread(self.sim.settings.sensor_thread)
            self._interpreter.start(self.sim)
            self._running = True
            if self.lockstep:
                self._run_lockstep()
            else:
                self._run_clocked()
        except BaseException as exc:  # the thread must never die silently
            self.error = exc
            log.exception("the simulation thread stopped on an unexpected error")
        finally:
            self._close()
            with self._lock:  # a STEP being run on another thread ends first; none starts after
                self._running = False
                try:
                    self.sim.measure_on_thread(False)
                except BaseException:  # a sensor's error was logged with the one that stopped the thread
                    log.debug("closing the measuring thread", exc_info=True)
                self._interpreter.stop()
            if self.error is not None and self.on_failure is not None:
                try:
                    self.on_failure(self.error)
                except Exception:
                    log.exception("telling the server that the simulation stopped")

    def _execute(self, req: Request) -> None:
        if self._stopping.is_set():
            self._refuse(req)  # shutting down: not run (see stop), but answered
            return
        error: Exception | None
        result, error = None, None
        if not req.concurrent:
            self.sim.settle()
        try:
            result = req.action(self.sim)
        except UsarsimError as exc:
            error = exc
        except Exception as exc:  # a bad request must not stop the world
            log.exception("request failed")
            error = exc
        if not req.concurrent:  # it may have changed the model (a spawn, a removal)
            self._interpreter.after_change(self.sim)
        if req.on_done is not None:
            if req.immediate and not req.concurrent:
                # what it output (a RES) reaches the server before its on_done: a connection
                # that waits for its answer to go on reads its lines in order
                self._flush()
            req.on_done(result, error)

    @staticmethod
    def _refuse(req: Request | StepRequest | _Stop) -> None:
        """Answer a request that will not run, or did not run to its end, with
        :class:`~usarsim.errors.SimulationStopped`."""
        try:
            if isinstance(req, Request) and req.on_done is not None:
                req.on_done(None, SimulationStopped("the simulation has stopped: the request was not carried out"))
            elif isinstance(req, StepRequest) and req.on_refused is not None:
                req.on_refused(SimulationStopped("the simulation has stopped: the world was not advanced"))
        except Exception:  # one waiter's error must not keep the others waiting
            log.exception("answering a request the simulation did not carry out")

    def _close(self) -> None:
        """The thread is ending: it takes no more requests, and answers those it still has
        (queued, or waiting in lock-step for a STEP that will not come)."""
        with self._closing_lock:
            self._closed = True
        with self._count_lock:
            left, self._pending = self._pending, []
        while True:
            try:
                left.append(self.queue.get_nowait())
            except queue.Empty:
                break
        for req in left:
            self._refuse(req)

    def _flush(self, wait: bool = True) -> None:
        """Hand the outputs over; ``wait=False``: as far as the readings are taken (the
        clock runs on meanwhile; the rest go with a later flush)."""
        outs = self.sim.take_outputs(wait)
        if outs:
            self.deliver(outs)

    def _run_lockstep(self) -> None:
        while True:
            item = self.queue.get()
            if isinstance(item, _Stop):
                return
            with self._lock:
                try:
                    if self._stopping.is_set():
                        self._refuse(item)
                        continue
                    if isinstance(item, StepRequest):
                        try:
                            self._step(item.seconds, item.on_done)
                        except BaseException:  # the thread ends on it (_run): its client is told
                            self._refuse(item)
                            raise
                    elif item.immediate:
                        self._execute(item)
                        self._flush()
                    else:
                        with self._count_lock:
                            self._pending.append(item)
                    self._interpreter.tick()
                finally:
                    with self._count_lock:
                        self._handled += 1

    def _step(self, seconds: float, on_done: Callable[[float], None]) -> None:
        """A lock-step STEP (holding the lock): the requests that waited for it, then the
        whole physics steps of ``seconds``, every output due, and ``on_done``."""
        t0 = time.perf_counter()
        with self._count_lock:
            pending, self._pending = self._pending, []
        for req in pending:
            self._execute(req)
        run = self._whole_steps(seconds)
        self.sim.advance(run, waited=True)
        self._flush()
        if run > 0:
            took = (time.perf_counter() - t0) / run
            if self._rate_model is not self.sim.model:
                self._rate_model, self._wall_per_s = self.sim.model, took
            else:  # a running mean: one slow STEP (a stall) does not keep the next ones off
                # set with _rate_model above: a float here (no cast on the STEP's path)
                self._wall_per_s = 0.8 * self._wall_per_s + 0.2 * took  # type: ignore[operator]
        self._interpreter.tick()
        on_done(self.sim.time)

    def _whole_steps(self, seconds: float) -> float:
        """The simulated time of the whole physics steps a STEP of ``seconds`` runs: what is
        left below one physics step is carried to the next STEP, so that STEPs add up (ten
        STEP {Time 0.01} run 0.1 s: 2, 3, 2, 3... steps of 4 ms)."""
        dt = self.sim.dt
        owed = self._owed + max(0.0, seconds)
        n = max(0, math.floor(owed / dt + STEP_EPS))
        self._owed = owed - n * dt
        return n * dt

    def _note_lag(self, skipped: float, now: float) -> None:
        """Count ``skipped`` simulated seconds let go to keep up with the wall clock; warn at
        most every 10 s, and only when what was skipped since the last warning shows as more
        than 0.00 s (a skip of microseconds is the scheduler's jitter, not lag)."""
        self._lag_lost += max(0.0, skipped)
        if round(self._lag_lost, 2) <= 0.0 or (self._lag_logged is not None and now - self._lag_logged <= 10.0):
            return
        if self._lag_logged is not None:
            log.warning(
                "simulation behind real time: %.2f simulated s skipped in the last %.0f s "
                "(the clock does not catch up in bursts)",
                self._lag_lost,
                now - self._lag_logged,
            )
        else:
            log.warning(
                "simulation behind real time: %.2f simulated s skipped (the clock does not catch up in bursts)",
                self._lag_lost,
            )
        self._lag_logged, self._lag_lost = now, 0.0

    def _run_clocked(self) -> None:
        sim = self.sim
        wall0 = time.perf_counter()
        sim0 = sim.time
        chunk = self.CHUNK_S  # as fast as it goes: grown toward FAST_LOOK_WALL_S of wall time
        while True:
            self._interpreter.tick()
            # apply everything that arrived
            while True:
                try:
                    item = self.queue.get_nowait()
                except queue.Empty:
                    break
                if isinstance(item, _Stop):
                    return
                if isinstance(item, StepRequest):
                    item.on_done(sim.time)  # STEP outside lock-step: nothing to do
                    continue
                self._execute(item)
            if self.speed is None:
                t0 = time.perf_counter()
                sim.advance(chunk)
                self._flush(wait=False)
                took = time.perf_counter() - t0
                chunk = min(self.FAST_CHUNK_MAX_S, max(self.CHUNK_S, chunk * self.FAST_LOOK_WALL_S / max(took, 1e-6)))
                continue
            now = time.perf_counter()
            target = sim0 + (now - wall0) * self.speed
            ahead = target - sim.time
            max_lag = self.MAX_LAG_S * self.speed
            if ahead > max_lag:
                # behind the wall clock (a stall, or more robots than the machine can run
                # in real time): do not catch up in a burst, let the excess go
                self._note_lag(ahead - max_lag, now)
                sim0, wall0 = sim.time + max_lag, now
                ahead = max_lag
            if ahead >= sim.dt:
                sim.advance(min(ahead, self.CHUNK_S))
                self._flush(wait=False)
                continue
            wait = (sim.dt - ahead) / self.speed
            try:
                item = self.queue.get(timeout=max(wait, 0.0005))
            except queue.Empty:
                continue
            if isinstance(item, _Stop):
                return
            if isinstance(item, StepRequest):
                item.on_done(sim.time)
                continue
            self._execute(item)
