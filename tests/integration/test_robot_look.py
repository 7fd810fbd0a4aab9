"""What cameras see of a robot beyond its solid pieces (a robot file's ``look``): tracks round a
tracked robot's wheels, hubs on a wheeled one's, and pieces in the real robot's colours.  It is
for pictures only: the physics of every robot is that of its solid pieces, to the bit, and the
label and thermal cameras count the look as the robot's own."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from helpers import gl_problem

ROBOTS = Path(__file__).resolve().parents[2] / "src" / "usarsim" / "data" / "robots"


def robot_model(names, *, look: bool = True) -> mujoco.MjModel:
    """The robots of ``names`` side by side on a floor, with their look or without (``look``
    False: no tracks, hubs or pieces)."""
    from usarsim.config.robot import load_robot
    from usarsim.sim.gallery import robots_scene

    return robots_scene([load_robot(ROBOTS / f"{name}.yaml") for name in names], look=look)[0]


def look_geoms(m: mujoco.MjModel) -> list[int]:
    return [
        g for g in range(m.ngeom) if "/look/" in m.geom(g).name or m.geom(g).name.endswith(("/hub", "/spoke", "/drum"))
    ]


@pytest.mark.parametrize("names", [("P2AT", "Kenaf"), ("Kurt3D", "Talon"), ("TeleMax", "Soryu")])
def test_the_look_leaves_the_physics_as_it_was_to_the_bit(names):
    with_look, bare = robot_model(names), robot_model(names, look=False)
    added = look_geoms(with_look)
    assert len(added) > 0 and with_look.ngeom == bare.ngeom + len(added)
    # nothing of the look touches anything or weighs anything
    assert all(with_look.geom_contype[g] == 0 and with_look.geom_conaffinity[g] == 0 for g in added)
    for field in ("body_mass", "body_inertia", "body_ipos", "body_iquat", "body_subtreemass"):
        assert np.array_equal(getattr(with_look, field), getattr(bare, field)), field
    # the same drive commands give the same motion, bit for bit: every wheel forward, then a turn
    runs = []
    for m in (with_look, bare):
        d = mujoco.MjData(m)
        trace = []
        for step in range(400):
            for a in range(m.nu):
                name = m.actuator(a).name
                if "Wheel" in name:
                    left = "Left" in name or name.split("/")[-1].startswith(("FL", "BL", "RL", "L"))
                    d.ctrl[a] = 3.0 if step < 200 or left else -3.0
            mujoco.mj_step(m, d)
            trace.append(d.qpos.copy())
        runs.append(np.array(trace))
    assert runs[0].shape == runs[1].shape
    assert np.array_equal(runs[0], runs[1])
    assert np.abs(runs[0][-1] - runs[0][0]).max() > 0.05  # the robots did move


def test_tracked_robots_have_belts_and_wheeled_ones_hubs():
    m = robot_model(("Kenaf", "P2AT"))
    names = [m.geom(g).name for g in look_geoms(m)]
    kenaf = [n for n in names if n.startswith("robot1/")]
    p2at = [n for n in names if n.startswith("robot2/")]
    # Kenaf: a belt each side of the body and of each of its four flippers
    belts = {n.rsplit("/", 1)[0] for n in kenaf if "/track/" in n}
    assert belts == {
        f"robot1/look/track/{body}/{side}"
        for body, side in [
            ("chassis", "left"),
            ("chassis", "right"),
            ("FRFlipper", "right"),
            ("FLFlipper", "left"),
            ("RRFlipper", "right"),
            ("RLFlipper", "left"),
        ]
    }
    assert not any(n.endswith("/hub") for n in kenaf)
    # a drum round each of its 18 wheels stands in the wheel's place: the wheels are not drawn
    drums = [n for n in kenaf if n.endswith("/drum")]
    assert len(drums) == 18
    for n in drums:
        wheel = m.geom(n.removesuffix("/drum"))
        assert m.geom_rgba[wheel.id][3] == 0.0 and m.geom_bodyid[m.geom(n).id] == m.geom_bodyid[wheel.id]
        assert m.geom_size[m.geom(n).id][0] > m.geom_size[wheel.id][0]
    # the P2AT: a hub and a spoke on each of its four wheels, turning with it
    hubs = [n for n in p2at if n.endswith("/hub")]
    assert len(hubs) == 4 and sum(n.endswith("/spoke") for n in p2at) == 4
    for n in hubs:
        wheel = n.rsplit("/", 1)[0]
        assert m.geom_bodyid[m.geom(n).id] == m.body(wheel).id


def test_a_belt_runs_tangent_to_the_wheels_it_goes_round():
    from usarsim.config.robot_parts import Wheel
    from usarsim.sim.robotlook import belt_segments

    small = Wheel(name="a", position=(0.0, 0.0, 0.0), radius_m=0.05, width_m=0.05, mass_kg=0.1, side="left")
    large = Wheel(name="b", position=(0.14, 0.0, 0.02), radius_m=0.075, width_m=0.05, mass_kg=0.1, side="left")
    t = 0.012
    runs = belt_segments([large, small], t)  # any order: sorted along X
    assert len(runs) == 2
    for centre, length, pitch in runs:
        # the run's line, in USARSim's X-Z plane: MuJoCo's pitch turns +X onto (cos, -sin) there
        direction = np.array([math.cos(pitch), math.sin(pitch)])
        normal = np.array([-direction[1], direction[0]])
        for w in (small, large):
            c = np.array([w.position[0], w.position[2]])
            assert abs(float(np.dot(c - centre, normal))) == pytest.approx(w.radius_m + t / 2.0, abs=1e-9)
        assert 0.10 < length < 0.15
    # one run above the wheels (Z down: smaller Z), one below
    zs = sorted(float(c[1]) for c, _, _ in runs)
    assert zs[0] < -0.05 and zs[1] > 0.05
    # wheels of one size: level runs at the belt's radius
    twin = dataclasses.replace(small, position=(0.2, 0.0, 0.0))
    flat = belt_segments([small, twin], t)
    assert [round(float(c[1]), 9) for c, _, _ in flat] == [-0.056, 0.056]
    assert all(p == pytest.approx(0.0) and n == pytest.approx(0.2) for _, n, p in flat)
    # a row of wheels: one run over them all and one under, first wheel to last
    row = [dataclasses.replace(small, position=(0.1 * k, 0.0, 0.0)) for k in range(5)]
    assert [round(n, 9) for _, n, _ in belt_segments(row, t)] == [0.4, 0.4]
    # a wheel raised in the middle (Z down): the upper runs go over it, the lower one passes below
    raised = [row[0], dataclasses.replace(small, position=(0.2, 0.0, -0.04)), row[4]]
    runs = belt_segments(raised, t)
    assert len(runs) == 3 and runs[-1][1] == pytest.approx(0.4)


def test_label_and_thermal_cameras_count_the_look_as_the_robots():
    from usarsim.config.world import bare_world
    from usarsim.sim import pictures

    m = robot_model(("Kenaf", "P2AT"))
    world = bare_world("look")
    tables = pictures.scene_tables(m, world, {2: frozenset({"LeftFWheel", "RightFWheel", "LeftRWheel", "RightRWheel"})})
    for g in look_geoms(m):
        uid = int(m.geom(g).name.split("/")[0].removeprefix("robot"))
        assert tables.classes[g + 1] == pictures.CLASSES.index("robot")
        assert tables.instances[g + 1] == uid
    # the P2AT's hubs sit on its wheels' motors: warm, as the wheels are
    hub = m.geom("robot2/LeftFWheel/hub").id
    assert tables.temperature[hub + 1] == pictures.MOTOR_C


def test_a_tracked_robot_shows_its_belts_and_a_wheeled_one_its_hubs_from_the_side():
    if problem := gl_problem():
        pytest.skip(problem)
    seen = {}
    for name in ("Kenaf", "P2AT"):
        m = robot_model((name,))
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        with mujoco.Renderer(m, 240, 320) as r:
            cam = mujoco.MjvCamera()
            cam.lookat[:] = d.xpos[m.body("robot1").id]
            cam.distance, cam.azimuth, cam.elevation = 1.4, -90.0, -5.0  # from the robot's left (MuJoCo +Y)
            opt = mujoco.MjvOption()
            opt.geomgroup[:5] = 1
            r.enable_segmentation_rendering()
            r.update_scene(d, cam, opt)
            ids = r.render()[..., 0]
        names = [m.geom(int(g)).name for g in np.unique(ids) if g >= 0]
        seen[name] = {n: int((ids == m.geom(n).id).sum()) for n in names}
    belt = sum(v for n, v in seen["Kenaf"].items() if "/look/track/chassis/left/" in n or n.endswith("/drum"))
    wheels = sum(v for n, v in seen["Kenaf"].items() if n.endswith("Wheel"))
    assert belt > 2000 and wheels == 0, seen["Kenaf"]  # the left track covers the Kenaf's side
    hubs = [n for n, v in seen["P2AT"].items() if n.endswith("/hub") and v > 100]
    assert sorted(hubs) == ["robot1/LeftFWheel/hub", "robot1/LeftRWheel/hub"], seen["P2AT"]


def test_a_look_piece_on_an_unknown_body_is_refused_by_name(tmp_path):
    from usarsim.config.robot import load_robot
    from usarsim.errors import ConfigError

    text = (ROBOTS / "Kurt3D.yaml").read_text()
    piece = "- {shape: box, center: [0.05, 0.0, -0.16], size: [0.164"
    assert piece in text
    bad = text.replace(piece, piece.replace("{shape", "{body: Mast, shape"))
    p = tmp_path / "Kurt3D.yaml"
    p.write_text(bad)
    with pytest.raises(ConfigError, match="unknown body 'Mast'"):
        load_robot(p)
    p.write_text(text.replace("color: [0.16, 0.33, 0.62]", "color: [1.6, 0.33, 0.62]"))
    with pytest.raises(ConfigError, match="a colour is red, green, blue from 0 to 1"):
        load_robot(p)


def test_usarsim_robots_draws_the_robots_asked_for(tmp_path, capsys):
    if problem := gl_problem():
        pytest.skip(problem)
    from PIL import Image

    from usarsim.cli import main

    out = tmp_path / "robots.png"
    assert main(["robots", "--picture", str(out), "--robot", "Kenaf", "--robot", "P2AT"]) == 0
    assert "2 robot(s), 640x262" in capsys.readouterr().out
    picture = np.asarray(Image.open(out).convert("RGB")).astype(int)
    # each tile shows its robot: the Kenaf's black tracks and the P2AT's red body near the middle
    kenaf, p2at = picture[:240, :320], picture[:240, 320:]
    dark = (kenaf.max(axis=2) < 40).sum()
    r, g, b = p2at[..., 0], p2at[..., 1], p2at[..., 2]
    red = ((r > 60) & (r > 2 * g) & (r > 2 * b)).sum()
    assert dark > 2000 and red > 5000, (dark, red)
    assert main(["robots", "--picture", str(out), "--robot", "P9AT"]) == 1
    assert "unknown robot class 'P9AT'" in capsys.readouterr().err
