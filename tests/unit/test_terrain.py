"""Where a ground robot can drive (usarsim.maps.terrain): up a ramp onto the platform it leads
to, under a table, not over a box's side or through a wall."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from usarsim.config.world import StaticObject, Victim
from usarsim.config.world_file import load_world
from usarsim.maps.grid import Solid, floor_grid, to_map_frame
from usarsim.maps.terrain import clear_cells, ground_and_ceiling
from usarsim.maps.truth import connected_to

WORLD = """\
name: terrain
floor: {center: [0.0, 0.0], size: [10.0, 6.0]}
objects:
  # a 0.3 m platform (x 1 .. 3) with a 10-degree ramp up to its west side (x -0.7 .. 1)
  - {name: platform, shape: box, center: [2.0, 0.0, -0.15], size: [2.0, 2.0, 0.3]}
  - {name: ramp, shape: ramp, foot: [-0.7, 0.0, 0.0], heading: 0.0, length: 1.7, width: 1.2, rise: 0.3}
  # a table: its top 0.7 m up, on four legs
  - {name: top, shape: box, center: [-3.0, 0.0, -0.72], size: [1.0, 1.2, 0.04]}
  - {name: leg1, shape: box, center: [-3.45, -0.55, -0.35], size: [0.04, 0.04, 0.7]}
  - {name: leg2, shape: box, center: [-2.55, -0.55, -0.35], size: [0.04, 0.04, 0.7]}
  - {name: leg3, shape: box, center: [-3.45, 0.55, -0.35], size: [0.04, 0.04, 0.7]}
  - {name: leg4, shape: box, center: [-2.55, 0.55, -0.35], size: [0.04, 0.04, 0.7]}
  # a 0.15 m box
  - {name: box, shape: box, center: [-1.5, 2.0, -0.075], size: [0.8, 0.8, 0.15]}
start_poses:
  - {name: S, location: [-4.5, -2.0, -0.25]}
"""


def _world(tmp_path, drop=()):
    import yaml

    data = yaml.safe_load(WORLD)
    data["objects"] = [o for o in data["objects"] if o["name"] not in drop]
    p = tmp_path / "terrain.yaml"
    p.write_text(yaml.safe_dump(data))
    return load_world(p)


def _at(grid, values, x, y):
    rows, cols, inside = grid.cell_of(np.array([to_map_frame(x, y)]))
    assert inside[0]
    return values[rows[0], cols[0]]


def test_the_ground_is_the_top_of_what_a_robot_cannot_pass_under(tmp_path):
    w = _world(tmp_path)
    grid = floor_grid(w, 0.05)
    ground, ceiling = ground_and_ceiling(grid, [Solid.of(o) for o in w.objects])
    assert _at(grid, ground, -4.5, 0.0) == 0.0 and _at(grid, ceiling, -4.5, 0.0) == np.inf  # bare floor
    assert _at(grid, ground, 2.0, 0.0) == pytest.approx(0.3, abs=0.01)  # on the platform
    assert 0.1 < _at(grid, ground, 0.4, 0.0) < 0.25  # half way up the ramp, on its plate
    assert _at(grid, ground, -3.0, 0.0) == 0.0  # under the table ...
    assert _at(grid, ceiling, -3.0, 0.0) == pytest.approx(0.70, abs=0.01)  # ... its top 0.7 m up
    assert _at(grid, ground, -1.5, 2.0) == pytest.approx(0.15, abs=0.01)  # on the box


def test_a_robot_drives_up_the_ramp_onto_the_platform_and_under_the_table_not_onto_the_box(tmp_path):
    w = _world(tmp_path)
    grid = floor_grid(w, 0.05)
    clear = clear_cells(grid, [Solid.of(o) for o in w.objects], 0.25)
    reach = connected_to(clear, [to_map_frame(-4.5, -2.0)], grid)
    assert _at(grid, reach, 2.2, 0.0)  # the platform, by the ramp
    assert _at(grid, reach, -3.0, 0.0)  # under the table
    assert not _at(grid, reach, -1.5, 2.0)  # the box's 0.15 m side is a step, not a slope
    # without the ramp the platform is out of reach
    w2 = _world(tmp_path, drop=("ramp",))
    g2 = floor_grid(w2, 0.05)
    reach2 = connected_to(clear_cells(g2, [Solid.of(o) for o in w2.objects], 0.25), [to_map_frame(-4.5, -2.0)], g2)
    assert not _at(g2, reach2, 2.2, 0.0)
    # a wall across the room cuts it in two
    wall = StaticObject(name="wall", shape="box", center=(0.0, 0.0, -0.6), size=(0.1, 6.0, 1.2))
    g3 = floor_grid(w, 0.05)
    reach3 = connected_to(clear_cells(g3, [Solid.of(wall)], 0.25), [to_map_frame(-4.0, 0.0)], g3)
    assert _at(g3, reach3, -1.0, 0.0) and not _at(g3, reach3, 1.0, 0.0)
    # the world checks agree: a victim on the platform is reachable by the ramp, not without it
    from usarsim.maps.variation import check_arena

    assert check_arena(dataclasses.replace(w, victims=(Victim(name="V", location=(2.2, 0.0, -0.4)),))) == []
    assert (
        "cannot be reached"
        in check_arena(dataclasses.replace(w2, victims=(Victim(name="V", location=(2.2, 0.0, -0.4)),)))[0]
    )
