"""The worked examples of docs/architecture.md run as written: each ```python block after an
``<!-- example: NAME -->`` marker is executed once, and then used the way the page says."""

from __future__ import annotations

import dataclasses
import math
import re
import sys
import types
from pathlib import Path

import pytest

from helpers import drive_skid

DOC = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"
_BLOCK = re.compile(r"<!-- example: (\w+) -->\s*```python\n(.*?)```", re.S)


def examples() -> dict[str, str]:
    return dict(_BLOCK.findall(DOC.read_text(encoding="utf-8")))


@pytest.fixture(scope="module")
def doc_plugins():
    """Every example's namespace (each registers its plugin once per test session)."""
    out = {}
    for name, code in examples().items():
        module = types.ModuleType(f"architecture_doc_{name}")
        sys.modules[module.__name__] = module  # dataclasses look their module up
        exec(compile(code, f"{DOC}:{name}", "exec"), module.__dict__)
        out[name] = module.__dict__
    return out


def test_the_page_has_its_worked_examples():
    assert {"sensor", "effecter", "drive", "system", "radio", "element"} <= set(examples())


def test_the_drive_example_drives_a_p2at_in_metres_per_second(doc_plugins, test_world):
    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.simulation import Simulation

    robot = dataclasses.replace(resolve_robot("P2AT"), drive="metric_skid")
    sim = Simulation(test_world, seed=1)
    sim.spawn(1, robot, "R", (-6.0, 0.0, -0.3), (0.0, 0.0, 0.0))
    sim.advance(0.5)
    drive_skid(sim, 1, 0.3, 0.3)  # m/s of the rims
    sim.advance(1.0)
    (x0, _, _), _ = sim.pose_of(1)
    sim.advance(2.0)
    (x1, _, _), _ = sim.pose_of(1)
    assert (x1 - x0) / 2.0 == pytest.approx(0.3, rel=0.1)


def test_the_drive_examples_own_section_limits_its_rim_speed(doc_plugins, test_world):
    from usarsim.config.catalog import resolve_robot
    from usarsim.errors import SimulationError
    from usarsim.sim.simulation import Simulation

    p2at = resolve_robot("P2AT")
    robot = dataclasses.replace(p2at, drive="metric_skid", drive_sections={"metric_skid": {"max_rim_m_s": 0.15}})
    sim = Simulation(test_world, seed=1)
    sim.spawn(1, robot, "R", (-6.0, 0.0, -0.3), (0.0, 0.0, 0.0))
    sim.advance(0.5)
    drive_skid(sim, 1, 0.3, 0.3)  # asked for 0.3 m/s, held to the section's 0.15
    sim.advance(1.0)
    (x0, _, _), _ = sim.pose_of(1)
    sim.advance(2.0)
    (x1, _, _), _ = sim.pose_of(1)
    assert (x1 - x0) / 2.0 == pytest.approx(0.15, rel=0.1)
    typo = dataclasses.replace(p2at, drive="metric_skid", drive_sections={"metric_skid": {"max_rim": 0.15}})
    with pytest.raises(
        SimulationError, match=r"metric_skid\.max_rim: unknown key 'max_rim' \(did you mean 'max_rim_m_s'\?\)"
    ):
        sim.spawn(2, typo, "T", (-6.0, 2.0, -0.3), (0.0, 0.0, 0.0))


def test_the_system_example_blows_robots_along_in_a_windy_world_only(doc_plugins, test_world):
    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.simulation import Simulation

    def drift(world) -> float:
        sim = Simulation(world, seed=1)
        sim.spawn(1, resolve_robot("AirRobot"), "Air", (-6.0, 0.0, -1.0), (0.0, 0.0, 0.0))
        sim.advance(0.5)
        (x0, _, _), _ = sim.pose_of(1)
        sim.advance(1.0)
        (x1, _, _), _ = sim.pose_of(1)
        return x1 - x0

    assert abs(drift(test_world)) < 0.01  # a hovering robot holds its place
    # the wind's 3 N against the hover servo's drag: it drifts downwind (+X)
    assert drift(dataclasses.replace(test_world, name="WindyField")) > 0.01


def _p2at_with(item_type: str, name: str, **params):
    from usarsim.config.catalog import resolve_robot
    from usarsim.config.robot import MountedItem

    p2at = resolve_robot("P2AT")
    return dataclasses.replace(p2at, items=(*p2at.items, MountedItem(item_type=item_type, name=name, params=params)))


def test_the_sensor_example_reports_the_pose_at_its_rate_within_its_noise(doc_plugins, test_world):
    from usarsim.protocol.messages import format_message
    from usarsim.protocol.outputs import message_for
    from usarsim.sim.simulation import Simulation

    sim = Simulation(test_world, seed=1)
    sim.spawn(1, _p2at_with("Tracker", "Mocap", Sigma=0.002), "R", (-6.0, 0.0, -0.3), (0.0, 0.0, 0.0))
    sim.take_outputs()
    sim.advance(1.0)
    seen = [o for o in sim.take_outputs() if o.key == "SEN:Tracker:Mocap"]
    assert len(seen) == 21  # 20 Hz: at 0, 0.05, ..., 1.0 s
    (x, y, z), _ = sim.pose_of(1)
    last = seen[-1].value
    assert all(abs(a - b) <= 0.002 + 1e-9 for a, b in zip(last.location, (x, y, z)))
    assert last.location != (x, y, z)  # with its noise
    line = format_message(message_for(last, seen[-1].time))
    assert line.startswith("SEN {Time 1.0000} {Type Tracker} {Name Mocap} {Location ")


def test_the_effecter_example_pans_the_camera_towards_a_point(doc_plugins, test_world):
    from usarsim.readings import ItemParams
    from usarsim.sim.simulation import Simulation

    sim = Simulation(test_world, seed=1)
    sim.spawn(1, _p2at_with("LookAt", "Aim"), "R", (-6.0, 0.0, -0.3), (0.0, 0.0, 0.0))
    sim.advance(0.5)
    # a point ahead and to the right (Y right): the camera pans right, a positive angle
    res = sim.operate(1, "LookAt", "Aim", "Aim", ItemParams(values=(-5.0, 0.5), text="-5,0.5"))
    assert res.ok
    sim.advance(4.0)  # the pan joint turns at 0.17 rad/s
    r = sim.robots[1]
    pan = float(sim.data.qpos[r.handle.joint_qpos["CameraPanTilt_Link1"]])
    (x, y, _), (_, _, yaw) = sim.pose_of(1)
    assert pan == pytest.approx(math.atan2(0.5 - y, -5.0 - x) - yaw, abs=0.02) and pan > 0.3
    assert not sim.operate(1, "LookAt", "Aim", "Aim", ItemParams(values=(1.0,), text="1")).ok


def test_the_radio_example_cuts_links_beyond_its_range(doc_plugins, test_world):
    from usarsim.sim.radio import resolve_model

    model = resolve_model(test_world.wireless, model="disc")
    assert type(model).__name__ == "Disc" and not model.counts_walls
    assert model.holds(model.signal_dbm(14.9)) and not model.holds(model.signal_dbm(15.1))


def test_the_element_example_lays_cones_the_world_holds_as_solids_and_landmarks(doc_plugins, tmp_path):
    from helpers import TEST_WORLD
    from usarsim.config.world_file import load_world

    p = tmp_path / "Coned.yaml"
    p.write_text(TEST_WORLD + "cones:\n  - {name: C1, location: [1.0, 2.0, 0.0]}\n")
    w = load_world(p)
    (body,) = [o for o in w.objects if o.name == "cones/C1/body"]
    assert body.shape == "cylinder" and body.center == (1.0, 2.0, -0.25)
    assert [(lm.name, lm.class_name) for lm in w.landmarks] == [("C1", "Cone")]
    assert w.solid_at((1.0, 2.0, -0.25), movable=False) == "cylinder 'cones/C1/body'"  # a robot may not start in it
