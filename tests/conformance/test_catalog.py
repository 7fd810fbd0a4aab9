"""Every robot file and world file shipped in usarsim/data, and every registered sensor plugin.

* robots: validate, compile in MuJoCo, mount only registered sensor types, describe every item;
* worlds: validate, compile, at least 4 start poses, and a P2AT dropped at every start pose
  lands on its wheels (after 2 s: level within 0.1 rad, resting height within 2 cm);
* sensor plugins: each can be mounted on a P2AT, measured in a world and written as a SEN line.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from helpers import drive_joint, drive_skid
from usarsim.config.catalog import ROBOTS_DIR, WORLDS_DIR, resolve_robot
from usarsim.config.robot import load_robot
from usarsim.config.world_file import check_world_file, load_world
from usarsim.protocol.messages import SensorMessage, format_message, parse_message
from usarsim.sensors import ITEMS
from usarsim.sim.robotspec import robot_model_summary
from usarsim.sim.simulation import Simulation, describe_items

ROBOT_FILES = sorted(ROBOTS_DIR.glob("*.yaml"))
WORLD_FILES = sorted(WORLDS_DIR.glob("*.yaml"))
P2AT_REST_Z = -0.1455  # chassis origin 0.14565 m above the floor (P2AT.yaml), Z down


def test_the_catalogue_is_not_empty():
    assert ROBOT_FILES and WORLD_FILES
    assert "P2AT" in [p.stem for p in ROBOT_FILES]
    assert "DM-USAR_yellow" in [p.stem for p in WORLD_FILES]


# --------------------------------------------------------------------------- robots


@pytest.mark.parametrize("path", ROBOT_FILES, ids=lambda p: p.stem)
def test_robot_file_validates_and_compiles(path: Path):
    r = load_robot(path)
    assert r.class_name == path.stem  # INIT {ClassName USARBot.<stem>} finds it
    assert resolve_robot(f"USARBot.{r.class_name}").path == resolve_robot(r.class_name).path
    summary = robot_model_summary(r)
    steered = sum(w.steer != "none" for w in r.wheels)
    rotors = 6 if r.drive == "aerial" else 0
    assert f"{sum(w.driven for w in r.wheels) + len(r.links) + steered + rotors} actuators" in summary
    for item in r.items:
        assert item.item_type in ITEMS, f"{path.name}: {item.item_type} is not a registered sensor type"
    described = describe_items(r)
    assert [(d.item_type, d.name) for d in described] == [(ITEMS.canonical(i.item_type), i.name) for i in r.items]
    names = [(d.item_type.lower(), d.name.lower()) for d in described]
    assert len(set(names)) == len(names)
    assert r.total_mass_kg == pytest.approx(r.mass_kg, rel=0.01)


# --------------------------------------------------------------------------- worlds


@pytest.mark.parametrize("path", WORLD_FILES, ids=lambda p: p.stem)
def test_world_file_validates_and_compiles(path: Path):
    w = check_world_file(path)
    assert w.name == path.stem  # --world <stem> finds it
    sim = Simulation(w)
    assert sim.model.ngeom >= 1 + len(w.objects)
    assert len(w.start_poses) >= 4
    fl = w.floor
    for p in w.start_poses:
        assert abs(p.location[0] - fl.center[0]) <= fl.size[0] / 2
        assert abs(p.location[1] - fl.center[1]) <= fl.size[1] / 2


def _start_poses():
    out = []
    for path in WORLD_FILES:
        w = load_world(path)
        out += [pytest.param(path, p.name, id=f"{path.stem}:{p.name}") for p in w.start_poses]
    return out


@pytest.fixture(scope="module")
def worlds():
    return {p: load_world(p) for p in WORLD_FILES}


@pytest.mark.parametrize("path, pose_name", _start_poses())
def test_p2at_lands_on_its_wheels_at_every_start_pose(worlds, path, pose_name):
    w = worlds[path]
    pose = w.start_pose(pose_name)
    robot = resolve_robot("P2AT")
    rest_z = -max(wh.position[2] + wh.radius_m for wh in robot.wheels)
    assert rest_z == pytest.approx(P2AT_REST_Z, abs=5e-4)
    sim = Simulation(w, seed=0)
    ground = sim._ground_below(pose.location)  # the floor, or an upper level
    sim.spawn(1, robot, "R1", pose.location, pose.rotation, set_down=True)
    sim.advance(2.0)
    (x, y, z), (roll, pitch, yaw) = sim.pose_of(1)
    rest_z += ground
    assert abs(math.remainder(roll, 2 * math.pi)) < 0.1, f"rolled over: roll {roll:.3f}"
    assert abs(math.remainder(pitch, 2 * math.pi)) < 0.1, f"tipped: pitch {pitch:.3f}"
    assert z == pytest.approx(rest_z, abs=0.02), f"not resting on its level: z {z:.4f}"
    assert math.hypot(x - pose.location[0], y - pose.location[1]) < 0.05  # it did not slide or get pushed
    assert abs(math.remainder(yaw - pose.rotation[2], 2 * math.pi)) < 0.1
    assert sim.resets == 0  # no physics blow-up


# --------------------------------------------------------------------------- sensor plugins


def _probe_run(tmp_path, sensor_type: str, seed: int, seconds: float):
    p2at = (ROBOTS_DIR / "P2AT.yaml").read_text()
    head = p2at.split("\nsensors:")[0].replace("class_name: P2AT", "class_name: Probe")
    extra = ", fingers: [CameraPanTilt_Link2]" if sensor_type == "Gripper" else ""  # a gripper needs finger links
    if getattr(ITEMS.get(sensor_type), "ON_REQUEST", False):  # silent until asked: asked to send unasked
        extra += ", continuous: true"
    text = head + f"\nsensors:\n  - {{type: {sensor_type}, name: Probe1, location: [0.1, 0.0, -0.1]{extra}}}\n"
    path = tmp_path / f"Probe{seed}.yaml"
    path.write_text(text)
    robot = load_robot(path)
    world = load_world(WORLD_FILES[0])
    start = world.start_poses[0]
    sim = Simulation(world, seed=seed)
    sim.spawn(1, robot, "R1", start.location, start.rotation)
    drive_skid(sim, 1, 1.0, 1.2)  # moving, so that readings change
    sim.advance(seconds)
    return robot, sim, [o for o in sim.take_outputs() if o.key != "STA" and not o.key.startswith("MISSTA")]


@pytest.mark.parametrize("sensor_type", ITEMS.names())  # sensors, effecters and cameras
def test_every_registered_sensor_mounts_reports_on_time_and_formats(tmp_path, sensor_type):
    """Every plugin, mounted with its defaults on a copy of the P2AT: CONF has something to
    say, SEN lines come at its ScanInterval of simulated time, the same seed gives the same
    readings, and each line is exact SEN syntax that the codec reads back."""
    robot, sim, outs = _probe_run(tmp_path, sensor_type, 0, 2.0)
    (desc,) = describe_items(robot)
    assert desc.item_type == sensor_type
    cls = ITEMS.get(sensor_type)
    if not cls.PERIODIC:  # cameras and effecters send no SEN on the control port
        assert outs == []
        return
    assert desc.conf  # CONF has something to say about it
    assert outs, f"{sensor_type} produced no reading in 2 s"
    interval = dict(desc.conf).get("ScanInterval") or cls.Config().scan_interval_s
    times = [o.time for o in outs]
    gaps = {round(b - a, 6) for a, b in zip(times, times[1:])}
    every = 4 if sensor_type == "VictSensor" else 1  # the victim sensor reports every 4th scan
    assert gaps == {round(interval * every, 6)}, f"{sensor_type}: gaps {gaps}, ScanInterval {interval}"
    assert len(outs) == (int(2.0 / interval + 1e-9) + 1) // every  # ticks at 0, interval, ... 2 s
    _, _, again = _probe_run(tmp_path, sensor_type, 0, 2.0)
    assert [o.value for o in again] == [o.value for o in outs], "not deterministic under a seed"
    for o in outs:
        line = format_message(SensorMessage(time=o.time, reading=o.value))
        assert line.startswith("SEN ") and line.endswith("\r\n")
        assert "{Type %s}" % sensor_type in line
        assert "nan" not in line.lower() and "inf" not in line.lower()
        # a client can read every line back (a 3D sweep too long for one line comes as one
        # line per row)
        rows = line[:-2].split("\r\n")
        assert all(len(r) + 2 <= 4096 for r in rows)
        assert "".join(format_message(parse_message(r)) for r in rows) == line


CAMERA_ROBOTS = [p for p in ROBOT_FILES if any(i.item_type in ("Camera", "OmniCam") for i in load_robot(p).items)]


@pytest.mark.parametrize("path", CAMERA_ROBOTS, ids=lambda p: p.stem)
def test_every_camera_robot_pans_and_tilts_its_camera(path: Path, test_world):
    """A robot with a camera has the mission package CameraPanTilt (link 1 pans, link 2
    tilts, protocol.md 5.6) and its first camera rides on it: panning turns the camera's
    view to the right, tilting raises it, each as far as its link's range allows (a
    drone's camera only tilts)."""
    from usarsim.sim import frames

    robot = load_robot(path)
    pkg = robot.package("CameraPanTilt")
    assert pkg is not None and len(pkg.links) == 2, "no CameraPanTilt of two links"
    pan, tilt = pkg.links
    cam = next(i for i in robot.items if i.item_type in ("Camera", "OmniCam"))
    sim = Simulation(test_world, seed=0)
    sim.spawn(1, robot, "R1", (-6.0, 0.0, -2.0), (0.0, 0.0, 0.0))
    sim.advance(0.5)
    r = sim.robots[1]

    def view():
        _, rot = r.handle.sensor_frame(sim.data, cam.location, cam.orientation, cam.mount)
        ahead = frames.from_mj_vec(rot[:, 0])  # the camera's forward axis, USARSim frame
        _, _, yaw = frames.mj_mat_to_usar_euler(r.handle.rotation_mj(sim.data))
        heading = math.atan2(ahead[1], ahead[0])
        return math.remainder(heading - yaw, 2 * math.pi), -math.asin(max(-1.0, min(1.0, ahead[2])))

    yaw0, pitch0 = view()
    reach = {}
    for name, value in ((pan, 0.3), (tilt, 0.2)):
        ln = robot.link(name)
        reach[name] = max(min(value, ln.max_range), ln.min_range) if ln.limited else value
        assert drive_joint(sim, 1, name, value)
    sim.advance(0.3 / min(robot.link(pan).max_speed, robot.link(tilt).max_speed) + 1.0)
    yaw1, pitch1 = view()
    assert reach[tilt] > 0.1, "the camera tilts"
    assert yaw1 - yaw0 == pytest.approx(reach[pan], abs=0.05), "panning turns the camera right"
    assert pitch1 - pitch0 == pytest.approx(reach[tilt], abs=0.05), "tilting raises the camera"
