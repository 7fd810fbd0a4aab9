"""The examples written on the client library run as a newcomer would run them: on a simulator
of their own, on a running one (real time, or lock-step with --lockstep), and, when there is
no simulator or it runs in the other mode, with one line saying so and exit status 1.  (How
client_drive.py explores for 60 s: tests/integration/test_example_drive.py.)"""

from __future__ import annotations

import re
import socket
import subprocess
import sys
from pathlib import Path

from usarsim.client import launch

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def run(name: str, *args: str, timeout: float = 180) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        stdin=subprocess.DEVNULL,
    )


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def one_line_and_exit_1(out: subprocess.CompletedProcess, line: str) -> None:
    assert out.returncode == 1, out.stderr
    assert "Traceback" not in out.stderr
    assert out.stderr == line + "\n"


def test_client_drive_drives_and_reports_its_odometry():
    out = run("client_drive.py", "--seconds", "25")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert lines[0] == "a P2AT at PlayerStart1 on DM-USAR_yellow, for 25 simulated seconds"
    assert re.fullmatch(r"t=\s*0\.1 s forward 0\.39 m/s \(laser \d+\.\d\d m clear\)", lines[1]), out.stdout
    m = re.fullmatch(r"t= 25\.0 s stopped: odometry (-?\d+\.\d\d), (-?\d+\.\d\d) m, heading -?\d+\.\d\d rad", lines[-1])
    assert m, out.stdout
    assert float(m.group(1)) > 3.0  # it drove into the arena
    # one line per decision, each at a later time than the one before
    times = [float(t) for t in re.findall(r"^t=\s*(\d+\.\d) s ", out.stdout, re.M)]
    assert len(times) >= 3 and times == sorted(times)


def test_client_drive_without_a_server_says_so_in_one_line():
    port = free_port()
    out = run("client_drive.py", "--port", str(port), "--seconds", "5", timeout=60)
    one_line_and_exit_1(
        out,
        f"client_drive: no simulator on 127.0.0.1:{port}: start one with 'usarsim serve' (or bash scripts/serve.sh)",
    )
    assert out.stdout == ""


def test_client_drive_on_a_lockstep_server_needs_lockstep_and_steps_it_with_it():
    with launch(lockstep=True) as srv:
        without = run("client_drive.py", "--port", str(srv.port), "--seconds", "2", timeout=60)
        with_it = run("client_drive.py", "--port", str(srv.port), "--lockstep", "--seconds", "2", timeout=60)
    one_line_and_exit_1(
        without,
        f"client_drive: the simulator on 127.0.0.1:{srv.port} runs in lock-step (usarsim "
        "serve --lockstep): add --lockstep to step its clock from here, or start it without "
        "--lockstep",
    )
    assert with_it.returncode == 0, with_it.stderr
    assert re.search(r"^t=  2\.0 s stopped: odometry 0\.[3-9]\d, ", with_it.stdout, re.M), with_it.stdout  # drove


def test_client_drive_on_a_real_time_server_runs_without_lockstep_and_refuses_it():
    with launch(lockstep=False, speed=1.0) as srv:
        real_time = run("client_drive.py", "--port", str(srv.port), "--seconds", "2", timeout=60)
        stepping = run("client_drive.py", "--port", str(srv.port), "--lockstep", "--seconds", "2", timeout=60)
        both = run("drive_p2at.py", "--port", str(srv.port), "--lockstep", "--seconds", "2", timeout=60)
    assert real_time.returncode == 0, real_time.stderr
    assert re.search(r"^t=\s*2\.\d s stopped: odometry \d\.\d\d, ", real_time.stdout, re.M), real_time.stdout
    one_line_and_exit_1(
        stepping, f"client_drive: the simulator on 127.0.0.1:{srv.port} runs in real time: leave out --lockstep"
    )
    one_line_and_exit_1(
        both,
        f"drive_p2at: the simulator on 127.0.0.1:{srv.port} runs in real time: leave out "
        "--lockstep (it is for a server started with usarsim serve --lockstep)",
    )


def test_gym_explore_runs_an_episode():
    out = run("gym_explore.py", "--steps", "30")
    assert out.returncode == 0, out.stderr
    assert re.match(r"return -?\d+\.\d over 30 steps; info: \{.*'explored_m2'", out.stdout), out.stdout
