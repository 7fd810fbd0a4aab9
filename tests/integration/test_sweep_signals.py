"""An interrupted ``usarsim sweep`` (a real one: the command in a process of its own, a local
Ray, real simulators): stopped by SIGTERM (``kill``) or by SIGINT sent to its whole process
group (Ctrl-C at a terminal), it stores the runs that finished, says so in one line on stderr
(no traceback, no native stack dump) and exits with 143 or 130; run again, it goes on where it
stopped and exits 0 when every run is done."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from usarsim.sweep.experiment import load_experiment
from usarsim.sweep.results import PARQUET, read_rows

pytest.importorskip("ray")

RUNS = 16  # enough that the sweep is far from done when it is stopped, twice
EXPERIMENT = f"""\
name: stopped
seeds: {RUNS}
team: P2AT
duration: 3
clock: lockstep
controller: usarsim.brains.wander:Wander
"""
STOPPED = re.compile(
    r"^usarsim: sweep stopped by (SIG\w+): (\d+) of (\d+) runs done and stored in (.+) \((\d+) "
    r"finished now, (\d+) failed\); run the same command again to run the other (\d+)$"
)


def start(path: Path, out: Path, *, sigint_ignored: bool = False) -> subprocess.Popen:
    """``usarsim sweep`` in a session of its own: a signal to its group reaches the sweep, its
    Ray and its simulators, as Ctrl-C at a terminal does.  ``sigint_ignored``: started with
    SIGINT ignored, as a script's background job is."""
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    signals = signal.SIG_IGN if sigint_ignored else signal.SIG_DFL
    return subprocess.Popen(
        [sys.executable, "-m", "usarsim", "sweep", str(path), "--out", str(out), "--workers", "2", "--no-progress"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signals),
    )


def done_rows(out: Path) -> int:
    try:
        return sum(1 for r in read_rows(out) if not r.get("error"))
    except Exception:  # not written yet (or being replaced)
        return 0


def wait_for_rows(proc: subprocess.Popen, out: Path, at_least: int, timeout: float = 120.0) -> None:
    """Until ``out`` holds ``at_least`` successful rows (the first row of a sweep is stored at
    once, the others at most every 2 s), the sweep still running."""
    deadline = time.monotonic() + timeout
    while done_rows(out) < at_least:
        assert proc.poll() is None, f"the sweep ended early ({proc.returncode}): {proc.communicate()}"
        assert time.monotonic() < deadline, f"no {at_least} runs stored in {timeout:g} s"
        time.sleep(0.1)
    assert proc.poll() is None and done_rows(out) < RUNS


def stopped_line(stderr: str) -> re.Match:
    """The one line an interrupted sweep writes on stderr, and nothing else."""
    assert "Traceback" not in stderr and "SIGTERM received" not in stderr and "logging.cc" not in stderr, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    m = STOPPED.match(lines[0])
    assert m, lines[0]
    return m


def test_an_interrupted_sweep_stores_what_finished_exits_non_zero_and_goes_on_next_time(tmp_path):
    path = tmp_path / "stopped.yaml"
    path.write_text(EXPERIMENT, encoding="utf-8")
    ids = {r.run_id for r in load_experiment(path).runs}
    assert len(ids) == RUNS
    out = tmp_path / "results"

    # SIGTERM (kill PID) once a run is stored: 143, one line, the runs that finished stored
    proc = start(path, out)
    wait_for_rows(proc, out, 1)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM == 143
    m = stopped_line(err)
    first = int(m[2])
    assert m[1] == "SIGTERM" and first >= 1 and int(m[3]) == RUNS and m[4] == str(out)
    assert int(m[7]) == RUNS - first
    stored = [r for r in read_rows(out) if not r.get("error")]
    assert len(stored) == first < RUNS and {r["run_id"] for r in stored} <= ids
    assert all(r["area_m2"] > 0.0 and 3.0 <= r["time_s"] <= 3.5 for r in stored)

    # again, started with SIGINT ignored (a script's background job); SIGINT to the whole
    # process group (as Ctrl-C sends) once it stored a run more: it stops all the same, 130
    proc = start(path, out, sigint_ignored=True)
    wait_for_rows(proc, out, first + 1)
    os.killpg(proc.pid, signal.SIGINT)
    outs, err = proc.communicate(timeout=60)
    assert f"{RUNS} runs, {first} done already, {RUNS - first} to run" in outs  # it went on from there
    assert proc.returncode == 128 + signal.SIGINT == 130
    m = stopped_line(err)
    second = int(m[2])
    assert m[1] == "SIGINT" and first + 1 <= second < RUNS and int(m[5]) == second - first
    assert done_rows(out) == second

    # and once more, to the end: only the missing runs run, exit 0
    proc = start(path, out)
    outs, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert f"{RUNS - second} runs in" in outs and f"{second} skipped as done" in outs
    rows = read_rows(out)
    assert sorted(r["run_id"] for r in rows) == sorted(ids)  # each run once
    assert all(r["error"] is None for r in rows)
    assert (out / PARQUET).exists() and (out / "results.csv").exists()
