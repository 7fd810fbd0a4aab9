"""Lock-step: where a STEP falls among the lines of every control connection.

The rule (docs/protocol.md, "Time: real time, accelerated, lock-step"): **a STEP is carried out once
every line that reached the server before it, on any control connection, has been read and
handled**, so that a controller's commands are applied by the STEP that follows them however
it wrote them: in one write or several, on the robot's connection or another one.

Three things make it hold, whatever the segmentation and the timing:

* The server acknowledges every segment of a control connection at once (``TCP_QUICKACK``,
  which Linux clears again, so it is set after every read and write:
  :mod:`usarsim.server.control`).
  A client's Nagle algorithm holds a small write back until its previous one is acknowledged;
  with the kernel's delayed acknowledgement (up to 40 ms on Linux) a ``MISPKG`` written just
  after a ``DRIVE`` reached the server after a ``STEP`` written after both on another
  connection, and waited for the next STEP.  Acknowledged at once, it follows within one
  round trip.
* A STEP that may have lines of other connections before it is not carried out where it is
  read: it waits for the event loop to look at every socket once more (lines that arrived
  meanwhile are read and handled first), for the lines already read and not yet handled (a
  connection's line budget, an INIT being spawned), and until no other connection has
  received anything for ``grace_s`` (``serve --step-grace-us``): a line held back by a
  client's TCP stack arrives within that.  The connection that sent the STEP reads nothing
  more until it is carried out: what it sent after the STEP is for the next one.
* STEPs are carried out in the order they were read.

A STEP on the only control connection is carried out at once: there is nothing to wait for
(the lock-step round trip of a single controller costs no more than before).  A connection
that keeps sending does not hold a STEP back for longer than ``MAX_SETTLE_S``.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Protocol

log = logging.getLogger("usarsim.server")

STEP_GRACE_S = 0.0002
"""How long every other control connection must have been quiet before a STEP is carried out
(``serve --step-grace-us``): several round trips of the loopback interface (10-30 us on the
2-core machine), and less than what a lock-step controller takes to read a STEPPED and send
its next commands, so that a controller that waits for its commands' replies loses nothing."""

MAX_SETTLE_S = 0.05
"""A STEP waits at most this long for the other connections to fall quiet (a client that
never stops sending does not stop the world)."""


class Reader(Protocol):
    """What the ordering needs of a control connection."""

    last_read: float  # time.perf_counter() of its last read (0.0: nothing yet)

    def unhandled(self) -> bool:
        """Lines read and not yet handled, other than those that wait behind its own STEP."""

    def holds_step(self) -> bool:
        """A STEP of its own is waiting here (its later lines are for the next STEP)."""


@dataclass
class _Waiting:
    sender: Reader
    carry_out: Callable[[], None]
    since: float  # when the STEP was read
    looked: float  # when the sockets were last looked at for it


class StepOrder:
    """The STEPs read and not yet carried out, in order; each is carried out once the rule of
    the module's description holds for it."""

    def __init__(self, readers: Callable[[], Iterable[Reader]], grace_s: float = STEP_GRACE_S):
        self.readers = readers
        self.grace_s = max(0.0, float(grace_s))
        self._waiting: deque[_Waiting] = deque()
        self._timer: asyncio.TimerHandle | None = None
        self._late_logged = False

    def at_once(self, sender: Reader) -> bool:
        """Whether a STEP read now from ``sender`` can be carried out at once: no STEP waits
        before it and no other control connection is open."""
        return not self._waiting and all(r is sender for r in self.readers())

    def submit(self, sender: Reader, carry_out: Callable[[], None]) -> None:
        """``carry_out()`` on the event loop once the STEP just read from ``sender`` may be."""
        now = time.perf_counter()
        self._waiting.append(_Waiting(sender, carry_out, now, now))
        self._look_again()

    def _look_again(self, delay: float = 0.0) -> None:
        """Look again after the event loop has polled its sockets once more (a timer due now
        runs after the reads that poll found) or after ``delay`` seconds."""
        if self._timer is not None:
            self._timer.cancel()
        loop = asyncio.get_running_loop()
        self._timer = loop.call_at(loop.time() + delay, self._check)

    def _check(self) -> None:
        self._timer = None
        while self._waiting:
            w = self._waiting[0]
            now = time.perf_counter()
            wait = self._wait_for(w, now)
            if wait is not None and now - w.since < MAX_SETTLE_S:
                w.looked = now
                self._look_again(wait)
                return
            if wait is not None and not self._late_logged:
                self._late_logged = True
                log.warning(
                    "a STEP waited %.0f ms for the control connections to fall quiet and was carried out "
                    "while they still sent (logged once)",
                    MAX_SETTLE_S * 1000,
                )
            self._waiting.popleft()
            try:
                w.carry_out()
            except Exception:  # one STEP's failure must not keep the others waiting
                log.exception("carrying out a STEP")

    def _wait_for(self, w: _Waiting, now: float) -> float | None:
        """None when the STEP ``w`` may be carried out now, else how long to wait before
        looking again (0: after one more poll of the sockets)."""
        last = 0.0
        for r in self.readers():
            if r is w.sender or r.holds_step():
                continue
            if r.unhandled():
                return max(self.grace_s / 4, 0.00005)  # its line budget or its spawn: it drains on its own
            last = max(last, r.last_read)
        if last > w.looked:
            return 0.0  # something arrived since the last look: look once more
        quiet = now - last
        if quiet < self.grace_s:
            return self.grace_s - quiet
        return None

    def cancel(self) -> None:
        """The server is closing: nothing more is carried out."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._waiting.clear()
