"""Tachometer, IMU, INU and Touch (protocol.md 6.3, 7.2, 7.5) on a P2AT in the test world:
physical behaviour against ground truth, noise statistics with fixed seeds, CONF fields,
ini aliases and the SEN lines they make.

Readings come from :class:`usarsim.sim.simulation.Simulation` directly (no sockets).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import usarsim.sensors.inertial  # noqa: F401  (registration)
import usarsim.sensors.touch  # noqa: F401  (registration)
from helpers import WALL_FACE_X, drive_skid
from usarsim.config.catalog import ROBOTS_DIR, resolve_robot
from usarsim.config.robot import load_robot
from usarsim.errors import ConfigError
from usarsim.protocol.messages import SensorMessage, format_message, parse_message
from usarsim.protocol.outputs import message_for
from usarsim.readings import ImuReading, OrientationReading, PoseReading, TachometerReading, TouchItem, TouchReading
from usarsim.sensors.base import SENSORS, build_config
from usarsim.sensors.touch import signed_distance
from usarsim.sim.simulation import Simulation, describe_items

G = 9.81  # the test world's gravity (WorldConfig default gravity_m_s2)
TWO_PI = 2 * math.pi

# Bumper: 1.8 cm in front of the chassis face (x = 0.2619, P2AT.yaml) and 6 mm ahead of
# the front wheels' leading edge (0.1442 + 0.13 = 0.2742), low on the front: the wheels
# meet a wall first, and a P2AT pushing a wall climbs it a little (pitch ~0.25 rad) until
# the lower chassis edge rests on it, so the bumper sits in the wall either way.
EXTRA_SENSORS = """\
  - {type: Tachometer, name: TachTest}
  - {type: IMU, name: IMU}
  - {type: INU, name: INU}
  - {type: Touch, name: Bumper, location: [0.28, 0.0, 0.05]}
  - {type: Touch, name: Inside, location: [0.0, 0.0, 0.0]}
  - {type: Touch, name: Belly, location: [0.0, 0.0, 0.145], Diameter: 0.01}
  - {type: Touch, name: Reach, location: [0.8, 0.0, 0.0]}
"""
# Inside: in the robot's own chassis (its own bodies never count).  Belly: 0.7 mm above
# the floor at rest (the chassis origin is 0.14565 m above the ground, P2AT.yaml), within
# the 5 mm radius of the default 0.01 m sphere (protocol.md 7.2).  Reach: 0.8 m ahead,
# used to touch another robot.

NOISY_SENSORS = """\
  - {type: Tachometer, name: TachTest, Noise: 0.05}
  - {type: IMU, name: IMU, XYZAccelerationSigma: 0.1, AngularVelSigma: 0.01, AngularAccelSigma: 0.2,
     RotationSigma: 0.02}
  - {type: INU, name: INU, Sigma: 0.05}
"""


def robot_file(directory, class_name: str, extra: str):
    """The shipped P2AT's body and wheels with GroundTruth and ``extra`` as its only sensors."""
    head = (ROBOTS_DIR / "P2AT.yaml").read_text().split("\nsensors:")[0]
    head = head.replace("class_name: P2AT", f"class_name: {class_name}")
    path = directory / f"{class_name}.yaml"
    path.write_text(head + "\nsensors:\n  - {type: GroundTruth, name: GroundTruth}\n" + extra)
    return load_robot(path)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    return robot_file(tmp_path_factory.mktemp("robots"), "P2ATProbe", EXTRA_SENSORS)


# A second IMU 0.2 m ahead of the centre, mounted upside down (roll pi): its vectors are
# in its own axes (X forward, Y left, Z up of the robot).
MOUNTED_IMUS = """\
  - {type: IMU, name: IMU}
  - {type: IMU, name: IMU2, location: [0.2, 0.0, 0.0], orientation: [3.141592653589793, 0.0, 0.0]}
"""


@pytest.fixture(scope="module")
def imu_pair(tmp_path_factory):
    return robot_file(tmp_path_factory.mktemp("robots"), "P2ATImus", MOUNTED_IMUS)


@pytest.fixture(scope="module")
def noisy(tmp_path_factory):
    return robot_file(tmp_path_factory.mktemp("robots"), "P2ATNoisy", NOISY_SENSORS)


def spawned(world, robot, pose: str = "Open", seed: int = 1, settle: float = 1.0) -> Simulation:
    sim = Simulation(world, seed=seed)
    p = world.start_pose(pose)
    sim.spawn(1, robot, "R1", p.location, p.rotation)
    sim.advance(settle)
    sim.take_outputs()
    return sim


def run(sim: Simulation, seconds: float) -> list:
    """(time, reading) of every sensor output in the next ``seconds``."""
    sim.advance(seconds)
    return [(o.time, o.value) for o in sim.take_outputs() if o.key != "STA"]


def of(outs, kind, sensor_type: str | None = None) -> list:
    return [(t, v) for t, v in outs if isinstance(v, kind) and (sensor_type is None or v.sensor_type == sensor_type)]


def touches(reading: TouchReading) -> dict[str, bool]:
    return {i.name: i.touching for i in reading.items}


def angle_err(a, b) -> np.ndarray:
    return np.remainder(np.asarray(a) - np.asarray(b) + math.pi, TWO_PI) - math.pi


# --------------------------------------------------------------------------- Tachometer


def test_tachometer_wheel_speeds_angles_and_reset(test_world, probe):
    sim = spawned(test_world, probe)
    drive_skid(sim, 1, 2.0, 2.0)
    tach = of(run(sim, 2.0), TachometerReading)
    assert len(tach) == 10  # ScanInterval 0.2 (protocol.md 7.5)
    (t1, a), (t2, b) = tach[4], tach[-1]
    assert a.name == "TachTest" and len(b.velocities_rad_s) == len(b.positions_rad) == 4  # one per wheel
    assert np.allclose(b.velocities_rad_s, 2.0, rtol=0.1)
    rate = (np.array(b.positions_rad) - np.array(a.positions_rad)) / (t2 - t1)
    assert np.allclose(rate, 2.0, rtol=0.1)  # angles grow ~2 rad per second
    assert all(p > 2.5 for p in b.positions_rad)

    # turning in place to the left: left wheels (LeftFWheel, LeftRWheel) back, right ones forward
    drive_skid(sim, 1, -1.0, 1.0)
    turn = of(run(sim, 1.0), TachometerReading)[-1][1]
    v = turn.velocities_rad_s
    assert v[0] < -0.5 and v[2] < -0.5 and v[1] > 0.5 and v[3] > 0.5

    # RESET zeroes the accumulated angles (protocol.md 5.4)
    res = message_for(sim.operate(1, "Tachometer", "TachTest", "RESET", None), sim.time)  # the RES
    assert res.status == "OK"
    assert message_for(sim.operate(1, "Tachometer", "TachTest", "SCAN", None), sim.time).status == "Failed"
    drive_skid(sim, 1, 0.0, 0.0)
    after = of(run(sim, 0.4), TachometerReading)
    assert max(abs(p) for p in after[0][1].positions_rad) < 0.25  # at most one 0.2 s tick of turning


# --------------------------------------------------------------------------- IMU


def test_imu_at_rest_reads_gravity_up_and_no_rotation(test_world, probe):
    sim = spawned(test_world, probe)
    imu = of(run(sim, 1.0), ImuReading)
    assert len(imu) == 10  # ScanInterval 0.1 (sensor base, protocol.md 7.1)
    for _, r in imu:
        # proper acceleration: the floor pushes up, Z is down
        assert r.acceleration == pytest.approx((0.0, 0.0, -G), abs=0.02)
        assert r.angular_velocity == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)
        assert r.angular_acceleration == pytest.approx((0.0, 0.0, 0.0), abs=1e-2)
        assert all(0.0 <= a < TWO_PI for a in r.orientation)


def test_imu_forward_acceleration_and_yaw_rate(test_world, probe):
    sim = spawned(test_world, probe)
    drive_skid(sim, 1, 2.0, 2.0)
    outs = run(sim, 1.0)
    imu = of(outs, ImuReading)
    ax = [r.acceleration[0] for _, r in imu]
    assert ax[0] > 0.5  # speeding up: forward for a moment
    assert abs(ax[-1]) < 0.05  # then cruising
    assert max(abs(r.acceleration[1]) for _, r in imu) < 0.05

    # spinning to the left: yaw decreases (positive yaw is clockwise, protocol.md section 3)
    drive_skid(sim, 1, -2.0, 2.0)
    outs = run(sim, 2.0)
    imu = of(outs, ImuReading)[5:]  # past the spin-up
    gt = dict(of(outs, PoseReading, "GroundTruth"))
    rates = np.array([r.angular_velocity[2] for _, r in imu])
    assert np.all(rates < -0.1)
    times = [t for t, _ in imu]
    yaw = np.unwrap([gt[t].orientation[2] for t in times])
    gt_rate = (yaw[-1] - yaw[0]) / (times[-1] - times[0])
    assert gt_rate < -0.1
    assert rates.mean() == pytest.approx(gt_rate, rel=0.15)
    # the rotation is the robot's orientation, as GroundTruth (both every 0.1 s)
    for t, r in imu:
        assert np.abs(angle_err(r.orientation, gt[t].orientation)).max() < 1e-9
    # spinning at a steady rate about the vertical: centripetal and gravity only, roughly
    assert abs(np.mean([r.acceleration[2] for _, r in imu]) + G) < 0.3


def test_imu_off_centre_and_rotated_mount(test_world, imu_pair):
    sim = spawned(test_world, imu_pair)
    drive_skid(sim, 1, -5.0, 5.0)  # spin in place, fast
    sim.advance(1.0)
    sim.take_outputs()
    imu = of(run(sim, 3.0), ImuReading)
    centre = [r for _, r in imu if r.name == "IMU"]
    ahead = [r for _, r in imu if r.name == "IMU2"]
    assert len(centre) == len(ahead) == 30
    for c, a in zip(centre, ahead):
        # same rigid body: angular velocity with Y and Z flipped by the mount
        assert a.angular_velocity == pytest.approx(
            (c.angular_velocity[0], -c.angular_velocity[1], -c.angular_velocity[2]), abs=1e-12
        )
        assert a.orientation == c.orientation  # the robot's orientation, whatever the mount
    w = np.mean([c.angular_velocity[2] for c in centre])
    assert w < -0.5
    acc = np.array([a.acceleration for a in ahead])
    # centripetal acceleration towards the centre (-X) of w^2 r, and gravity's reaction
    # now along the sensor's +Z (its Z points up)
    assert acc[:, 0].mean() == pytest.approx(-w * w * 0.2, rel=0.1)
    assert acc[:, 2].mean() == pytest.approx(G, abs=0.3)


# --------------------------------------------------------------------------- INU


def test_inu_is_the_ground_truth_orientation(test_world, probe):
    sim = spawned(test_world, probe, pose="OpenEast")
    drive_skid(sim, 1, 3.0, 1.0)  # a right-hand curve
    outs = run(sim, 2.0)
    inu = of(outs, OrientationReading)
    gt = dict(of(outs, PoseReading, "GroundTruth"))
    assert len(inu) == 20 and all(r.name == "INU" and r.sensor_type == "INU" for _, r in inu)
    for t, r in inu:
        assert all(0.0 <= a < TWO_PI for a in r.orientation)
        assert np.abs(angle_err(r.orientation, gt[t].orientation)).max() < 1e-9
    assert abs(angle_err(inu[-1][1].orientation[2], inu[0][1].orientation[2])) > 0.3  # it turned


# --------------------------------------------------------------------------- Touch


def test_touch_bumper_against_the_wall(test_world, probe):
    sim = spawned(test_world, probe, pose="FacingWall")
    outs = run(sim, 0.3)
    packed = of(outs, TouchReading)
    assert len(packed) == 3  # ScanInterval 0.1 (protocol.md 7.2), every Touch in one line
    first = packed[-1][1]
    assert [i.name for i in first.items] == ["Bumper", "Inside", "Belly", "Reach"]
    assert touches(first) == {"Bumper": False, "Inside": False, "Belly": True, "Reach": False}

    drive_skid(sim, 1, 3.0, 3.0)
    last_x = sim.pose_of(1)[0][0]
    for _ in range(40):  # until it stops against the wall
        sim.advance(0.5)
        x = sim.pose_of(1)[0][0]
        if abs(x - last_x) < 1e-3:
            break
        last_x = x
    assert x > WALL_FACE_X - 0.3
    at_wall = of(run(sim, 0.1), TouchReading)[-1][1]
    assert touches(at_wall)["Bumper"] is True
    assert touches(at_wall)["Inside"] is False

    drive_skid(sim, 1, -3.0, -3.0)
    backed = of(run(sim, 1.5), TouchReading)[-1][1]
    assert sim.pose_of(1)[0][0] < WALL_FACE_X - 0.6
    # (Reach, 0.8 m ahead, is now in the 0.1 m thick wall: not asserted here)
    assert {k: touches(backed)[k] for k in ("Bumper", "Inside", "Belly")} == {
        "Bumper": False,
        "Inside": False,
        "Belly": True,
    }


def test_touch_feels_another_robot(test_world, probe):
    sim = Simulation(test_world, seed=1)
    p = test_world.start_pose("Open")
    sim.spawn(1, probe, "R1", p.location, p.rotation)
    sim.advance(0.5)
    assert touches(of(run(sim, 0.1), TouchReading)[-1][1])["Reach"] is False
    # a second P2AT whose chassis holds the point 0.8 m ahead of R1
    sim.spawn(2, resolve_robot("P2AT"), "R2", (p.location[0] + 0.8, p.location[1], p.location[2]), p.rotation)
    sim.advance(0.5)
    outs = [o for o in sim.take_outputs() if o.uid == 1 and isinstance(o.value, TouchReading)]
    assert touches(outs[-1].value)["Reach"] is True
    sim.remove(2)
    sim.advance(0.2)
    outs = [o for o in sim.take_outputs() if isinstance(o.value, TouchReading)]
    assert touches(outs[-1].value)["Reach"] is False


@pytest.mark.parametrize(
    "gtype, size, point, expected",
    [
        ("plane", (1, 1, 0.1), (3.0, -7.0, 0.2), 0.2),
        ("plane", (1, 1, 0.1), (0.0, 0.0, -0.1), -0.1),
        ("sphere", (0.5, 0, 0), (0.0, 0.6, 0.0), 0.1),
        ("sphere", (0.5, 0, 0), (0.0, 0.0, 0.2), -0.3),
        ("capsule", (0.1, 0.5, 0), (0.0, 0.3, 0.4), 0.2),
        ("capsule", (0.1, 0.5, 0), (0.0, 0.0, 0.8), 0.2),
        ("cylinder", (0.2, 0.5, 0), (0.5, 0.0, 0.0), 0.3),
        ("cylinder", (0.2, 0.5, 0), (0.0, 0.0, 0.7), 0.2),
        ("cylinder", (0.2, 0.5, 0), (0.5, 0.0, 0.9), 0.5),
        ("cylinder", (0.2, 0.5, 0), (0.1, 0.0, 0.0), -0.1),
        ("box", (0.5, 1.0, 2.0), (0.7, 0.0, 0.0), 0.2),
        ("box", (0.5, 1.0, 2.0), (0.8, 1.4, 0.0), 0.5),
        ("box", (0.5, 1.0, 2.0), (0.0, 0.0, 1.5), -0.5),
        ("ellipsoid", (1.0, 2.0, 3.0), (1.5, 0.0, 0.0), 0.5),
        ("ellipsoid", (1.0, 2.0, 3.0), (0.0, 0.0, 2.9), -0.1),
    ],
)
def test_signed_distances(gtype, size, point, expected):
    import mujoco

    t = int(getattr(mujoco.mjtGeom, f"mjGEOM_{gtype.upper()}"))
    d = signed_distance(t, np.array(size, float), np.zeros(6), np.array(point, float))
    assert d == pytest.approx(expected, abs=1e-9 if gtype != "ellipsoid" else 0.02)


# --------------------------------------------------------------------------- noise and seeds


def noisy_run(world, robot, seed: int) -> list:
    sim = spawned(world, robot, seed=seed)
    drive_skid(sim, 1, 2.0, 2.0)
    sim.advance(1.0)  # spin-up
    sim.take_outputs()
    return run(sim, 8.0)


def test_noise_statistics(test_world, noisy):
    outs = noisy_run(test_world, noisy, seed=3)
    gt = dict(of(outs, PoseReading, "GroundTruth"))

    # Tachometer: relative, uniform in +-Noise (protocol.md 7.1); true speed 2 rad/s
    tach = np.array([r.velocities_rad_s for _, r in of(outs, TachometerReading)]) / 2.0 - 1.0
    assert tach.shape == (40, 4)
    assert np.abs(tach).max() <= 0.05 + 1e-3
    assert abs(tach.mean()) < 0.01
    assert 0.7 * 0.05 / math.sqrt(3) < tach.std() < 1.3 * 0.05 / math.sqrt(3)

    # IMU: Gaussian, zero mean, the configured sigmas; cruising straight on a level floor
    imu = of(outs, ImuReading)
    acc = np.array([r.acceleration for _, r in imu])
    assert len(acc) == 80
    assert np.abs(acc.mean(axis=0) - (0.0, 0.0, -G)).max() < 0.05
    assert np.all((0.07 < acc.std(axis=0)) & (acc.std(axis=0) < 0.13))
    gyro = np.array([r.angular_velocity for _, r in imu])
    assert np.abs(gyro.mean(axis=0)).max() < 0.005
    assert np.all((0.007 < gyro.std(axis=0)) & (gyro.std(axis=0) < 0.013))
    rot_err = np.array([angle_err(r.orientation, gt[t].orientation) for t, r in imu])
    assert np.all((0.014 < rot_err.std(axis=0)) & (rot_err.std(axis=0) < 0.026))
    assert all(0.0 <= a < TWO_PI for _, r in imu for a in r.orientation)

    # INU: N(0, Sigma 0.05) per angle
    inu = of(outs, OrientationReading)
    err = np.array([angle_err(r.orientation, gt[t].orientation) for t, r in inu])
    assert len(err) == 80
    assert np.abs(err.mean(axis=0)).max() < 0.02
    assert np.all((0.035 < err.std(axis=0)) & (err.std(axis=0) < 0.065))
    assert all(0.0 <= a < TWO_PI for _, r in inu for a in r.orientation)


def test_same_seed_same_readings(test_world, noisy):
    def values(outs):
        return [v for _, v in outs if isinstance(v, (TachometerReading, ImuReading, OrientationReading))]

    a = values(noisy_run(test_world, noisy, seed=5))
    b = values(noisy_run(test_world, noisy, seed=5))
    c = values(noisy_run(test_world, noisy, seed=6))
    assert a == b
    assert len(a) == len(c) and a != c


def test_no_noise_by_default(test_world, probe):
    sim = spawned(test_world, probe)
    outs = run(sim, 1.0)
    inu = of(outs, OrientationReading)
    gt = dict(of(outs, PoseReading, "GroundTruth"))
    assert all(np.abs(angle_err(r.orientation, gt[t].orientation)).max() < 1e-12 for t, r in inu)


# --------------------------------------------------------------------------- config and wire


def test_conf_fields_and_ini_aliases(probe):
    desc = {d.name: d for d in describe_items(probe)}
    assert desc["TachTest"].conf == (("ScanInterval", 0.2),)  # protocol.md 6.7 / 7.5
    assert desc["IMU"].conf == (("ScanInterval", 0.1),)
    assert desc["INU"].conf == (("ScanInterval", 0.1),)
    assert desc["Bumper"].conf == (("ScanInterval", 0.1),)  # protocol.md 7.2
    assert SENSORS.get("touch").TYPE == "Touch" and SENSORS.get("tachometer").TYPE == "Tachometer"

    item = next(i for i in probe.items if i.name == "Belly")
    cfg = build_config(SENSORS.get("Touch"), item, probe.path)
    assert cfg.diameter_m == 0.01 and cfg.scan_interval_s == 0.1

    def config(sensor_type, **params):
        return build_config(
            SENSORS.get(sensor_type),
            type(item)(
                item_type=sensor_type, name="X", location=(0, 0, 0), orientation=(0, 0, 0), mount="HARD", params=params
            ),
            "robot.yaml",
        )

    assert config("Touch", Diameter=0.02).diameter_m == 0.02
    assert config("INU", Sigma=0.1, Mean=0.01).sigma_rad == 0.1
    assert config("Tachometer", Noise=0.02, ScanInterval=0.5).noise == 0.02
    imu = config("IMU", XYZAccelerationSigma=0.3, IncludeGravity=False)
    assert imu.acceleration_sigma_m_s2 == 0.3 and imu.include_gravity is False
    with pytest.raises(ConfigError, match="Diameter"):
        config("Touch", Diametr=0.02)
    with pytest.raises(ConfigError):
        config("Touch", Diameter=0.0)
    with pytest.raises(ConfigError):
        config("INU", Sigma=-1.0)


NUM = r"-?\d+\.\d{4}"
LINE_SHAPES = {
    TachometerReading: rf"^SEN \{{Time {NUM}\}} \{{Type Tachometer\}} \{{Name TachTest\}} "
    rf"\{{Vel ({NUM},){{3}}{NUM}\}} \{{Pos ({NUM},){{3}}{NUM}\}}\r\n$",
    ImuReading: rf"^SEN \{{Time {NUM}\}} \{{Type IMU\}} \{{Name IMU\}} \{{XYZAcceleration ({NUM},){{2}}{NUM}\}} "
    rf"\{{AngularVel ({NUM},){{2}}{NUM}\}} \{{AngularAccel ({NUM},){{2}}{NUM}\}} "
    rf"\{{Rotation ({NUM},){{2}}{NUM}\}}\r\n$",
    OrientationReading: rf"^SEN \{{Time {NUM}\}} \{{Type INU\}} \{{Name INU\}} "
    rf"\{{Orientation ({NUM},){{2}}{NUM}\}}\r\n$",
    TouchReading: rf"^SEN \{{Time {NUM}\}} \{{Type Touch\}}( \{{Name \w+ Touch (True|False)\}}){{4}}\r\n$",
}


def test_sen_lines_have_the_spec_shape_and_parse_back(test_world, probe):
    sim = spawned(test_world, probe, settle=0.5)
    drive_skid(sim, 1, -1.0, 1.5)
    outs = run(sim, 0.6)
    seen = set()
    for t, r in outs:
        shape = LINE_SHAPES.get(type(r))
        if shape is None:
            continue
        seen.add(type(r))
        line = format_message(SensorMessage(time=t, reading=r))
        assert re.match(shape, line), line
        back = parse_message(line)
        assert back.time == pytest.approx(t, abs=5e-5)
        got = back.reading
        assert type(got) is type(r) and getattr(got, "name", None) == getattr(r, "name", None)
        if isinstance(r, TachometerReading):
            assert got.velocities_rad_s == pytest.approx(r.velocities_rad_s, abs=5e-5)
            assert got.positions_rad == pytest.approx(r.positions_rad, abs=5e-5)
        elif isinstance(r, ImuReading):
            for f in ("acceleration", "angular_velocity", "angular_acceleration"):
                assert getattr(got, f) == pytest.approx(getattr(r, f), abs=5e-5)
            assert np.abs(angle_err(got.orientation, r.orientation)).max() < 5e-5
        elif isinstance(r, OrientationReading):
            assert np.abs(angle_err(got.orientation, r.orientation)).max() < 5e-5
        else:
            assert got == r
    assert seen == set(LINE_SHAPES)
    # the spec's own examples (protocol.md 6.3)
    line = format_message(SensorMessage(time=1.0, reading=TouchReading((TouchItem("Touch", False),))))
    assert line == "SEN {Time 1.0000} {Type Touch} {Name Touch Touch False}\r\n"
    tach = TachometerReading("TachTest", (1.2, 1.2, 1.2, 1.2), (3.4, 3.4, 3.1, 3.1))
    assert format_message(SensorMessage(time=2.0, reading=tach)) == (
        "SEN {Time 2.0000} {Type Tachometer} {Name TachTest} {Vel 1.2000,1.2000,1.2000,1.2000} "
        "{Pos 3.4000,3.4000,3.1000,3.1000}\r\n"
    )
