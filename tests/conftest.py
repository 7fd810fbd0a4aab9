"""Shared fixtures: worlds, in-process servers on port 0, the golden-update switch."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import usarsim  # noqa: F401  (first: it chooses MuJoCo's offscreen GL backend before MuJoCo loads)
from helpers import ServerThread, write_test_world


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--update-golden", action="store_true", default=False,
                     help="rewrite tests/golden/transcripts/*.txt from the current server output "
                          "(same as USARSIM_UPDATE_GOLDEN=1); review the diff before committing")


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
    from usarsim.config.world import load_world

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
