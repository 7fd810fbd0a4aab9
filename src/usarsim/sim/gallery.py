"""Robot classes on their own: a row of robots standing on a grey floor where their drives put
them, and a portrait of each as a world's cameras see it (its solid pieces, its look and its
sensors' housings), for ``usarsim robots --picture`` and the camera benchmark's robots in view."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import mujoco
import numpy as np

from usarsim.config.robot import Look, RobotConfig
from usarsim.config.world import bare_world
from usarsim.sim.builder import world_spec
from usarsim.sim.plugins import PluginSet, builtin_plugins
from usarsim.sim.render import SEEN, camera_renderer
from usarsim.sim.robotspec import add_robot

# A portrait's view: from 35 degrees left of straight ahead and 20 degrees above, the robot's
# longest side about a third of the picture across
AZIMUTH_DEG, ELEVATION_DEG = 215.0, -20.0
FILL = 2.6  # the camera this many times the robot's longest side away
FLOOR_RGBA = (0.55, 0.55, 0.56, 1.0)
GAP_M = 0.4  # between two robots of a row


def robots_scene(
    robots: Sequence[RobotConfig], *, look: bool = True, plugins: PluginSet | None = None
) -> tuple[mujoco.MjModel, mujoco.MjData, np.ndarray]:
    """``robots`` side by side along their Y axis (``GAP_M`` between them), facing along X,
    standing on a floor; with ``look`` False they are drawn as their solid pieces and sensors'
    housings only.  Returns the model, its data and the middle of the row (MuJoCo frame)."""
    plugins = plugins or builtin_plugins()
    world = bare_world("robots", 60.0, FLOOR_RGBA)
    spec = world_spec(world)
    y = 0.0
    for i, robot in enumerate(robots):
        if not look:
            robot = dataclasses.replace(robot, look=Look(hub_color=None))
        width = robot.geometry.dimensions[1]
        y += width / 2.0 if i == 0 else width / 2.0 + GAP_M
        drive = plugins.make_drive(robot)
        items = [plugins.make_item(item, robot, 0, "robots") for item in robot.items]
        add_robot(spec, robot, f"robot{i + 1}", (0.0, y, -drive.lowest_point_m(robot)), (0.0, 0.0, 0.0), drive, items)
        y += width / 2.0
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    ids = [m.body(f"robot{i + 1}").id for i in range(len(robots))]
    return m, d, d.xpos[ids].mean(axis=0)


def robot_portrait(
    robot: RobotConfig, width: int = 320, height: int = 240, plugins: PluginSet | None = None
) -> np.ndarray:
    """An RGB picture (height x width x 3, uint8) of ``robot`` alone, as described above."""
    m, d, middle = robots_scene([robot], plugins=plugins)
    cam = mujoco.MjvCamera()
    cam.lookat[:] = middle
    cam.distance = FILL * max(max(robot.geometry.dimensions[:3]), 0.3)
    cam.azimuth, cam.elevation = AZIMUTH_DEG, ELEVATION_DEG
    r = camera_renderer(m, width, height, shadows=True)
    try:
        r.update_scene(d, cam, SEEN)
        return r.render().copy()
    finally:
        r.close()
