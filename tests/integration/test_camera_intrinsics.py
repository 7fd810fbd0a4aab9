"""A camera's CONF intrinsics are those of the pictures it is drawn with: a small red marker at a
known place in the world (a thin square facing the camera: its picture's centroid is its
centre's projection), projected through the camera's pose with the FocalLength and
PrincipalPoint its CONF gives, lands on the pixels where the rendered picture shows it, before
and after a zoom (which changes them).  Rendering needs an OpenGL context; where none can be
made the test is skipped, with the reason."""

from __future__ import annotations

import numpy as np
import pytest

from helpers import gl_problem, settled
from usarsim.readings import ItemParams

GL_PROBLEM = gl_problem()
pytestmark = pytest.mark.skipif(bool(GL_PROBLEM), reason=GL_PROBLEM or "ok")

WIDTH, HEIGHT = 320, 240
MARKERS = {"near": (2.0, -0.35, -0.45), "far": (3.2, 0.55, -0.25)}  # USARSim frame: x ahead, y right, z down
WORLD = """\
name: MarkerField
description: a floor, two small red squares facing the robot at known places (tests only)
floor: {center: [0.0, 0.0], size: [20.0, 20.0]}
materials:
  red: {rgba: [1.0, 0.0, 0.0, 1.0]}
objects:
  - {name: near, shape: box, center: [2.0, -0.35, -0.45], size: [0.002, 0.05, 0.05], material: red}
  - {name: far, shape: box, center: [3.2, 0.55, -0.25], size: [0.002, 0.05, 0.05], material: red}
start_poses:
  - {name: Origin, location: [0.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""


def red_blobs(rgb: np.ndarray) -> list[tuple[float, float]]:
    """Centroids (u, v: pixel centres at +0.5) of the red patches, left to right."""
    import cv2

    mask = ((rgb[..., 0] > 120) & (rgb[..., 1] < 60) & (rgb[..., 2] < 60)).astype(np.uint8)
    n, labels, _, _ = cv2.connectedComponentsWithStats(mask)
    out = []
    for k in range(1, n):
        vs, us = np.nonzero(labels == k)
        out.append((float(us.mean()) + 0.5, float(vs.mean()) + 0.5))
    return sorted(out)


def project(point_world_mj: np.ndarray, cam_pos: np.ndarray, cam_mat: np.ndarray, f: float, c: tuple) -> tuple:
    """A MuJoCo-world point through a MuJoCo camera (looking along its -z, x right, y up) and
    a pinhole of focal length ``f`` pixels and principal point ``c``: its (u, v)."""
    x, y, z = cam_mat.T @ (point_world_mj - cam_pos)
    return c[0] + f * x / -z, c[1] - f * y / -z


def test_conf_intrinsics_put_known_points_where_the_picture_shows_them(tmp_path):
    import mujoco

    from usarsim.config.catalog import resolve_robot
    from usarsim.config.world_file import load_world
    from usarsim.sim.render import RenderService
    from usarsim.sim.robotspec import camera_name
    from usarsim.sim.simulation import Simulation
    from usarsim.sim.tiles import Tile

    path = tmp_path / "MarkerField.yaml"
    path.write_text(WORLD)
    sim = Simulation(load_world(path))
    sim.spawn(1, resolve_robot("P2AT"), "R1", (0.0, 0.0, -0.2), (0.0, 0.0, 0.0), set_down=True)
    sim.advance(0.5)
    service = RenderService(lambda reuse: settled(sim.cameras.render_snapshot(reuse)), max_fps=0)
    try:
        camera = next(s for s in sim.robots[1].sensors if s.TYPE == "Camera")
        for zoom in (None, 0.5):
            if zoom is not None:
                sim.operate(1, "Camera", "Camera", "Zoom", ItemParams(values=(zoom,)))
            conf = dict(camera.conf_fields())
            f, fy = conf["FocalLength"]
            assert f == fy and conf["PrincipalPoint"] == (WIDTH / 2, HEIGHT / 2)
            rgb = service.render(WIDTH, HEIGHT, [Tile(1, "Camera", 0, 0, WIDTH, HEIGHT)]).result(timeout=60)
            cid = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_CAMERA, camera_name("robot1", "Camera"))
            pos, mat = sim.data.cam_xpos[cid].copy(), sim.data.cam_xmat[cid].reshape(3, 3).copy()
            expected = sorted(
                project(np.array([x, -y, -z]), pos, mat, f, conf["PrincipalPoint"]) for x, y, z in MARKERS.values()
            )
            seen = red_blobs(rgb)
            assert len(seen) == 2, f"zoom {zoom}: {len(seen)} red patches"
            for (u, v), (eu, ev) in zip(seen, expected):
                assert abs(u - eu) < 1.0 and abs(v - ev) < 1.0, (
                    f"zoom {zoom}: seen {u:.2f},{v:.2f}, projected {eu:.2f},{ev:.2f}"
                )
        # the zoom moved both markers away from the centre, by the ratio of the focal lengths
        assert f == pytest.approx(WIDTH / 2 / np.tan(0.25))
    finally:
        service.stop()
