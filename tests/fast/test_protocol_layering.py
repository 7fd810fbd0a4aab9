"""The protocol layer is sans-IO: importing it pulls in no simulation, numpy or asyncio."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"

_PROBE = """
import sys
import usarsim.protocol
import usarsim.protocol.commands
import usarsim.protocol.framing
import usarsim.protocol.grammar
import usarsim.protocol.messages
import usarsim.protocol.numbers
forbidden = sorted(
    name for name in sys.modules
    if name.split(".")[0] in {"mujoco", "numpy", "asyncio"}
    or name.startswith(("usarsim.sim", "usarsim.server"))
)
print(",".join(forbidden))
"""


def test_protocol_imports_no_simulation_numpy_or_asyncio() -> None:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(SRC)
    result = subprocess.run(
        [sys.executable, "-c", _PROBE],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "", f"protocol layer imported: {result.stdout.strip()}"


def test_package_reexports_main_names() -> None:
    import usarsim.protocol as protocol

    for name in ("LineBuffer", "parse_command", "format_command", "parse_message", "format_message"):
        assert callable(getattr(protocol, name)), name
