"""Dependencies point downwards only (design.md section 2), checked in fresh interpreters."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest


def loaded_after(imports: list[str]) -> set[str]:
    code = (
        "import sys, importlib\n"
        f"for name in {imports!r}:\n"
        "    importlib.import_module(name)\n"
        "sys.stdout.write('\\n'.join(sorted(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == 0, out.stderr
    return set(out.stdout.split())


def top(modules: set[str], *names: str) -> set[str]:
    """The modules among ``names`` (or their submodules) that were loaded."""
    return {m for m in modules if any(m == n or m.startswith(n + ".") for n in names)}


PROTOCOL_MODULES = [
    "usarsim.protocol",
    "usarsim.protocol.commands",
    "usarsim.protocol.messages",
    "usarsim.protocol.framing",
    "usarsim.protocol.grammar",
    "usarsim.protocol.numbers",
    "usarsim.protocol.outputs",
    "usarsim.protocol.wireless",
    "usarsim.protocol.upis",
]


def test_protocol_loads_no_numpy_mujoco_asyncio_sim_or_server():
    mods = loaded_after(PROTOCOL_MODULES)
    assert "usarsim.protocol.commands" in mods  # the probe did import it
    assert top(mods, "mujoco", "numpy", "asyncio") == set()
    assert top(mods, "usarsim.sim", "usarsim.server", "usarsim.sensors", "usarsim.effecters", "usarsim.config") == set()


def test_config_loads_no_mujoco_or_asyncio():
    mods = loaded_after(["usarsim.config", "usarsim.config.world", "usarsim.config.robot", "usarsim.config.catalog"])
    assert "usarsim.config.catalog" in mods
    assert top(mods, "mujoco", "asyncio") == set()
    assert top(mods, "usarsim.sim", "usarsim.server", "usarsim.protocol") == set()


def test_the_client_loads_no_mujoco_simulation_or_server():
    """usarsim.client talks to a simulator over the wire only: a controller can run where
    MuJoCo is not installed."""
    mods = loaded_after(["usarsim.client", "usarsim.client.aio"])
    assert "usarsim.client.blocking" in mods
    assert top(mods, "mujoco") == set()
    assert top(mods, "usarsim.sim", "usarsim.server", "usarsim.web", "usarsim.sensors", "usarsim.config") == set()


def test_the_servers_and_the_console_load_no_mujoco():
    """They are written against the facade's interface (usarsim.sim.api), so that the fast test
    tier runs them with a fake facade and no physics; only the composition root (server.app)
    brings the real simulation."""
    mods = loaded_after(
        [
            "usarsim.server.session",
            "usarsim.server.control",
            "usarsim.server.truth",
            "usarsim.server.wireless",
            "usarsim.server.image",
            "usarsim.web.console",
        ]
    )
    assert "usarsim.web.console" in mods and "usarsim.sim.api" in mods
    assert (
        top(mods, "mujoco", "usarsim.sim.simulation", "usarsim.sim.facade", "usarsim.sensors", "usarsim.robots")
        == set()
    )


@pytest.mark.parametrize(
    "module",
    ["usarsim.sim.simulation", "usarsim.sim.runner", "usarsim.sim.facade", "usarsim.sensors", "usarsim.effecters"],
)
def test_sim_loads_no_asyncio_protocol_or_server(module):
    mods = loaded_after([module])
    assert "mujoco" in top(mods, "mujoco")  # it really is the simulation layer
    assert top(mods, "asyncio", "usarsim.protocol", "usarsim.server") == set()


SRC = Path(__file__).resolve().parents[2] / "src" / "usarsim"
# What the servers and the console may import of the simulation layer: its facade and the
# types that cross it (design.md 2 and 5).
SIM_DOOR = ("usarsim.sim.api", "usarsim.sim.facade", "usarsim.sim.settings", "usarsim.sim.types")
BELOW_THE_DOOR = ("usarsim.sim", "usarsim.sensors", "usarsim.effecters", "usarsim.robots", "mujoco")


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, module) of every import in a file, at any depth (also inside functions)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out += [(node.lineno, node.module)] + [
                (node.lineno, f"{node.module}.{a.name}") for a in node.names if node.module == "usarsim.sim"
            ]
    return out


def _server_files() -> list[Path]:
    return sorted([*(SRC / "server").rglob("*.py"), *(SRC / "web").rglob("*.py"), *(SRC / "scoring").rglob("*.py")])


@pytest.mark.parametrize("path", _server_files(), ids=lambda p: str(p.relative_to(SRC)))
def test_servers_reach_the_simulation_only_through_its_facade(path):
    bad = [
        (line, mod)
        for line, mod in _imports(path)
        if any(mod == b or mod.startswith(b + ".") for b in BELOW_THE_DOOR)
        and not any(mod == d or mod.startswith(d + ".") for d in SIM_DOOR)
    ]
    assert not bad, f"{path.relative_to(SRC)} imports below the simulation's facade: {bad}"
    # and does not reach past the facade's methods: no facade.sim, facade.runner, facade.call
    tree = ast.parse(path.read_text(encoding="utf-8"))
    past = [
        (n.lineno, n.attr)
        for n in ast.walk(tree)
        if isinstance(n, ast.Attribute) and n.attr in ("sim", "runner", "call") and _names_facade(n.value)
    ]
    assert not past, f"{path.relative_to(SRC)} reaches past the facade: {past}"


def _names_facade(node: ast.AST) -> bool:
    return (isinstance(node, ast.Name) and node.id == "facade") or (
        isinstance(node, ast.Attribute) and node.attr == "facade"
    )


def test_the_layering_check_sees_a_reach_past_the_facade(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text(
        "from usarsim.sim.simulation import Simulation\ndef f(server):\n    server.facade.call(lambda sim: sim.time)\n"
    )
    assert "usarsim.sim.simulation" in {m for _, m in _imports(probe)}
    tree = ast.parse(probe.read_text())
    assert any(isinstance(n, ast.Attribute) and n.attr == "call" and _names_facade(n.value) for n in ast.walk(tree))
