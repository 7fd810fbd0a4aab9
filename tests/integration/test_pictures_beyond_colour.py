"""Depth, thermal and label pictures through the image server (an extension: PNG frames, type
6): a depth picture reads a wall at its distance from the lens, the thermal picture's hottest
blob is the victim in view at skin temperature with the walls at the room's, and the label
picture's victim pixels are where the colour picture shows the victim's skin.  A camera is
made one kind or another by its robot file (DepthCamera, ThermalCamera, LabelCamera) or by
``SET {Type Camera} {Name n} {Opcode Picture} {Params depth}``.  Rendering needs an OpenGL
context; where none can be made these tests are skipped, with the reason."""

from __future__ import annotations

import numpy as np
import pytest
from test_image_server import Viewer
from test_pictures import skin_mask

from helpers import gl_problem
from usarsim.protocol import upis
from usarsim.sim import pictures

GL_PROBLEM = gl_problem()
pytestmark = pytest.mark.skipif(bool(GL_PROBLEM), reason=GL_PROBLEM or "ok")

WALL_FACE_X = 4.0
WORLD = """\
name: VictimRoom
description: a wall ahead and a victim lying across the view (tests only)
floor: {center: [0.0, 0.0], size: [20.0, 20.0]}
materials:
  wall: {rgba: [0.85, 0.85, 0.80, 1.0]}
objects:
  - {name: front_wall, shape: box, center: [4.05, 0.0, -1.0], size: [0.1, 8.0, 2.0], material: wall}
victims:
  - {name: Dana, location: [2.0, 0.3, -0.1], rotation: [0.0, 0.0, 1.5708]}
start_poses:
  - {name: Start, location: [0.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    from usarsim.config.world_file import load_world

    p = tmp_path_factory.mktemp("pics") / "VictimRoom.yaml"
    p.write_text(WORLD)
    return load_world(p)


def png_picture(viewer: Viewer) -> np.ndarray:
    import cv2

    kind, payload = viewer.frame()
    assert kind == upis.PNG and payload[:8] == b"\x89PNG\r\n\x1a\n"
    return cv2.imdecode(np.frombuffer(payload, np.uint8), cv2.IMREAD_UNCHANGED)


def robot_with_viewer(server_factory, room):
    from usarsim.server.image import ImageSettings

    srv = server_factory(world=room, image=ImageSettings(width=320, height=240, image_type=0))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.P2AT} {Name R1} {Start Start}")
    c.step(1.0)
    c.send("SET {Type Camera} {Robot R1} {Name Camera} {Client 127.0.0.1}")
    c.step(0.1)
    return srv, c, Viewer(srv.app.image.port)


def set_picture(c, word: str) -> str:
    c.send(f"SET {{Type Camera}} {{Name Camera}} {{Opcode Picture}} {{Params {word}}}")
    return next(ln.text for ln in c.step(0.01) if ln.text.startswith("RES"))


def test_a_depth_picture_reads_the_wall_at_its_distance_from_the_lens(server_factory, room):
    srv, c, viewer = robot_with_viewer(server_factory, room)
    try:
        assert set_picture(c, "depth").endswith("{Status OK}")
        depth = png_picture(viewer)
        assert depth.dtype == np.uint16 and depth.shape == (240, 320)

        def lens_x(sim) -> float:
            from usarsim.sim.robotspec import camera_name

            return float(sim.data.cam_xpos[sim.model.camera(camera_name(sim.robots[1].prefix, "Camera")).id][0])

        x = srv.on_sim(lens_x)
        wall_mm = (WALL_FACE_X - x) * 1000.0
        top = depth[:60].astype(float)  # above the victim: the wall, a plane square to the axis
        assert np.median(top) == pytest.approx(wall_mm, abs=10.0)
        assert top.std() < 10.0
        assert depth[200].max() < wall_mm  # lower rows: the floor and the victim, nearer
        c.send("GETCONF {Type Camera} {Name Camera}")
        conf = next(ln.text for ln in c.step(0.01) if ln.text.startswith("CONF"))
        assert conf.endswith("{PrincipalPoint 160.0000,120.0000} {Picture depth}")
    finally:
        viewer.close()


def test_the_thermal_pictures_hottest_blob_is_the_victim_and_labels_match_the_colour_picture(server_factory, room):
    srv, c, viewer = robot_with_viewer(server_factory, room)
    try:
        assert set_picture(c, "label").endswith("{Status OK}")
        label = png_picture(viewer)  # B, G, R: instance low, high; class
        classes = label[..., 2]
        victim = classes == pictures.VICTIM
        assert victim.sum() > 500
        assert {pictures.FLOOR, pictures.WALL, pictures.VICTIM} <= set(np.unique(classes).tolist())
        assert set(((label[..., 1].astype(int) << 8) | label[..., 0])[victim].tolist()) == {1}  # Dana, the first

        assert set_picture(c, "thermal").endswith("{Status OK}")
        thermal = png_picture(viewer).astype(float) * pictures.THERMAL_STEP_C
        assert thermal.shape == (240, 320)
        hot = thermal > 32.0
        assert hot.sum() > 100
        assert (hot & victim).sum() >= 0.95 * hot.sum()  # the hottest blob is the victim
        assert thermal.max() == pytest.approx(pictures.SKIN_C, abs=0.5)
        wall = classes == pictures.WALL
        assert np.median(thermal[wall]) == pytest.approx(pictures.AMBIENT_C, abs=0.3)

        assert set_picture(c, "colour").endswith("{Status OK}")
        colour = viewer.picture()  # raw RGB again
        skin = skin_mask(colour)
        assert skin.sum() > 50
        assert (skin & victim).sum() >= 0.9 * skin.sum()  # the skin seen in colour is the victim's
        assert set_picture(c, "sepia").endswith("{Status Failed}")
    finally:
        viewer.close()


def test_camera_kinds_from_the_robot_file(tmp_path):
    from usarsim.config.catalog import resolve_robot
    from usarsim.sensors import make_item
    from usarsim.sensors.camera import Camera

    p2at = resolve_robot("P2AT")
    (cam,) = [i for i in p2at.items if i.item_type == "Camera"]
    import dataclasses

    for kind, picture, size in (
        ("DepthCamera", "depth", (320, 240)),
        ("ThermalCamera", "thermal", (160, 120)),
        ("LabelCamera", "label", (320, 240)),
    ):
        item = make_item(dataclasses.replace(cam, item_type=kind), p2at, 0, "t")
        assert isinstance(item, Camera) and item.config.picture == picture
        assert (item.config.width_px, item.config.height_px) == size
    with pytest.raises(Exception, match="picture must be one of colour, depth, thermal, label"):
        make_item(dataclasses.replace(cam, params={"picture": "xray"}), p2at, 0, "t")


def test_a_thermal_camera_of_the_robot_file_is_served_at_its_own_size(server_factory, room, tmp_path):
    """The league's thermal camera: 160 x 120 pictures, whatever size the server gives colour ones."""
    from usarsim.config.catalog import ROBOTS_DIR
    from usarsim.server.image import ImageSettings

    text = (ROBOTS_DIR / "P2AT.yaml").read_text().replace("class_name: P2AT", "class_name: ThermalP2AT")
    text += "  - {type: ThermalCamera, name: Thermal, location: [0.082, 0.0, 0.04], mount: CameraPanTilt_Link2}\n"
    (tmp_path / "ThermalP2AT.yaml").write_text(text)
    srv = server_factory(world=room, robot_dirs=(str(tmp_path),), image=ImageSettings(width=640, height=480))
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.ThermalP2AT} {Name R1} {Start Start}")
    c.step(1.0)
    c.send("SET {Type Camera} {Robot R1} {Name Thermal} {Client 127.0.0.1}")
    c.step(0.1)
    viewer = Viewer(srv.app.image.port)
    try:
        thermal = png_picture(viewer)
        assert thermal.shape == (120, 160) and thermal.dtype == np.uint8
        assert thermal.max() * pictures.THERMAL_STEP_C == pytest.approx(pictures.SKIN_C, abs=0.5)  # the victim ahead
        c.send("GETCONF {Type ThermalCamera} {Name Thermal}")
        conf = next(ln.text for ln in c.step(0.01) if ln.text.startswith("CONF"))
        assert "{CameraFov 0.9948}" in conf and conf.endswith("{PrincipalPoint 80.0000,60.0000} {Picture thermal}")
    finally:
        viewer.close()
