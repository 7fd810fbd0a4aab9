"""Arenas varied by seed (usarsim.maps.variation) and their ground-truth maps (usarsim.maps.truth,
usarsim map): two variants differ, both keep the rules, the same variant is the same arena byte
for byte."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from usarsim.config.catalog import resolve_world
from usarsim.config.world_file import load_world
from usarsim.errors import ConfigError
from usarsim.maps.grid import FREE, OCCUPIED, UNKNOWN, to_map_frame
from usarsim.maps.mapfile import read_map, write_map
from usarsim.maps.truth import ground_truth_map
from usarsim.maps.variation import apply_variant, check_arena, load_arena


@pytest.fixture(scope="module")
def yellow():
    return resolve_world("DM-USAR_yellow")


def _places(world):
    return (
        [v.location for v in world.victims],
        [t.location for t in world.rfid_tags],
        [a.center for a in world.false_alarms],
        [o.center for o in world.objects if o.mass_kg > 0],
    )


def test_two_variants_differ_in_victims_and_tags_and_keep_every_rule(yellow):
    a, b = apply_variant(yellow, 3), apply_variant(yellow, 4)
    assert a.variant == 3 and b.variant == 4
    for w in (a, b):
        # the same things, as many and of the same kinds
        assert [v.name for v in w.victims] == [v.name for v in yellow.victims]
        assert [(v.posture, v.build, v.waving) for v in w.victims] == [
            (v.posture, v.build, v.waving) for v in yellow.victims
        ]
        assert sorted(t.tag_id for t in w.rfid_tags) == sorted(t.tag_id for t in yellow.rfid_tags)
        assert len(w.false_alarms) == len(yellow.false_alarms)
        assert check_arena(w) == []  # every victim reachable, nothing inside a solid
        for p in [*(v.location for v in w.victims), *(t.location for t in w.rfid_tags)]:
            assert w.solid_at(p, movable=False) is None
            assert min(math.dist(p[:2], s.location[:2]) for s in w.start_poses) >= 2.0  # start poses kept clear
        for v, u in zip(w.victims, w.victims[1:]):
            assert math.dist(v.location[:2], u.location[:2]) >= 1.5
    va, vb = _places(a), _places(b)
    assert va[0] != vb[0] and va[1] != vb[1]  # victims and tags moved between the variants
    assert va[0] != _places(yellow)[0]  # and away from where the file puts them


def test_the_same_variant_is_the_same_arena_byte_for_byte(yellow, tmp_path):
    one, two = load_arena("DM-USAR_yellow", 17), load_arena("DM-USAR_yellow", 17)
    assert one == two
    paths = []
    for name, w in (("one", one), ("two", two)):
        truth = ground_truth_map(w, variant=17)
        paths.append(
            write_map(tmp_path / name / "map.yaml", truth.grid, victims=[(m.name, m.x, m.y) for m in truth.victims()])
        )
    assert paths[0].read_bytes() == paths[1].read_bytes()
    assert paths[0].with_suffix(".pgm").read_bytes() == paths[1].with_suffix(".pgm").read_bytes()
    other = ground_truth_map(load_arena("DM-USAR_yellow", 18), variant=18)
    assert [m for m in other.victims()] != [m for m in ground_truth_map(one).victims()]


def test_no_variant_is_the_world_as_written(yellow):
    assert apply_variant(yellow, None) is yellow
    with pytest.raises(ConfigError, match="whole number"):
        apply_variant(yellow, -1)


@pytest.mark.parametrize("name", ["DM-USAR_orange", "DM-USAR_red", "DM-CollapsedBuilding"])
def test_every_arena_varies_within_the_rules(name):
    w = load_arena(name, 5)
    assert check_arena(w) == []
    assert [v.location for v in w.victims] != [v.location for v in resolve_world(name).victims]


def test_a_doorway_is_closed_only_while_every_room_stays_reachable(yellow):
    """The yellow arena's SE room has one door (the corridor's, corridor_se): no variant closes
    it; the two others close in some variants, never both (the foyer would be cut off)."""
    closed = [{o.name for o in apply_variant(yellow, v).objects if o.name.startswith("door_")} for v in range(24)]
    assert "door_corridor_se" not in set().union(*closed)
    assert any("door_corridor_s" in c for c in closed) and any("door_corridor_sw" in c for c in closed)
    assert not any({"door_corridor_s", "door_corridor_sw"} <= c for c in closed)
    assert any(not c for c in closed)


def test_a_variation_section_is_checked(tmp_path):
    from pathlib import Path

    text = Path(resolve_world("DM-USAR_yellow").path).read_text(encoding="utf-8")
    bad = text.split("\nvariation:")[0] + "\nvariation:\n  spacing: 2.0\n"
    p = tmp_path / "w.yaml"
    p.write_text(bad)
    with pytest.raises(ConfigError, match="spacing"):
        load_world(p)
    p.write_text(text.split("\nvariation:")[0] + "\nvariation:\n  doorways:\n    - {name: d, object: no_such_wall}\n")
    with pytest.raises(ConfigError, match="no_such_wall"):
        load_world(p)
    p.write_text(text.split("\nvariation:")[0] + "\nvariation:\n  region: [0, 0, 0.5, 0.5]\n  start_clearance_m: 0\n")
    with pytest.raises(ConfigError, match="found no place"):
        apply_variant(load_world(p), 1)  # no room for a 1.9 m victim in half a metre


def test_the_ground_truth_map_holds_walls_free_floor_and_markers(yellow, tmp_path):
    truth = ground_truth_map(yellow)
    g = truth.grid
    assert g.resolution == 0.05 and g.shape == (440, 560)

    def state(x, y):  # a USARSim point's cell
        rows, cols, inside = g.cell_of(np.array([to_map_frame(x, y)]))
        assert inside[0]
        return int(g.data[rows[0], cols[0]])

    assert state(6.0, 0.0) == OCCUPIED  # the outer north wall
    assert state(0.0, 0.0) == FREE  # the arena's middle
    assert state(-12.0, 0.0) == FREE  # the staging area
    assert {int(v) for v in np.unique(g.data)} <= {FREE, OCCUPIED, UNKNOWN}
    assert [m.name for m in truth.victims()] == ["Anna", "Ben", "Carl"]
    assert truth.victims()[0].x == pytest.approx(0.4) and truth.victims()[0].y == pytest.approx(-2.2)
    back = read_map(write_map(tmp_path / "m.yaml", g))
    assert np.array_equal(back.grid.data, g.data) and back.grid.origin == g.origin
    some = g.copy()  # unknown, free and occupied cells all read back as they were written
    some.data[:50, :] = UNKNOWN
    back = read_map(write_map(tmp_path / "u.yaml", some))
    assert np.array_equal(back.grid.data, some.data)


def test_usarsim_map_and_validate_a_variant(tmp_path):
    run = [sys.executable, "-m", "usarsim"]
    out = subprocess.run(
        [*run, "map", "DM-USAR_yellow", "--variant", "7", "--out", str(tmp_path / "y7")],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    assert "variant 7" in out.stdout
    for suffix in (".yaml", ".pgm", ".png"):
        assert (tmp_path / f"y7{suffix}").stat().st_size > 0
    m = read_map(tmp_path / "y7.yaml")
    assert m.victims and np.array_equal(m.grid.data, ground_truth_map(load_arena("DM-USAR_yellow", 7)).grid.data)
    for v in ("7", "8"):
        out = subprocess.run(
            [*run, "validate", "DM-USAR_yellow", "--variant", v],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
        assert out.returncode == 0, out.stderr
        assert out.stdout.startswith(f"ok: world DM-USAR_yellow variant {v}: ")
