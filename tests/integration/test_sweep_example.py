"""The sample experiment that ships, examples/explorers.yaml: it loads into the 12 runs the
docs describe, docs/experiments.md shows that very file and its runs (their run ids), and a
run of it scores the same, to the last digit, every time (lock-step, same seed)."""

from __future__ import annotations

import re
from pathlib import Path

from usarsim.sweep.experiment import load_experiment
from usarsim.sweep.runner import execute

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "explorers.yaml"
DOC = ROOT / "docs" / "experiments.md"
SCORES = (
    "score",
    "victims_found",
    "victims_reported",
    "false_reports",
    "area_m2",
    "distance_m",
    "collisions",
    "robots_lost",
    "radio_contact_share",
    "time_s",
    "robots",
)


def test_the_shipped_sample_experiment_loads_into_twelve_runs():
    exp = load_experiment(EXAMPLE)
    assert exp.name == "explorers" and len(exp.runs) == 12
    assert exp.axes == ("world", "controller")
    assert sorted({r.world for r in exp.runs}) == ["DM-USAR_red", "DM-USAR_yellow"]
    assert sorted({r.controller.label for r in exp.runs}) == ["frontier", "wander"]
    assert {r.seed for r in exp.runs} == {1, 2, 3}
    assert {(r.duration_s, r.clock, r.team_label, r.wireless) for r in exp.runs} == {
        (60.0, "lockstep", "P2AT", "world")
    }


def test_the_docs_show_the_shipped_file_and_its_runs():
    doc = DOC.read_text(encoding="utf-8")
    shipped = EXAMPLE.read_text(encoding="utf-8")
    body = "\n".join(line for line in shipped.splitlines() if not line.startswith("#"))
    assert body.strip() in doc  # the experiment file, as it ships
    # the sample outputs were made with it: the dry run lists its runs by their ids
    exp = load_experiment(EXAMPLE)
    listed = re.findall(r"^\s+\d+\s+([0-9a-f]{16})\s", doc, re.M)
    assert len(listed) >= 5 and set(listed) <= {r.run_id for r in exp.runs}
    assert exp.runs[0].run_id in listed and exp.runs[-1].run_id in listed
    assert "usarsim sweep examples/explorers.yaml" in doc


def test_a_run_of_the_sample_scores_the_same_twice():
    run = load_experiment(EXAMPLE).runs[0]  # the frontier explorer in DM-USAR_yellow, seed 1
    first, second = execute(run), execute(run)
    assert first["error"] is None and second["error"] is None
    assert first["area_m2"] > 30.0 and 60.0 <= first["time_s"] <= 60.5
    assert {k: first[k] for k in SCORES} == {k: second[k] for k in SCORES}
