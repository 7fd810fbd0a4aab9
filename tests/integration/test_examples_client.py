"""The examples written on the client library run as a newcomer would run them."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def run(name: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(EXAMPLES / name), *args], capture_output=True, text=True,
                          timeout=180, stdin=subprocess.DEVNULL)


def test_client_drive_drives_and_reports_its_odometry():
    out = run("client_drive.py", "--seconds", "25")
    assert out.returncode == 0, out.stderr
    last = out.stdout.strip().splitlines()[-1]
    m = re.fullmatch(r"t= 25\.0 s: odometry (-?\d+\.\d\d), (-?\d+\.\d\d) m, heading -?\d+\.\d\d rad", last)
    assert m, out.stdout
    assert float(m.group(1)) > 3.0  # it drove into the arena


def test_gym_explore_runs_an_episode():
    out = run("gym_explore.py", "--steps", "30")
    assert out.returncode == 0, out.stderr
    assert re.match(r"return -?\d+\.\d over 30 steps; info: \{.*'explored_m2'", out.stdout), out.stdout
