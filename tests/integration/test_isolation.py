"""Isolated controllers (docs/experiments.md, "Isolation"): with ``isolate: true`` each robot's
controller runs in a network and mount namespace of its own, reaching the simulator's control
and wireless ports and nothing else."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from usarsim.errors import ConfigError
from usarsim.sweep.experiment import load_experiment
from usarsim.sweep.isolation import isolation_problem

# Each controller: the control port answers; the ground truth does not; it binds the same
# loopback port as its teammate (possible only in a namespace of its own) and holds it until
# both have; its /dev/shm holds its own mark only.
PROBE = """\
import json, os, socket, sys, time
host, port, truth, wcs, name = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
out = {}
with socket.create_connection((host, port), timeout=10) as s:
    s.sendall(b"GETSTARTPOSES\\r\\n")
    s.settimeout(10)
    out["control"] = s.recv(4096).decode("ascii", "replace")[:4]
with socket.create_connection((host, wcs), timeout=10):
    out["comserver"] = "reached"
try:
    socket.create_connection((host, truth), timeout=3).close()
    out["truth"] = "reached"
except OSError as exc:
    out["truth"] = type(exc).__name__
srv = socket.socket()
try:
    srv.bind(("127.0.0.1", 47001))
    srv.listen()
    out["bound"] = True
except OSError:
    out["bound"] = False
open(f"/dev/shm/mark-{name}", "w").write(name)
open(f"bound-{name}", "w").write("1")
deadline = time.monotonic() + 20
while len([f for f in os.listdir(".") if f.startswith("bound-")]) < 2 and time.monotonic() < deadline:
    time.sleep(0.05)
out["shm"] = sorted(f for f in os.listdir("/dev/shm") if f.startswith("mark-"))
json.dump(out, open(f"result-{name}.json", "w"))
"""


def experiment(folder: Path, clock: str = "max", controller: str | None = None) -> Path:
    (folder / "probe.py").write_text(PROBE, encoding="utf-8")
    command = f"{sys.executable} probe.py {{host}} {{port}} {{truth_port}} {{wcs_port}} {{name}}"
    controller = controller or f'{{command: "{command}", isolate: true}}'
    path = folder / "isolated.yaml"
    path.write_text(
        f"name: isolated\nseeds: [1]\nworld: DM-USAR_yellow\nteam: [{{robot: P2AT, count: 2}}]\n"
        f"duration: 3600\nclock: {clock}\ncontroller: {controller}\n",
        encoding="utf-8",
    )
    return path


def test_isolated_controllers_reach_the_simulator_and_not_each_other(tmp_path):
    problem = isolation_problem()
    if problem is not None:
        pytest.skip(problem)
    from usarsim.sweep.worker import execute

    (run,) = load_experiment(experiment(tmp_path)).runs
    assert run.controller.isolate
    row = execute(run)
    assert row["error"] is None, row["error"]
    names = [m.name for m in run.team]
    assert len(names) == 2
    for name in names:
        out = json.loads((tmp_path / f"result-{name}.json").read_text())
        assert out["control"] == "NFO "  # the simulator's answer
        assert out["comserver"] == "reached"
        assert out["truth"] == "ConnectionRefusedError"  # not relayed into the namespace
        assert out["bound"] is True  # both bound 127.0.0.1:47001: two loopbacks
        assert out["shm"] == [f"mark-{name}"]  # shared memory of its own


def test_the_documented_isolated_wanderers_drive_and_are_scored(tmp_path):
    problem = isolation_problem()
    if problem is not None:
        pytest.skip(problem)
    from usarsim.sweep.worker import execute

    command = (
        f"{sys.executable} -m usarsim.brains.wander --host {{host}} --port {{port}} --robot {{robot}} "
        "--name {name} --start {start} --seconds {seconds}"
    )
    path = experiment(tmp_path, controller=f'{{command: "{command}", isolate: true}}')
    path.write_text(path.read_text().replace("duration: 3600", "duration: 10"))
    (run,) = load_experiment(path).runs
    row = execute(run)
    assert row["error"] is None, row["error"]
    robots = json.loads(row["robots"])
    assert sorted(robots) == ["R1", "R2"]  # each controller spawned its own robot
    assert all(r["distance_m"] > 0.5 for r in robots.values())  # and drove it


def test_isolation_is_refused_in_lockstep_and_for_brains(tmp_path):
    with pytest.raises(ConfigError, match="isolated controllers need 'clock: max'"):
        load_experiment(experiment(tmp_path, clock="lockstep"))
    with pytest.raises(ConfigError, match="isolation runs commands, one per robot"):
        load_experiment(experiment(tmp_path, controller="{brain: usarsim.brains.wander:Wander, isolate: true}"))


def test_the_launcher_refuses_to_run_outside_a_namespace_of_its_own(tmp_path):
    import subprocess

    from usarsim.sweep.isolated import namespaces

    out = subprocess.run(
        [sys.executable, "-m", "usarsim.sweep.isolated", "--dir", str(tmp_path), "--ports", "3000"]
        + ["--outside", namespaces(), "--", "true"],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert out.returncode == 2 and "would change the machine's /dev/shm" in out.stderr
