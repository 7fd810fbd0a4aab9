"""The connection base every port shares (server/connection.py), without sockets."""

from __future__ import annotations

import logging

from usarsim.server.connection import MAX_LOGGED_KINDS, LogOnce, ReadGate, ServerConnection, transport_peer


class FakeTransport:
    def __init__(self, peer=("10.0.0.7", 4321)):
        self.peer = peer
        self.reading = True
        self.closing = False
        self.written: list[bytes] = []

    def get_extra_info(self, name):
        return self.peer if name == "peername" else None

    def pause_reading(self):
        self.reading = False

    def resume_reading(self):
        self.reading = True

    def is_closing(self):
        return self.closing

    def close(self):
        self.closing = True

    def write(self, data):
        self.written.append(data)


class FakeServer:
    def __init__(self, max_connections: int):
        self.connections: set = set()
        self.max_connections = max_connections


class Viewer(ServerConnection):
    what = "image"
    limit_option = "--max-viewers"


def test_a_peer_is_ip_colon_port_with_ip_and_port_kept_apart():
    assert transport_peer(FakeTransport()) == ("10.0.0.7", 4321, "10.0.0.7:4321")
    assert transport_peer(FakeTransport(None)) == ("", 0, "?")


def test_each_kind_is_logged_once_and_the_kinds_are_bounded(caplog):
    once = LogOnce(logging.getLogger("usarsim.test"), "wss 1.2.3.4:5", " (logged once per connection)")
    with caplog.at_level(logging.INFO, logger="usarsim.test"):
        for i in range(3 * MAX_LOGGED_KINDS):
            once(f"kind{i % (2 * MAX_LOGGED_KINDS)}", "problem %d", i)
    msgs = [r.getMessage() for r in caplog.records]
    assert len(msgs) == MAX_LOGGED_KINDS + 1
    assert msgs[0] == "wss 1.2.3.4:5: problem 0 (logged once per connection)"
    assert "more than 32 kinds of problem" in msgs[-1]


def test_the_read_gate_closes_at_its_limit_and_opens_below_half():
    t, gate = FakeTransport(), ReadGate(8)
    assert not gate.queued(t, 7) and t.reading
    assert gate.queued(t, 8) and not t.reading
    assert not gate.queued(t, 9)  # closed already: nothing more to log
    gate.taken(t, 4)
    assert not t.reading
    gate.taken(t, 3)
    assert t.reading


def test_past_the_limit_a_connection_is_refused_and_logged(caplog):
    server = FakeServer(max_connections=1)
    first, second = Viewer(server), Viewer(server)
    with caplog.at_level(logging.INFO, logger="usarsim"):
        first.connection_made(FakeTransport())
        t = FakeTransport(("10.0.0.8", 99))
        second.connection_made(t)
    assert server.connections == {first} and t.closing and not second.accepted
    assert "image 10.0.0.8:99: refused: 1 connections already (limit --max-viewers 1)" in caplog.text
    second.connection_lost(None)  # a refused connection leaves nothing to undo
    first.connection_lost(None)
    assert server.connections == set() and first.transport is None


def test_writes_are_dropped_once_the_connection_closes_and_writing_pauses():
    conn = Viewer(FakeServer(4))
    t = FakeTransport()
    conn.connection_made(t)
    assert conn.write_text("OK\u00e9") and t.written == [b"OK?"]
    conn.pause_writing()
    assert not conn.writable
    conn.resume_writing()
    assert conn.writable
    t.closing = True
    assert not conn.write(b"x") and t.written == [b"OK?"]
