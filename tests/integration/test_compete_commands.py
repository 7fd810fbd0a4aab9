"""A competition's teams as commands (``usarsim compete``): a program hands its map in at
``{map}`` and scores it, a program that fails is a failed run that scores 0, and the command
says so (exit 1)."""

from __future__ import annotations

import csv
import subprocess
import sys

HANDIN = '''\
"""A team's program: drives the clock, hands in the ground truth as its map, exits."""
import sys
from usarsim.client import connect
from usarsim.maps.grid import OccupancyMap
from usarsim.maps.mapfile import write_map
host, port, path, truth_port, seconds = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4]), float(sys.argv[5])
with connect(host, port, lockstep=True, truth_port=truth_port) as world:
    world.spawn("P2AT", "R1", start="PlayerStart1")
    world.step(seconds)
    g = world.ground_truth_map()
    write_map(path, OccupancyMap(g.resolution, g.origin, g.data.copy()), victims=[("V", 0.0, 0.0)])
'''

COMPETITION = f"""\
name: cmdcup
scenarios: {{worlds: [DM-USAR_yellow], variants: 1, seeds: [1]}}
duration: 3
teams:
  - name: mapper
    controller: {{command: "{sys.executable} handin.py {{host}} {{port}} {{map}} {{truth_port}} {{seconds}}"}}
  - name: broken
    controller: {{command: "{sys.executable} -c 'import sys; sys.exit(3)'"}}
"""


def test_command_teams_hand_their_maps_in_and_a_failing_one_fails(tmp_path):
    (tmp_path / "handin.py").write_text(HANDIN)
    (tmp_path / "cup.yaml").write_text(COMPETITION)
    out = subprocess.run(
        [sys.executable, "-m", "usarsim", "compete", "cup.yaml", "--workers", "1", "--no-progress"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert out.returncode == 1, out.stdout[-2000:] + out.stderr[-2000:]
    assert "(broken, DM-USAR_yellow, seed 1) failed: the controller exited with code 3" in out.stderr
    with open(tmp_path / "results" / "cmdcup" / "leaderboard.csv", newline="") as f:
        board = {r["team"]: r for r in csv.DictReader(f)}
    mapper, broken = board["mapper"], board["broken"]
    assert mapper["rank"] == "1" and float(mapper["map_coverage"]) > 0.99 and float(mapper["map_accuracy"]) > 0.99
    assert float(mapper["total"]) >= 100.0  # the map's 100 points, at least
    assert broken["failed"] == "1" and float(broken["total"]) == 0.0 and broken["map_coverage"] == ""
    maps = tmp_path / "results" / "cmdcup" / "maps"
    assert len(list(maps.glob("*.yaml"))) == 1 and len(list(maps.glob("*.png"))) == 3  # 2 runs + the truth
