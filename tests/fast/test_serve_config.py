"""One frozen, validated value sets up a server (usarsim.server.config.ServeConfig): a bad
setting fails when the value is made, with the setting named, before any listener opens."""

from __future__ import annotations

import dataclasses

import pytest

from usarsim.server.config import ServeConfig
from usarsim.sim.settings import SimSettings


def test_the_defaults_are_usarsims_ports_and_real_time(yellow_world):
    c = ServeConfig(world=yellow_world)
    assert (c.port, c.truth_port, c.image_port, c.web_port) == (3000, 3989, 5003, 8080)
    assert c.speed == 1.0 and not c.lockstep and c.sim == SimSettings()
    assert c.robot_limit == c.max_connections == 64
    assert ServeConfig(world=yellow_world, max_robots=3).robot_limit == 3
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.port = 1  # type: ignore[misc]


@pytest.mark.parametrize(
    ("settings", "named"),
    [
        ({"port": 70000}, "port must be a port number"),
        ({"image_port": -1}, "image_port must be a port number"),
        ({"speed": 0.0}, "speed must be a positive number"),
        ({"speed": float("nan")}, "speed must be a positive number"),
        ({"max_connections": 0}, "max_connections must be at least 1"),
        ({"max_line_bytes": 10}, "max_line_bytes must be at least 64"),
        ({"max_web_connections": 1}, "max_web_connections must be at least 2"),
        ({"record_cameras_fps": -1.0}, "record_cameras_fps"),
    ],
)
def test_a_bad_setting_is_refused_and_named(yellow_world, settings, named):
    with pytest.raises(ValueError, match=named):
        ServeConfig(world=yellow_world, **settings)


def test_a_bad_simulation_setting_is_refused_by_its_own_value():
    with pytest.raises(ValueError, match="physics_threads must be within 0..256"):
        SimSettings(physics_threads=-1)


def test_robot_folders_are_kept_as_a_tuple(yellow_world):
    assert ServeConfig(world=yellow_world, robot_dirs=["a", "b"]).robot_dirs == ("a", "b")
