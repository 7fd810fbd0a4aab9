"""The radio channel over TCP (docs/wireless.md, "The channel"): a ComServer link between two
ComStations in line of sight of each other, in a lock-step server whose world's ``wireless``
section sets the channel.  The messages go through the robots' own sockets, as a controller's
do, and what arrives is read after each STEP."""

from __future__ import annotations

import json
import socket
import struct

import pytest
from test_wireless import Wcs, listener, positions, stations, wcs_open

from helpers import ServerThread, wait_for

WORLD = """\
name: ChannelArena
description: two ComStations 20 m apart in the open (tests only)
floor: {{center: [0.0, 0.0], size: [60.0, 40.0]}}
wireless:
  channel: {channel}
start_poses:
  - {{name: S, location: [0.0, 5.0, -0.2], rotation: [0.0, 0.0, 0.0]}}
"""


# a bursty, faded, jittery, capped channel (the lock-step determinism tests)
BURSTY = (
    "{loss: {model: gilbert_elliott, p_good_bad: 0.1, p_bad_good: 0.3}, fading: rayleigh, "
    "link_bytes_per_s: 20000, latency_s: 0.02, jitter_s: 0.03}"
)


def channel_server(tmp_path, channel: str, seed: int = 4, **serve_options) -> ServerThread:
    from usarsim.config.world_file import load_world

    p = tmp_path / "ChannelArena.yaml"
    p.write_text(WORLD.format(channel=channel))
    srv = ServerThread(load_world(p), seed=seed, **serve_options).start()
    stations(srv, ["A0", "B0"])
    return srv


def open_link(srv: ServerThread, keep) -> tuple[socket.socket, socket.socket, object]:
    """A ComServer link A0 -> B0: (A0's end, B0's end, the command connection)."""
    w = Wcs(srv.app.wireless.comserver.port)
    keep(w.sock)
    for name in ("A0", "B0"):
        assert w.ask(f"REGISTER {name} 127.0.0.1;") == "OK;"
    la, lb = keep(listener(), listener())
    reply, ends = wcs_open(w, "A0", la, "B0", lb)
    assert reply == "OK;" and ends is not None
    keep(*ends)
    ends[1].setblocking(False)
    return ends[0], ends[1], w


def pending(srv: ServerThread) -> int:
    return srv.on_sim(lambda sim: srv.app.facade.radio_net.channel.pending)


def delivered_bytes(srv: ServerThread, link: tuple[str, str] | None = None) -> int:
    """Bytes the channel delivered so far: on ``link`` (sender, receiver), or on every link."""
    counts = srv.on_sim(lambda sim: srv.app.facade.radio_net.counts())
    return sum(c.delivered_bytes for k, c in counts.items() if link is None or k == link)


def read_delivered(srv: ServerThread, sock: socket.socket, so_far: int, link: tuple[str, str] | None = None) -> bytes:
    """What the channel has delivered to ``sock`` (on ``link``) beyond the ``so_far`` bytes read
    before (the server writes it before its STEPPED; this waits for it to cross the loopback)."""
    want = delivered_bytes(srv, link) - so_far
    out = b""

    def more() -> bool:
        nonlocal out
        try:
            out += sock.recv(1 << 20)
        except BlockingIOError:
            pass
        return len(out) >= want

    wait_for(more, what=f"{want} delivered bytes to arrive")
    return out


def frames(payloads: list[bytes]) -> bytes:
    return b"".join(b"SEND %d %s;" % (len(p), p) for p in payloads)


@pytest.fixture
def sockets():
    made: list[socket.socket] = []

    def keep(*socks):
        made.extend(socks)
        return socks

    yield keep
    for s in made:
        s.close()


def test_a_megabyte_over_a_link_capped_at_125_kb_s_takes_8_simulated_seconds(tmp_path, sockets):
    srv = channel_server(tmp_path, "{link_bytes_per_s: 125000, queue_bytes: 2000000}")
    try:
        a, b, _w = open_link(srv, sockets)
        a.sendall(frames([bytes([k % 251]) * 1000 for k in range(1000)]))  # 1,000,000 bytes
        wait_for(lambda: pending(srv) == 1000, what="the ComServer to hand every message to the channel")
        ctl = srv.connect()
        got, done_at = b"", None
        t0 = srv.on_sim(lambda sim: sim.time)
        for _ in range(100):  # 10 simulated seconds in steps of 0.1 s
            ctl.step(0.1)
            got += read_delivered(srv, b, len(got))
            if len(got) >= 1_000_000 and done_at is None:
                done_at = srv.on_sim(lambda sim: sim.time) - t0
        assert len(got) == 1_000_000
        assert got == b"".join(bytes([k % 251]) * 1000 for k in range(1000))  # whole and in order
        assert done_at == pytest.approx(8.0, rel=0.05)
        counts = srv.on_sim(lambda sim: srv.app.facade.radio_net.counts())[("a0", "b0")]
        assert counts.delivered == 1000 and counts.delivered_bytes == 1_000_000
    finally:
        srv.stop()


def test_an_independent_loss_of_20_percent_drops_20_percent_of_10000_messages(tmp_path, sockets):
    record, score = tmp_path / "loss.mcap", tmp_path / "score.json"
    srv = channel_server(
        tmp_path, "{loss: {model: independent, rate: 0.2}}", record=str(record), score=True, score_file=str(score)
    )
    try:
        a, b, _w = open_link(srv, sockets)
        a.sendall(frames([struct.pack(">I", k) for k in range(10_000)]))
        wait_for(lambda: pending(srv) == 10_000, what="the ComServer to hand every message to the channel")
        srv.connect().step(0.1)
        assert pending(srv) == 0  # every message settled
        got = read_delivered(srv, b, 0)
        arrived = [struct.unpack(">I", got[i : i + 4])[0] for i in range(0, len(got), 4)]
        assert arrived == sorted(arrived)  # in the order sent
        lost = 1.0 - len(arrived) / 10_000
        assert abs(lost - 0.2) < 0.02, lost
        counts = srv.on_sim(lambda sim: srv.app.facade.radio_net.counts())[("a0", "b0")]
        assert counts.delivered == len(arrived) and counts.dropped["loss"] == 10_000 - len(arrived)
        srv.connect().step(1.0)  # the traffic is sampled with the links, every simulated second
    finally:
        srv.stop()
    # the numbers, in the score file and the recording
    team = json.loads(score.read_text())
    assert team["team"]["messages_lost"] == 10_000 - len(arrived)
    assert team["team"]["messages_delivered"] == len(arrived)
    assert team["radio"]["a0>b0"]["dropped"] == {"range": 0, "loss": 10_000 - len(arrived), "capacity": 0}
    from mcap.reader import make_reader

    with open(record, "rb") as f:
        traffic = [json.loads(m.data) for _, _, m in make_reader(f).iter_messages(topics=["/usarsim/radio/traffic"])]
    assert traffic[-1]["a0>b0"]["dropped_loss"] == 10_000 - len(arrived)
    assert traffic[-1]["a0>b0"]["delivered"] == len(arrived)


def test_a_gilbert_elliott_link_loses_in_bursts_of_the_documented_length(tmp_path, sockets):
    # docs/wireless.md: a bad spell lasts 1 / p_bad_good messages on average (4 here) and the
    # long-run loss is p_good_bad / (p_good_bad + p_bad_good) = 0.074
    srv = channel_server(tmp_path, "{loss: {model: gilbert_elliott, p_good_bad: 0.02, p_bad_good: 0.25}}")
    n = 40_000
    try:
        a, b, _w = open_link(srv, sockets)
        a.sendall(frames([struct.pack(">I", k) for k in range(n)]))
        wait_for(lambda: pending(srv) == n, what="the ComServer to hand every message to the channel")
        srv.connect().step(0.1)
        got = read_delivered(srv, b, 0)
    finally:
        srv.stop()
    arrived = {struct.unpack(">I", got[i : i + 4])[0] for i in range(0, len(got), 4)}
    runs, run = [], 0  # the lengths of the runs of lost messages
    for k in range(n):
        if k not in arrived:
            run += 1
        elif run:
            runs.append(run)
            run = 0
    assert sum(runs) / len(runs) == pytest.approx(4.0, rel=0.1)
    assert 1.0 - len(arrived) / n == pytest.approx(0.02 / 0.27, rel=0.1)


def handed(srv: ServerThread) -> int:
    """Messages handed to the channel so far: under way, delivered or dropped."""

    def count(sim) -> int:
        net = srv.app.facade.radio_net
        done = sum(c.delivered + sum(c.dropped.values()) for c in net.counts().values())
        return done + net.channel.pending

    return srv.on_sim(count)


def run_bursty(tmp_path, sockets, seed: int) -> list[tuple[int, list[int]]]:
    """(STEP number, messages that arrived by it) over 3 s of 0.05 s STEPs, with 20 messages
    of 100 bytes sent before each STEP, on a bursty, faded, jittery, capped channel."""
    srv = channel_server(tmp_path, BURSTY, seed=seed)
    try:
        a, b, _w = open_link(srv, sockets)
        ctl = srv.connect()
        out, buf, total, sent = [], b"", 0, 0
        for step in range(60):
            a.sendall(frames([struct.pack(">I", sent + k) * 25 for k in range(20)]))
            sent += 20
            wait_for(lambda: handed(srv) == sent, what="the messages to reach the channel")  # noqa: B023
            ctl.step(0.05)
            new = read_delivered(srv, b, total)
            total += len(new)
            buf += new
            whole = len(buf) // 100 * 100
            out.append((step, [struct.unpack(">I", buf[i : i + 4])[0] for i in range(0, whole, 100)]))
            buf = buf[whole:]
        return out
    finally:
        srv.stop()


def test_two_lockstep_runs_with_the_same_seed_deliver_the_same_messages_at_the_same_times(tmp_path, sockets):
    first = run_bursty(tmp_path, sockets, seed=8)
    second = run_bursty(tmp_path, sockets, seed=8)
    assert first == second
    delivered = [m for _, ms in first for m in ms]
    assert 300 < len(delivered) < 1150  # some lost, most through
    assert run_bursty(tmp_path, sockets, seed=9) != first


def relayed_pair(srv, sockets) -> tuple[socket.socket, socket.socket]:
    """Robot A0's end and robot B0's end of a WSS relay from A0 to B0 (both closed with the test)."""
    from test_wireless import wss_dns

    from helpers import DEFAULT_TIMEOUT

    la, lb = sockets(listener(), listener())
    ca, cb, relay = wss_dns(srv, "A0", "B0", la, lb)
    a = socket.create_connection(("127.0.0.1", relay), timeout=DEFAULT_TIMEOUT)
    b, _ = lb.accept()
    sockets(a, b, ca.sock, cb.sock)
    return a, b


def test_a_wss_relay_carries_its_bytes_through_the_capped_channel_both_ways(tmp_path, sockets):
    srv = channel_server(tmp_path, "{link_bytes_per_s: 50000, queue_bytes: 1000000}")
    try:
        a, b = relayed_pair(srv, sockets)
        up, down = bytes(range(256)) * 400, bytes(range(255, -1, -1)) * 200  # 100 kB and 50 kB
        a.sendall(up)
        b.sendall(down)
        wait_for(lambda: handed_bytes(srv) == len(up) + len(down), what="the relay to hand both ways to the channel")
        for s in (a, b):
            s.setblocking(False)
        ctl = srv.connect()
        got_a = got_b = b""
        times = {}
        for step in range(1, 41):  # 4 simulated seconds
            ctl.step(0.1)
            got_b += read_delivered(srv, b, len(got_b), ("a0", "b0"))
            got_a += read_delivered(srv, a, len(got_a), ("b0", "a0"))
            for key, got, want in (("up", got_b, up), ("down", got_a, down)):
                if len(got) == len(want) and key not in times:
                    times[key] = step * 0.1
        assert got_b == up and got_a == down  # whole and in order, both ways
        # each robot's radio sends at 50 kB/s: 100 kB take 2 s, 50 kB 1 s
        assert times["up"] == pytest.approx(2.0, abs=0.11) and times["down"] == pytest.approx(1.0, abs=0.11)
    finally:
        srv.stop()


def run_wss_bursty(tmp_path, sockets, seed: int) -> list[tuple[int, list[int]]]:
    """(STEP number, messages that arrived by it) over 2 s of 0.05 s STEPs through a WSS relay,
    5 messages of 100 bytes written before each STEP, each read by the relay alone (one
    message: the next is written once it is in the channel's hands)."""
    srv = channel_server(tmp_path, BURSTY, seed=seed)
    try:
        a, b = relayed_pair(srv, sockets)
        b.setblocking(False)
        ctl = srv.connect()
        out, got, sent = [], b"", 0
        for step in range(40):
            for _ in range(5):
                a.sendall(struct.pack(">I", sent) * 25)
                sent += 1
                wait_for(lambda: handed(srv) == sent, what="the message to reach the channel")  # noqa: B023
            ctl.step(0.05)
            new = read_delivered(srv, b, len(got), ("a0", "b0"))
            out.append((step, [struct.unpack(">I", new[i : i + 4])[0] for i in range(0, len(new), 100)]))
            got += new
        return out
    finally:
        srv.stop()


def test_two_lockstep_runs_through_a_wss_relay_deliver_the_same_messages_at_the_same_times(tmp_path, sockets):
    first = run_wss_bursty(tmp_path, sockets, seed=8)
    assert first == run_wss_bursty(tmp_path, sockets, seed=8)
    delivered = [m for _, ms in first for m in ms]
    assert 40 < len(delivered) < 200 and delivered == sorted(delivered)  # some lost, the rest in order
    assert run_wss_bursty(tmp_path, sockets, seed=9) != first


def handed_bytes(srv: ServerThread) -> int:
    """Bytes handed to the channel so far: under way or delivered (nothing is dropped here)."""

    def count(sim) -> int:
        net = srv.app.facade.radio_net
        ch = net.channel
        under_way = ch.under_way_bytes()
        return under_way + sum(c.delivered_bytes for c in net.counts().values())

    return srv.on_sim(count)


def test_the_python_client_lists_a_radios_neighbours(tmp_path):
    from usarsim.client.radio import Radio

    srv = channel_server(tmp_path, "{shadowing_db: 3}")
    radios = []
    try:
        radios = [Radio("127.0.0.1", srv.app.wireless.comserver.port, name) for name in ("A0", "B0")]
        (n,) = radios[0].neighbours()
        assert n.name == "B0" and n.quality == pytest.approx(1.0, abs=1e-3)
        # the shadowed signal: GETSS and the neighbour list agree on it
        assert n.dbm == pytest.approx(radios[0].signal("B0"), abs=0.006)
        assert [m.name for m in radios[1].neighbours()] == ["A0"]
    finally:
        for r in radios:
            r.close()
        srv.stop()


RELAY_WORLD = """\
name: RelayLane
description: a short-range radio (n = 3) along an open lane (tests only)
floor: {center: [0.0, 0.0], size: [60.0, 20.0]}
wireless: {eN: 3.0, eCutoff: -70.0}
start_poses:
  - {name: S, location: [0.0, 5.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""


def relay_run(tmp_path, drop: bool, **serve_options) -> tuple[str, list[str], bytes]:
    """A ComStation at x = -10 and a robot with a RelayDropper starting at x = -2: it drops a
    relay there (or not), drives to x = 5, beyond the station's reach (9.5 m with n = 3 and a
    -70 dBm cutoff), and opens a link to it.  (OPEN's reply, the robot's neighbours, what the
    station received)."""
    from test_wireless import spawn

    from usarsim.client.radio import Radio, link
    from usarsim.config.catalog import ROBOTS_DIR
    from usarsim.config.world_file import load_world

    head = (ROBOTS_DIR / "P2AT.yaml").read_text().split("\nsensors:")[0]
    robots = tmp_path / ("robots-drop" if drop else "robots-keep")
    robots.mkdir()
    (robots / "Courier.yaml").write_text(
        head.replace("class_name: P2AT", "class_name: Courier")
        + "\nsensors:\n  - {type: RelayDropper, name: Relays, location: [-0.2, 0.0, 0.08], capacity: 1}\n"
    )
    p = tmp_path / "RelayLane.yaml"
    p.write_text(RELAY_WORLD)
    srv = ServerThread(load_world(p), seed=3, robot_dirs=(str(robots),), **serve_options).start()
    radios = []
    try:
        (station,) = spawn(srv, [("ComStation", "Base", "-10,0,-0.61")])
        (courier,) = spawn(srv, [("Courier", "Courier", "-2,0,-0.2")])
        if drop:
            reply = courier.ask("SET {Type RelayDropper} {Name Relays} {Opcode Drop}", "RES")
            assert "{Status OK}" in reply.text, reply.text
            again = courier.ask("SET {Type RelayDropper} {Name Relays} {Opcode Drop}", "RES")
            assert "{Status Failed}" in again.text  # it carried one
        courier.send("DRIVE {Left 5} {Right 5}")
        for _ in range(200):
            courier.step(0.1)
            if positions(srv)["Courier"][0] >= 5.0:
                break
        courier.send("DRIVE {Left 0} {Right 0}")
        courier.step(0.5)
        assert positions(srv)["Courier"][0] >= 5.0
        port = srv.app.wireless.comserver.port
        radios = [Radio("127.0.0.1", port, name) for name in ("Courier", "Base")]
        if drop:  # the ground-truth service (and with it the console's map) shows the relay
            from usarsim.sim.truth import truth_rows

            rows = srv.on_sim(lambda sim: truth_rows(sim, "RadioRelay", None))
            assert [(r[0], r[1]) for r in rows] == [("Courier-Relay1", "RadioRelay")]
            assert abs(rows[0][3][0] - (-2.2)) < 0.15  # dropped at x = -2, the item 0.2 m behind the centre
        opened = link(radios[0], radios[1])
        neighbours = [n.name for n in radios[0].neighbours()]
        got = b""
        if opened:
            assert radios[0].send("Base", b"victim at 3,4")
            courier.step(0.1)
            courier.step(1.0)  # the traffic is sampled with the links, every simulated second
            msgs = wait_for(lambda: radios[1].poll(), what="the message to arrive")  # noqa: B023
            got = msgs[0][1] if msgs[0][0] == "Courier" else b""
        return ("OK;" if opened else "Fail;"), neighbours, got
    finally:
        for r in radios:
            r.close()
        srv.stop()


def test_a_robot_out_of_reach_of_the_comstation_reaches_it_through_a_relay_it_dropped(tmp_path):
    without, neighbours_without, _ = relay_run(tmp_path, drop=False)
    assert without == "Fail;" and neighbours_without == []
    record, score = tmp_path / "relay.mcap", tmp_path / "score.json"
    with_relay, neighbours_with, got = relay_run(
        tmp_path, drop=True, record=str(record), score_file=str(score), score=True
    )
    assert with_relay == "OK;" and got == b"victim at 3,4"
    assert neighbours_with == ["Courier-Relay1"]  # the relay is in reach; the station is not
    # the recording has the relay where it was dropped (x = -2 less the item's 0.2 m)
    from mcap.reader import make_reader

    relays = []
    with open(record, "rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages(topics=["/usarsim/relays"]):
            relays.append(json.loads(message.data) if channel.message_encoding == "json" else message.data)
    assert relays, "no relay in the recording"
    assert b"Courier-Relay1" in (relays[-1] if isinstance(relays[-1], bytes) else json.dumps(relays[-1]).encode())


def test_a_dropped_relay_is_drawn_in_pictures():
    from helpers import gl_problem

    if problem := gl_problem():
        pytest.skip(problem)
    import mujoco

    from usarsim.sim.render import SEEN, camera_renderer, draw_relays

    m = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><light pos='0 -1 3' dir='0 0.3 -1'/>"
        "<geom type='plane' size='5 5 0.1' rgba='0.5 0.5 0.5 1'/></worldbody></mujoco>"
    )
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    cam = mujoco.MjvCamera()
    cam.lookat[:] = (0.0, 0.0, 0.1)
    cam.distance, cam.azimuth, cam.elevation = 1.5, 90.0, -30.0
    r = camera_renderer(m, 160, 120, shadows=False)
    try:
        pictures = []
        for relays in ((), ((0.0, 0.0, 0.2),)):
            r.update_scene(d, cam, SEEN)
            draw_relays(r.scene, relays)
            pictures.append(r.render().astype(int))
    finally:
        r.close()
    orange = [((p[..., 0] > 150) & (p[..., 1] > 60) & (p[..., 1] < 160) & (p[..., 2] < 60)).sum() for p in pictures]
    assert orange[0] == 0 and orange[1] > 150, orange  # the box is about 17 x 17 pixels here
