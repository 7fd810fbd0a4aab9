"""``usarsim bench``: how fast the simulator runs, measured the way a user runs it.

* :mod:`~usarsim.bench.rtf`: the real-time factor with N driven P2ATs beside bare
  ``mj_step`` on the same model, and the simulator's memory (``--robots N``);
  :mod:`~usarsim.bench.profile`: where the time goes (``--profile``);
  :mod:`~usarsim.bench.record`: what a recording costs (``--record``);
  :mod:`~usarsim.bench.command` picks the measurement and prints it;
* :mod:`~usarsim.bench.cameras`: frames a second through the image server (``--cameras``);
* :mod:`~usarsim.bench.roundtrips`: lock-step STEP/STEPPED round trips (``--round-trips``);
* :mod:`~usarsim.bench.spots` places the robots; :mod:`~usarsim.bench.clients` are the
  clients each run in a process of its own (``python -m usarsim.bench``);
  :mod:`~usarsim.bench.serving` is what the benchmarks share.

The learning environments' benchmark (``--env``) is :mod:`usarsim.envs.bench`.
"""

from __future__ import annotations

from usarsim.bench.cameras import run_camera_bench
from usarsim.bench.command import run_bench
from usarsim.bench.roundtrips import run_round_trip_bench
from usarsim.bench.rtf import measure_rtf, raw_mujoco_rtf, raw_mujoco_rtf_over
from usarsim.bench.spots import Spot, free_spots, spread_spots

__all__ = [
    "Spot",
    "free_spots",
    "measure_rtf",
    "raw_mujoco_rtf",
    "raw_mujoco_rtf_over",
    "run_bench",
    "run_camera_bench",
    "run_round_trip_bench",
    "spread_spots",
]
