"""The lock-step server's event loop polls its sockets for a moment after it found something
(usarsim.server.polling), and sleeps as any other when there is nothing to do."""

from __future__ import annotations

import asyncio
import contextlib
import socket
import threading
import time

from usarsim.server.polling import PollingSelector, new_event_loop

POLL_S = 0.05


def cpu_during(fn) -> tuple[float, float, object]:
    """(processor seconds, wall seconds, result) of ``fn()`` on this thread."""
    c0, w0 = time.thread_time(), time.perf_counter()
    out = fn()
    return time.thread_time() - c0, time.perf_counter() - w0, out


@contextlib.contextmanager
def busy_selector(poll_s: float):
    """A polling selector watching one end of a socket pair, which has just found a byte
    there (so its next select polls); yields (selector, the other end)."""
    a, b = socket.socketpair()
    sel = PollingSelector(poll_s)
    try:
        sel.register(a, 1)  # EVENT_READ
        b.send(b"x")
        assert sel.select(1.0)
        a.recv(1)
        yield sel, b
    finally:
        sel.close()
        a.close()
        b.close()


def test_it_polls_after_finding_something_and_sleeps_after_finding_nothing():
    with busy_selector(POLL_S) as (sel, _):
        cpu, wall, ready = cpu_during(lambda: sel.select(0.2))
        assert ready == []
        assert wall >= 0.19
        assert cpu >= 0.3 * POLL_S, f"polled for {cpu:.3f} s of processor time"
        # that one found nothing: the next one sleeps at once
        cpu, wall, ready = cpu_during(lambda: sel.select(0.2))
        assert ready == [] and wall >= 0.19
        assert cpu < 0.3 * POLL_S, f"slept, yet used {cpu:.3f} s of processor time"


def test_what_arrives_while_it_polls_is_returned_at_once():
    with busy_selector(0.5) as (sel, b):
        # a look with no wait (the loop has callbacks ready) neither polls nor ends the polling
        assert sel.select(0) == []
        threading.Timer(0.01, lambda: b.send(b"y")).start()
        _, wall, ready = cpu_during(lambda: sel.select(5.0))
        assert len(ready) == 1 and wall < 0.4


def test_a_polling_loop_serves_a_lock_step_conversation():
    loop = new_event_loop(0.001)
    assert isinstance(loop._selector, PollingSelector)  # noqa: SLF001 (what the loop was made with)

    accepted = []

    class Echo(asyncio.Protocol):
        def connection_made(self, transport):
            self.transport = transport
            accepted.append(transport)

        def data_received(self, data):
            self.transport.write(data.replace(b"STEP", b"STEPPED"))

    async def main() -> list[bytes]:
        server = await loop.create_server(Echo, "127.0.0.1", 0)
        port = server.sockets[0].getsockname()[1]
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        got = []
        for i in range(50):
            writer.write(b"STEP %d\r\n" % i)
            got.append(await reader.readline())
        writer.close()
        await writer.wait_closed()
        for transport in accepted:
            transport.close()
        server.close()
        await server.wait_closed()
        return got

    try:
        got = loop.run_until_complete(main())
    finally:
        loop.close()
    assert got == [b"STEPPED %d\r\n" % i for i in range(50)]
    plain = new_event_loop(0.0)
    try:
        assert type(plain._selector) is not PollingSelector  # noqa: SLF001
    finally:
        plain.close()


def test_a_wait_shorter_than_the_polling_ends_it_when_nothing_came():
    """A loop whose next timer is due sooner than the polling would end (a timer ticking every
    fraction of a millisecond) polls through that wait once, then sleeps: a tick is not a request."""
    with busy_selector(POLL_S) as (sel, _):
        assert sel.select(0.2 * POLL_S) == []  # polled all of it: nothing came
        cpu, wall, ready = cpu_during(lambda: sel.select(0.2))
        assert ready == [] and wall >= 0.19
        assert cpu < 0.3 * POLL_S, f"still polling: {cpu:.3f} s of processor time"
