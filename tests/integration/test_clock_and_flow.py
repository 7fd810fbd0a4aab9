"""The clock modes measured against the wall clock, a client that never reads, and a
battery that runs out."""

from __future__ import annotations

import dataclasses
import socket
import time

import pytest

from helpers import drive_skid, segments, wait_for

INIT = "INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}"


def sim_time(server) -> float:
    return server.on_sim(lambda sim: sim.time)


def wall_seconds_for(server, sim_seconds: float) -> float:
    """Wall time the server takes to run ``sim_seconds`` of simulated time."""
    t0 = sim_time(server)
    w0 = time.perf_counter()
    wait_for(
        lambda: sim_time(server) >= t0 + sim_seconds,
        timeout=30,
        interval=0.002,
        what=f"{sim_seconds} simulated seconds",
    )
    return time.perf_counter() - w0


@pytest.mark.alone  # wall-clock pacing: run by itself (scripts/test.sh)
@pytest.mark.parametrize("speed", [1.0, 4.0])
def test_real_time_and_accelerated_clocks_follow_the_wall_clock(server_factory, speed):
    srv = server_factory(lockstep=False, speed=speed)
    c = srv.connect()
    c.nfo()
    c.send(INIT)
    c.wait_line("STA")
    wall = wall_seconds_for(srv, 1.0 * speed)
    assert wall == pytest.approx(1.0, abs=0.25), f"--speed {speed}: {speed:g} simulated s took {wall:.3f} s"
    # the Time stamps of the stream advance with the simulated clock
    times = [float(segments(c.wait_line("STA").text)["Time"]) for _ in range(3)]
    assert times[1] - times[0] == pytest.approx(0.2, abs=1e-6) and times[2] - times[1] == pytest.approx(0.2, abs=1e-6)


@pytest.mark.alone  # wall-clock pacing: run by itself (scripts/test.sh)
def test_max_speed_runs_faster_than_real_time(server_factory):
    srv = server_factory(lockstep=False, speed=None)
    c = srv.connect()
    c.nfo()
    c.send(INIT)
    c.wait_line("STA")
    wall = wall_seconds_for(srv, 5.0)
    assert wall < 2.5, f"5 simulated seconds took {wall:.2f} s at --speed max"


def test_a_client_that_never_reads_is_bounded_and_harms_nobody(server_factory):
    srv = server_factory(lockstep=False, speed=None)
    # the sleeper: a small receive buffer, INIT, then it never reads
    sleeper = socket.create_connection(("127.0.0.1", srv.port))
    sleeper.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 65536)
    sleeper.sendall(b"INIT {ClassName USARBot.P2AT} {Name Sleeper} {Start PlayerStart2}\r\n")
    wait_for(lambda: srv.robot_count() == 1, what="the sleeper's robot")
    awake = srv.connect()
    awake.nfo()
    awake.send("INIT {ClassName USARBot.P2AT} {Name Awake} {Start PlayerStart1}")
    awake.wait_line("STA")

    def sleeper_conn():
        return next(c for c in srv.app.control.connections.values() if c.session and c.session.robot_name == "Sleeper")

    # its output piles up until the server holds back its periodic lines
    wait_for(
        lambda: srv.on_loop(lambda: sleeper_conn().dropped_periodic) > 100,
        timeout=60,
        what="periodic lines dropped for the sleeper",
    )
    for _ in range(3):
        buffered = srv.on_loop(lambda: sleeper_conn().transport.get_write_buffer_size())
        held = srv.on_loop(lambda: len(sleeper_conn()._held))
        assert buffered < 2 * 256 * 1024, f"{buffered} bytes queued for a client that does not read"
        assert held <= 16  # at most one line per stream: STA and the P2AT's twelve sensor streams
        wall_seconds_for(srv, 2.0)
    # meanwhile the other robot got every STA, 0.2 simulated seconds apart
    start = float(segments(awake.wait_line("STA").text)["Time"])
    stamps = [start] + [float(segments(awake.wait_line("STA").text)["Time"]) for _ in range(25)]
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    assert all(g == pytest.approx(0.2, abs=1e-6) for g in gaps), gaps
    # a reply to the sleeper is never dropped: it is there when it finally reads
    sleeper.sendall(b"GETGEO {Type Robot}\r\n")
    sleeper.settimeout(10)
    got = b""
    deadline = time.monotonic() + 30
    while b"GEO {Type GroundVehicle}" not in got and time.monotonic() < deadline:
        got = (got + sleeper.recv(1 << 20))[-(1 << 21) :]
    assert b"GEO {Type GroundVehicle}" in got
    sleeper.close()
    wait_for(lambda: srv.robot_count() == 1, what="the sleeper's robot removed")


def test_when_the_battery_runs_out_the_robot_stops(test_world):
    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.simulation import Simulation

    robot = dataclasses.replace(resolve_robot("P2AT"), battery_s=3.0)
    sim = Simulation(test_world, seed=1)
    pose = test_world.start_pose("Open")
    sim.spawn(1, robot, "R1", pose.location, pose.rotation)
    drive_skid(sim, 1, 3.0, 3.0)
    sim.advance(2.0)
    x_moving = sim.pose_of(1)[0][0]
    assert x_moving > pose.location[0] + 0.3  # it drove
    sim.take_outputs()
    sim.advance(3.0)  # the battery dies at t = 3 s
    outs = sim.take_outputs()
    sta = [o for o in outs if o.key == "STA"]
    assert sta[-1].value.battery_s == 0
    assert sta[0].value.battery_s > 0
    # after it died: no more sensor lines, only STA
    dead_at = next(o.time for o in sta if o.value.battery_s == 0)
    assert not [o for o in outs if o.key != "STA" and o.time is not None and o.time > dead_at + 1e-9]
    x_dead = sim.pose_of(1)[0][0]
    drive_skid(sim, 1, 3.0, 3.0)  # ignored: no power
    sim.advance(2.0)
    assert abs(sim.pose_of(1)[0][0] - x_dead) < 0.02


def test_the_battery_drains_faster_under_load_and_then_only_sta_flows(test_world):
    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.simulation import Simulation

    robot = resolve_robot("P2AT")
    sim = Simulation(test_world, seed=1)
    for uid, pose in ((1, "Open"), (2, "Far")):
        p = test_world.start_pose(pose)
        sim.spawn(uid, robot, f"R{uid}", p.location, p.rotation)
    sim.advance(1.0)
    idle0, busy0 = sim.robots[1].battery_used_s, sim.robots[2].battery_used_s
    drive_skid(sim, 2, 5.0, -5.0)  # spinning on the spot at full speed: hard work for the motors
    sim.advance(10.0)
    idle = sim.robots[1].battery_used_s - idle0
    busy = sim.robots[2].battery_used_s - busy0
    assert idle == pytest.approx(10.0, rel=0.02)  # one second per second at rest
    assert 11.0 < busy <= 20.0  # faster under load, at most twice as fast
    # run robot 2 flat: then STA only (no SEN, no MISSTA), and its pan-tilt goes limp
    sim.robots[2].battery_used_s = robot.battery_s - 0.5
    sim.take_outputs()
    sim.advance(2.0)
    outs = [o for o in sim.take_outputs() if o.uid == 2]
    late = [o for o in outs if o.time is not None and o.time > sim.time - 1.0]
    assert late and {o.key for o in late} == {"STA"}
    assert all(o.value.battery_s == 0 for o in late)


def test_lockstep_steps_add_up_below_one_physics_step(server_factory):
    """Ten STEP {Time 0.01} run exactly 0.1 s of simulated time (issue: 0.08 before, the part
    below one 4 ms physics step was dropped each time)."""
    srv = server_factory()
    c = srv.connect()
    c.nfo()
    times = []
    for _ in range(10):
        lines = c.step(0.01)
        times.append(float(segments(lines[-1].text)["Time"]))
    assert times[-1] == pytest.approx(0.1, abs=1e-9)
    assert all(0.0079 < b - a < 0.0121 for a, b in zip([0.0, *times], times))  # 2 or 3 steps of 4 ms
    c.step(0.004)
    assert float(segments(c.step(0.6)[-1].text)["Time"]) == pytest.approx(0.704, abs=1e-9)


def test_spread_report_phases_put_a_second_robots_readings_half_a_period_after_the_firsts(test_world):
    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.settings import SimSettings
    from usarsim.sim.simulation import Simulation

    robot = resolve_robot("P2AT")
    sim = Simulation(test_world, seed=1, settings=SimSettings(report_phases="spread"))
    for uid, pose in ((1, "Open"), (2, "Far")):
        p = test_world.start_pose(pose)
        sim.spawn(uid, robot, f"R{uid}", p.location, p.rotation)
    sim.advance(1.0)
    outs = sim.take_outputs()
    period = robot.status_interval_s
    for uid, share in ((1, 0.0), (2, 0.5)):
        times = [o.time for o in outs if o.uid == uid and o.key == "STA"]
        assert len(times) >= 4
        for t in times:  # on the robot's own grid
            k = (t - share * period) / period
            assert abs(k - round(k)) < 1e-6, (uid, t)
        sonar = [o.time for o in outs if o.uid == uid and o.key == "SEN:Sonar"]
        assert sonar and all(t in times for t in sonar)  # its sensors keep its phase
    # the readings are of the world: the second robot's scanner still sees walls within range
    scans = [o.value for o in outs if o.uid == 2 and o.key.startswith("SEN:RangeScanner")]
    assert scans and min(scans[-1].ranges_m) < 20.0
