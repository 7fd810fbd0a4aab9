"""The arena features of a world file at work (manual 3.2.1): ramps and stairs that robots
climb and objects rest on, mesh walls that range sensors see, mirrors and grid fenders that
change what lasers, IR, cameras and sonar read, and the world's lights in the MuJoCo model.

Two worlds with everything at known places (EFFECTS_WORLD, MESH_WORLD); physics and
readings are checked on the Simulation directly.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from helpers import drive_skid
from usarsim.config.catalog import ROBOTS_DIR, resolve_robot
from usarsim.config.robot import load_robot
from usarsim.config.world_file import load_world
from usarsim.readings import RangeReading, RangeScanReading
from usarsim.sim import builder
from usarsim.sim.entities import Entities
from usarsim.sim.raycaster import RayCaster
from usarsim.sim.simulation import Simulation

DATA = Path(__file__).resolve().parent.parent / "data"
REST_Z = -0.1455  # P2AT chassis origin above the floor (Z down)
PROBE_X = 0.27  # the probe's sensors, robot frame (ahead of the chassis)
SCANNER_X = 0.144  # P2AT Scanner1 mount, robot frame

EFFECTS_WORLD = """\
name: EffectsArena
description: ramps, stairs, mirrors and grid fences at known places (tests only)
floor: {center: [0.0, 0.0], size: [60.0, 60.0]}
materials:
  wall: {rgba: [0.9, 0.8, 0.4, 1.0]}
  mirror: {rgba: [0.85, 0.9, 0.95, 1.0], mirror: true}
  fence: {rgba: [0.5, 0.5, 0.5, 1.0], porosity: 0.4}
objects:
  # lane y = 0: a ramp from x = 2.0 rising 0.3 m over 2.4 m of run onto a deck 0.3 m high
  - {name: ramp1, shape: ramp, foot: [2.0, 0.0, 0.0], heading: 0.0, length: 2.4, width: 1.6, rise: 0.3}
  - {name: deck, shape: box, center: [5.9, 0.0, -0.15], size: [3.0, 1.6, 0.3], material: wall}
  # lane y = 10: four steps of 0.15 m x 0.3 m from x = 2.0; a crate held 5 cm above the top one
  - {name: stairs1, shape: stairs, foot: [2.0, 10.0, 0.0], heading: 0.0, width: 1.2, steps: 4,
     step_rise: 0.15, step_run: 0.3, material: wall}
  - {name: crate, shape: box, center: [3.05, 10.0, -0.75], size: [0.2, 0.2, 0.2], mass_kg: 2.0}
  # lane y = -10: a mirror at x = 3.0 turned 45 degrees (it sends +X rays to -Y), and the
  # wall it shows, whose face is at y = -13.0
  - {name: mirror45, shape: box, center: [3.0, -10.0, -0.5], size: [0.02, 1.2, 1.0],
     rotation: [0.0, 0.0, 0.7853981633974483], material: mirror}
  - {name: shown, shape: box, center: [3.0, -13.05, -0.5], size: [3.0, 0.1, 1.0], material: wall}
  # lane y = -20: a mirror facing the robot, its face at x = 2.99
  - {name: mirror0, shape: box, center: [3.0, -20.0, -0.5], size: [0.02, 1.2, 1.0], material: mirror}
  # lane y = 20: a grid fence whose face is at x = 2.985, a wall behind it at x = 5.0
  - {name: fence1, shape: box, center: [3.0, 20.0, -0.5], size: [0.03, 8.0, 1.0], material: fence}
  - {name: behind, shape: box, center: [5.05, 20.0, -0.5], size: [0.1, 12.0, 1.0], material: wall}
lights:
  - {name: lamp, type: point, position: [0.0, 0.0, -2.5], color: [1.0, 0.9, 0.8], intensity: 0.5,
     attenuation: [1.0, 0.1, 0.0]}
  - {name: beam, type: spot, position: [2.0, 10.0, -3.0], direction: [0.0, 0.0, 1.0], cutoff_deg: 30.0,
     cast_shadows: false}
  - {name: sky, type: directional, direction: [1.0, 0.0, 1.0]}
start_poses:
  - {name: Ramp, location: [0.0, 0.0, -0.2]}
  - {name: Mirror45, location: [0.73, -10.0, -0.2]}
  - {name: Mirror0, location: [0.73, -20.0, -0.2]}
  - {name: Fence, location: [1.0, 20.0, -0.2]}
"""

MESH_WORLD = """\
name: MeshArena
description: mesh walls at known places (tests only)
floor: {center: [0.0, 0.0], size: [30.0, 30.0]}
materials:
  wall: {rgba: [0.9, 0.8, 0.4, 1.0]}
objects:
  # the wedge of tests/data/wedge.obj: its vertical back face at x = 3.0, 0.5 m tall
  - {name: wedge, shape: mesh, file: wedge.obj, center: [3.5, 0.0, 0.0], material: wall}
  # turned half round and twice as tall: its slope rises from x = 3.0 (floor) to x = 4.0 (1 m)
  - {name: tall, shape: mesh, file: wedge.obj, center: [3.5, 5.0, 0.0], rotation: [0.0, 0.0, 3.141592653589793],
     scale: [1.0, 1.0, 2.0], material: wall}
start_poses:
  - {name: Wedge, location: [1.0, 0.0, -0.2]}
  - {name: Tall, location: [1.0, 5.0, -0.2]}
"""

PROBE_SENSORS = """\
  - {type: RangeSensor, name: Beam, location: [0.27, 0.0, -0.1], MaxRange: 20.0}
  - {type: Sonar, name: S1, location: [0.27, 0.0, -0.1]}
  - {type: RangeScanner, name: Scanner1, location: [0.144, 0.0, -0.092], preset: SICK}
"""


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    p = tmp_path_factory.mktemp("effects") / "EffectsArena.yaml"
    p.write_text(EFFECTS_WORLD)
    return load_world(p)


@pytest.fixture(scope="module")
def mesh_world(tmp_path_factory):
    d = tmp_path_factory.mktemp("mesh")
    (d / "wedge.obj").write_bytes((DATA / "wedge.obj").read_bytes())  # beside the world file
    p = d / "MeshArena.yaml"
    p.write_text(MESH_WORLD)
    return load_world(p)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    """A P2AT body with a long single beam, a sonar and a SICK scanner only."""
    head = (
        (ROBOTS_DIR / "P2AT.yaml").read_text().split("\nsensors:")[0].replace("class_name: P2AT", "class_name: Probe")
    )
    path = tmp_path_factory.mktemp("probe") / "Probe.yaml"
    path.write_text(head + "\nsensors:\n" + PROBE_SENSORS)
    return load_robot(path)


def settled(world, robot, pose: str, seed: int = 5, seconds: float = 1.0) -> Simulation:
    sim = Simulation(world, seed=seed)
    p = world.start_pose(pose)
    sim.spawn(1, robot, "R1", p.location, p.rotation)
    sim.advance(seconds)
    sim.take_outputs()
    return sim


def readings(sim, seconds: float):
    sim.advance(seconds)
    out = [o.value for o in sim.take_outputs() if o.uid == 1]
    beams = [r.items[0].range_m for r in out if isinstance(r, RangeReading) and r.sensor_type == "RangeSensor"]
    sonar = [r.items[0].range_m for r in out if isinstance(r, RangeReading) and r.sensor_type == "Sonar"]
    scans = [r for r in out if isinstance(r, RangeScanReading)]
    return beams, sonar, scans


def model_of(world):
    m = builder.world_spec(world).compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    ents = Entities(world)
    ents.resolve(m)
    return m, d, ents


# --------------------------------------------------------------------------- mirrors


def test_a_laser_reads_the_path_to_the_wall_a_45_degree_mirror_shows(world, probe):
    sim = settled(world, probe, "Mirror45")
    xs = sim.pose_of(1)[0][0] + PROBE_X
    assert 3.0 - xs == pytest.approx(2.0, abs=0.02)  # the beam starts 2 m from the mirror
    beams, _, scans = readings(sim, 1.0)
    face_x = 3.0 - 0.01 * math.sqrt(2.0)  # the mirror's front face on the lane's axis
    expected = (face_x - xs) + 3.0  # to the mirror, then 3 m to the wall it shows
    assert beams and np.mean(beams) == pytest.approx(expected, abs=0.02)
    # the scanner's middle beam too (it sits 0.126 m behind the single beam)
    mid = [s.ranges_m[90] for s in scans]
    assert mid and np.mean(mid) == pytest.approx(expected + PROBE_X - SCANNER_X, abs=0.02)


def test_sonar_reads_a_mirror_facing_it_while_the_laser_beam_comes_back(world, probe):
    sim = settled(world, probe, "Mirror0")
    xs = sim.pose_of(1)[0][0] + PROBE_X
    beams, sonar, _ = readings(sim, 1.0)
    assert sonar and np.mean(sonar) == pytest.approx(2.99 - xs, abs=0.02)  # the mirror's face
    # the laser beam goes back past the sensor onto the robot itself: twice as far and more
    assert 2.0 * (2.99 - xs) < np.mean(beams) < 2.0 * (2.99 - xs) + 0.3


@pytest.mark.parametrize("backend", ["compiled", "mujoco"])
def test_mirrors_by_kind_of_ray_with_either_caster(world, backend):
    m, d, ents = model_of(world)
    caster = RayCaster(m, d, backend, see_through=ents.see_through)
    assert caster.backend == backend
    origin = np.array([1.0, 10.0, 0.25])  # MuJoCo frame: USARSim (1, -10, -0.25)
    ahead = np.array([[1.0, 0.0, 0.0]])
    face = 3.0 - 0.01 * math.sqrt(2.0) - 1.0
    for kind in ("laser", "ir"):
        dist, _, gid = caster.cast(origin, ahead, 20.0, -1, kind=kind)
        assert dist[0] == pytest.approx(face + 3.0, abs=1e-6) and m.geom(int(gid[0])).name == "world/shown"
    for kind in ("sonar", "camera", None):
        dist, _, gid = caster.cast(origin, ahead, 20.0, -1, kind=kind)
        assert dist[0] == pytest.approx(face, abs=1e-6) and m.geom(int(gid[0])).name == "world/mirror45"
    # asked for normals (sensors that count the walls on a line), the mirror is a surface
    dist, nrm, _ = caster.cast(origin, ahead, 20.0, -1, normals=True, kind="laser")
    assert dist[0] == pytest.approx(face, abs=1e-6)
    assert abs(nrm[0] @ np.array([math.sqrt(0.5), -math.sqrt(0.5), 0.0])) == pytest.approx(1.0, abs=1e-9)
    # out of range after the mirror: nothing
    dist, _, gid = caster.cast(origin, ahead, 4.0, -1, kind="laser")
    assert np.isinf(dist[0]) and gid[0] == -1


def test_both_casters_agree_on_mirrors_and_grids(world):
    m, d, ents = model_of(world)
    fast = RayCaster(m, d, "compiled", see_through=ents.see_through)
    ref = RayCaster(m, d, "mujoco", see_through=ents.see_through)
    rng = np.random.default_rng(7)
    n = 3000
    orig = np.column_stack(
        [
            rng.uniform(0.0, 2.0, n),
            rng.choice([10.0, 20.0, -20.0, -10.0], n) + rng.uniform(-1, 1, n),
            rng.uniform(0.1, 0.9, n),
        ]
    )
    ang = rng.uniform(-1.2, 1.2, n)
    dirs = np.column_stack([np.cos(ang), np.sin(ang), rng.uniform(-0.2, 0.2, n)])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    for kind in ("laser", "ir", "camera", "sonar"):
        da, _, ga = fast.cast_from(orig, dirs, 15.0, -1, kind=kind)
        db, _, gb = ref.cast_from(orig, dirs, 15.0, -1, kind=kind)
        hit = np.isfinite(da)
        np.testing.assert_array_equal(hit, np.isfinite(db))
        np.testing.assert_array_equal(ga, gb)
        np.testing.assert_allclose(da[hit], db[hit], atol=1e-6)


# --------------------------------------------------------------------------- grid fences


def test_a_grid_fence_lets_its_porosity_through_repeatably(world, probe):
    sim = settled(world, probe, "Fence")
    caster = sim.caster
    x0 = sim.pose_of(1)[0][0]
    # many rays from in front of the fence: 40 % reach the wall behind it, the same ones each time
    rng = np.random.default_rng(3)
    ang = rng.uniform(-0.8, 0.8, 4000)
    dirs = np.column_stack([np.cos(ang), np.sin(ang), rng.uniform(-0.05, 0.05, 4000)])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origin = np.array([x0 + 0.5, -20.0, 0.5])
    dist, _, gid = caster.cast(origin, dirs, 20.0, -1, kind="laser")
    names = np.array([sim.model.geom(int(g)).name for g in gid])
    assert set(names) == {"world/fence1", "world/behind"}
    assert np.mean(names == "world/behind") == pytest.approx(0.4, abs=0.03)
    again, _, _ = caster.cast(origin, dirs, 20.0, -1, kind="laser")
    np.testing.assert_array_equal(dist, again)
    # cameras see through the same share; sonar never passes
    _, _, cam = caster.cast(origin, dirs, 20.0, -1, kind="camera")
    assert np.mean(cam == sim.model.geom("world/behind").id) == pytest.approx(0.4, abs=0.03)
    _, _, son = caster.cast(origin, dirs, 20.0, -1, kind="sonar")
    assert set(son.tolist()) == {sim.model.geom("world/fence1").id}
    # the robot's scanner: the beams that pass are the same in every sweep
    _, sonar, scans = readings(sim, 1.0)
    assert len(scans) >= 4
    xs = x0 + SCANNER_X
    split = (2.985 - xs + 5.0 - xs) / 2.0  # between the fence and the wall behind it
    passed = [np.array(s.ranges_m[30:151]) > split for s in scans]  # beams within 60 degrees
    for p in passed[1:]:
        np.testing.assert_array_equal(p, passed[0])
    assert 0.25 < passed[0].mean() < 0.6  # some beams pass, most are stopped (121 beams: coarse)
    assert np.mean(sonar) == pytest.approx(2.985 - (x0 + PROBE_X), abs=0.02)


def test_a_robot_does_not_drive_through_a_grid_fence(world):
    sim = settled(world, resolve_robot("P2AT"), "Fence")
    drive_skid(sim, 1, 3.0, 3.0)
    sim.advance(8.0)  # 0.39 m/s for 8 s: 3 m if nothing stopped it
    x = sim.pose_of(1)[0][0]
    assert x < 2.985 - 0.2  # the chassis front (0.26 m ahead of its origin) pushes on the fence


# --------------------------------------------------------------------------- ramps and stairs


def test_a_p2at_drives_up_a_ramp_onto_the_deck(world):
    sim = settled(world, resolve_robot("P2AT"), "Ramp")
    (x0, y0, z0), _ = sim.pose_of(1)
    assert z0 == pytest.approx(REST_Z, abs=0.01)
    drive_skid(sim, 1, 3.0, 3.0)
    zs = []
    for _ in range(28):  # 14 s at 0.39 m/s: about 5.5 m, from the floor up the ramp onto the deck
        sim.advance(0.5)
        zs.append(sim.pose_of(1)[0][2])
    drive_skid(sim, 1, 0.0, 0.0)
    sim.advance(1.0)
    (x1, y1, z1), (roll, pitch, _) = sim.pose_of(1)
    assert 4.6 < x1 < 7.2 and abs(y1 - y0) < 0.3  # on the deck
    assert z1 - z0 == pytest.approx(-0.3, abs=0.02)  # up by the ramp's rise
    assert abs(roll) < 0.05 and abs(pitch) < 0.05
    assert all(b <= a + 0.01 for a, b in zip(zs, zs[1:]))  # it climbed steadily


def test_a_box_dropped_on_the_top_step_rests_there(world):
    sim = Simulation(world, seed=1)
    sim.advance(2.0)
    (row,) = [r for r in sim.truth("MovableObject") if r[0] == "crate"]
    x, y, z = row[3]
    # the top step (x 2.9..3.2) is 4 x 0.15 = 0.6 m high: the crate's centre 0.1 m above it
    assert 2.95 < x < 3.15 and abs(y - 10.0) < 0.05
    assert z == pytest.approx(-0.7, abs=0.01)


def test_ramp_and_stairs_are_boxes_named_after_them(world):
    m, _, _ = model_of(world)
    assert m.geom("world/ramp1").type == mujoco.mjtGeom.mjGEOM_BOX
    for k in range(1, 5):
        assert m.geom(f"world/stairs1/step{k}").type == mujoco.mjtGeom.mjGEOM_BOX
    assert RayCaster(m, mujoco.MjData(m)).backend == "compiled"  # boxes only: the fast kernel


# --------------------------------------------------------------------------- meshes


def test_a_mesh_wall_is_seen_at_the_right_distance(mesh_world, probe):
    sim = settled(mesh_world, probe, "Wedge")
    assert sim.caster.backend == "mujoco"  # meshes: mj_multiRay
    xs = sim.pose_of(1)[0][0] + PROBE_X
    beams, sonar, scans = readings(sim, 1.0)
    assert beams and np.mean(beams) == pytest.approx(3.0 - xs, abs=0.02)
    assert sonar and np.mean(sonar) == pytest.approx(3.0 - xs, abs=0.02)
    mid = [s.ranges_m[90] for s in scans]
    assert mid and np.mean(mid) == pytest.approx(3.0 - xs + PROBE_X - SCANNER_X, abs=0.02)


def test_a_turned_and_scaled_mesh(mesh_world, probe):
    sim = settled(mesh_world, probe, "Tall")
    (x, _, z), _ = sim.pose_of(1)
    xs = x + PROBE_X
    height = -(z - 0.1)  # the beam's height above the floor
    beams, _, _ = readings(sim, 1.0)
    # the slope rises 1 m over 1 m from x = 3.0: the beam meets it at x = 3.0 + height
    assert np.mean(beams) == pytest.approx(3.0 + height - xs, abs=0.02)


def test_a_robot_does_not_drive_through_a_mesh_wall(mesh_world):
    sim = settled(mesh_world, resolve_robot("P2AT"), "Wedge")
    drive_skid(sim, 1, 3.0, 3.0)
    sim.advance(8.0)  # 0.39 m/s for 8 s: 3 m if nothing stopped it
    x = sim.pose_of(1)[0][0]
    assert 2.4 < x < 3.0 - 0.2  # the chassis front (0.26 m ahead of its origin) against the back face


# --------------------------------------------------------------------------- lights


def test_world_lights_are_in_the_compiled_model(world):
    m, _, _ = model_of(world)
    names = {m.light(i).name for i in range(m.nlight)}
    assert names == {"light/lamp", "light/beam", "light/sky"}  # no default light
    lamp, beam, sky = m.light("light/lamp"), m.light("light/beam"), m.light("light/sky")
    assert lamp.type == mujoco.mjtLightType.mjLIGHT_POINT
    np.testing.assert_allclose(m.light_pos[lamp.id], [0.0, 0.0, 2.5])  # USARSim z = -2.5 is up
    np.testing.assert_allclose(m.light_diffuse[lamp.id], [0.5, 0.45, 0.4])
    np.testing.assert_allclose(m.light_attenuation[lamp.id], [1.0, 0.1, 0.0])
    assert beam.type == mujoco.mjtLightType.mjLIGHT_SPOT and m.light_cutoff[beam.id] == pytest.approx(30.0)
    np.testing.assert_allclose(m.light_pos[beam.id], [2.0, -10.0, 3.0])
    np.testing.assert_allclose(m.light_dir[beam.id], [0.0, 0.0, -1.0], atol=1e-12)
    assert not m.light_castshadow[beam.id]
    assert sky.type == mujoco.mjtLightType.mjLIGHT_DIRECTIONAL and m.light_castshadow[sky.id]
    np.testing.assert_allclose(m.light_dir[sky.id], [math.sqrt(0.5), 0.0, -math.sqrt(0.5)])


def test_a_world_without_lights_keeps_the_default_lighting(yellow_world):
    import dataclasses

    # the arena without its lamps and ambient light (DM-USAR_yellow has its own)
    bare = dataclasses.replace(yellow_world, lights=(), ambient_light=None)
    m = builder.world_spec(bare).compile()
    assert m.nlight == 1 and m.light(0).name == "sun"
    assert m.light_type[0] == mujoco.mjtLightType.mjLIGHT_SPOT
    np.testing.assert_allclose(m.light_dir[0], [0.0, 0.0, -1.0])
    np.testing.assert_allclose(m.vis.headlight.ambient, [0.1, 0.1, 0.1], atol=1e-6)
