"""What the benchmarks share: a server's event loop on a thread of its own, this process's
memory, and quiet logs."""

from __future__ import annotations

import asyncio
import os
import sys
import threading


class LoopThread:
    """An event loop on a thread of its own (polling as a lock-step server's does, with
    ``lockstep``), running from once ``start()`` has run on it until ``stop_loop()``."""

    def __init__(self, lockstep: bool, name: str, start) -> None:
        from usarsim.server.polling import new_event_loop, poll_seconds

        self.loop = new_event_loop(poll_seconds(lockstep))  # as `serve` makes it
        ready = threading.Event()

        def serve():
            asyncio.set_event_loop(self.loop)
            self.loop.run_until_complete(start())
            ready.set()
            self.loop.run_forever()

        self.thread = threading.Thread(target=serve, name=name, daemon=True)
        self.thread.start()
        ready.wait(30)

    def stop_loop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(5)
        self.loop.close()


class ServedApp(LoopThread):
    """An Application served by its own event loop on a thread, until ``stop()``."""

    def __init__(self, app):
        self.app = app
        super().__init__(app.facade.lockstep, "bench-server", app.start)

    def stop(self) -> None:
        asyncio.run_coroutine_threadsafe(self.app.stop(), self.loop).result(120)
        self.stop_loop()


def bench_app(world, **options):
    """The Application a benchmark serves: ``world`` on a free control port of 127.0.0.1, seed 0,
    no ground-truth service, image server or console, with ``options`` (ServeConfig's fields:
    ``lockstep``, ``speed``, ``wireless``...) on top."""
    from usarsim.server.app import Application
    from usarsim.server.config import ServeConfig

    base = {"host": "127.0.0.1", "port": 0, "seed": 0, "truth_port": None, "image_port": None, "web_port": None}
    return Application(ServeConfig(world=world, **(base | options)))


def rss_mb() -> float:
    """This process's resident memory now (MB; Linux /proc, else the peak so far)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6
    except (OSError, ValueError, IndexError):
        return peak_rss_mb()


def peak_rss_mb() -> float:
    """This process's peak resident memory so far (MB)."""
    import resource

    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return kb / 1e3 if sys.platform != "darwin" else kb / 1e6


def logging_quiet() -> None:
    import logging

    logging.getLogger("usarsim").setLevel(logging.WARNING)


def fetch_picture(sock) -> None:
    """Ask an image server for one whole picture on ``sock`` and read it to its end (UPIS,
    protocol.md 10); ConnectionError when the server closes the connection."""
    from usarsim.protocol import upis

    sock.sendall(upis.ask_whole())
    reader = upis.FrameReader()
    while True:
        data = sock.recv(max(1, min(1 << 20, reader.wanted())))
        if not data:
            raise ConnectionError("the image server closed the connection")
        if reader.feed(data):
            return
