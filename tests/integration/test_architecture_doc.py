"""The worked examples of docs/architecture.md run as written: each ```python block after an
``<!-- example: NAME -->`` marker is executed once, and then used the way the page says."""

from __future__ import annotations

import dataclasses
import re
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
        ns: dict = {"__name__": f"architecture_doc_{name}"}
        exec(compile(code, f"{DOC}:{name}", "exec"), ns)
        out[name] = ns
    return out


def test_the_page_has_its_worked_examples():
    assert {"drive", "system"} <= set(examples())


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
