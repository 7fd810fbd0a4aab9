"""Hostile and broken input on the control, ground-truth and image ports (issue:
reliability): each gets the documented reply or is ignored, and the connection, the
server and another client's robot stay healthy."""

from __future__ import annotations

import math
import os
import socket
import struct
import time

import pytest

from helpers import ground_truth, sensor_lines


@pytest.fixture
def witness_server(server_factory):
    """A lock-step server with a witness robot whose SEN lines prove the world runs on."""
    srv = server_factory(seed=4)
    w = srv.connect()
    w.nfo()
    w.send("INIT {ClassName USARBot.P2AT} {Name Witness} {Start PlayerStart1}")
    w.step(0.5)
    srv.witness = w
    return srv


def assert_world_runs(srv, seconds: float = 0.5) -> None:
    lines = srv.witness.step(seconds)
    assert len(sensor_lines(lines, "GroundTruth")) >= int(seconds / 0.1)
    ((_, loc, ori),) = ground_truth(lines)[-1:]
    assert all(math.isfinite(v) for v in (*loc, *ori)) and abs(ori[0]) < 0.1 and abs(ori[1]) < 0.1


def assert_alive(client) -> None:
    assert client.ask("GETSTARTPOSES", "NFO {StartPoses").text.startswith("NFO {StartPoses")


@pytest.mark.parametrize(
    "payload",
    [
        os.urandom(4096) + b"\r\n",
        b"DRIVE {Left \xff\xfe\xfd} {Right 1}\r\n",  # invalid UTF-8
        b"DRIVE " + b"9" * 100_000 + b"\r\n",  # far longer than a line may be
        b"\x00\x01\x02\r\n{{{{}}}}\r\n}}}{{\r\n",
        b"INIT {ClassName USARBot.P2AT} {Location nan,0,0}\r\n",
        b"INIT {ClassName USARBot.P2AT} {Location 1e308,1e308,1e308}\r\n",
        b"INIT {ClassName USARBot.P2AT} {Location 500,500,-0.3}\r\n",  # outside the world
        b"INIT {ClassName USARBot.NoSuchRobot} {Start PlayerStart2}\r\n",
        b"DRIVE {Left 1} {Right 1}\r\nSET {Type Camera} {Name Camera} {Opcode Zoom} {Params 1}\r\n",  # before INIT
    ],
    ids=[
        "garbage",
        "bad-utf8",
        "over-long",
        "braces",
        "init-nan",
        "init-huge",
        "init-outside",
        "unknown-class",
        "before-init",
    ],
)
def test_broken_lines_are_refused_and_everything_runs_on(witness_server, payload):
    srv = witness_server
    c = srv.connect()
    c.nfo()
    c.send_raw(payload)
    assert_alive(c)
    assert_world_runs(srv)
    assert srv.on_sim(lambda sim: sorted(r.name for r in sim.robots.values())) == ["Witness"]


def test_absurd_numbers_for_a_live_robot_change_nothing_else(witness_server):
    srv = witness_server
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name Target} {Start PlayerStart3}")
    c.step(0.3)
    for line in [
        "DRIVE {Left NaN} {Right inf}",
        "DRIVE {Left 1e308} {Right -1e308}",
        "DRIVE {Speed nan}",
        "MISPKG {Name CameraPanTilt} {Link 1} {Value nan}",
        "MISPKG {Name CameraPanTilt} {Link 2} {Value 1e300}",
        "MULTIDRIVE {CameraPanTilt_Link1 inf}",
        "SET {Type Camera} {Name Camera} {Opcode Zoom} {Params inf}",
        "SET {Type Joint} {Name CameraPanTilt_Link2} {Opcode Torque} {Params 1e30}",
        "CAMERA {Rotation nan,inf,-inf} {Zoom nan}",
        "INIT {ClassName USARBot.P2AT} {Name Twice}",
    ]:
        c.send(line)
    lines = c.step(1.0)
    ((_, loc, _),) = ground_truth(lines)[-1:]
    assert all(math.isfinite(v) for v in loc)
    assert_alive(c)
    assert_world_runs(srv)
    assert srv.on_sim(lambda sim: sorted(r.name for r in sim.robots.values())) == ["Target", "Witness"]


def test_a_robot_put_inside_a_wall_does_not_disturb_the_others(witness_server):
    srv = witness_server
    before = ground_truth(srv.witness.step(0.1))[-1][1]
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name Walled} {Location 0.0,-7.2,-0.3}")  # in the west outer wall
    refused = [ln.text for ln in c.step(1.0) if ln.text.startswith("ERROR")]
    assert refused and "is inside box 'outer_w'" in refused[0], refused
    assert_alive(c)
    after = ground_truth(srv.witness.step(0.1))[-1][1]
    assert math.dist(before, after) < 0.05  # the witness stood still, untouched


def test_half_a_line_then_a_disconnect_leaves_nothing_behind(witness_server):
    srv = witness_server
    for abrupt in (False, True):
        s = socket.create_connection(("127.0.0.1", srv.port), timeout=5)
        s.recv(4096)
        s.sendall(b"INIT {ClassName USARBot.P2")
        if abrupt:  # a reset rather than a close
            s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        s.close()
    assert_world_runs(srv)
    assert srv.on_sim(lambda sim: sorted(r.name for r in sim.robots.values())) == ["Witness"]


def test_the_truth_and_image_ports_shrug_off_garbage(witness_server):
    srv = witness_server
    truth = socket.create_connection(("127.0.0.1", srv.app.truth.port), timeout=5)
    truth.sendall(os.urandom(3000) + b"\r\n" + b"{Class " + b"x" * 10_000 + b"\r\n{Class Victim}\r\n")
    data = b""
    while data.count(b"{End}") < 2:
        chunk = truth.recv(65536)
        assert chunk
        data += chunk
    image = socket.create_connection(("127.0.0.1", srv.app.image.port), timeout=5)
    image.sendall(os.urandom(2000).replace(b"O", b"o").replace(b"U", b"u"))
    image.sendall(b"U" + struct.pack(">IIII", 2**32 - 1, 2**32 - 1, 2**32 - 1, 2**32 - 1))  # far off the picture
    head = b""
    while len(head) < 5:
        chunk = image.recv(5 - len(head))
        assert chunk
        head += chunk
    kind, length = struct.unpack(">BI", head)
    assert (kind, length) == (0, 4)  # an empty raw picture: 0 x 0
    assert image.recv(4) == b"\x00\x00\x00\x00"
    truth.close()
    image.close()
    assert_world_runs(srv)


def test_repeated_drive_lines_collapse_but_actions_and_joint_orders_do_not():
    from usarsim.protocol.framing import REPEATED_DRIVE as _REPEATED_DRIVE

    data = (
        b"DRIVE {Left 1} {Right 1}\r\n" * 1000
        + b"DRIVE {Flip True}\r\n" * 2
        + b"DRIVE {Name Arm} {Value 0.1} {Order 10}\r\n" * 2
        + b"MISPKG {Name DRIVE}\r\nDRIVE}\r\nDRIVE}\r\n"
    )
    assert _REPEATED_DRIVE.sub(rb"\1", data) == (
        b"DRIVE {Left 1} {Right 1}\r\n"
        + b"DRIVE {Flip True}\r\n" * 2
        + b"DRIVE {Name Arm} {Value 0.1} {Order 10}\r\n" * 2
        + b"MISPKG {Name DRIVE}\r\nDRIVE}\r\n"
    )


def test_limits_are_refused_and_logged(server_factory, caplog):
    """Past --max-robots an INIT is refused (logged), past --max-viewers a viewer is turned
    away (logged); the robots and viewers already there go on."""
    import logging

    srv = server_factory(seed=8)
    srv.app.control.max_robots = 2
    srv.app.truth.max_connections = 1
    clients = []
    with caplog.at_level(logging.INFO, logger="usarsim"):
        for i, start in enumerate(("PlayerStart1", "PlayerStart2", "PlayerStart3")):
            c = srv.connect()
            c.nfo()
            c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name R{i}}} {{Start {start}}}")
            clients.append(c)
        clients[0].step(0.3)
        assert srv.on_sim(lambda sim: sorted(r.name for r in sim.robots.values())) == ["R0", "R1"]
        assert any("INIT refused" in r.getMessage() and "--max-robots" in r.getMessage() for r in caplog.records)
        first = socket.create_connection(("127.0.0.1", srv.app.truth.port), timeout=5)
        first.sendall(b"{Class Victim}\r\n")
        assert b"{End}" in first.recv(65536)
        second = socket.create_connection(("127.0.0.1", srv.app.truth.port), timeout=5)
        assert second.recv(100) == b""  # turned away
        assert any("refused" in r.getMessage() for r in caplog.records if "truth" in r.getMessage())
        first.sendall(b"{Class Victim}\r\n")
        assert b"{End}" in first.recv(65536)
        first.close()
        second.close()
    assert_alive(clients[2])


def test_the_web_port_shrugs_off_garbage_and_oversized_messages(witness_server):
    """Garbage instead of HTTP, and a page sending binary junk and a message over the size
    limit on its control socket: the console turns them away and goes on serving."""
    import asyncio
    import threading

    import aiohttp

    srv = witness_server
    port = srv.app.web.port
    raw = socket.create_connection(("127.0.0.1", port), timeout=5)
    raw.sendall(os.urandom(4096) + b"\r\n\r\n")
    raw.settimeout(5)
    try:
        while raw.recv(65536):
            pass
    except (TimeoutError, ConnectionResetError):
        pass
    raw.close()

    async def page():
        async with aiohttp.ClientSession() as s:
            async with s.ws_connect(f"http://127.0.0.1:{port}/ws/control") as ws:
                await ws.send_bytes(os.urandom(1000))
                await ws.send_str("x" * 200_000)  # over the page message limit
                closed = False
                try:
                    while True:
                        msg = await asyncio.wait_for(ws.receive(), 5)
                        if msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.ERROR):
                            closed = True
                            break
                except TimeoutError:
                    pass
            async with s.get(f"http://127.0.0.1:{port}/api/info") as r:
                return closed, r.status

    box = {}  # on a thread of its own: the browser tests may leave an event loop running here
    t = threading.Thread(target=lambda: box.update(result=asyncio.run(page())))
    t.start()
    t.join(30)
    closed, status = box["result"]
    assert status == 200
    assert_world_runs(srv)
    assert srv.on_sim(lambda sim: sorted(r.name for r in sim.robots.values())) == ["Witness"]


def test_wireless_and_web_connection_limits_are_refused_and_logged(witness_server, caplog):
    """Past --max-wireless-connections a ComServer, WSS or ComServerInterface connection is
    closed at once (logged); past --max-web-connections a console request is answered 503
    (logged).  The connections already there, and the robots, go on."""
    import logging
    import urllib.error
    import urllib.request

    srv = witness_server
    wireless = srv.app.wireless
    with caplog.at_level(logging.INFO, logger="usarsim"):
        for server, ask, answer in (
            (wireless.comserver, b"GETSS Witness Witness;", b"Fail"),
            (wireless.wss, b"INIT {Robot W1} {Port 9000}\r\n", b"INITREPLY {Status OK}"),
            (wireless.interface, b"GETPOS\r\n", b"POSITIONS {Robots 1}"),
        ):
            server.listener.max_connections = 1
            first = socket.create_connection(("127.0.0.1", server.port), timeout=5)
            second = socket.create_connection(("127.0.0.1", server.port), timeout=5)
            second.settimeout(5)
            assert second.recv(100) == b""  # turned away
            first.sendall(ask)
            first.settimeout(5)
            assert answer in first.recv(4096), server
            first.close()
            second.close()
        refusals = [r.getMessage() for r in caplog.records if "--max-wireless-connections" in r.getMessage()]
        assert len(refusals) == 3

        web = srv.app.web
        web.max_connections = 2
        url = f"http://127.0.0.1:{web.port}/api/info"
        idle = [socket.create_connection(("127.0.0.1", web.port), timeout=5) for _ in range(2)]
        try:
            with pytest.raises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(url, timeout=5)
            assert refused.value.code == 503 and b"connections" in refused.value.read()
        finally:
            for s in idle:
                s.close()
        assert any("--max-web-connections" in r.getMessage() for r in caplog.records)
        deadline = time.monotonic() + 5
        while True:  # the idle connections are gone once the server has seen them close
            try:
                with urllib.request.urlopen(url, timeout=5) as r:
                    assert r.status == 200
                break
            except urllib.error.HTTPError:
                assert time.monotonic() < deadline
    assert_world_runs(srv)
    assert_alive(srv.witness)


def test_camera_bindings_cannot_grow_without_bound(witness_server, caplog):
    """SET {Type Camera} with ever new viewer addresses (and absurdly long ones): the table
    of bindings stops at its limit, the refusal is logged once, bound viewers keep theirs."""
    import logging

    from usarsim.server.image import CameraBindings

    srv = witness_server
    bindings = srv.app.camera_bindings
    c = srv.witness
    with caplog.at_level(logging.WARNING, logger="usarsim"):
        c.send("SET {Type Camera} {Robot Witness} {Name Camera} {Client 10.0.0.1}")
        c.send("SET {Type Camera} {Robot Witness} {Name Camera} {Client " + "9" * 5000 + "}")
        burst = "".join(
            f"SET {{Type Camera}} {{Robot Witness}} {{Name Camera}} {{Client 10.{i >> 16}.{(i >> 8) & 255}."
            f"{i & 255}:{1000 + i % 50000}}}\r\n"
            for i in range(CameraBindings.MAX_BINDINGS + 500)
        )
        c.send_raw(burst.encode())
        c.sync()
    assert len(bindings) == CameraBindings.MAX_BINDINGS
    assert bindings.lookup("10.0.0.1", 5) == ("Witness", "Camera")
    refusals = [r for r in caplog.records if "viewer address" in r.getMessage()]
    assert len(refusals) == 1
    assert_world_runs(srv)


def test_comserver_tables_cannot_grow_without_bound(witness_server):
    """REGISTER and LISTEN with ever new names and ports: past the ComServer's limits each
    is refused with a Fail reply; what was registered before keeps working."""
    from usarsim.server.wireless import MAX_LISTENING, MAX_REGISTERED

    srv = witness_server
    s = socket.create_connection(("127.0.0.1", srv.app.wireless.comserver.port), timeout=10)
    s.settimeout(10)
    buf = b""

    def replies(n: int) -> list[bytes]:
        nonlocal buf
        while buf.count(b";") < n:
            data = s.recv(65536)
            assert data
            buf += data
        *out, buf = buf.split(b";", n)
        return out

    s.sendall(b"".join(b"REGISTER R%d 127.0.0.1;" % i for i in range(MAX_REGISTERED + 3)))
    got = replies(MAX_REGISTERED + 3)
    assert got[:MAX_REGISTERED] == [b"OK"] * MAX_REGISTERED
    assert got[MAX_REGISTERED:] == [b"Fail: Too many robots registered"] * 3
    s.sendall(b"".join(b"LISTEN R%d %d;" % (i % 8, 1 + i) for i in range(MAX_LISTENING + 2)))
    got = replies(MAX_LISTENING + 2)
    assert got[:MAX_LISTENING] == [b"OK"] * MAX_LISTENING and got[-1] == b"Fail: Too many robots listening"
    s.sendall(b"REGISTER R5 127.0.0.1;")  # registered before: still known
    assert replies(1) == [b"OK"]
    s.close()
    assert_world_runs(srv)


def test_ever_new_garbage_is_logged_within_bounds(witness_server, caplog):
    """Thousands of different unknown commands on the control, WSS and ComServerInterface
    ports: each connection logs a bounded number of warnings (the first kinds, then one
    note that more follow) and keeps answering."""
    import logging

    from usarsim.server.connection import MAX_LOGGED_KINDS

    srv = witness_server
    junk = b"".join(b"NOSUCH%d {A 1}\r\n" % i for i in range(3000))
    wss, interface = srv.app.wireless.wss.port, srv.app.wireless.interface.port
    with caplog.at_level(logging.INFO, logger="usarsim"):
        c = srv.connect()
        c.nfo()
        c.send_raw(junk)
        assert_alive(c)
        for port, first, last, answers in (
            (wss, b"INIT {Robot G} {Port 9}\r\n", b"", 3001),
            (interface, b"", b"GETPOS\r\n", 1),
        ):
            with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
                s.sendall(first + junk + last)
                s.settimeout(10)
                got = b""
                while got.count(b"\n") < answers:
                    data = s.recv(1 << 16)
                    assert data
                    got += data
    per_peer: dict[str, int] = {}
    for r in caplog.records:
        if "NOSUCH" in r.getMessage() or "kinds of problem" in r.getMessage():
            peer = r.getMessage().split(": ")[0]
            per_peer[peer] = per_peer.get(peer, 0) + 1
    assert len(per_peer) == 3 and all(n <= MAX_LOGGED_KINDS + 1 for n in per_peer.values()), per_peer
    assert_world_runs(srv)


def test_wss_relay_ports_are_bounded(witness_server, monkeypatch, caplog):
    """DNS for ever new ports of a robot that declared many: each relay port is a listening
    socket, so past the limit the WSS answers Could.Not.Allocate.Port (logged) and keeps
    the file descriptors for everyone else; ports allocated before keep their numbers."""
    import logging

    from helpers import Client
    from usarsim.server.wireless import wss as wireless

    monkeypatch.setattr(wireless, "MAX_RELAY_PORTS", 3)
    srv = witness_server
    port = srv.app.wireless.wss.port
    with Client(port) as a, Client(port) as b, caplog.at_level(logging.WARNING, logger="usarsim"):
        assert (
            a.ask("INIT {Robot Witness} {Port " + ",".join(str(p) for p in range(2000, 2400)) + "}", "INITREPLY").text
            == "INITREPLY {Status OK}"
        )
        assert b.ask("INIT {Robot Other} {Port 7}", "INITREPLY").text == "INITREPLY {Status OK}"
        replies = [b.ask(f"DNS {{Robot Witness}} {{Port {p}}}", "").text for p in range(2000, 2005)]
        assert all(r.startswith("DNSREPLY {Robot Witness} {Port ") for r in replies[:3])
        assert replies[3:] == ["ERROR {Reason Could.Not.Allocate.Port}"] * 2
        assert b.ask("DNS {Robot Witness} {Port 2001}", "").text == replies[1]
        assert any("no relay port" in r.getMessage() for r in caplog.records)
    assert_world_runs(srv)


def test_comserver_links_are_bounded(witness_server, monkeypatch, caplog):
    """OPEN past the limit of open links is refused (logged), as a link the server cannot
    establish."""
    import logging

    from usarsim.server.wireless import comserver as wireless

    monkeypatch.setattr(wireless, "MAX_LINKS", 0)
    s = socket.create_connection(("127.0.0.1", witness_server.app.wireless.comserver.port), timeout=10)
    with caplog.at_level(logging.WARNING, logger="usarsim"):
        s.sendall(b"REGISTER A0 127.0.0.1;REGISTER B0 127.0.0.1;LISTEN B0 4000;OPEN A0 4001 B0 4000;")
        got = b""
        while got.count(b";") < 4:
            data = s.recv(4096)
            assert data
            got += data
    assert got.split(b";")[:4] == [b"OK", b"OK", b"OK", b"Fail: Could not establish connection"]
    assert any("links open already" in r.getMessage() for r in caplog.records)
    s.close()
