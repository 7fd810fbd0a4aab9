"""Experiments at scale: sweeps of simulator runs on Ray, their results, their report.

* :mod:`usarsim.sweep.experiment` reads an experiment file (a grid and/or a list over
  worlds, seeds, teams, wireless models, durations, clocks and controllers) into runs;
* :mod:`usarsim.sweep.runner` runs each as a Ray task with a simulator of its own
  (``usarsim sweep``);
* :mod:`usarsim.sweep.results` keeps one row per run in Parquet and CSV, keyed by the hash
  of the run's configuration;
* :mod:`usarsim.sweep.report` summarizes them: table, plots, one HTML page (``usarsim report``).

See docs/experiments.md.
"""

from __future__ import annotations

from usarsim.sweep.experiment import Experiment, Run, load_experiment

__all__ = ["Experiment", "Run", "load_experiment"]
