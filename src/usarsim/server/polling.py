"""The event loop of a lock-step server: it polls its sockets for a moment before it sleeps.

A lock-step controller sends its next STEP a few tens of microseconds after it read the last
STEPPED.  An event loop that goes to sleep in the meantime is woken by the kernel when the
line arrives, on a processor that has gone idle (in a virtual machine, one the host took
back), and then runs its Python from cold caches: on a 2-core machine that doubled what a
round trip cost the server (STEP/STEPPED round trips of 4 ms with no robot, 8,700-8,900 a
second sleeping, 12,700-13,400 polling for up to 0.2 or 1 ms).

So after a ``select`` that found something ready, the next one polls (``select`` with no
wait) for up to ``poll_s`` before it waits as usual.  A loop with nothing to do sleeps as
before: a ``select`` that waited and found nothing ends the polling until something happens
again.
Outside lock-step the simulation thread needs the processor, so servers there do not poll.
"""

from __future__ import annotations

import asyncio
import selectors
import time

LOCKSTEP_POLL_S = 0.0005
"""How long a lock-step server polls after a request before it sleeps (``serve --poll-us``):
longer than a controller's turn-around (0.05-0.2 ms for a Python one that only steps), short
enough that a slow controller costs the server at most this much processor time a STEP."""


class PollingSelector(selectors.DefaultSelector):
    """The default selector, polling for up to ``poll_s`` after a ``select`` that found
    something (see the module's description)."""

    def __init__(self, poll_s: float = LOCKSTEP_POLL_S):
        super().__init__()
        self.poll_s = max(0.0, float(poll_s))
        self._busy = False  # the last select found something

    def select(self, timeout: float | None = None):
        waits = timeout is None or timeout > 0  # a look with no wait (callbacks are ready) changes nothing
        if self._busy and self.poll_s > 0 and (timeout is None or timeout > 0):
            start = time.perf_counter()
            end = start + (self.poll_s if timeout is None else min(timeout, self.poll_s))
            while True:
                ready = super().select(0)
                if ready:
                    return ready
                now = time.perf_counter()
                if now >= end:
                    break
            if timeout is not None:
                timeout = max(0.0, timeout - (now - start))
        ready = super().select(timeout)
        if waits:  # also when polling used up all of a short wait: a timer's tick is not a request
            self._busy = bool(ready)
        return ready


def poll_seconds(lockstep: bool, poll_us: int | None = None) -> float:
    """How long a server polls (``serve --poll-us``, else LOCKSTEP_POLL_S in lock-step, 0 outside it)."""
    if poll_us is not None:
        return max(0, poll_us) / 1e6
    return LOCKSTEP_POLL_S if lockstep else 0.0


def new_event_loop(poll_s: float = 0.0) -> asyncio.AbstractEventLoop:
    """A new event loop; with ``poll_s`` > 0 one that polls its sockets for up to that long
    after each one that found something, before it sleeps (lock-step servers)."""
    if poll_s <= 0:
        return asyncio.new_event_loop()
    return asyncio.SelectorEventLoop(PollingSelector(poll_s))
