"""The bench's clients, each a process of its own (``python -m usarsim.bench --client`` and
``--round-trip-client``): one that spawns and drives N P2ATs, one connection each, and reads
every line they are sent; and a lock-step controller that times STEP/STEPPED round trips."""

from __future__ import annotations

import asyncio
import json
import time


async def drive_clients(port: int, poses: list, seconds_hint: float) -> None:
    """Child process: one connection per robot, INIT, then drive and read everything."""
    conns = []
    for i, (x, y, z, yaw) in enumerate(poses):
        r, w = await asyncio.open_connection("127.0.0.1", port, limit=1 << 20)
        w.write(
            f"INIT {{ClassName USARBot.P2AT}} {{Name Bench{i + 1}}} {{Location {x:.2f},{y:.2f},{z:.2f}}} "
            f"{{Rotation 0,0,{yaw:.4f}}}\r\n".encode()
        )
        conns.append((r, w))

    async def drive(i, r, w):
        lines = 0
        phase = 0
        last_t = -1.0
        try:
            while True:
                line = await r.readline()
                if not line:
                    return
                lines += 1
                if line.startswith(b"STA"):
                    t = float(line.split(b"{Time ", 1)[1].split(b"}", 1)[0])
                    if t - last_t >= 2.0:
                        last_t = t
                        phase += 1
                        left, right = ((2.0, 2.0), (-1.0, 1.0), (1.5, 1.5), (1.0, -1.0))[(phase + i) % 4]
                        w.write(f"DRIVE {{Left {left}}} {{Right {right}}}\r\n".encode())
        except (ConnectionError, OSError):
            return

    await asyncio.gather(*(drive(i, r, w) for i, (r, w) in enumerate(conns)))


ROUND_TRIP_STEP_S = 0.004  # one physics step of the shipped worlds (their timestep_s)


def round_trip_client(port: int, robot: bool, count: int) -> None:
    """Child process: optionally spawn a P2AT, then ``count`` STEP/STEPPED round trips, one at
    a time, as a lock-step controller does; prints the round trips a second."""
    import socket

    s = socket.create_connection(("127.0.0.1", port))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    f = s.makefile("rb")
    f.readline()  # NFO
    if robot:
        s.sendall(b"INIT {ClassName USARBot.P2AT} {Name R1}\r\nPING {Id spawned}\r\n")
        while not f.readline().startswith(b"PONG"):
            pass
    line = b"STEP {Time %g}\r\n" % ROUND_TRIP_STEP_S
    for _ in range(min(200, count // 10)):  # warm up
        s.sendall(line)
        while not f.readline().startswith(b"STEPPED"):
            pass
    t0 = time.perf_counter()
    for _ in range(count):
        s.sendall(line)
        while not f.readline().startswith(b"STEPPED"):
            pass
    print(json.dumps({"round_trips_per_s": count / (time.perf_counter() - t0)}), flush=True)
