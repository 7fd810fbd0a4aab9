"""Lock-step ordering over real sockets: commands are applied by the STEP that follows them,
however the controller wrote them (usarsim.server.ordering), and the requests of one
connection are answered in order, whatever the segmentation.

The clients here are raw sockets with Nagle's algorithm on (as most USARSim clients left it):
a small write that follows an unacknowledged one is held back by the client's kernel.
"""

from __future__ import annotations

import contextlib
import re
import socket
import subprocess
import sys
import time

import pytest

from helpers import segments

RUNS = 20
STEP_S = 0.2
STEPS = 4


class Raw:
    """A control connection that writes exactly what it is given, one write per call, with
    Nagle's algorithm on."""

    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=10)
        self.buf = b""
        self.until(b"NFO")

    def write(self, *lines: str) -> None:
        self.sock.sendall("".join(f"{ln}\r\n" for ln in lines).encode("ascii"))

    def until(self, prefix: bytes) -> list[str]:
        """Every line up to and including the first that starts with ``prefix``."""
        out = []
        while True:
            while b"\r\n" not in self.buf:
                data = self.sock.recv(1 << 16)
                assert data, "the server closed the connection"
                self.buf += data
            line, self.buf = self.buf.split(b"\r\n", 1)
            out.append(line.decode("ascii"))
            if line.startswith(prefix):
                return out

    def close(self) -> None:
        self.sock.close()


@contextlib.contextmanager
def busy_core():
    """The second core kept busy by another process for the duration."""
    p = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        p.kill()
        p.wait()


# What each robot's controller writes before each STEP: one list of writes per step, each
# write a tuple of lines ("sleep" pauses the writer 1 ms between two writes).
A_WRITES = [
    [("DRIVE {Left 1} {Right 1}",), ("MISPKG {Name CameraPanTilt} {Link 2} {Value 0.4}",), ("DRIVE {Light True}",)],
    [("DRIVE {Left 0.5} {Right 1.5}",), "sleep", ("MISPKG {Name CameraPanTilt} {Link 1} {Value -0.5}",)],
    [("SET {Type Odometry} {Opcode RESET}",), ("DRIVE {Left 0} {Right 0}",)],
    [("DRIVE {Left -1} {Right -1}",), ("DRIVE {Light False}",)],
]
B_WRITES = [
    [("DRIVE {Left -1} {Right 1}",), ("MISPKG {Name CameraPanTilt} {Link 1} {Value 0.8}",)],
    [("DRIVE {Left 1} {Right 1}",), ("DRIVE {Light True}",), "sleep", ("DRIVE {Left 1.2} {Right 1.2}",)],
    [("MISPKG {Name CameraPanTilt} {Link 2} {Value -0.3}",)],
    [("DRIVE {Left 0} {Right 0}",)],
]


def _write(conn: Raw, writes, together: bool) -> None:
    if together:
        conn.write(*(ln for w in writes if w != "sleep" for ln in w))
        return
    for w in writes:
        if w == "sleep":
            time.sleep(0.001)
        else:
            conn.write(*w)


def _session(port: int, together: bool) -> list[str]:
    """Two P2ATs and a third connection that steps: the transcript of every line the robots
    and the stepper received, step by step."""
    a, b, c = Raw(port), Raw(port), Raw(port)
    try:
        a.write("INIT {ClassName USARBot.P2AT} {Name A} {Start Open}", "PING")
        b.write("INIT {ClassName USARBot.P2AT} {Name B} {Start OpenEast}", "PING")
        a.until(b"PONG")
        b.until(b"PONG")
        transcript = []
        for k in range(STEPS):
            _write(a, A_WRITES[k], together)
            _write(b, B_WRITES[k], together)
            c.write(f"STEP {{Time {STEP_S}}}")
            transcript += [f"C {ln}" for ln in c.until(b"STEPPED")]
            a.write("PING")
            b.write("PING")
            transcript += [f"A {ln}" for ln in a.until(b"PONG")]
            transcript += [f"B {ln}" for ln in b.until(b"PONG")]
        return transcript
    finally:
        for conn in (a, b, c):
            conn.close()


def _last(transcript: list[str], who: str, word: str, before: str) -> str:
    """The last line of ``who`` starting with ``word`` before the line ``before``."""
    end = transcript.index(before)
    return next(ln for ln in reversed(transcript[:end]) if ln.startswith(f"{who} {word}"))


def _link(missta: str, n: int) -> float:
    return float(re.search(r"\{Link %d\} \{Value ([-0-9.]+)\}" % n, missta).group(1))


@pytest.mark.alone  # it loads the second core itself
def test_separate_writes_on_three_connections_give_one_transcript(server_factory, test_world):
    reference = _session(server_factory(world=test_world, seed=3).port, together=True)
    with busy_core():
        runs = [_session(server_factory(world=test_world, seed=3).port, together=False) for _ in range(RUNS)]
    # the commands of the first step were all applied by the first STEP
    second = [ln for ln in reference if ln.startswith("C STEPPED")][1]
    assert _link(_last(reference, "A", "MISSTA", second), 2) > 0.01  # the tilt moved within the first step
    assert _link(_last(reference, "B", "MISSTA", second), 1) > 0.01  # B's pan too
    assert segments(_last(reference, "A", "STA", second)[2:])["LightToggle"] == "True"
    different = [i for i, t in enumerate(runs) if t != reference]
    if different:
        first = runs[different[0]]
        diff = next((r, s) for r, s in zip(reference, first) if r != s)
        pytest.fail(
            f"{len(different)} of {RUNS} runs with separate writes differ from the one with single "
            f"writes; the first difference: {diff}"
        )


def test_lines_after_a_step_in_the_same_write_are_for_the_next_step(server):
    robot, stepper = Raw(server.port), Raw(server.port)
    try:
        robot.write("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}", "PING")
        robot.until(b"PONG")
        # the STEP of the robot's own connection, with a tilt after it in the same write; and
        # a STEP of another connection read while it waits
        robot.write("STEP {Time 0.4}", "MISPKG {Name CameraPanTilt} {Link 2} {Value 0.4}")
        lines = robot.until(b"STEPPED")
        tilt = _link([ln for ln in lines if ln.startswith("MISSTA")][-1], 2)
        assert abs(tilt) < 0.01, "a MISPKG written after the STEP moved the tilt within it"
        stepper.write("STEP {Time 0.4}")
        stepper.until(b"STEPPED")
        robot.write("PING")
        lines = robot.until(b"PONG")
        assert _link([ln for ln in lines if ln.startswith("MISSTA")][-1], 2) > 0.05  # applied by the next one
    finally:
        robot.close()
        stepper.close()


def test_ping_after_a_set_is_answered_after_its_res(server):
    robot = Raw(server.port)
    try:
        robot.write("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}")
        robot.write("SET {Type Odometry} {Opcode RESET}", "PING {Id 7}")
        lines = robot.until(b"PONG")
        assert any(ln.startswith("RES ") and "{Type Odometry}" in ln for ln in lines), lines
        assert lines[-1].startswith("PONG {Id 7}")
    finally:
        robot.close()


@pytest.mark.parametrize("gap", [False, True])
def test_a_failing_init_and_the_query_after_it_are_answered_in_order(server, gap):
    conn = Raw(server.port)
    try:
        if gap:
            conn.write("INIT {ClassName USARBot.P2AT} {Location 900,900,0}")
            time.sleep(0.011)
            conn.write("GETCONF {Type Robot}", "PING")
        else:
            conn.write("INIT {ClassName USARBot.P2AT} {Location 900,900,0}", "GETCONF {Type Robot}", "PING")
        lines = [ln for ln in conn.until(b"PONG") if ln.startswith(("ERROR", "CONF"))]
        assert [ln.split("}", 1)[0] for ln in lines] == ["ERROR {Command INIT", "ERROR {Command GETCONF"], lines
    finally:
        conn.close()


@pytest.mark.parametrize("lockstep", [True, False])
def test_requests_in_one_write_are_answered_in_the_order_sent(server_factory, lockstep):
    srv = server_factory(lockstep=lockstep, speed=1.0)
    conn = Raw(srv.port)
    try:
        conn.write("INIT {ClassName USARBot.P2AT} {Start PlayerStart1}", "PING {Id 0}")
        conn.until(b"PONG")
        for k in range(1, 4):
            conn.write("SET {Type Odometry} {Opcode RESET}", f"PING {{Id {k}}}", "GETSTARTPOSES", "GETGEO {Type Robot}")
            answers = [
                " ".join(ln.split(" ")[:2])
                for ln in conn.until(b"GEO ")
                if ln.startswith(("RES", "PONG", "NFO", "GEO"))
            ]
            assert answers == ["RES {Time", "PONG {Id", "NFO {StartPoses", "GEO {Type"], answers
    finally:
        conn.close()
