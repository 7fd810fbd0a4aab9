"""Lock-step on the caller's thread: the runner of an in-process simulator
(:mod:`usarsim.server.direct`), which has no simulation thread and no event loop.

Every request is carried out as :class:`~usarsim.sim.runner.SimulationRunner` carries it out
in lock-step, in the same order and with the same outputs, but at once on the thread that
submits it: a spawn, a removal, a query, a SET or a REPORT runs and hands its outputs over
before :meth:`InlineRunner.submit` returns; a DRIVE or a joint order waits for the next STEP;
a STEP runs its pending requests, its whole physics steps and hands every output due over.
The sensor readings are still taken on the measuring thread while the physics runs on
(:mod:`usarsim.sim.measuring`), unless the settings say otherwise.  Only one thread may use
an inline runner at a time.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from usarsim.sim.runner import Request, SimulationRunner, StepRequest, _Stop
from usarsim.sim.simulation import Output, Simulation

log = logging.getLogger("usarsim.sim")


class InlineRunner(SimulationRunner):
    """A lock-step runner without a thread: each request is carried out by :meth:`submit` on
    the calling thread (see the module's description)."""

    def __init__(self, sim: Simulation, deliver: Callable[[list[Output]], None]):
        super().__init__(sim, deliver, speed=None, lockstep=True)

    def start(self) -> None:
        """Start the measuring thread, and tune the interpreter as a simulation thread does
        (:mod:`usarsim.sim.interpreter`): with the default switch interval of 5 ms the caller's
        thread waited that long for the interpreter lock each time the measuring thread held it,
        and a P2AT's env steps a second fell to a third."""
        self.sim.measure_on_thread(self.sim.settings.sensor_thread)
        self._interpreter.start(self.sim)
        self._running = True

    def stop(self, timeout: float | None = None) -> None:
        """Take no more requests (each later one is answered with
        :class:`~usarsim.errors.SimulationStopped`, as are the DRIVEs still waiting for a STEP)
        and end the measuring thread."""
        if self._closed:
            return
        self._stopping.set()
        self._close()
        if self._running:
            self._running = False
            try:
                self.sim.measure_on_thread(False)
            except BaseException:  # a sensor's error was logged with the one that stopped the runner
                log.debug("closing the measuring thread", exc_info=True)
            self._interpreter.stop()

    @property
    def alive(self) -> bool:
        return self._running and not self._closed

    def _put(self, req: Request | StepRequest) -> None:
        if isinstance(req, _Stop):  # pragma: no cover - only the threaded runner queues stops
            return
        if isinstance(req, StepRequest):
            try:
                self._step(req.seconds, req.on_done)
            except BaseException as exc:  # as on the simulation thread: the simulation stops
                self.error = exc
                log.exception("the simulation stopped on an unexpected error")
                self._refuse(req)
                self.stop()
                raise
            return
        if req.immediate:
            self._execute(req)
            self._flush()
        else:
            self._pending.append(req)

    def step(
        self,
        seconds: float,
        on_done: Callable[[float], None],
        on_refused: Callable[[BaseException], None] | None = None,
    ) -> None:
        self.submit(StepRequest(seconds, on_done, on_refused))
