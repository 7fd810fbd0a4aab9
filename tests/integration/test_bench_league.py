"""usarsim bench --league: the league's robot and a short run of its load."""

from __future__ import annotations

import json
import math
import subprocess
import sys

from usarsim.bench.league import LASER_BEAMS, LEAGUE_CLASS, league_robot_file
from usarsim.config.robot import load_robot


def test_the_league_robot_has_the_leagues_laser_and_a_thermal_camera(tmp_path):
    from usarsim.sensors.base import make_item

    robot = load_robot(league_robot_file(tmp_path))
    assert robot.class_name == LEAGUE_CLASS
    items = {i.name: make_item(i, robot, 0, "r") for i in robot.items}
    laser = items["Scanner1"]
    assert laser.config.beam_count == LASER_BEAMS and laser.config.scan_interval_s == 1.0 / 30.0
    assert laser.config.max_range_m == 30.0
    thermal = items["Thermal"]
    assert type(thermal).__name__ == "ThermalCamera" and (thermal.config.width_px, thermal.config.height_px) == (
        160,
        120,
    )
    assert {"Camera", "VictSensor", "GPS", "RFID", "Odometry"} <= set(items)  # the rest of the kit


def test_a_short_league_run_reports_every_camera_and_laser():
    out = subprocess.run(
        [sys.executable, "-m", "usarsim", "bench", "--league", "--seconds", "3", "--runs", "1", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    (run,) = json.loads(out.stdout.strip().splitlines()[-1])
    assert run["robots"] == 4 and 0.5 < run["rtf"] < 1.1  # real time, or near it
    assert len(run["colour_fps"]) == len(run["thermal_fps"]) == len(run["laser_hz"]) == 4
    assert all(f > 0 for f in run["colour_fps"] + run["thermal_fps"])  # every camera delivered pictures
    assert all(math.isclose(h, 30.0, rel_tol=0.2) for h in run["laser_hz"])  # 30 sweeps a second
    assert isinstance(run["at_rate"], bool) and LASER_BEAMS == 1040


def test_antialias_0_draws_without_multisampling_the_same_scene(test_world):
    """serve --antialias 0: the model's offsamples, and a picture that differs from the
    multisampled one only along edges."""
    import numpy as np

    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.render import camera_renderer
    from usarsim.sim.settings import SimSettings
    from usarsim.sim.simulation import Simulation

    pictures = []
    for samples in (4, 0):
        sim = Simulation(test_world, seed=1, settings=SimSettings(antialias=samples))
        sim.spawn(1, resolve_robot("P2AT"), "R", (-6.0, 0.0, -0.3), (0.0, 0.0, 0.0))
        sim.advance(0.3)
        assert sim.model.vis.quality.offsamples == samples
        r = camera_renderer(sim.model, 160, 120, False)
        r.update_scene(sim.data, camera=next(c.cam_id for c in sim.cameras.render_snapshot(None).cameras.values()))
        pictures.append(r.render())
        r.close()
    differ = (pictures[0] != pictures[1]).any(axis=2).mean()
    assert 0.0 < differ < 0.2 and np.abs(pictures[0].mean() - pictures[1].mean()) < 5.0
