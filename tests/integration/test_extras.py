"""The extras: without them the simulator runs, and a command that needs one says which in one
line (exit 1).  The packages are hidden from a real ``usarsim`` process (``sys.modules[name] =
None`` makes every import of them fail, as on a core install)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from usarsim.extras import EXTRAS

HIDE = "import sys\nfor m in {modules!r}: sys.modules[m] = None\n"


def run_without(modules: tuple[str, ...], code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", HIDE.format(modules=modules) + code],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def usarsim_without(modules: tuple[str, ...], *argv: str) -> subprocess.CompletedProcess:
    return run_without(modules, f"from usarsim.cli import main\nsys.exit(main({list(argv)!r}))")


HEAVY = EXTRAS["sweep"] + EXTRAS["record"]


@pytest.mark.parametrize(
    ("argv", "extra"),
    [
        (("sweep", "explorers.yaml"), "sweep"),
        (("report", "results/explorers"), "sweep"),
        (("replay", "run.mcap"), "record"),
        (("serve", "--record", "run.mcap"), "record"),
        (("serve", "--foxglove"), "record"),
    ],
)
def test_a_command_needing_a_missing_extra_says_which_in_one_line(argv, extra):
    out = usarsim_without(HEAVY, *argv)
    assert out.returncode == 1, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert f"needs the '{extra}' extra" in lines[0] and f"pip install 'usarsim[{extra}]'" in lines[0]


def test_the_core_runs_a_robot_without_the_extras():
    code = """
from usarsim.client import launch
import usarsim.envs, usarsim.web.console, usarsim.brains.frontier, usarsim.scoring
with launch(world="DM-USAR_yellow", seed=1) as server, server.connect() as world:
    robot = world.spawn("P2AT", start="PlayerStart1")
    for _ in range(10):
        robot.drive(left=2.0, right=2.0)
        world.step(0.1)
    print("ran", world.time, sorted(m for m in sys.modules if m.split('.')[0] in %r and sys.modules[m]))
""" % (HEAVY,)
    out = run_without(HEAVY, code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ran 1.0 []"
