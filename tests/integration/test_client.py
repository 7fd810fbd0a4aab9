"""The Python client (usarsim.client) against real simulators: launched on free ports in a
subprocess, or in-process servers; lock-step steps that leave every robot's messages read;
the server's refusals as errors with its reason; timeouts instead of hangs; the asyncio
client with the same names; the PING/PONG extension it relies on."""

from __future__ import annotations

import asyncio
import math
import re
import socket
import threading
import time

import pytest

from usarsim.client import ClientError, ClientTimeout, ServerError, aio, connect, launch
from usarsim.readings import PoseReading


@pytest.fixture(scope="module")
def server():
    with launch(world="DM-USAR_yellow", seed=1) as srv:
        yield srv


def test_launch_spawn_drive_and_step(server):
    with server.connect() as world:
        assert world.level == "DM-USAR_yellow"
        assert [p.name for p in world.start_poses][:2] == ["PlayerStart1", "PlayerStart2"]
        robot = world.spawn("P2AT", name="R1", start="PlayerStart1")
        t0 = world.time
        x0 = world.truth("P2AT", "R1")[0].location[0]
        for _ in range(30):
            robot.drive(left=2.0, right=2.0)
            t = world.step(0.1)
        assert t == pytest.approx(t0 + 3.0, abs=1e-6)
        # 2 rad/s on 0.13 m wheels: about 0.26 m/s straight ahead (+x)
        x, y, yaw = robot.odometry()
        assert x == pytest.approx(0.7, abs=0.15) and abs(y) < 0.05
        (gx, gy, _), _ = robot.ground_truth()
        assert gx - x0 == pytest.approx(x, abs=0.05)
        scan = robot.scan()
        assert scan.name == "Scanner1" and len(scan.ranges) == 181 and scan.max_range == pytest.approx(20.0)
        assert scan.angles[0] == pytest.approx(-math.pi / 2, abs=0.01)  # the first beam is the rightmost
        pts = scan.points()
        assert pts.shape == (181, 2) and pts[0, 1] > 0  # ... to the right: +Y
        assert robot.status.battery_s > 0
        assert {"Scanner1", "Odometry", "GroundTruth", "Sonar"} <= set(robot.readings)
        robot.move("CameraPanTilt", {1: 0.2, 2: 0.1})
        for _ in range(20):
            world.step(0.1)
        assert robot.links("CameraPanTilt") == pytest.approx({1: 0.2, 2: 0.1}, abs=0.02)
        robot.close()


def test_after_a_step_every_robot_has_read_up_to_the_new_time(server):
    with server.connect() as world:
        robots = [world.spawn("P2AT", name=f"S{i}", start=f"PlayerStart{i + 2}") for i in range(3)]
        for _ in range(5):
            t = world.step(0.1)
            for r in robots:
                # GroundTruth every 0.1 s: its latest reading is the one at the new time
                times = [
                    m.time
                    for m in r.messages
                    if getattr(m, "reading", None) is not None
                    and isinstance(m.reading, PoseReading)
                    and m.reading.sensor_type == "GroundTruth"
                ]
                assert times and times[-1] == pytest.approx(t, abs=1e-4), (r.name, times[-3:], t)
                r.take_messages()


def test_the_servers_refusals_are_errors_with_its_reason(server):
    with server.connect() as world:
        with pytest.raises(ServerError, match="unknown robot class 'USARBot.NoSuchBot'") as err:
            world.spawn("NoSuchBot")
        assert err.value.command == "INIT"
        with pytest.raises(ServerError, match="inside box 'outer_n'"):
            world.spawn("P2AT", name="W", location=(6.0, 1.0, -0.3))
        with pytest.raises(ServerError, match="unknown start pose"):
            world.spawn("P2AT", name="X", start="Nowhere")
        assert world.robots == {}
        robot = world.spawn("P2AT", name="W")  # the world's first start pose
        assert robot.conf().class_name == "P2AT"
        with pytest.raises(TypeError, match="unknown keys"):
            robot.drive(lft=1.0)


def test_ping_is_answered_after_everything_before_it():
    # over the wire, as any client could use it (an extension)
    with launch(world="DM-USAR_yellow", seed=2) as srv:
        s = socket.create_connection((srv.host, srv.port), timeout=10)
        with s:
            s.sendall(b"INIT {ClassName USARBot.NoSuchBot}\r\nPING {Id a1}\r\nPING\r\n")
            data = b""
            while data.count(b"PONG") < 2:
                data += s.recv(65536)
        lines = data.decode().split("\r\n")
        err = next(i for i, ln in enumerate(lines) if ln.startswith("ERROR {Command INIT}"))
        pongs = [i for i, ln in enumerate(lines) if ln.startswith("PONG")]
        assert err < pongs[0]  # the spawn's answer comes first
        assert re.fullmatch(r"PONG \{Id a1\} \{Time 0\.0000\}", lines[pongs[0]])
        assert re.fullmatch(r"PONG \{Time 0\.0000\}", lines[pongs[1]])


def test_real_time_reading_without_steps():
    with launch(world="DM-USAR_yellow", seed=1, lockstep=False, speed=None) as srv, srv.connect() as world:
        robot = world.spawn("P2AT", start="PlayerStart1")
        with pytest.raises(ClientError, match="lock-step"):
            world.step(0.1)
        robot.drive(left=2.0, right=2.0)
        world.wait(1.0)
        assert world.time > 0.5 and robot.odometry() is not None
        res = robot.set("Odometry", "Odometry", "RESET")
        assert res.status == "OK"


def test_a_silent_server_times_out_naming_what_did_not_come():
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    port = listener.getsockname()[1]
    accepted = []
    threading.Thread(target=lambda: accepted.append(listener.accept()), daemon=True).start()
    t0 = time.monotonic()
    with pytest.raises(ClientTimeout, match="NFO greeting"):
        connect("127.0.0.1", port, timeout=1.0)
    assert time.monotonic() - t0 < 3.0
    for s, _ in accepted:
        s.close()
    listener.close()
    with pytest.raises(ClientError, match="cannot connect"):
        connect("127.0.0.1", port, timeout=1.0)


def test_launch_returns_with_every_listener_it_asked_for_and_each_answers():
    with launch(world="DM-USAR_yellow", wireless=True, image=True) as srv:
        assert set(srv.ports) == {"control", "truth", "image", "comserver", "wss", "cominterface"}
        for port in srv.ports.values():  # each is listening already
            socket.create_connection((srv.host, port), timeout=5).close()


def test_a_simulator_that_cannot_start_is_an_error_with_its_reason():
    with pytest.raises(ClientError, match="did not start.*no-such-world"):
        launch(world="no-such-world")


def test_killing_the_server_mid_run_raises_instead_of_hanging():
    srv = launch(world="DM-USAR_yellow", seed=1)
    world = None
    try:
        world = srv.connect(timeout=5.0)
        robot = world.spawn("P2AT")
        world.step(0.2)
        srv.proc.kill()
        srv.proc.wait(10)
        t0 = time.monotonic()
        with pytest.raises(ClientError, match="closed the connection"):
            for _ in range(100):
                robot.drive(left=1.0, right=1.0)
                world.step(0.2)
        assert time.monotonic() - t0 < 5.0
    finally:
        if world is not None:
            world.close()
        srv.close()


def test_the_asyncio_client_has_the_same_names(server):
    async def main():
        world = await aio.connect(server.host, server.port, lockstep=True, truth_port=server.ports["truth"])
        async with world:
            robot = await world.spawn("P2AT", name="A1", start="PlayerStart5")
            for _ in range(20):
                await robot.drive(left=-1.0, right=1.0)  # turn on the spot
                await world.step(0.1)
            scan = await robot.scan()
            conf = await robot.conf("Robot")
            truth = await world.truth(name="A1")
            with pytest.raises(ServerError):
                await world.spawn("NoSuchBot")
            return robot.odometry(), scan, conf, truth

    odo, scan, conf, truth = asyncio.run(main())
    assert abs(odo[2]) > 0.2  # it turned
    assert len(scan.ranges) == 181 and conf.class_name == "P2AT"
    assert truth[0].name == "A1"


def test_the_readme_example_runs_as_printed():
    import subprocess
    import sys
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    section = readme.split("## Write a controller in Python", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    assert "from usarsim.client import launch" in code and len(code.splitlines()) <= 24
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    *decisions, last = out.stdout.splitlines()
    assert re.fullmatch(r"t=30\.0 s: odometry -?\d+\.\d\d, -?\d+\.\d\d m, heading -?\d+\.\d\d rad", last)
    assert decisions and all(re.fullmatch(r"t=\d+\.\d s (stuck|\d\.\d\d m from a wall): turning", d) for d in decisions)
    # at PlayerStart1 it is caught on something below the laser (the brick, the doll) and gets away
    assert any(" stuck: " in d for d in decisions)
    x, y = (float(v) for v in re.search(r"odometry (\S+), (\S+) m", last).groups())
    assert abs(x) + abs(y) > 3.0  # it went somewhere


def test_a_robot_cameras_picture_as_a_numpy_array():
    with launch(world="DM-USAR_yellow", seed=1, image=True) as srv, srv.connect() as world:
        robot = world.spawn("P2AT", start="PlayerStart1")
        world.step(0.5)
        ahead = robot.picture()
        assert ahead.shape == (480, 640, 3) and ahead.dtype.name == "uint8"
        assert ahead.std() > 5.0  # a scene, not a blank frame
        for _ in range(20):  # turn away: the picture changes
            robot.drive(left=-2.0, right=2.0)
            world.step(0.1)
        turned = robot.picture()
        assert abs(turned.astype(float) - ahead.astype(float)).mean() > 5.0


def test_commands_sent_before_a_step_take_effect_in_it_every_time(server):
    """A DRIVE goes out on the robot's connection, the STEP on the world's: the client makes
    sure the DRIVE is in the simulation first, so that two runs are alike."""

    def run():
        with launch(world="DM-USAR_yellow", seed=3) as srv, srv.connect() as world:
            robot = world.spawn("P2AT", start="PlayerStart1")
            poses = []
            for i in range(15):
                robot.drive(left=3.0 if i % 3 else -3.0, right=3.0)
                world.step(0.05)
                poses.append(robot.ground_truth())
            return poses

    first = run()
    assert first[-1][0][0] > first[0][0][0]  # it moved
    assert run() == first


def test_robots_talk_over_the_simulated_radio_only_while_the_link_holds(tmp_path):
    # a short-range radio: the link holds within about 4 m only (cutoff -53 dBm)
    ini = tmp_path / "radio.ini"
    ini.write_text("[USARBot.ComServer]\nModel=distance\neCutoff=-53\n")
    with (
        launch(world="DM-USAR_yellow", seed=1, wireless=True, extra_args=("--wireless-config", str(ini))) as srv,
        srv.connect() as world,
    ):
        a = world.spawn("P2AT", name="A", start="PlayerStart1")
        b = world.spawn("P2AT", name="B", location=(-9.5, 2.0, -0.25))  # 2 m away
        far = world.spawn("P2AT", name="C", start="PlayerStart8")  # 8 m away
        world.step(0.2)
        near_dbm, far_dbm = a.signal_to(b), a.signal_to("C")
        assert near_dbm > -53 > far_dbm
        assert a.send_to(b, b"victim at 3,4")
        assert not a.send_to(far, b"out of range")  # the ComServer refuses the link
        world.step(0.2)
        deadline = time.monotonic() + 5
        got = []
        while not got and time.monotonic() < deadline:
            got = b.received()
            time.sleep(0.02)
        assert got == [("A", b"victim at 3,4")]
        assert far.received() == []
