"""Physical behaviour seen through the protocol: a lock-step server (seed 3) on a small test
world with walls at known places (helpers.TEST_WORLD), a P2AT driven with DRIVE and observed
through its GroundTruth, Odometry, Encoder, RangeScanner and Sonar lines.

P2AT figures (protocol.md 9): wheel radius 0.13 m, so DRIVE {Left w} {Right w} rolls at
0.13 w m/s; its chassis origin rests 0.1455 m above the floor (z = -0.1455, Z down).
"""

from __future__ import annotations

import math

import pytest

from helpers import (
    RIGHT_WALL_FACE_Y,
    WALL_FACE_X,
    angle_diff,
    drive_skid,
    ground_truth,
    segment_list,
    segments,
    sensor_lines,
    vec,
    wait_for,
)

WHEEL_RADIUS = 0.13
REST_Z = -0.1455
SCANNER_X = 0.144  # Scanner1 mount, robot frame (P2AT.yaml)


@pytest.fixture
def arena(server_factory, test_world):
    return server_factory(world=test_world, seed=3)


def spawn(server, start: str, name: str = "R1", settle: float = 1.0):
    c = server.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name {name}}} {{Start {start}}}")
    lines = c.step(settle)
    assert ground_truth(lines), "the robot did not spawn"
    return c, lines


def gt_last(lines):
    return ground_truth(lines)[-1]


def check_orientations(gts):
    for _, _, ori in gts:
        for a in ori:
            assert 0.0 <= a < 2 * math.pi, ori


def test_drive_reaches_the_commanded_speed(arena):
    c, _ = spawn(arena, "Open")
    c.send("DRIVE {Left 2} {Right 2}")
    t0, p0, _ = gt_last(c.step(1.0))  # accelerate
    lines = c.step(2.0)
    t1, p1, o1 = gt_last(lines)
    speed = math.hypot(p1[0] - p0[0], p1[1] - p0[1]) / (t1 - t0)
    assert t1 - t0 == pytest.approx(2.0)
    assert speed == pytest.approx(2 * WHEEL_RADIUS, rel=0.10)
    assert abs(p1[1] - p0[1]) < 0.02  # straight
    assert abs(angle_diff(o1[2], 0.0)) < 0.02
    check_orientations(ground_truth(lines))


@pytest.mark.parametrize("start, axis", [("Open", 0), ("OpenEast", 1)], ids=["yaw0-X", "yaw90-Y"])
def test_forward_follows_the_heading(arena, start, axis):
    """Yaw 0 drives along +X; yaw +pi/2 (clockwise from above) drives along +Y (right)."""
    c, lines = spawn(arena, start)
    _, p0, o0 = gt_last(lines)
    assert o0[2] == pytest.approx(0.0 if axis == 0 else 1.5708, abs=0.01)
    c.send("DRIVE {Left 3} {Right 3}")
    _, p1, _ = gt_last(c.step(2.0))
    assert p1[axis] - p0[axis] > 0.5
    assert abs(p1[1 - axis] - p0[1 - axis]) < 0.05


def test_left_backwards_right_forwards_turns_left_in_place(arena):
    c, lines = spawn(arena, "Open")
    _, p0, o0 = gt_last(lines)
    c.send("DRIVE {Left -1} {Right 1}")
    lines = c.step(2.0)
    gts = ground_truth(lines)
    check_orientations(gts)
    yaws = [o[2] for _, _, o in gts]
    steps = [angle_diff(b, a) for a, b in zip(yaws, yaws[1:])]
    assert all(s <= 1e-4 for s in steps), steps  # yaw only decreases: counter-clockwise seen from above
    total = angle_diff(yaws[-1], o0[2])
    assert total < -0.2
    assert yaws[-1] > math.pi  # reported in [0, 2 pi): just below 2 pi after turning left from 0
    assert all(math.hypot(p[0] - p0[0], p[1] - p0[1]) < 0.1 for _, p, _ in gts)


def test_at_rest_it_neither_sinks_nor_jitters(arena):
    c, _ = spawn(arena, "Open", settle=1.0)
    gts = ground_truth(c.step(5.0))
    assert len(gts) == 50
    zs = [p[2] for _, p, _ in gts]
    assert max(zs) - min(zs) < 0.01
    assert all(z == pytest.approx(REST_Z, abs=0.01) for z in zs)
    p0 = gts[0][1]
    assert all(math.hypot(p[0] - p0[0], p[1] - p0[1]) < 0.001 for _, p, _ in gts)
    assert all(abs(angle_diff(o[0], 0)) < 0.01 and abs(angle_diff(o[1], 0)) < 0.01 for _, _, o in gts)


def test_driving_into_a_wall_stops_at_the_wall(arena):
    c, _ = spawn(arena, "FacingWall")
    c.send("DRIVE {Left 5.385} {Right 5.385}")
    gts = ground_truth(c.step(6.0))
    xs = [p[0] for _, p, _ in gts]
    # the front wheels reach 0.2742 m ahead of the origin: touching the wall at x = 4.726
    front = 0.1442 + WHEEL_RADIUS
    assert max(xs) < WALL_FACE_X - front + 0.02  # never through the wall
    assert xs[-1] > WALL_FACE_X - front - 0.1  # but it did get there
    assert max(xs[-10:]) - min(xs[-10:]) < 0.02  # and stays there
    check_orientations(gts)


def test_laser_reads_the_wall_distance(arena):
    c, lines = spawn(arena, "FacingWall")
    x = gt_last(lines)[1][0]
    scans = sensor_lines(lines, "RangeScanner")
    ranges = vec(segments(scans[-1].text)["Range"])
    assert len(ranges) == 181
    ahead = WALL_FACE_X - (x + SCANNER_X)
    assert ahead == pytest.approx(1.856, abs=0.01)
    assert ranges[90] == pytest.approx(ahead, abs=0.02)  # centre beam
    # 45 degrees to either side: the same wall at d / cos 45
    assert ranges[45] == pytest.approx(ahead / math.cos(math.pi / 4), abs=0.03)
    assert ranges[135] == pytest.approx(ahead / math.cos(math.pi / 4), abs=0.03)
    # the first value is the rightmost beam (+Y): the short wall on the right at y = 1.5
    assert ranges[0] == pytest.approx(RIGHT_WALL_FACE_Y, abs=0.02)
    assert ranges[180] == pytest.approx(20.0)  # nothing on the left: MaxRange


def test_sonar_reads_the_walls(arena):
    c, lines = spawn(arena, "FacingWall")
    x = gt_last(lines)[1][0]
    sonar = {}
    for item in segment_list(sensor_lines(lines, "Sonar")[-1].text)[2:]:
        _, name, _, value = item.split()
        sonar[name] = float(value)
    perpendicular = WALL_FACE_X - (x + 0.24)  # F4/F5 sit 0.24 m ahead of the origin, 10 degrees off axis
    along_axis = perpendicular / math.cos(0.1745)
    for name in ("F4", "F5"):
        assert perpendicular - 0.02 <= sonar[name] <= along_axis + 0.02, (name, sonar[name], perpendicular)
    assert sonar["F8"] == pytest.approx(RIGHT_WALL_FACE_Y - 0.13, abs=0.03)  # pointing right
    assert sonar["F1"] == pytest.approx(5.0)  # pointing left: nothing within MaxRange
    assert sonar["R4"] == pytest.approx(5.0)  # pointing back


def test_odometry_and_encoders_after_driving_one_metre(arena):
    c, lines = spawn(arena, "Open")
    _, p0, _ = gt_last(lines)
    c.send("SET {Type Odometry} {Opcode RESET}")
    c.send("SET {Type Encoder} {Name ECLeft} {Opcode RESET}")
    c.send("SET {Type Encoder} {Name ECRight} {Opcode RESET}")
    c.send("DRIVE {Left 2} {Right 2}")
    drive_lines = []
    for _ in range(20):
        chunk = c.step(0.5)
        drive_lines += chunk
        _, p, _ = gt_last(chunk)
        if math.hypot(p[0] - p0[0], p[1] - p0[1]) >= 1.0:
            break
    c.send("DRIVE {Left 0} {Right 0}")
    lines = c.step(1.0)
    _, p1, _ = gt_last(lines)
    travelled = math.hypot(p1[0] - p0[0], p1[1] - p0[1])
    assert 1.0 <= travelled < 1.3
    x, y, theta = vec(segments(sensor_lines(lines, "Odometry")[-1].text)["Pose"])
    assert x == pytest.approx(travelled, rel=0.05)
    assert abs(y) < 0.05 * travelled
    assert abs(math.remainder(theta, 2 * math.pi)) < 0.05

    ticks = []
    for ln in sensor_lines(drive_lines + lines, "Encoder"):
        items = segment_list(ln.text)[2:]
        ticks.append({i.split()[1]: int(i.split()[3]) for i in items})
    assert ticks[0]["ECLeft"] < 50 and ticks[0]["ECRight"] < 50  # they were reset
    for name in ("ECLeft", "ECRight"):
        series = [t[name] for t in ticks]
        # counts up; Encoder noise is relative (Noise 0.005 of the accumulated angle, protocol.md 7.5)
        assert all(b >= a - (0.01 * a + 1) for a, b in zip(series, series[1:])), series
        assert series[len(series) // 2] > series[0] + 100
        expected = travelled / WHEEL_RADIUS / 0.01745  # wheel turns / resolution
        assert 0.9 * expected < series[-1] < 1.2 * expected, (series[-1], expected)


def test_spawning_and_removing_robots_does_not_disturb_a_driving_robot(arena):
    a, _ = spawn(arena, "Open", "A")
    a.send("DRIVE {Left 2} {Right 2}")
    track = []
    for _ in range(15):
        track += ground_truth(a.step(0.1))
    b = arena.connect()
    b.nfo()
    b.send_raw(b"INIT {ClassName USARBot.P2AT} {Name B} {Start Far}\r\nSTEP {Time 0.1}\r\n")
    b.lines_until("STEPPED")
    assert arena.robot_count() == 2
    for _ in range(10):
        track += ground_truth(a.step(0.1))
    c = arena.connect()
    c.nfo()
    c.send_raw(b"INIT {ClassName USARBot.P2AT} {Name C} {Start OpenEast}\r\nSTEP {Time 0.1}\r\n")
    c.lines_until("STEPPED")
    b.close()
    wait_for(lambda: arena.robot_count() == 2, what="robot B to be removed")
    for _ in range(10):
        track += ground_truth(a.step(0.1))
    times = [t for t, _, _ in track]
    assert times == sorted(times) and len(set(times)) == len(times)
    assert len(track) >= 35
    jumps = [math.hypot(q[0] - p[0], q[1] - p[1]) + abs(q[2] - p[2]) for (_, p, _), (_, q, _) in zip(track, track[1:])]
    assert max(jumps) < 0.05, jumps
    # it kept moving at a steady pace through the spawns and the removal
    late = jumps[10:]
    assert min(late) > 0.015 and max(late) < 0.04, late
    c.close()


# --------------------------------------------------------------------------- blow-ups


def _twin(test_world, perturb: bool):
    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.simulation import Simulation

    sim = Simulation(test_world, seed=1)
    robot = resolve_robot("P2AT")
    for uid, pose in ((1, "Open"), (2, "Far")):
        p = test_world.start_pose(pose)
        sim.spawn(uid, robot, f"R{uid}", p.location, p.rotation)
    sim.advance(1.0)
    for uid in (1, 2):
        drive_skid(sim, uid, 2.0, 1.0)
    sim.advance(1.0)
    if perturb:  # robot 1 blows up: its chassis spins at an absurd rate
        h = sim.robots[1].handle
        sim.data.qvel[h.root_qvel + 3 : h.root_qvel + 6] = 5.0e4
    sim.advance(2.0)
    return sim


def test_a_robot_that_blows_up_is_reset_alone(test_world, caplog):
    calm, hurt = _twin(test_world, False), _twin(test_world, True)
    assert calm.resets == 0
    assert hurt.resets >= 1 and hurt.robots[1].resets >= 1 and hurt.robots[2].resets == 0
    assert "R1" in caplog.text and "unstable" in caplog.text
    # the victim is back on its wheels near where it was, and at rest or driving again
    (x, y, z), (roll, pitch, _) = hurt.pose_of(1)
    p0 = test_world.start_pose("Open").location
    assert math.hypot(x - p0[0], y - p0[1]) < 1.5
    assert abs(math.remainder(roll, 2 * math.pi)) < 0.2 and abs(math.remainder(pitch, 2 * math.pi)) < 0.2
    assert z == pytest.approx(REST_Z, abs=0.05)
    # the other robot did not notice anything
    (xa, ya, _), (_, _, yawa) = calm.pose_of(2)
    (xb, yb, _), (_, _, yawb) = hurt.pose_of(2)
    assert math.hypot(xa - xb, ya - yb) < 1e-6 and abs(yawa - yawb) < 1e-6
