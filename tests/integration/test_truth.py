"""The ground-truth service (protocol.md 12.4): robots, victims, tags, false alarms and
movable objects, filtered by Class and Name, each answer ending with {End}; bad lines get
a bare {End} and the connection stays open."""

from __future__ import annotations

import re
import socket

import pytest

from helpers import Client
from usarsim.config.world_file import load_world

WORLD = """\
name: TruthArena
description: a victim, a tag, a false alarm and a brick (tests only)
floor: {center: [0, 0], size: [20, 20]}
objects:
  - {name: brick, shape: box, center: [3.0, 3.0, -0.05], size: [0.2, 0.1, 0.1], mass_kg: 0.5}
victims:
  - {name: Alice, location: [2.0, -3.0, -0.1], rotation: [0, 0, 1.5708]}
false_alarms:
  - {name: glove, center: [-2.0, 4.0, -0.1], size: [0.2, 0.2, 0.2], part: Hand}
rfid_tags:
  - {id: 11137, location: [1.0, 1.0, -0.02], memory: hi}
start_poses:
  - {name: Here, location: [-5.0, 0.0, -0.2], rotation: [0, 0, 0]}
"""
LINE = re.compile(
    r"\{Name (\S+)\} \{Class (\S+)\} \{Time \d+\.\d{4}\} \{Location (-?\d+\.\d{4}),(-?\d+\.\d{4}),"
    r"(-?\d+\.\d{4})\} \{Rotation (\d+\.\d{4}),(\d+\.\d{4}),(\d+\.\d{4})\}"
)


@pytest.fixture
def served(server_factory, tmp_path):
    (tmp_path / "TruthArena.yaml").write_text(WORLD)
    srv = server_factory(world=load_world(tmp_path / "TruthArena.yaml"))
    robot = srv.connect()
    robot.nfo()
    robot.send("INIT {ClassName USARBot.P2AT} {Name Scout} {Start Here}")
    robot.step(1.0)
    truth = Client(srv.app.truth.port)
    srv.clients.append(truth)
    return srv, truth


def ask(truth: Client, request: str) -> list[tuple]:
    truth.send(request)
    rows = []
    for line in truth.lines_until("{End}"):
        if line.text == "{End}":
            assert line.raw == b"{End}\r\n"
            break
        m = LINE.fullmatch(line.text)
        assert m, line.text
        rows.append((m.group(1), m.group(2), tuple(float(v) for v in m.group(3, 4, 5))))
    return rows


def test_everything_then_by_class_and_name(served):
    srv, truth = served
    rows = {(n, c): loc for n, c, loc in ask(truth, "{Class} {Name}")}
    everything = {(n, c): loc for n, c, loc in ask(truth, "{Other 1}")}
    assert set(everything) == set(rows)  # keys other than Class and Name are ignored
    assert set(rows) == {
        ("Scout", "P2AT"),
        ("Alice", "Victim"),
        ("11137", "RFIDTag"),
        ("glove", "FalseAlarm"),
        ("brick", "MovableObject"),
    }
    assert rows[("11137", "RFIDTag")] == (1.0, 1.0, -0.02)
    assert rows[("Alice", "Victim")] == pytest.approx((2.0, -3.0, -0.1), abs=1e-3)
    scout = rows[("Scout", "P2AT")]
    assert scout[0] == pytest.approx(-5.0, abs=0.02) and scout[2] == pytest.approx(-0.1455, abs=0.01)
    assert [r[:2] for r in ask(truth, "{class victim}")] == [("Alice", "Victim")]
    assert [r[:2] for r in ask(truth, "{Name scout}")] == [("Scout", "P2AT")]
    assert ask(truth, "{Class P2AT} {Name Nobody}") == []


def test_it_follows_the_world_and_survives_bad_lines(served):
    srv, truth = served
    robot = srv.clients[0]
    robot.send("DRIVE {Left 3} {Right 3}")
    robot.step(2.0)
    (x1,) = [loc[0] for _, _, loc in ask(truth, "{Class P2AT}")]
    assert x1 > -5.0 + 0.5  # it moved, and the service says so
    for bad in ("hello", "{unclosed", "\x00\xff"):
        truth.sock.sendall(bad.encode("latin-1") + b"\r\n")
        assert truth.wait_line(lambda ln: True).text == "{End}"
    assert len(ask(truth, "{Class Victim}")) == 1  # still serving


def test_the_service_lists_the_victims_of_the_yellow_arena(server_factory):
    srv = server_factory()
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
    c.step(0.5)

    def request(line: bytes) -> list[bytes]:
        with socket.create_connection(("127.0.0.1", srv.app.truth.port), timeout=10) as s:
            s.sendall(line)
            data = b""
            while b"{End}\r\n" not in data:
                data += s.recv(4096)
        return data.split(b"\r\n")[:-1]

    assert request(b"{Class P2AT}\r\n")[0].startswith(b"{Name R1} {Class P2AT} {Time ")
    victims = request(b"{Class Victim}\r\n")
    assert victims[-1] == b"{End}"
    names = sorted(re.match(rb"\{Name (\S+)\} \{Class Victim\}", v).group(1) for v in victims[:-1])
    assert names == [b"Anna", b"Ben", b"Carl"]
