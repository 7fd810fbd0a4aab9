"""Sensor models (protocol.md section 7): noise statistics with fixed seeds, ground truth,
INS, and the SET operations of the P2AT's sensors.

Statistics use :class:`usarsim.sim.simulation.Simulation` directly (no sockets: the readings
are the values before formatting); SET operations go through a lock-step server.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from helpers import WALL_FACE_X, drive_skid, ground_truth, segment_list, segments, sensor_lines, vec
from usarsim.config.catalog import resolve_robot
from usarsim.readings import EncoderReading, PoseReading, RangeReading, RangeScanReading
from usarsim.sim import frames
from usarsim.sim.simulation import Simulation

SCANNER_X = 0.144


@pytest.fixture(scope="module")
def p2at():
    return resolve_robot("P2AT")


def at_wall(world, robot, seed: int, settle: float = 1.0) -> Simulation:
    """A P2AT at the FacingWall start pose of the test world, settled and outputs cleared."""
    sim = Simulation(world, seed=seed)
    pose = world.start_pose("FacingWall")
    sim.spawn(1, robot, "R1", pose.location, pose.rotation)
    sim.advance(settle)
    sim.take_outputs()
    return sim


def readings(sim: Simulation, kind: type, seconds: float) -> list:
    sim.advance(seconds)
    return [o.value for o in sim.take_outputs() if isinstance(o.value, kind)]


def scans(sim, seconds):
    return [r for r in readings(sim, RangeScanReading, seconds)]


def test_laser_noise_is_small_unbiased_and_bounded(test_world, p2at):
    sim = at_wall(test_world, p2at, seed=11)
    x = sim.pose_of(1)[0][0]
    true = WALL_FACE_X - (x + SCANNER_X)
    centre = np.array([s.ranges_m[90] for s in scans(sim, 20.0)])  # 100 scans at rest
    assert len(centre) == 100
    # RangeScanner noise: relative, uniform in +-0.1 % (Noise 0.001)
    assert np.all(np.abs(centre - true) <= 0.001 * true + 5e-4)
    assert abs(centre.mean() - true) < 0.0005
    expected_sd = 0.001 * true / math.sqrt(3)
    assert 0.6 * expected_sd < centre.std() < 1.4 * expected_sd
    assert len(set(centre.round(6))) > 50  # really noisy, not a constant


def test_same_seed_same_readings_other_seed_other_noise(test_world, p2at):
    a = scans(at_wall(test_world, p2at, seed=4), 2.0)
    b = scans(at_wall(test_world, p2at, seed=4), 2.0)
    c = scans(at_wall(test_world, p2at, seed=5), 2.0)
    assert [s.ranges_m for s in a] == [s.ranges_m for s in b]
    assert [s.ranges_m for s in a] != [s.ranges_m for s in c]
    # the noise differs, the world does not
    assert np.allclose(np.array(a[-1].ranges_m), np.array(c[-1].ranges_m), rtol=0.003)


def test_sonar_noise_is_bounded_and_max_range_is_exact(test_world, p2at):
    sim = at_wall(test_world, p2at, seed=2)
    sonar = readings(sim, RangeReading, 10.0)
    assert len(sonar) == 50
    f4 = np.array([{i.name: i.range_m for i in r.items}["F4"] for r in sonar])
    assert f4.max() - f4.min() <= 2 * 0.001 * f4.mean() + 1e-6  # Noise 0.001, relative
    for r in sonar:
        values = {i.name: i.range_m for i in r.items}
        assert list(values) == [
            "F1",
            "F2",
            "F3",
            "F4",
            "F5",
            "F6",
            "F7",
            "F8",
            "R1",
            "R2",
            "R3",
            "R4",
            "R5",
            "R6",
            "R7",
            "R8",
        ]
        assert values["F1"] == 5.0  # nothing seen: exactly MaxRange, no noise
        assert all(0.1 <= v <= 5.0 for v in values.values())


def test_ground_truth_is_the_exact_pose(test_world, p2at):
    sim = at_wall(test_world, p2at, seed=1)
    drive_skid(sim, 1, -1.0, 1.0)
    sim.advance(0.9)
    sim.take_outputs()
    sim.advance(0.1)  # to t = 2.0: one GroundTruth, at the end
    gt = [
        o.value for o in sim.take_outputs() if isinstance(o.value, PoseReading) and o.value.sensor_type == "GroundTruth"
    ]
    assert len(gt) == 1
    assert sim.time == pytest.approx(2.0)
    loc, ori = sim.pose_of(1)
    assert gt[0].location == pytest.approx(loc, abs=1e-12)
    for got, want in zip(gt[0].orientation, ori):
        assert 0.0 <= got < 2 * math.pi
        # exact, but for a hair below 2 pi reported as 0 (a level robot reads 0, not 6.2832)
        tol = 1e-9 if not 0.0 < (-want) % (2 * math.pi) <= frames.WRAP_SNAP_RAD else frames.WRAP_SNAP_RAD
        assert math.isclose(math.cos(got), math.cos(want), abs_tol=tol)
        assert math.isclose(math.sin(got), math.sin(want), abs_tol=tol)


def test_ins_follows_the_truth_with_noise(test_world, p2at):
    world = test_world
    sim = Simulation(world, seed=8)
    pose = world.start_pose("Open")
    sim.spawn(1, p2at, "R1", pose.location, pose.rotation)
    sim.advance(1.0)  # at rest: the INS starts integrating
    sim.take_outputs()
    drive_skid(sim, 1, 3.0, 2.5)  # a gentle right-hand curve
    sim.advance(4.0)
    outs = sim.take_outputs()
    ins = [o.value for o in outs if isinstance(o.value, PoseReading) and o.value.sensor_type == "INS"]
    gt = [o.value for o in outs if isinstance(o.value, PoseReading) and o.value.sensor_type == "GroundTruth"]
    assert len(ins) == 20
    est, true = ins[-1], gt[-1]
    err = math.dist(est.location, true.location)
    travelled = math.dist(gt[0].location, true.location)
    assert travelled > 1.0
    assert 1e-5 < err < 0.1 * travelled  # noisy but close
    assert all(0.0 <= a < 2 * math.pi for r in ins for a in r.orientation)
    yaw_err = abs(math.remainder(est.orientation[2] - true.orientation[2], 2 * math.pi))
    assert yaw_err < 0.1
    assert true.orientation[2] > 0.1  # it turned right (clockwise): yaw grew


def test_encoders_count_wheel_turns(test_world, p2at):
    sim = at_wall(test_world, p2at, seed=1)
    drive_skid(sim, 1, -2.0, -2.0)  # backwards, away from the wall
    enc = readings(sim, EncoderReading, 2.0)
    last = {i.name: i.tick for i in enc[-1].items}
    assert list(last) == ["ECLeft", "ECRight"]
    # about 2 s x 2 rad/s backwards (minus the spin-up) / 0.01745 rad per tick
    assert -240 < last["ECLeft"] < -150 and -240 < last["ECRight"] < -150


# --------------------------------------------------------------------------- SET over the protocol


@pytest.fixture
def wall_client(server_factory, test_world):
    srv = server_factory(world=test_world, seed=6)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start FacingWall}")
    c.step(0.6)
    return c


def test_set_scan_triggers_an_immediate_scan(wall_client):
    c = wall_client
    assert not sensor_lines(c.step(0.1), "RangeScanner")  # next periodic scan at t = 0.8
    c.send("SET {Type RangeScanner} {Name Scanner1} {Opcode SCAN} {Value 0.0}")  # MOAST adds {Value}
    lines = c.step(0.05)
    res = [ln.text for ln in lines if ln.text.startswith("RES ")]
    assert res == ["RES {Time 0.70} {Type RangeScanner} {Name Scanner1} {Status OK}"]
    scan = sensor_lines(lines, "RangeScanner")
    assert len(scan) == 1
    assert len(vec(segments(scan[0].text)["Range"])) == 181


def test_set_encoder_reset_zeroes_the_ticks(wall_client):
    c = wall_client
    c.send("DRIVE {Left -2} {Right -2}")
    c.step(1.0)
    c.send("DRIVE {Left 0} {Right 0}")
    before = segment_list(sensor_lines(c.step(0.5), "Encoder")[-1].text)[2:]
    assert all(abs(int(i.split()[3])) > 50 for i in before)
    c.send("SET {Type Encoder} {Name ECLeft} {Opcode RESET}")
    lines = c.step(0.3)
    assert [ln.text[ln.text.index("{Type") :] for ln in lines if ln.text.startswith("RES ")] == [
        "{Type Encoder} {Name ECLeft} {Status OK}"
    ]
    after = {i.split()[1]: int(i.split()[3]) for i in segment_list(sensor_lines(lines, "Encoder")[-1].text)[2:]}
    assert abs(after["ECLeft"]) <= 1
    assert abs(after["ECRight"]) > 50  # only the named encoder


def test_set_ins_pose_moves_the_estimate(wall_client):
    c = wall_client
    c.step(0.6)
    c.send("SET {Type INS} {Name INS} {Opcode POSE} {Params 1.0,2.0,-0.5,0,0,0.5}")
    lines = c.step(0.4)
    res = [ln.text for ln in lines if ln.text.startswith("RES ")]
    assert len(res) == 1 and res[0].endswith("{Type INS} {Name INS} {Status OK}")
    ins = segments(sensor_lines(lines, "INS")[-1].text)
    assert vec(ins["Location"]) == pytest.approx((1.0, 2.0, -0.5), abs=0.01)
    assert vec(ins["Orientation"])[2] == pytest.approx(0.5, abs=0.01)
    gt = ground_truth(lines)[-1]
    assert gt[1][0] == pytest.approx(3.0, abs=0.05)  # the robot itself did not move


@pytest.mark.parametrize("params", ["1,2,3", "a,b,c,d,e,f", "1,2,3,4,5,nan"])
def test_set_ins_pose_with_bad_params_fails(wall_client, params):
    c = wall_client
    c.send(f"SET {{Type INS}} {{Name INS}} {{Opcode POSE}} {{Params {params}}}")
    res = [ln.text for ln in c.step(0.2) if ln.text.startswith("RES ")]
    assert len(res) == 1 and re.search(r"\{Status Failed\}$", res[0])
