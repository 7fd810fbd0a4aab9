"""A served variant and its ground-truth map, the way users reach them: ``{Map}`` on the
ground-truth service, the recording's /usarsim/map, a team's map handed in through
``serve --team-map`` and scored into the score file, the environments' variants and a sweep's
``variant`` run parameter."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from usarsim.client import launch
from usarsim.maps.grid import OccupancyMap
from usarsim.maps.mapfile import write_map
from usarsim.maps.truth import ground_truth_map
from usarsim.maps.variation import load_arena


@pytest.fixture(scope="module")
def truth17():
    return ground_truth_map(load_arena("DM-USAR_yellow", 17), variant=17)


@pytest.mark.parametrize("transport", ["tcp", "inproc"])
def test_a_served_variant_and_its_map_on_the_ground_truth_service(truth17, transport):
    arena = load_arena("DM-USAR_yellow", 17)
    with launch("DM-USAR_yellow", variant=17, transport=transport) as srv, srv.connect() as world:
        victims = {o.name: o.location[:2] for o in world.truth(class_name="Victim")}
        for v in arena.victims:  # the victims stand where the variant put them
            assert math.dist(victims[v.name], v.location[:2]) < 1e-3
        g = world.ground_truth_map()
        assert (g.world, g.variant, g.resolution, g.sensing_height) == ("DM-USAR_yellow", 17, 0.05, 0.3)
        assert g.origin == truth17.grid.origin
        assert np.array_equal(g.data, truth17.grid.data)
        coarse = world.ground_truth_map(resolution=0.2, height=0.1)
        assert coarse.data.shape == (110, 140)


def test_the_recording_holds_the_ground_truth_map(tmp_path, truth17):
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    path = tmp_path / "run.mcap"
    with launch("DM-USAR_yellow", variant=17, record=path) as srv, srv.connect() as world:
        world.step(0.2)
    with open(path, "rb") as f:
        grids = [
            proto
            for _, _, _, proto in make_reader(f, decoder_factories=[DecoderFactory()]).iter_decoded_messages(
                topics=["/usarsim/map"]
            )
        ]
    assert len(grids) == 1
    grid = grids[0]
    assert grid.column_count == 560 and grid.cell_size.x == pytest.approx(0.05)
    assert (grid.pose.position.x, grid.pose.position.y) == truth17.grid.origin
    data = np.frombuffer(grid.data, np.int8).reshape(-1, grid.column_count)
    assert np.array_equal(data, truth17.grid.data)


def test_a_team_map_handed_in_is_scored_into_the_score_file(tmp_path, truth17):
    """The controller writes its map where serve --team-map says; the score file gets "map"."""
    team_map, score = tmp_path / "team.yaml", tmp_path / "score.json"
    # the team's map: the ground truth with its west half unknown, 5 cm cells
    g = truth17.grid.copy()
    g.data[:, : g.shape[1] // 2] = -1
    args = ("--score-file", str(score), "--team-map", str(team_map))
    with launch("DM-USAR_yellow", variant=17, extra_args=args) as srv, srv.connect() as world:
        world.step(0.5)
        write_map(team_map, OccupancyMap(g.resolution, g.origin, g.data), victims=[("V", *_victim(truth17, 0))])
    m = json.loads(score.read_text())["map"]
    assert 0.3 < m["coverage"] < 0.8  # half the floor's columns
    assert m["accuracy"] > 0.99 and m["victims_on_map"] == 1 and m["victims_total"] == 3
    # no map handed in: the score says so
    score2 = tmp_path / "score2.json"
    args = ("--score-file", str(score2), "--team-map", str(tmp_path / "none.yaml"))
    with launch("DM-USAR_yellow", extra_args=args) as srv, srv.connect() as world:
        world.step(0.2)
    assert "no map was handed in" in json.loads(score2.read_text())["map"]["error"]


def _victim(truth, i: int) -> tuple[float, float]:
    v = truth.victims()[i]
    return (v.x + 0.3, v.y - 0.2)


def test_environments_play_variants_by_seed():
    from usarsim.envs import ExploreEnv

    env = ExploreEnv(transport="inproc", variants=range(800, 1000), time_limit_s=5.0)
    try:
        seen = []
        for seed in (1, 2, 1):
            _, info = env.reset(seed=seed)
            assert 800 <= info["variant"] < 1000
            assert env.sim.world is not None
            seen.append(
                (info["variant"], sorted((o.name, o.location[:2]) for o in env.sim.world.truth(class_name="Victim")))
            )
        assert seen[0] == seen[2]  # the same seed, the same variant and arena
        assert seen[0][0] != seen[1][0] and seen[0][1] != seen[1][1]
        with pytest.raises(ValueError, match="variants"):
            ExploreEnv(transport="inproc", variants=[-1])
    finally:
        env.close()


def test_a_sweep_takes_a_variant(tmp_path):
    from usarsim.errors import ConfigError
    from usarsim.sweep.experiment import load_experiment

    p = tmp_path / "exp.yaml"
    p.write_text("name: v\nduration: 1\ngrid:\n  variant: [null, 3, 4]\n")
    runs = load_experiment(p).runs
    assert [r.variant for r in runs] == [None, 3, 4]
    assert len({r.run_id for r in runs}) == 3 and runs[1].columns()["variant"] == 3
    p.write_text("name: v\nvariant: -2\n")
    with pytest.raises(ConfigError, match="variant"):
        load_experiment(p)
