"""Load and faults (issue: reliability): connect/INIT/drive/disconnect cycles leave nothing
behind; a client flooding DRIVE lines does not slow the others' status messages; a client
that never reads is held to latest-wins and bounded memory while everyone else runs on."""

from __future__ import annotations

import gc
import os
import socket
import struct
import threading
import time

import pytest
from stress_scale import scaled

from helpers import Client

# wall-clock rates and deadlines: run by itself when the suite is shared among processes (scripts/test.sh)
pytestmark = pytest.mark.alone


def open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return 0.0


def test_connect_init_drive_disconnect_cycles_leave_nothing_behind(server_factory):
    srv = server_factory(lockstep=False, speed=None, seed=2)
    port = srv.port
    cycles = scaled(150, 1000)

    def cycle(i: int) -> None:
        s = socket.create_connection(("127.0.0.1", port), timeout=10)
        f = s.makefile("rb")
        f.readline()  # NFO
        s.sendall(
            f"INIT {{ClassName USARBot.P2AT}} {{Name C{i}}} {{Location {-16 + (i % 5) * 1.5},-6,-0.3}}\r\n"
            "DRIVE {Left 2} {Right 2}\r\n".encode()
        )
        while b"STA" not in f.readline():  # the robot exists and reports
            pass
        if i % 2:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # abrupt reset
        f.close()
        s.close()

    for i in range(10):  # warm up: caches, compiled kernels, the event loop's buffers
        cycle(i)
    gc.collect()
    time.sleep(0.5)
    fds, threads, mem = open_fds(), threading.active_count(), rss_mb()
    t0 = time.perf_counter()
    for i in range(cycles):
        cycle(i)
    elapsed = time.perf_counter() - t0
    deadline = time.monotonic() + 10
    while srv.on_sim(lambda sim: len(sim.robots)) and time.monotonic() < deadline:
        time.sleep(0.05)
    gc.collect()
    assert srv.on_sim(lambda sim: len(sim.robots)) == 0
    assert threading.active_count() <= threads
    assert open_fds() <= fds + 2
    grown = rss_mb() - mem
    print(
        f"\n{cycles} cycles in {elapsed:.1f} s; fds {fds} -> {open_fds()}, threads {threads}, "
        f"memory {mem:.0f} MB -> {rss_mb():.0f} MB"
    )
    assert grown < 40.0


def test_a_drive_flood_does_not_slow_the_other_robots(server_factory):
    """One client sends DRIVE lines as fast as it can; the others' STA lines keep their 5 Hz."""
    others = scaled(7, 63)
    flood_lines = int(os.environ.get("USARSIM_FLOOD_LINES", scaled(100_000, 500_000)))
    srv = server_factory(lockstep=False, speed=1.0, seed=3, max_connections=others + 2)
    clients = []
    for i in range(others):
        c = srv.connect()
        c.nfo()
        c.send(
            f"INIT {{ClassName USARBot.Zerg}} {{Name O{i}}} {{Location {-19 + (i % 9) * 1.2},{-9 + (i // 9) * 1.2},-0.3}}"
        )
        clients.append(c)
    flooder = socket.create_connection(("127.0.0.1", srv.port), timeout=10)
    flooder.recv(4096)
    flooder.sendall(b"INIT {ClassName USARBot.Zerg} {Name Flood} {Location -8,8,-0.3}\r\n")
    time.sleep(2.0)
    for c in clients:
        c.sock.settimeout(0.0) if hasattr(c, "sock") else None
    counts = [0] * others
    stop = threading.Event()

    def reader(k: int, c: Client) -> None:
        while not stop.is_set():
            try:
                line = c.next_line(timeout=0.5)
            except Exception:
                continue
            if line.text.startswith("STA") and t_start <= time.monotonic() <= t_end:
                counts[k] += 1

    line = b"DRIVE {Left 1.5} {Right -1.5}\r\n"
    burst = line * 1000
    t_start = time.monotonic() + 0.3
    t_end = t_start + 3.0
    readers = [threading.Thread(target=reader, args=(k, c), daemon=True) for k, c in enumerate(clients)]
    for th in readers:
        th.start()
    sent = 0
    while sent < flood_lines:
        flooder.sendall(burst)
        sent += 1000
    flood_s = time.monotonic() - (t_start - 0.3)
    while time.monotonic() < t_end + 0.3:
        time.sleep(0.05)
    stop.set()
    for th in readers:
        th.join(2)
    flooder.close()
    window = 3.0
    rates = [n / window for n in counts]
    print(
        f"\n{flood_lines} DRIVE lines sent in {flood_s:.2f} s; STA rates of {others} robots: "
        f"{min(rates):.2f} .. {max(rates):.2f} per s (5 expected)"
    )
    assert all(abs(r - 5.0) <= 0.5 + 1e-9 for r in rates), rates


def test_a_client_that_never_reads_is_bounded_and_harms_no_one(server_factory):
    """A client whose socket is never read: once what waits for it passes the high-water
    mark, its sensor lines are held latest-wins (one per stream) and the rest dropped, its
    replies still queue, memory stays bounded and the other client is served throughout."""
    from usarsim.server.control import HIGH_WATER

    srv = server_factory(lockstep=False, speed=None, seed=5)
    lazy = socket.socket()
    try:
        lazy.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # a small window, set before connecting
        lazy.settimeout(10)
        lazy.connect(("127.0.0.1", srv.port))
        lazy.sendall(b"INIT {ClassName USARBot.P2AT} {Name Lazy} {Start PlayerStart2}\r\nDRIVE {Left 1} {Right 1}\r\n")
        busy = srv.connect()
        busy.nfo()
        busy.send("INIT {ClassName USARBot.P2AT} {Name Busy} {Start PlayerStart3}")
        time.sleep(0.5)
        mem = rss_mb()

        def lazy_stats():
            rows = srv.on_loop(
                lambda: [
                    (c.transport.get_write_buffer_size(), len(c._held), c.dropped_periodic)
                    for c in srv.app.control.connections.values()
                    if c.transport is not None and getattr(c.session, "robot_name", "") == "Lazy"
                ]
            )
            return rows[0]

        t0 = time.monotonic()
        t_min, t_max = t0 + scaled(4.0, 30.0), t0 + scaled(60.0, 120.0)
        n = asked = 0
        while True:  # at least t_min, and until the lazy client's lines are being dropped
            line = busy.next_line(timeout=5.0)
            n += line.text.startswith("SEN")
            if n % 200 == 0:
                lazy.sendall(b"GETSTARTPOSES\r\n")  # replies pile up too: they are never dropped
                asked += 1
                now = time.monotonic()
                if now > t_max or (now > t_min and lazy_stats()[2] > 0):
                    break
        wall = time.monotonic() - t0
        sim_time = srv.on_sim(lambda sim: sim.time)
        buffered, held, dropped = lazy_stats()
        grown = rss_mb() - mem
        print(
            f"\nbusy client got {n} SEN lines in {wall:.0f} s wall ({sim_time:.0f} simulated s); "
            f"memory grew {grown:.1f} MB; the lazy client: {buffered} bytes waiting, {held} streams held "
            f"latest-wins, {dropped} periodic lines dropped"
        )
        assert n > 100 and grown < 60.0
        assert dropped > 0, "the lazy client's buffer never reached the high-water mark"
        reply = len(srv.connect().nfo().text) + len(srv.clients[-1].ask("GETSTARTPOSES", "NFO").text) + 4
        assert buffered < HIGH_WATER + asked * reply + 64 * 1024 and held <= 64
    finally:
        lazy.close()


def _real_time_witness(server_factory, seed: int):
    """A real-time server and the client of a P2AT whose status lines show the world runs."""
    srv = server_factory(lockstep=False, speed=1.0, seed=seed)
    w = srv.connect()
    w.nfo()
    w.send("INIT {ClassName USARBot.P2AT} {Name Witness} {Start PlayerStart1}")
    w.wait_line("STA")
    return srv, w


def test_query_floods_on_the_other_ports_do_not_stall_the_world(server_factory):
    """Clients that pour requests into the ground-truth, ComServerInterface, WSS and image
    ports and never read the answers: each connection is answered one request at a time
    (its socket unread beyond a backlog, no answer asked while its unread answers pass the
    high-water mark), so the robot's status keeps its 5 Hz and memory stays bounded; a
    polite client of each port is still answered."""
    from helpers import gl_problem

    lines = scaled(100_000, 1_000_000)
    srv, w = _real_time_witness(server_factory, seed=9)
    floods = [
        (srv.app.truth.port, b"{Class Victim}\r\n{Class}\r\n"),
        (srv.app.wireless.interface.port, b"GETOBS {Start -1e30,0,1} {End 1e30,0,1}\r\nGETPOS\r\n"),
        (srv.app.wireless.wss.port, b"GETSS {Robot Witness}\r\n"),
    ]
    if not gl_problem():
        floods.append((srv.app.image.port, b"OKU" + struct.pack(">IIII", 0, 0, 64, 64)))
        with socket.create_connection(("127.0.0.1", srv.app.image.port), timeout=30) as first:
            first.sendall(b"OK")  # the renderer is made before memory is measured
            assert first.recv(5)
    socks = []
    for port, _unit in floods:
        s = socket.create_connection(("127.0.0.1", port), timeout=10)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        if port == srv.app.wireless.wss.port:
            s.sendall(b"INIT {Robot Flooder} {Port 9}\r\n")
        socks.append(s)
    mem = rss_mb()
    stop = threading.Event()
    sent = [0] * len(floods)

    def pour(k: int, s: socket.socket, unit: bytes) -> None:
        chunk = unit * max(1, 8192 // len(unit))
        per = len(chunk) // len(unit)
        s.settimeout(0.2)
        while not stop.is_set() and sent[k] < lines:
            try:
                s.sendall(chunk)
                sent[k] += per
            except TimeoutError:
                pass  # the server reads no more for now: it answers what it has first
            except OSError:
                return

    threads = [
        threading.Thread(target=pour, args=(k, s, u), daemon=True) for k, (s, (_, u)) in enumerate(zip(socks, floods))
    ]
    for th in threads:
        th.start()
    window = scaled(4.0, 20.0)
    t0 = time.monotonic() + 0.5
    count = 0
    while time.monotonic() < t0 + window:
        line = w.next_line(timeout=5.0)
        count += line.text.startswith("STA") and time.monotonic() >= t0
    # polite clients are answered meanwhile
    probe = socket.create_connection(("127.0.0.1", srv.app.truth.port), timeout=10)
    probe.sendall(b"{Class Victim}\r\n")
    assert b"{End}" in probe.recv(65536)
    probe.close()
    with Client(srv.app.wireless.interface.port) as polite:
        assert polite.ask("GETPOS", "POSITIONS").text.startswith("POSITIONS {Robots 1}")
    stop.set()
    for th in threads:
        th.join(5)
    grown = rss_mb() - mem
    for s in socks:
        s.close()
    rate = count / window
    print(
        f"\nfloods of {', '.join(str(n) for n in sent)} request lines on {len(floods)} ports: the robot's STA "
        f"at {rate:.2f} per s (5 expected); memory grew {grown:.1f} MB"
    )
    assert abs(rate - 5.0) <= 0.5
    assert grown < 80.0
    assert min(sent) > 0
    assert w.sync()


def test_a_client_that_asks_and_never_reads_is_bounded_and_loses_nothing(server_factory):
    """A client pours GETSTARTPOSES lines and does not read: once its unread replies pass
    a few high-water marks its further lines wait unread (memory stays bounded, the other
    robot runs on); when it reads at last, every reply arrives, none lost."""
    from usarsim.server.control import HIGH_WATER, REPLY_CAP_FACTOR

    asks = scaled(20_000, 200_000)
    srv, w = _real_time_witness(server_factory, seed=12)
    asker = socket.create_connection(("127.0.0.1", srv.port), timeout=30)
    mem = rss_mb()
    burst = b"GETSTARTPOSES\r\n" * 1000
    done = threading.Event()

    def pour():
        for _ in range(asks // 1000):
            asker.sendall(burst)  # blocks once the server stops reading: TCP pushes back
        done.set()

    threading.Thread(target=pour, daemon=True).start()
    t0 = time.monotonic()
    sta = 0
    while time.monotonic() < t0 + 4.0:
        sta += w.next_line(timeout=5.0).text.startswith("STA")
    waiting = srv.on_loop(
        lambda: max(
            c.transport.get_write_buffer_size() for c in srv.app.control.connections.values() if c.transport is not None
        )
    )
    grown = rss_mb() - mem
    print(
        f"\nunread replies held at {waiting // 1024} kB (cap {REPLY_CAP_FACTOR * HIGH_WATER // 1024} kB); "
        f"memory grew {grown:.1f} MB; the witness got {sta} STA lines in 4 s"
    )
    assert waiting < REPLY_CAP_FACTOR * HIGH_WATER + 256 * 1024
    assert grown < 40.0 and sta >= 18
    # it reads at last: every one of its questions is answered
    asker.settimeout(30)
    got = 0
    while got < asks + 1:  # the NFO greeting, then one NFO {StartPoses ...} per question
        data = asker.recv(1 << 20)
        assert data
        got += data.count(b"\n")
    assert done.wait(30)
    asker.close()
    assert got == asks + 1
