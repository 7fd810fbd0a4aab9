"""What a camera under water sees (usarsim.sim.underwater): the Submarine's camera at
DM-Harbour's start pose Dive1, 2 m under the surface and heading up the basin, sends over the
image server a picture of murky water (the far end of the basin gone into the water's colour,
the bottom fading with distance, the surface seen from below brighter than the water ahead, no
sky), while a robot's camera on a quay sends exactly what MuJoCo renders; close to a quay wall
under water the wall keeps most of its colours.  Rendering needs an OpenGL context; where none
can be made these tests are skipped, with the reason."""

from __future__ import annotations

import numpy as np
import pytest
from test_image_server import Viewer

from helpers import gl_problem, settled

GL_PROBLEM = gl_problem()
pytestmark = pytest.mark.skipif(bool(GL_PROBLEM), reason=GL_PROBLEM or "ok")

WIDTH, HEIGHT = 320, 240
HORIZON = HEIGHT // 2  # the cameras look level
# The sky behind the world (builder.world_spec: a pale blue gradient) is bluer than it is green
# and much bluer than red; harbour water is greener than it is blue.
SKY_BLUE_OVER_GREEN, SKY_BLUE_OVER_RED = 8, 20


def sky_share(pixels: np.ndarray) -> float:
    p = pixels.astype(int)
    return float(((p[..., 2] > p[..., 1] + SKY_BLUE_OVER_GREEN) & (p[..., 2] > p[..., 0] + SKY_BLUE_OVER_RED)).mean())


@pytest.fixture(scope="module")
def harbour():
    from usarsim.config.catalog import resolve_world

    return resolve_world("DM-Harbour")


def water_colour(model, data) -> np.ndarray:
    from usarsim.sim.underwater import water_of

    return water_of(model, data).colour


def test_the_submarine_sees_murky_water_and_the_quay_camera_is_unchanged(server_factory, harbour):
    import mujoco

    from usarsim.server.image import ImageSettings
    from usarsim.sim.render import SEEN, camera_renderer
    from usarsim.sim.robotspec import camera_name

    srv = server_factory(world=harbour, image=ImageSettings(image_type=0, width=WIDTH, height=HEIGHT))
    sub = srv.connect()
    sub.nfo()
    sub.send("INIT {ClassName USARBot.Submarine} {Name Nemo} {Start Dive1}")
    dock = srv.connect()
    dock.nfo()
    dock.send("INIT {ClassName USARBot.P2AT} {Name Docker} {Start Quay1}")
    sub.step(1.0)  # the P2AT landed on the quay
    viewer = Viewer(srv.app.image.port)
    try:
        sub.send(f"SET {{Type Camera}} {{Robot Nemo}} {{Name Camera}} {{Client 127.0.0.1:{viewer.local_port}}}")
        sub.step(0.1)
        under = viewer.picture().astype(float)
        sub.send(f"SET {{Type Camera}} {{Robot Docker}} {{Name Camera}} {{Client 127.0.0.1:{viewer.local_port}}}")
        sub.step(0.1)
        above = viewer.picture()
    finally:
        viewer.close()
    water = srv.on_sim(lambda sim: water_colour(sim.model, sim.data))

    assert under.shape == (HEIGHT, WIDTH, 3)
    # no sky: the camera is 2 m under water
    assert sky_share(under) < 0.005, sky_share(under)
    # the far end of the basin (the north quay 45 m ahead, at the horizon) is the water's colour
    far = under[HORIZON - 6 : HORIZON + 6].reshape(-1, 3).mean(axis=0)
    assert np.all(np.abs(far - water) < 10), (far, water)
    # the bottom fades into the water with distance: its difference from the water's colour
    # (the contrast a vision pipeline can use) near the picture's foot, 5 m ahead, is several
    # times what is left just below the horizon, 20 m and more ahead
    contrast = np.abs(under - water).mean(axis=(1, 2))
    near, distant = contrast[HEIGHT - 20 :].mean(), contrast[HORIZON + 2 : HORIZON + 12].mean()
    assert near > 3 * distant and distant < 5, (near, distant)
    # the surface seen from below fills the upper part: brighter than the water ahead (the
    # water near the surface is lit more), and of the water's hue, green before blue and red
    top = under[: HEIGHT // 8].reshape(-1, 3).mean(axis=0)
    assert top.mean() > 1.1 * far.mean(), (top, far)
    assert top[1] > top[0] and top[1] > top[2], top

    # the P2AT on the quay (1 m above the water) sees what MuJoCo renders, byte for byte: its
    # picture is not made over
    def plain(sim):
        snap = sim.cameras.render_snapshot()
        cam = mujoco.mj_name2id(snap.model, mujoco.mjtObj.mjOBJ_CAMERA, camera_name("robot2", "Camera"))
        return snap, cam

    snap, cam = srv.on_sim(plain)
    r = camera_renderer(snap.model, WIDTH, HEIGHT, shadows=False)
    try:
        r.update_scene(snap.data, camera=cam, scene_option=SEEN)
        assert np.array_equal(r.render(), above)
    finally:
        r.close()
    assert sky_share(above[:HORIZON]) > 0.3  # and it sees the sky


def test_a_wall_1_m_away_under_water_keeps_most_of_its_colours(harbour, monkeypatch):
    """The Submarine 1 m in front of the north quay's wall, 1.75 m under water: each colour
    channel keeps at least 60 % of its difference from the water's colour (what the same camera
    sees of the wall without the water), and most of the wall's texture."""
    from usarsim.config.catalog import resolve_robot
    from usarsim.sim import render
    from usarsim.sim.simulation import Simulation
    from usarsim.sim.tiles import Tile
    from usarsim.sim.underwater import Water

    sim = Simulation(harbour)
    # the camera is 0.75 m ahead of the hull's centre (Submarine.yaml); the wall is at X = 15
    sim.spawn(1, resolve_robot("Submarine"), "Nemo", (13.25, 6.0, -1.75), (0.0, 0.0, 0.0), set_down=False)

    def picture():
        service = render.RenderService(lambda reuse: settled(sim.cameras.render_snapshot(reuse)), max_fps=0)
        try:
            return service.render(WIDTH, HEIGHT, [Tile(1, "Camera", 0, 0, WIDTH, HEIGHT)]).result(timeout=120)
        finally:
            service.stop()

    wet = picture().astype(float)
    monkeypatch.setattr(render, "water_of", lambda model, data: Water(boxes=(), colour=np.zeros(3)))
    dry = picture().astype(float)
    water = water_colour(sim.model, sim.data)
    wall = (slice(60, 180), slice(80, 240))  # the middle of the picture: all wall
    kept = (wet[wall].reshape(-1, 3).mean(axis=0) - water) / (dry[wall].reshape(-1, 3).mean(axis=0) - water)
    assert np.all(kept > 0.6) and np.all(kept < 1.0), kept
    assert wet[wall].mean(axis=2).std() > 0.7 * dry[wall].mean(axis=2).std()
