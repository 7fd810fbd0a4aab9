"""Dependencies point downwards only (design.md section 2), checked in fresh interpreters."""

from __future__ import annotations

import subprocess
import sys

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


PROTOCOL_MODULES = ["usarsim.protocol", "usarsim.protocol.commands", "usarsim.protocol.messages",
                    "usarsim.protocol.framing", "usarsim.protocol.grammar", "usarsim.protocol.numbers"]


def test_protocol_loads_no_numpy_mujoco_asyncio_sim_or_server():
    mods = loaded_after(PROTOCOL_MODULES)
    assert "usarsim.protocol.commands" in mods  # the probe did import it
    assert top(mods, "mujoco", "numpy", "asyncio") == set()
    assert top(mods, "usarsim.sim", "usarsim.server", "usarsim.sensors", "usarsim.config") == set()


def test_config_loads_no_mujoco_or_asyncio():
    mods = loaded_after(["usarsim.config", "usarsim.config.world", "usarsim.config.robot", "usarsim.config.catalog"])
    assert "usarsim.config.catalog" in mods
    assert top(mods, "mujoco", "asyncio") == set()
    assert top(mods, "usarsim.sim", "usarsim.server", "usarsim.protocol") == set()


@pytest.mark.parametrize("module", ["usarsim.sim.simulation", "usarsim.sim.runner", "usarsim.sim.facade",
                                    "usarsim.sensors"])
def test_sim_loads_no_asyncio_protocol_or_server(module):
    mods = loaded_after([module])
    assert "mujoco" in top(mods, "mujoco")  # it really is the simulation layer
    assert top(mods, "asyncio", "usarsim.protocol", "usarsim.server") == set()
