"""The ``usarsim`` command as a real process (``python -m usarsim``)."""

from __future__ import annotations

import os
import re
import selectors
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from helpers import Client, sensor_lines

NFO_ON_CONNECT = b"NFO {Gametype BotDeathMatch} {Level DM-USAR_yellow} {TimeLimit 0}\r\n"
LISTENING = re.compile(r"usarsim: control listening on 127\.0\.0\.1:(\d+)")
SHIPPED = Path(__import__("usarsim").__file__).parent / "data"
ROOT = Path(__file__).resolve().parents[2]
# every listener beside the control port, on a free port
PORT_OPTIONS = ("--truth-port", "--image-port", "--wcs-port", "--wss-port", "--cominterface-port", "--web-port")
FREE_PORTS = tuple(x for opt in PORT_OPTIONS for x in (opt, "0"))


def usarsim(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "usarsim", *args], capture_output=True, text=True, timeout=timeout, check=False
    )


class Serve:
    """``python -m usarsim serve ...`` with its stdout read line by line under a deadline."""

    def __init__(self, *args: str, stderr_path: Path, prelude: str = ""):
        """``prelude``: Python run in the server's process before the command (a fault to inject)."""
        self._stderr = open(stderr_path, "wb")
        self.stderr_path = stderr_path
        command = (
            ["-m", "usarsim"]
            if not prelude
            else ["-c", f"{prelude}\nimport sys\nfrom usarsim.cli import main\nsys.exit(main(sys.argv[1:]))"]
        )
        self.proc = subprocess.Popen(
            [sys.executable, *command, "serve", *args],
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            stdin=subprocess.DEVNULL,
        )
        self._sel = selectors.DefaultSelector()
        self._sel.register(self.proc.stdout, selectors.EVENT_READ)
        self._buf = b""

    def read_line(self, timeout: float = 30.0) -> str:
        deadline = time.monotonic() + timeout
        while b"\n" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0 or not self._sel.select(left):
                raise AssertionError(f"no line from usarsim serve within {timeout} s; stderr: {self.stderr()}")
            chunk = os.read(self.proc.stdout.fileno(), 4096)
            if not chunk:
                raise AssertionError(
                    f"usarsim serve closed its stdout (exit {self.proc.poll()}); stderr: {self.stderr()}"
                )
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        return line.decode()

    def port(self) -> int:
        line = self.read_line()
        m = LISTENING.fullmatch(line)
        assert m, line
        return int(m.group(1))

    def stderr(self) -> str:
        self._stderr.flush()
        return self.stderr_path.read_text(errors="replace")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)
        self._sel.close()
        self.proc.stdout.close()
        self._stderr.close()


@pytest.fixture
def serve(tmp_path):
    started: list[Serve] = []

    def start(*args: str, prelude: str = "") -> Serve:
        s = Serve(*args, *FREE_PORTS, stderr_path=tmp_path / f"serve{len(started)}.err", prelude=prelude)
        started.append(s)
        return s

    yield start
    for s in started:
        s.close()


# --------------------------------------------------------------------------- help and listings


def test_help_lists_the_commands():
    out = usarsim("--help")
    assert out.returncode == 0
    for word in ("serve", "validate", "worlds", "robots", "--version", "--verbose"):
        assert word in out.stdout


def test_serve_help_lists_the_options():
    out = usarsim("serve", "--help")
    assert out.returncode == 0
    for option in ("--world", "--host", "--port", "--seed", "--speed", "--lockstep", "--max-connections"):
        assert option in out.stdout
    assert "DM-USAR_yellow" in out.stdout  # the default world is named


def test_serve_help_lists_verbose():
    out = usarsim("serve", "--help")
    assert out.returncode == 0
    assert "-v, --verbose" in out.stdout and "-vv" in out.stdout


def test_console_script_is_installed():
    exe = shutil.which("usarsim")
    if exe is None:
        pytest.skip("the 'usarsim' console script is not on PATH (package not installed as a script)")
    out = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == 0 and out.stdout.startswith("usarsim ")


def test_worlds_and_robots_list_the_shipped_files():
    worlds = usarsim("worlds")
    robots = usarsim("robots")
    assert worlds.returncode == 0 and robots.returncode == 0
    names = [ln.split()[0] for ln in worlds.stdout.splitlines()]
    assert "DM-USAR_yellow" in names and names == sorted(names)
    assert re.search(r"^DM-USAR_yellow\s+NIST yellow arena", worlds.stdout, re.M)
    assert re.search(r"^P2AT\s+skid \(SkidSteered\)\s+\S.*\n\s+kit: .*RangeScanner", robots.stdout, re.M)


def test_robots_list_says_each_robot_and_its_drive_without_none():
    out = usarsim("robots").stdout
    assert "(None)" not in out
    assert re.search(r"^AirRobot\s+aerial\s+AirRobot AR100-B quadrotor", out, re.M)
    assert re.search(r"^\s+kit: Camera, GPS, GroundTruth, IMU, Sonar$", out, re.M)


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (
            ("serve", "--speed", "fast"),
            "usarsim serve: error: argument --speed: expected a number > 0 or 'max', "
            "got 'fast'; see 'usarsim serve --help'",
        ),
        (
            ("serve", "--wrold", "x"),
            "usarsim serve: error: unrecognized arguments: --wrold x (did you mean --world?); "
            "see 'usarsim serve --help'",
        ),
        (("serv",), "did you mean 'serve'?"),
    ],
)
def test_a_usage_error_is_one_line_with_a_suggestion(args, said):
    out = usarsim(*args)
    assert out.returncode == 2
    assert out.stdout == ""
    lines = out.stderr.splitlines()
    assert len(lines) == 1 and said in lines[0], out.stderr


def test_no_command_prints_help_and_exits_2():
    out = usarsim()
    assert out.returncode == 2
    assert "serve" in out.stdout


def _fake_python(folder: Path, venv: bool) -> Path:
    """A stand-in for the Python scripts/test.sh installs into: it accepts pip and ruff, and
    for ``-m pytest`` prints the PATH it was given and where 'usarsim' is found on it."""
    (folder / "bin").mkdir(parents=True)
    if venv:
        (folder / "pyvenv.cfg").write_text("home = /usr/bin\n")
    python = folder / "bin" / "python"
    python.write_text(
        '#!/bin/sh\nif [ "$1 $2" = "-m pytest" ]; then echo "PATH=$PATH"; '
        'echo "usarsim=$(command -v usarsim)"; fi\nexit 0\n'
    )
    script = folder / "bin" / "usarsim"
    script.write_text("#!/bin/sh\necho usarsim 0\n")
    for f in (python, script):
        f.chmod(0o755)
    return python


def _fake_chromium(tools: Path) -> Path:
    """A folder with a stand-in chromium, so that scripts/test.sh does not try to install one."""
    tools.mkdir()
    (tools / "chromium").write_text("#!/bin/sh\nexit 0\n")
    (tools / "chromium").chmod(0o755)
    return tools


@pytest.mark.parametrize("venv", [True, False], ids=["venv", "not-a-venv"])
def test_test_script_puts_the_venv_bin_folder_first_on_path(tmp_path, venv):
    """scripts/test.sh runs pytest with the virtual environment's bin folder first on PATH,
    so that the 'usarsim' console script is found (test_console_script_is_installed runs)."""
    python = _fake_python(tmp_path / "env", venv)
    tools = _fake_chromium(tmp_path / "tools")
    path = os.pathsep.join(
        [str(tools)]
        + [d for d in os.environ.get("PATH", "").split(os.pathsep) if d and not (Path(d) / "usarsim").exists()]
    )
    env = {**os.environ, "PATH": path, "USARSIM_PYTHON": str(python)}
    out = subprocess.run(
        ["bash", str(ROOT / "scripts" / "test.sh")],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env=env,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr
    given = re.search(r"^PATH=(.*)$", out.stdout, re.M).group(1)
    found = re.search(r"^usarsim=(.*)$", out.stdout, re.M).group(1)
    if venv:
        assert given.split(os.pathsep)[0] == str(python.parent)
        assert found == str(python.parent / "usarsim")
    else:
        assert given == path and found == ""


def _run_test_script(tmp_path: Path, *args: str, cores: int, failing: str = "") -> tuple[int, list[str]]:
    """scripts/test.sh with a stand-in Python that writes each pytest command line it is given
    to a file (and fails the one whose arguments contain ``failing``): its exit status and
    those command lines, in order."""
    log = tmp_path / "pytest.log"
    folder = tmp_path / "env" / "bin"
    folder.mkdir(parents=True)
    python = folder / "python"
    python.write_text(
        '#!/bin/sh\nif [ "$1 $2" = "-m pytest" ]; then shift 2; echo "$*" >> "$PYTEST_LOG"; '
        'case "$*" in *"$PYTEST_FAIL"*) [ -n "$PYTEST_FAIL" ] && exit 1;; esac; fi\nexit 0\n'
    )
    python.chmod(0o755)
    tools = _fake_chromium(tmp_path / "tools")
    env = {
        **os.environ,
        "PATH": f"{tools}{os.pathsep}{os.environ.get('PATH', '')}",
        "USARSIM_PYTHON": str(python),
        "PYTEST_LOG": str(log),
        "PYTEST_FAIL": failing,
        "OMP_NUM_THREADS": str(cores),
    }  # nproc reads it
    out = subprocess.run(
        ["bash", str(ROOT / "scripts" / "test.sh"), *args],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env=env,
        cwd=tmp_path,
    )
    return out.returncode, log.read_text().splitlines() if log.exists() else []


PORTS_RUN = "-q -p no:cacheprovider --basetemp BASETEMP -m ports"
SHARED_RUN = "-q -n 2 -m not alone and not ports and not fast"
FAST_RUN = "-q -p no:cacheprovider tests/fast"


def _runs(tmp_path: Path, *args: str, cores: int, failing: str = "") -> tuple[int, list[str]]:
    rc, calls = _run_test_script(tmp_path, *args, cores=cores, failing=failing)
    return rc, [re.sub(r"--basetemp \S+", "--basetemp BASETEMP", c) for c in calls]


def test_test_script_shares_the_suite_among_the_cores_then_runs_the_wall_clock_tests_alone(tmp_path):
    # the fast tier; the shared phase and, beside it, the pages' commands (in either order); then the
    # wall-clock tests
    rc, calls = _runs(tmp_path / "a", cores=2)
    assert rc == 0 and calls[0] == FAST_RUN and sorted(calls[1:3]) == sorted([PORTS_RUN, SHARED_RUN])
    assert calls[3:] == ["-q -m alone"]
    assert "-q -n 4 -m not alone and not ports and not fast" in _runs(tmp_path / "b", cores=16)[1]  # at most 4
    assert _runs(tmp_path / "c", cores=1) == (0, [FAST_RUN, "-q -m not fast"])  # one core: one process
    # a failure in the fast tier stops the run at once; in any later phase it fails the run, and the
    # others still run
    assert _runs(tmp_path / "h", cores=2, failing="tests/fast") == (1, [FAST_RUN])
    for case, failing in (("d", "not alone and not ports"), ("e", "-m alone"), ("g", "-m ports")):
        rc, calls = _runs(tmp_path / case, cores=2, failing=failing)
        assert rc == 1 and len(calls) == 4, (failing, calls)
    # arguments select what runs, in one process, as given
    assert _runs(tmp_path / "f", "tests/unit", "-k", "lidar", cores=2) == (0, ["-q tests/unit -k lidar"])


def test_readme_says_how_to_get_the_command_after_the_first_two():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert lines[2:6] == [
        "```bash",
        "bash scripts/serve.sh    # install, then start the simulator on DM-USAR_yellow (control port 3000)",
        "bash scripts/test.sh     # install with the test dependencies, then run the whole test suite",
        "```",
    ]
    after = next(ln for ln in lines[6:] if ln.strip())
    assert ". .venv/bin/activate" in after and "usarsim" in after


# --------------------------------------------------------------------------- validate


def test_validate_shipped_files():
    for path, prefix in (
        (SHIPPED / "worlds" / "DM-USAR_yellow.yaml", "ok: world DM-USAR_yellow: "),
        (SHIPPED / "robots" / "P2AT.yaml", "ok: robot P2AT: "),
    ):
        out = usarsim("validate", str(path))
        assert out.returncode == 0, out.stderr
        assert out.stdout.startswith(prefix)
        assert out.stdout.count("\n") == 1
        assert out.stderr == ""


@pytest.mark.parametrize(
    "name, prefix",
    [
        ("DM-USAR_yellow", "ok: world DM-USAR_yellow: "),
        ("dm-usar_red", "ok: world DM-USAR_red: "),
        ("P2AT", "ok: robot P2AT: "),
        ("USARBot.P2DX", "ok: robot P2DX: "),
    ],
)
def test_validate_a_shipped_world_or_robot_by_name(name, prefix):
    out = usarsim("validate", name)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith(prefix) and out.stdout.count("\n") == 1
    assert out.stderr == ""


def test_validate_unknown_name_exits_1_with_the_known_ones():
    out = usarsim("validate", "P2ATT")
    assert out.returncode == 1 and out.stdout == ""
    assert "'P2ATT' is no file, shipped world or robot class (did you mean 'P2AT'?)" in out.stderr
    assert "DM-USAR_yellow" in out.stderr


def test_validate_bad_file_exits_1_with_the_reason_on_stderr(tmp_path):
    p = tmp_path / "w.yaml"
    p.write_text("name: W\nfloor: {center: [0, 0], size: [4, 4]}\nstart_poses: []\nstrat_poses: []\n")
    out = usarsim("validate", str(p))
    assert out.returncode == 1
    assert out.stdout == ""
    assert "usarsim: error:" in out.stderr
    assert str(p) in out.stderr and "strat_poses" in out.stderr and "did you mean 'start_poses'" in out.stderr


# --------------------------------------------------------------------------- serve


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_serve_listens_serves_and_exits_cleanly_on_signal(serve, sig):
    s = serve("--port", "0", "--world", "DM-USAR_yellow")
    port = s.port()
    assert 0 < port < 65536
    with Client(port) as c:
        assert c.next_line().raw == NFO_ON_CONNECT
        assert c.ask("GETSTARTPOSES", "NFO").text.startswith("NFO {StartPoses 8} {PlayerStart1 ")
        c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}")
        # real-time mode: data flows without STEP
        c.wait_line(lambda ln: ln.text.startswith("SEN") and "{Type GroundTruth}" in ln.text)
        s.proc.send_signal(sig)
        assert s.proc.wait(5) == 0, s.stderr()
        c.wait_closed(5)  # the server closed the connection (raises on timeout)
    assert "Traceback" not in s.stderr()


BROKEN_PHYSICS = """
from usarsim.sim.simulation import Simulation
def advance(self, seconds, *, waited=False):
    raise RuntimeError("a physics bug")
Simulation.advance = advance
"""


def test_serve_stops_with_exit_1_when_the_simulation_stops_on_an_error(serve):
    """A bug that stops the simulation (here its physics raises on the first STEP) stops the
    server: the STEP is answered with an ERROR, the connection closes, the command says why
    and exits 1, instead of serving a world that stands still."""
    s = serve("--port", "0", "--lockstep", prelude=BROKEN_PHYSICS)
    with Client(s.port()) as c:
        c.nfo()
        c.send("INIT {ClassName P2AT} {Name R1} {Start PlayerStart2}")
        c.send("STEP {Time 0.2}")
        assert c.wait_line(lambda ln: ln.text.startswith(("ERROR", "STEPPED"))).text == (
            "ERROR {Command STEP} {Reason the simulation has stopped: the world was not advanced}"
        )
        c.wait_closed(10)
    assert s.proc.wait(10) == 1
    err = s.stderr()
    assert "usarsim: error: the simulation stopped on an unexpected error (RuntimeError('a physics bug')" in err
    assert "Traceback" in err and "a physics bug" in err  # the log has where it happened


def test_serve_lockstep_with_seed(serve):
    s = serve("--port", "0", "--lockstep", "--seed", "42")
    port = s.port()
    with Client(port) as c:
        c.nfo()
        c.send("INIT {ClassName P2AT} {Name R1} {Start PlayerStart2}")
        lines = c.step(0.5)
        assert lines[-1].text == "STEPPED {Time 0.5000}"
        assert len(sensor_lines(lines, "GroundTruth")) == 6
        more = c.step(0.3)
        assert more[-1].text == "STEPPED {Time 0.8000}"
    s.proc.send_signal(signal.SIGTERM)
    assert s.proc.wait(5) == 0


@pytest.mark.parametrize("verbose", [(), ("-v",), ("-vv",)], ids=["quiet", "-v", "-vv"])
def test_connections_are_logged_with_v_after_the_command_and_not_without(serve, verbose):
    s = serve("--port", "0", *verbose)
    port = s.port()
    with Client(port) as c:
        c.nfo()
        c.send("INIT {ClassName P2AT} {Name R1} {Start PlayerStart1}")
        c.wait_line(lambda ln: ln.text.startswith("SEN"))
    s.proc.send_signal(signal.SIGTERM)
    assert s.proc.wait(5) == 0, s.stderr()
    err = s.stderr()
    logged = re.search(r"INFO usarsim[\w.]*: .*: connected", err) is not None
    assert logged == bool(verbose), err
    assert ("spawned P2AT 'R1'" in err) == bool(verbose)
    assert (" DEBUG " in err) == (verbose == ("-vv",))


def _free_offset() -> int:
    """An offset that puts every default port on a free one (on 127.0.0.1, just now)."""
    from usarsim.cli import DEFAULT_PORTS

    for offset in range(1013, 65535 - 50000, 97):
        socks = []
        try:
            for port in DEFAULT_PORTS.values():
                sock = socket.socket()
                socks.append(sock)
                sock.bind(("127.0.0.1", port + offset))
            return offset
        except OSError:
            continue
        finally:
            for sock in socks:
                sock.close()
    pytest.skip("no offset with every default port free")


def test_serve_port_offset_moves_every_default_port(tmp_path):
    offset = _free_offset()
    s = Serve("--port-offset", str(offset), "--image-port", "0", stderr_path=tmp_path / "serve.err")
    try:
        lines = [s.read_line() for _ in range(7)]
        ports = {}
        for line in lines:
            m = re.fullmatch(r"usarsim: (\w+) listening on 127\.0\.0\.1:(\d+)", line)
            assert m, line
            ports[m.group(1)] = int(m.group(2))
        expected = {"control": 3000, "truth": 3989, "comserver": 5874, "wss": 50000, "cominterface": 7435, "web": 8080}
        assert {k: v for k, v in ports.items() if k != "image"} == {k: v + offset for k, v in expected.items()}
        assert ports["image"] not in (5003, 5003 + offset)  # given explicitly (0): a free port, no offset
        assert s.read_line() == f"usarsim: operator console at http://127.0.0.1:{8080 + offset}/"
        with Client(ports["control"]) as c:
            assert c.next_line().raw == NFO_ON_CONNECT
        s.proc.send_signal(signal.SIGTERM)
        assert s.proc.wait(5) == 0, s.stderr()
    finally:
        s.close()


def test_serve_port_offset_beyond_the_last_port_is_refused():
    out = usarsim("serve", "--port-offset", "20000")
    assert out.returncode == 2 and "--port-offset" in out.stderr and "expected a number 0..15535" in out.stderr


def test_unknown_world_exits_1_listing_the_known_ones():
    out = usarsim("serve", "--port", "0", "--world", "DM-NoSuchMap")
    assert out.returncode == 1
    assert "DM-NoSuchMap" in out.stderr
    assert "DM-USAR_yellow" in out.stderr
    assert out.stdout == ""


def test_port_in_use_exits_1(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        out = usarsim("serve", "--port", str(port), *FREE_PORTS)
        assert out.returncode == 1
        assert f"cannot listen on 127.0.0.1, the control port {port} (--port)" in out.stderr
        names = {
            "--truth-port": "the ground-truth port",
            "--image-port": "the image port",
            "--wcs-port": "the ComServer port",
            "--wss-port": "the WSS port",
            "--cominterface-port": "the ComServerInterface port",
            "--web-port": "the web port",
        }
        for option, name in names.items():
            args = [x for opt in PORT_OPTIONS for x in (opt, str(port) if opt == option else "0")]
            busy_one = usarsim("serve", "--port", "0", *args)
            assert busy_one.returncode == 1, option
            assert f"cannot listen on 127.0.0.1, {name} {port} ({option})" in busy_one.stderr


@pytest.mark.parametrize(
    "args, message",
    [
        (["--port", "70000"], "expected a port number"),
        (["--speed", "fast"], "expected a number > 0 or 'max'"),
        (["--speed", "0"], "expected a number > 0 or 'max'"),
    ],
)
def test_bad_option_values_are_rejected(args, message):
    out = usarsim("serve", *args)
    assert out.returncode == 2
    assert message in out.stderr


def test_bench_reports_real_time_factors_as_json():
    import json

    out = usarsim("bench", "--robots", "2", "--seconds", "2", "--json", timeout=180)
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout.strip().splitlines()[-1])
    for key in ("robots", "sim_seconds", "wall_seconds", "rtf", "raw_mujoco_rtf", "ratio"):
        assert key in result, key
    assert result["robots"] == 2
    assert result["sim_seconds"] >= 2.0
    assert result["rtf"] > 0 and result["raw_mujoco_rtf"] > 0
    assert result["ratio"] == pytest.approx(result["rtf"] / result["raw_mujoco_rtf"], rel=0.01)
    assert result["physics_resets"] == 0
    # the simulator's memory: the whole process, and what each robot added
    assert 50 < result["peak_rss_mb"] < 4000 and 0 <= result["rss_per_robot_mb"] < 200


def test_bench_round_trips_counts_lock_step_steps_a_second():
    import json

    out = usarsim("bench", "--round-trips", "--count", "200", "--json", timeout=180)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["step_s"] == 0.004 and r["count"] == 200
    assert r["no_robot"] > 100 and r["one_p2at"] > 100  # hundreds a second at the very least, anywhere
    # the bare echo server on the same event loop: what the machine and the client allow
    assert r["bare_echo"] > 100


@pytest.mark.parametrize("mode", [[], ["--targets"], ["--cameras"], ["--round-trips"]])
def test_bench_with_an_unknown_world_says_so_in_one_line(mode):
    out = usarsim("bench", *mode, "--world", "nowhere")
    assert out.returncode == 1
    assert out.stderr.startswith("usarsim: error: --world: unknown world 'nowhere'; allowed: ")
    assert "Traceback" not in out.stderr


def test_bench_targets_runs_a_sitting_and_judges_every_target_it_measured():
    import json

    # one run of each (tests/unit/test_bench_targets.py judges several runs)
    out = usarsim(
        "bench",
        "--targets",
        "--counts",
        "2",
        "3",
        "--runs",
        "1",
        "--seconds",
        "0.5",
        "--count",
        "100",
        "--frames",
        "5",
        "--sizes",
        "320x240",
        "--json",
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["machine"]["cores"] == os.cpu_count() and r["machine"]["mujoco"]
    assert r["runs"] == 1 and [x["robots"] for runs in r["rtf"].values() for x in runs] == [2, 3]
    assert all(x["rtf"] > 0 and x["raw_mujoco_rtf"] > 0 and x["peak_rss_mb"] > 50 for x in r["rtf"]["2"])
    assert len(r["round_trips"]) == 1 and all(x["no_robot"] > 100 and x["bare_echo"] > 100 for x in r["round_trips"])
    assert [[row["size"] for row in rows] for rows in r["cameras"]] == [["320x240"]]
    targets = {t["target"]: t for t in r["targets"]}
    assert len(targets) == 9
    # measured: a verdict from the run; the robot counts of the targets were not run here
    trips = targets["round trips/s, no robot"]
    assert trips["values"] == [x["no_robot"] for x in r["round_trips"]]
    assert trips["met"] == all(v >= 15000 for v in trips["values"])
    cam = targets["camera ratio, 320x240"]
    assert cam["values"] == [rows[0]["ratio"] for rows in r["cameras"]] and isinstance(cam["met"], bool)
    for name in ("ratio, 16 robots", "real-time factor, 256 robots", "camera ratio, 640x480"):
        assert targets[name]["values"] == [] and targets[name]["met"] is None


@pytest.mark.alone  # wall-clock pacing: run by itself (scripts/test.sh)
def test_bench_profile_says_where_the_time_goes():
    import json

    out = usarsim("bench", "--robots", "2", "--seconds", "2", "--profile", "--json", timeout=180)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    sim, sensors, loop = r["sim"], r["sensors"], r["loop"]
    # the sensors are read on the measuring thread; the simulation thread hands instants over
    assert sim["physics (MuJoCo steps)"] > 0 and sim["handing instants to the measuring thread"] > 0
    # the physics split by MuJoCo's own timers: its parts fit in it, and the solver has work
    parts = {k: v for k, v in sim.items() if k.startswith("  of which")}
    assert set(parts) == {
        "  of which collision, broad phase",
        "  of which collision, narrow phase",
        "  of which making constraints",
        "  of which solving constraints",
        "  of which kinematics, inertia",
        "  of which the rest of its step",
    }
    assert parts["  of which solving constraints"] > 0 and parts["  of which collision, narrow phase"] > 0
    assert sum(parts.values()) <= sim["physics (MuJoCo steps)"] * 1.05
    assert r["contacts"]["contacts"] >= 8 and r["contacts"]["islands"] >= 1  # two P2ATs on their wheels
    assert "sensor RangeScanner" not in sim
    assert sensors["sensor RangeScanner"] > 0 and sensors["  of which ray casting (all sensors)"] > 0
    # the robots' statuses are made where the sensors are read, and counted there, not as idle time
    assert sensors["statuses (STA, MISSTA)"] > 0 and "statuses (STA, MISSTA)" not in sim
    assert 0 < r["sim_cpu_s"] <= r["sim_wall_s"] * 1.05
    assert 0 < r["sensors_cpu_s"] <= r["sensors_wall_s"] * 1.05
    # the lines account for each thread's wall time (the rest, and the idle time, are lines of their own)
    for lines, wall in ((sim, r["sim_wall_s"]), (sensors, r["sensors_wall_s"])):
        parts = sum(v for k, v in lines.items() if not k.startswith("  of which"))
        assert parts == pytest.approx(wall, rel=0.05)
    assert loop["formatting lines"] > 0 and loop["socket writes"] > 0
    text = usarsim("bench", "--robots", "1", "--seconds", "1", "--profile", timeout=180).stdout
    assert "physics (MuJoCo steps)" in text and "ms per simulated s" in text and "interpreter lock" in text
    assert "measuring thread (sensor readings)" in text
    assert "of which solving constraints" in text and "MuJoCo's own timers" in text


def test_bench_refuses_nonsense():
    out = usarsim("bench", "--robots", "0", "--seconds", "2")
    assert out.returncode == 2 and "--robots" in out.stderr


def test_serve_refuses_a_robot_dir_file_named_unlike_its_class(tmp_path):
    # INIT finds a class by its file's name: a file that declares another class is refused at
    # start-up (a client asking for it would otherwise be refused at INIT, much later)
    src = (ROOT / "src" / "usarsim" / "data" / "robots" / "P2AT.yaml").read_text()
    (tmp_path / "MyBot.yaml").write_text(src)
    out = usarsim("serve", "--port", "0", "--robot-dir", str(tmp_path), "--no-web", "--no-image", timeout=60)
    assert out.returncode == 1, out
    assert "MyBot.yaml" in out.stderr and "class_name is 'P2AT'" in out.stderr, out.stderr


def test_bench_env_prints_steps_per_second():
    out = usarsim("bench", "--env", "--steps", "20", "--team", "2", "--worlds", "2", "--json", timeout=300)
    assert out.returncode == 0, out.stderr
    import json

    rows = json.loads(out.stdout.strip().splitlines()[-1])["rows"]
    assert [(r["transport"], r["env"]) for r in rows] == [
        ("tcp", "Explore-v0"),
        ("tcp", "TeamExplore"),
        ("inproc", "Explore-v0"),
        ("inproc", "ExploreVectorEnv(2)"),
        ("inproc", "TeamExplore"),
    ]
    assert rows[3]["worlds"] == 2 and rows[3]["times_one"] > 0
    assert all(r["steps_per_s"] > 0 for r in rows)


def test_bench_env_profile_splits_a_steps_time_between_the_processes_and_the_physics():
    out = usarsim("bench", "--env", "--profile", "--steps", "20", "--team", "2", "--worlds", "0", "--json", timeout=300)
    assert out.returncode == 0, out.stderr
    import json

    profiles = json.loads(out.stdout.strip().splitlines()[-1])
    assert [(p["transport"], p["robots"]) for p in profiles] == [("tcp", 1), ("tcp", 2), ("inproc", 1), ("inproc", 2)]
    for p in profiles:
        assert p["steps_per_s"] > 0 and p["env_cpu_ms"] > 0 and p["physics_ms"] > 0
        if p["transport"] == "tcp":
            assert p["sim_cpu_ms"] is not None and p["sim_cpu_ms"] >= 0  # read from /proc on Linux
        else:
            assert p["sim_cpu_ms"] is None  # the simulator's time is the environment process's own
        # a step cannot take less wall time than the environment's own processor time in it
        assert p["wall_ms"] >= p["env_cpu_ms"] * 0.9


def test_talk_sends_typed_lines_and_prints_the_answers(serve):
    port = serve("--port", "0", "--lockstep").port()
    lines = "GETSTARTPOSES\nINIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}\nSTEP {Time 0.2}\n"
    out = subprocess.run(
        [sys.executable, "-m", "usarsim.client.talk", "--port", str(port), "--hide", "SEN,MISSTA"],
        input=lines,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    said = out.stdout.splitlines()
    assert said[0] == NFO_ON_CONNECT.decode().strip()
    assert said[1].startswith("NFO {StartPoses 8} {PlayerStart1 -9.50,0.00,-0.25 ")
    assert said[-1] == "STEPPED {Time 0.2000}" and any(s.startswith("STA {Type GroundVehicle}") for s in said)
    assert not any(s.startswith(("SEN", "MISSTA")) for s in said)


def test_talk_without_a_simulator_says_so_in_one_line():
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = subprocess.run(
        [sys.executable, "-m", "usarsim.client.talk", "--port", str(port)],
        input="",
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert out.returncode == 1 and len(out.stderr.splitlines()) == 1
    assert f"no simulator on 127.0.0.1:{port}" in out.stderr and "usarsim serve" in out.stderr
