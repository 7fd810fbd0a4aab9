"""Shared fixtures: worlds, in-process servers on port 0, the golden-update switch; the fast
tier's guard and marker."""

from __future__ import annotations

import importlib.abc
import os
import sys
from pathlib import Path

import pytest

import usarsim  # noqa: F401  (first: it chooses MuJoCo's offscreen GL backend before MuJoCo loads)
from helpers import ServerThread, write_test_world

FAST_DIR = Path(__file__).parent / "fast"
# USARSIM_FAST_TIER=1 (scripts/test.sh's first phase: pytest tests/fast): importing MuJoCo fails,
# so that a test of the fast tier cannot build a physics model, even through an import deep down.
FAST_TIER = os.environ.get("USARSIM_FAST_TIER") == "1"


class _NoMuJoCo(importlib.abc.MetaPathFinder):
    def find_spec(self, name: str, path: object = None, target: object = None) -> None:
        if name == "mujoco" or name.startswith("mujoco."):
            raise ImportError(
                "the fast test tier (USARSIM_FAST_TIER=1) loads no MuJoCo: this test belongs in "
                "tests/unit or tests/integration, or its code imports the physics it does not need"
            )


if FAST_TIER:
    sys.meta_path.insert(0, _NoMuJoCo())


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Every test under tests/fast is marked ``fast`` (``pytest -m fast`` selects the tier)."""
    for item in items:
        if FAST_DIR in Path(str(item.path)).parents:
            item.add_marker(pytest.mark.fast)


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="rewrite tests/golden/transcripts/*.txt from the current server output "
        "(same as USARSIM_UPDATE_GOLDEN=1); review the diff before committing",
    )


@pytest.fixture(scope="session")
def update_golden(request: pytest.FixtureRequest) -> bool:
    return bool(request.config.getoption("--update-golden")) or os.environ.get("USARSIM_UPDATE_GOLDEN") == "1"


@pytest.fixture(scope="session")
def yellow_world():
    from usarsim.config.catalog import resolve_world

    return resolve_world("DM-USAR_yellow")


@pytest.fixture(scope="session")
def test_world_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_test_world(tmp_path_factory.mktemp("worlds"))


@pytest.fixture(scope="session")
def test_world(test_world_path: Path):
    """A flat 20 x 20 m floor with a wall face at x = 5.0 (see helpers.TEST_WORLD)."""
    from usarsim.config.world_file import load_world

    return load_world(test_world_path)


@pytest.fixture
def server_factory(yellow_world):
    """Start in-process servers (port 0, own event-loop thread); all are stopped at teardown.

    ``server_factory(world=None, seed=1, lockstep=True, speed=None, max_connections=64)``
    """
    servers: list[ServerThread] = []

    def make(world=None, **kwargs) -> ServerThread:
        kwargs.setdefault("seed", 1)
        kwargs.setdefault("lockstep", True)
        srv = ServerThread(world if world is not None else yellow_world, **kwargs)
        servers.append(srv)
        return srv.start()

    yield make
    for srv in servers:
        srv.stop()


@pytest.fixture
def server(server_factory) -> ServerThread:
    """A lock-step server on DM-USAR_yellow, seed 1."""
    return server_factory()
