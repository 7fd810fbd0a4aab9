"""``usarsim bench --round-trips``: lock-step STEP/STEPPED round trips a second, with no robot,
with one P2AT and against a bare echo server on the same event loop."""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
import sys

from usarsim.bench.clients import ROUND_TRIP_STEP_S
from usarsim.bench.serving import LoopThread, ServedApp, bench_app, logging_quiet


class EchoServer(LoopThread):
    """The least a lock-step server does, on the event loop a lock-step server runs: it
    greets a client with one line and answers each line with a fixed STEPPED line (no
    parsing, no simulation).  Its round trips are what the machine and the client allow."""

    REPLY = b"STEPPED {Time 0.004}\r\n"

    def __init__(self) -> None:
        self.port = 0
        self._server: asyncio.base_events.Server | None = None
        super().__init__(True, "bench-echo", self._start)

    async def _start(self) -> None:
        async def handle(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            writer.write(b"NFO {Gametype BotDeathMatch} {Level echo} {TimeLimit 0}\r\n")
            while await reader.readline():
                writer.write(self.REPLY)
            writer.close()

        self._server = await asyncio.start_server(handle, "127.0.0.1", 0)
        self.port = self._server.sockets[0].getsockname()[1]

    def stop(self) -> None:
        if self._server is not None:
            self.loop.call_soon_threadsafe(self._server.close)
        self.stop_loop()


def round_trips(port: int, robot: bool, count: int) -> float | None:
    """Round trips a second of :func:`round_trip_client` against ``port`` (None: it failed)."""
    out = subprocess.run(
        [sys.executable, "-m", "usarsim.bench", "--round-trip-client", str(port), "1" if robot else "0", str(count)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    if out.returncode != 0:
        print(f"usarsim bench: the client failed: {out.stderr.strip()[-500:]}", file=sys.stderr)
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])["round_trips_per_s"]


def run_round_trip_bench(args) -> int:
    """``bench --round-trips``: lock-step STEP/STEPPED round trips per second of a client in
    another process over loopback, with no robot and with one P2AT (4 ms steps), and of the
    same client against a bare echo server on the same event loop (:class:`EchoServer`):
    what the machine allows, to read the others against."""
    from usarsim.config.catalog import resolve_world

    logging_quiet()
    result = round_trip_result(resolve_world(args.world), int(args.count))
    if result is None:
        return 1
    if args.json:
        print(json.dumps(result))
    else:
        print(
            f"lock-step STEP/STEPPED round trips of {ROUND_TRIP_STEP_S * 1000:g} ms, one client in another "
            f"process: {result['no_robot']:.0f} a second with no robot, {result['one_p2at']:.0f} with one P2AT; "
            f"a bare echo server on the same event loop: {result['bare_echo']:.0f}"
        )
    return 0


def round_trip_result(world, count: int) -> dict | None:
    """Round trips a second with no robot, with one P2AT and against the bare echo server,
    ``count`` each (at least 100): what ``usarsim bench --round-trips --json`` prints; None
    when a client failed (said on stderr)."""

    count = max(100, int(count))
    result = {"world": world.name, "step_s": ROUND_TRIP_STEP_S, "count": count, "cpu_count": os.cpu_count()}
    for robot in (False, True):
        app = bench_app(world, lockstep=True)
        served = ServedApp(app)
        try:
            rate = round_trips(app.control.port, robot, count)
        finally:
            served.stop()
        if rate is None:
            return None
        result["one_p2at" if robot else "no_robot"] = round(rate, 1)
    echo = EchoServer()
    try:
        rate = round_trips(echo.port, False, count)
    finally:
        echo.stop()
    if rate is None:
        return None
    result["bare_echo"] = round(rate, 1)
    return result
