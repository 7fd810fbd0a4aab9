"""Victims of several builds and postures (world files' ``build`` and ``posture``): a child is
smaller and a heavy adult broader than the average body, each part where its build puts it; a
trapped victim lies under a slab and a board that lasers see and that lie on its legs and hips,
and its face is still there for cameras."""

from __future__ import annotations

import numpy as np
import pytest

WORLD = """\
name: Bodies
description: victims of every build, and a trapped one (tests only)
floor: {center: [0.0, 0.0], size: [20.0, 20.0]}
victims:
  - {name: Avery, location: [0.0, -4.0, -0.1], build: average}
  - {name: Kid, location: [0.0, -2.0, -0.1], build: child}
  - {name: Big, location: [0.0, 0.0, -0.1], build: heavy}
  - {name: Thin, location: [0.0, 2.0, -0.1], build: slim, posture: sitting}
  - {name: Stuck, location: [0.0, 4.0, -0.1], posture: trapped}
start_poses:
  - {name: S, location: [-5.0, 0.0, -0.3]}
"""


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    from usarsim.config.world_file import load_world
    from usarsim.sim.simulation import Simulation

    p = tmp_path_factory.mktemp("bodies") / "Bodies.yaml"
    p.write_text(WORLD)
    s = Simulation(load_world(p))
    s.advance(0.1)
    return s


def geom(sim, name: str):
    return sim.model.geom(name)


def test_builds_scale_the_body_along_and_across(sim):
    from usarsim.sim.victims import BUILDS

    avg_head = geom(sim, "victim/Avery/Head/0").size[0]
    assert avg_head == pytest.approx(0.10)
    assert geom(sim, "victim/Kid/Head/0").size[0] == pytest.approx(0.10 * BUILDS["child"][1])
    # the child's head lies nearer its pelvis: the body is shorter
    kid_head_x = float(sim.data.geom_xpos[geom(sim, "victim/Kid/Head/0").id][0])
    avg_head_x = float(sim.data.geom_xpos[geom(sim, "victim/Avery/Head/0").id][0])
    assert kid_head_x == pytest.approx(0.78 * BUILDS["child"][0], abs=1e-6)
    assert avg_head_x == pytest.approx(0.78, abs=1e-6)
    # the heavy chest is broader, as long
    big, avg = geom(sim, "victim/Big/Chest/1").size, geom(sim, "victim/Avery/Chest/1").size
    assert big[0] == pytest.approx(avg[0]) and big[1] == pytest.approx(1.3 * avg[1])
    # every victim has its face, as big as its head allows
    for name in ("Avery", "Kid", "Big", "Thin", "Stuck"):
        assert geom(sim, f"look/victim/{name}/face").size[1] < geom(sim, f"victim/{name}/Head/0").size[0]


def test_a_trapped_victim_lies_under_debris_that_lasers_see(sim):
    slab, board = geom(sim, "debris/Stuck/slab"), geom(sim, "debris/Stuck/board")
    legs = [geom(sim, f"victim/Stuck/Leg/{k}") for k in (7, 8)]
    # the slab lies on the legs: its bottom just above their top (MuJoCo's Z is up)
    slab_bottom = float(sim.data.geom_xpos[slab.id][2]) - slab.size[2]
    legs_top = max(float(sim.data.geom_xpos[g.id][2]) + g.size[0] for g in legs)
    assert 0.0 < slab_bottom - legs_top < 0.12
    # a laser looking straight down at the legs meets the slab first (the board over the hips too)
    view = sim.view()
    for g in (slab, board):
        x, y, _ = sim.data.geom_xpos[g.id]
        dist, _, gid = view.caster.cast(np.array([x, y, 2.0]), np.array([[0.0, 0.0, -1.0]]), 5.0, -1, kind="laser")
        assert int(gid[0]) == g.id
    # the other victims lie in the open
    assert sim.model.geom("look/victim/Stuck/face") is not None
    with pytest.raises(KeyError):
        sim.model.geom("debris/Avery/slab")
