"""The road world DM-Road_UrbanChallenge is lit everywhere: a robot camera anywhere in the
town, facing any way, sends a picture of lit streets and walls, with the road showing right
up to the robot.  Pictures come from the image server, as a client gets them.  Rendering
needs an OpenGL context; where none can be made these tests are skipped, with the reason."""

from __future__ import annotations

import numpy as np
import pytest
from test_image_server import Viewer

from helpers import gl_problem

GL_PROBLEM = gl_problem()
pytestmark = pytest.mark.skipif(bool(GL_PROBLEM), reason=GL_PROBLEM or "ok")

WIDTH, HEIGHT = 160, 120
# Places besides the eight start poses (which are on every road, facing each of the four
# ways): the middle of a crossing facing south (at the walls in the shade of a sun that
# stands in the south), the parking lot facing west, and the open ground outside the town
# near the floor's edge, facing north.
PLACES = (
    ("Crossing", "41,41,-0.25", "0,0,3.1416"),
    ("Lot", "0,90,-0.25", "0,0,4.7124"),
    ("Outskirts", "0,-142,-0.25", "0,0,0"),
)
# The picture's lower part: rows from 10 below the horizon (the camera is level) down, the
# ground within about 6 m of the camera, which is road at every place above but the last.
GROUND_ROWS = slice(HEIGHT // 2 + 10, HEIGHT)
MIN_MEAN = 70.0  # brightness 0..255 of the whole picture, on average
MIN_GROUND_MEAN = 35.0  # of the ground ahead (asphalt reflects 22 % of the light)
MIN_DARK_PERCENTILE = 20.0  # the darkest 5 % of the pixels: no part of the picture is black


def sky_share(pixels: np.ndarray) -> float:
    """The share of pixels that show the sky (the blue gradient behind the world: blue
    at least 20 levels above red), not the world."""
    p = pixels.astype(int)
    return float(((p[..., 2] - p[..., 0]) > 20).mean())


@pytest.fixture(scope="module")
def road_world():
    from usarsim.config.catalog import resolve_world

    return resolve_world("DM-Road_UrbanChallenge")


def test_the_road_world_is_lit_wherever_a_camera_looks(server_factory, road_world):
    from usarsim.server.image import ImageSettings

    srv = server_factory(world=road_world, image=ImageSettings(image_type=0, width=WIDTH, height=HEIGHT))
    robots = []
    for k, pose in enumerate(road_world.start_poses, start=1):
        c = srv.connect()
        c.nfo()
        c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name R{k}}} {{Start {pose.name}}}")
        robots.append((pose.name, f"R{k}", c))
    for k, (place, location, rotation) in enumerate(PLACES, start=len(robots) + 1):
        c = srv.connect()
        c.nfo()
        c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name R{k}}} {{Location {location}}} {{Rotation {rotation}}}")
        robots.append((place, f"R{k}", c))
    first = robots[0][2]
    first.step(1.0)  # every robot landed
    viewer = Viewer(srv.app.image.port)
    try:
        for place, name, _ in robots:
            first.send(f"SET {{Type Camera}} {{Robot {name}}} {{Name Camera}} {{Client 127.0.0.1:{viewer.local_port}}}")
            first.step(0.1)
            picture = viewer.picture()
            assert picture.shape == (HEIGHT, WIDTH, 3)
            ground = picture[GROUND_ROWS]
            brightness = picture.mean(axis=2)
            # the ground reaches the robot: the camera does not look through the near road
            # at the sky behind the world
            assert sky_share(ground) < 0.02, (place, sky_share(ground))
            assert ground.mean() > MIN_GROUND_MEAN, (place, ground.mean())
            assert picture.mean() > MIN_MEAN, (place, picture.mean())
            assert np.percentile(brightness, 5) > MIN_DARK_PERCENTILE, (place, np.percentile(brightness, 5))
    finally:
        viewer.close()
