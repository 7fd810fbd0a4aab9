"""The image server (protocol.md 10, 11) as a USARSim image client meets it: pictures of
what robot cameras see, raw and JPEG frames, sub-rectangles, zoom, the MultiView and
camera bindings.  Rendering needs an OpenGL context (Mesa EGL on a machine without a
GPU); where none can be made these tests are skipped, with the reason."""

from __future__ import annotations

import io
import socket
import struct

import numpy as np
import pytest

from helpers import DEFAULT_TIMEOUT, gl_problem, segments

IMAGE_WORLD = """\
name: CameraRange
description: four coloured walls, one in front of each of four robots (tests only)
floor: {center: [0.0, 0.0], size: [30.0, 30.0]}
materials:
  red: {rgba: [0.9, 0.05, 0.05, 1.0]}
  green: {rgba: [0.05, 0.85, 0.05, 1.0]}
  blue: {rgba: [0.05, 0.05, 0.9, 1.0]}
  white: {rgba: [0.95, 0.95, 0.95, 1.0]}
objects:
  - {name: red_wall, shape: box, center: [1.3, -6.0, -0.75], size: [0.1, 1.8, 1.5], material: red}
  - {name: green_wall, shape: box, center: [1.3, -2.0, -0.75], size: [0.1, 1.8, 1.5], material: green}
  - {name: blue_wall, shape: box, center: [1.3, 2.0, -0.75], size: [0.1, 1.8, 1.5], material: blue}
  - {name: white_wall, shape: box, center: [1.3, 6.0, -0.75], size: [0.1, 1.8, 1.5], material: white}
  # a white wall with a red stripe, for the zoom
  - {name: stripe_back, shape: box, center: [1.3, 10.0, -0.75], size: [0.1, 3.0, 1.5], material: white}
  - {name: stripe, shape: box, center: [1.24, 10.0, -0.75], size: [0.02, 0.2, 1.5], material: red}
start_poses:
  - {name: Red, location: [0.0, -6.0, -0.25]}
  - {name: Green, location: [0.0, -2.0, -0.25]}
  - {name: Blue, location: [0.0, 2.0, -0.25]}
  - {name: White, location: [0.0, 6.0, -0.25]}
  - {name: Stripe, location: [0.0, 10.0, -0.25]}
"""
COLOURS = {"Red": (1, 0, 0), "Green": (0, 1, 0), "Blue": (0, 0, 1), "White": (1, 1, 1)}


GL_PROBLEM = gl_problem()
pytestmark = pytest.mark.skipif(bool(GL_PROBLEM), reason=GL_PROBLEM or "ok")


@pytest.fixture(scope="module")
def image_world(tmp_path_factory):
    from usarsim.config.world_file import load_world

    p = tmp_path_factory.mktemp("img") / "CameraRange.yaml"
    p.write_text(IMAGE_WORLD)
    return load_world(p)


class Viewer:
    """A USARSim image client: sends OK (or U x y w h), reads type, length, payload."""

    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=DEFAULT_TIMEOUT)

    @property
    def local_port(self) -> int:
        return self.sock.getsockname()[1]

    def _read(self, n: int) -> bytes:
        out = bytearray()
        while len(out) < n:
            chunk = self.sock.recv(n - len(out))
            assert chunk, "the image server closed the connection"
            out += chunk
        return bytes(out)

    def frame(self, rect=None) -> tuple[int, bytes]:
        if rect is None:
            self.sock.sendall(b"OK\r\n")
        else:
            self.sock.sendall(b"U" + struct.pack(">IIII", *rect))
        kind, length = struct.unpack(">BI", self._read(5))
        return kind, self._read(length)

    def picture(self, rect=None) -> np.ndarray:
        """The next frame as RGB (height x width x 3)."""
        kind, payload = self.frame(rect)
        if kind == 0:
            w, h = struct.unpack(">HH", payload[:4])
            assert len(payload) == 4 + 3 * w * h
            return np.frombuffer(payload[4:], dtype=np.uint8).reshape(h, w, 3)[:, :, ::-1]
        from PIL import Image

        assert payload[:2] == b"\xff\xd8"  # a JPEG file
        return np.asarray(Image.open(io.BytesIO(payload)).convert("RGB"))

    def close(self) -> None:
        self.sock.close()


def colour_of(pixels: np.ndarray) -> tuple[int, int, int]:
    """Which of red, green, blue dominate a patch (1 where a channel is strong)."""
    mean = pixels.reshape(-1, 3).mean(axis=0)
    return tuple(int(c > 0.5 * mean.max() and c > 40) for c in mean)


def serve(server_factory, image_world, **settings):
    from usarsim.server.image import ImageSettings

    return server_factory(world=image_world, image=ImageSettings(**settings))


def spawn(srv, name: str, start: str):
    c = srv.connect()
    c.nfo()
    c.send(f"INIT {{ClassName USARBot.P2AT}} {{Name {name}}} {{Start {start}}}")
    return c


def bound_viewer(srv, start: str):
    """Robot R1 at ``start``, landed, and an image viewer bound to its camera."""
    robot = spawn(srv, "R1", start)
    robot.step(1.0)
    robot.send("SET {Type Camera} {Robot R1} {Name Camera} {Client 127.0.0.1}")
    robot.step(0.1)
    return robot, Viewer(srv.app.image.port)


def test_a_camera_facing_a_red_wall_sends_a_red_jpeg(server_factory, image_world):
    srv = serve(server_factory, image_world)
    robot, viewer = bound_viewer(srv, "Red")
    kind, payload = viewer.frame()
    assert kind == 3  # JPEG "normal" by default
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(payload)).convert("RGB"))
    assert img.shape == (480, 640, 3)
    centre = img[200:280, 280:360]
    assert colour_of(centre) == (1, 0, 0), centre.reshape(-1, 3).mean(axis=0)
    viewer.close()


def test_a_raw_frame_decodes_to_its_size_and_u_returns_the_rectangle(server_factory, image_world):
    srv = serve(server_factory, image_world, image_type=0, width=320, height=240)
    robot, viewer = bound_viewer(srv, "Green")
    kind, payload = viewer.frame()
    assert kind == 0
    w, h = struct.unpack(">HH", payload[:4])
    assert (w, h) == (320, 240) and len(payload) == 4 + 3 * 320 * 240
    full = np.frombuffer(payload[4:], dtype=np.uint8).reshape(h, w, 3)  # B, G, R
    assert colour_of(full[100:140, 140:180][:, :, ::-1]) == (0, 1, 0)
    part = viewer.picture(rect=(10, 20, 100, 50))  # lock-step: the same instant, the same picture
    assert part.shape == (50, 100, 3)
    assert np.array_equal(part, full[20:70, 10:110][:, :, ::-1])
    edge = viewer.picture(rect=(300, 230, 100, 100))  # cut to the picture
    assert edge.shape == (10, 20, 3)
    viewer.close()


def test_zoom_changes_what_is_seen(server_factory, image_world):
    srv = serve(server_factory, image_world, image_type=0, width=320, height=240)
    robot, viewer = bound_viewer(srv, "Stripe")

    def red_share(img):
        return float(np.mean((img[:, :, 0] > 120) & (img[:, :, 1] < 80)))

    wide = red_share(viewer.picture())
    robot.send("SET {Type Camera} {Name Camera} {Opcode Zoom} {Params 0.35}")
    res = [ln.text for ln in robot.step(0.1) if ln.text.startswith("RES")]
    assert res and "{Status OK}" in res[0]
    narrow = red_share(viewer.picture())
    assert 0.02 < wide and narrow > 2.0 * wide  # zoomed in, the stripe fills more of the picture
    viewer.close()


def test_the_multiview_tiles_four_robots_where_their_sta_view_says(server_factory, image_world):
    srv = serve(server_factory, image_world, image_type=0)
    clients = {}
    for name in ("Red", "Green", "Blue", "White"):
        clients[name] = spawn(srv, f"Robot{name}", name)
        clients[name].step(0.05)
    views = {}
    for name, c in clients.items():
        sta = [ln.text for ln in c.step(1.0) if ln.text.startswith("STA")][-1]
        views[name] = int(segments(sta)["View"])
    assert sorted(views.values()) == [0, 1, 2, 3]
    viewer = Viewer(srv.app.image.port)
    img = viewer.picture()
    assert img.shape == (480, 640, 3)  # 2 x 2 tiles of 320 x 240 (CameraNum 4, WideMode 0)
    for name, view in views.items():
        x, y = (view % 2) * 320, (view // 2) * 240
        tile = img[y + 100 : y + 140, x + 140 : x + 180]
        assert colour_of(tile) == COLOURS[name], (name, view, tile.reshape(-1, 3).mean(axis=0))
    viewer.close()


def test_sta_view_follows_the_robots_that_come_and_go(server_factory, image_world):
    srv = serve(server_factory, image_world, image_type=0)
    red = spawn(srv, "RobotRed", "Red")
    red.step(0.05)
    green = spawn(srv, "RobotGreen", "Green")

    def view_of(c) -> int:
        return int(segments([ln.text for ln in c.step(0.5) if ln.text.startswith("STA")][-1])["View"])

    assert view_of(green) == 1
    red.close()  # its robot is removed: Green moves up to the first tile
    for _ in range(50):
        if srv.on_sim(lambda sim: len(sim.robots)) == 1:
            break
        green.step(0.05)
    assert view_of(green) == 0
    blue = spawn(srv, "RobotBlue", "Blue")
    assert view_of(blue) == 1 and view_of(green) == 0


def test_two_viewers_bound_to_two_robots_see_two_pictures(server_factory, image_world):
    srv = serve(server_factory, image_world, image_type=0, width=160, height=120)
    red = spawn(srv, "A", "Red")
    spawn(srv, "B", "Blue")
    red.step(1.0)
    v1, v2 = Viewer(srv.app.image.port), Viewer(srv.app.image.port)
    red.send(f"SET {{Type Camera}} {{Robot A}} {{Name Camera}} {{Client 127.0.0.1:{v1.local_port}}}")
    red.send(f"SET {{Type Camera}} {{Robot B}} {{Name Camera}} {{Client 127.0.0.1:{v2.local_port}}}")
    red.step(0.1)
    a, b = v1.picture(), v2.picture()
    assert colour_of(a[50:70, 70:90]) == (1, 0, 0) and colour_of(b[50:70, 70:90]) == (0, 0, 1)
    red.send(f"SET {{Type Camera}} {{Client 127.0.0.1:{v2.local_port}}}")  # released: the MultiView again
    red.step(0.1)
    assert v2.picture().shape == (480, 640, 3)
    v1.close()
    v2.close()


def test_set_viewports_answers_per_viewport(server_factory, image_world):
    srv = serve(server_factory, image_world)
    robot = spawn(srv, "R1", "Red")
    robot.step(0.2)
    res = robot.ask(
        "SET {Type Viewports} {Config SingleView} {Viewport1 Camera} {Viewport2 Disable} {Viewport3 Nothing}", "RES"
    )
    assert res.text.startswith("RES {Time ")
    assert res.text.endswith(
        "{Type Viewports} {Config SingleView} {Status OK} {Viewport1 Camera} {Status OK} "
        "{Viewport2 Disabled} {Status OK} {Viewport3 None} {Status Failed}"
    )


def test_an_omnidirectional_camera_renders_a_panorama(server_factory, image_world, tmp_path):
    """A robot with an OmniCam facing the red wall: the middle of its panorama is red (ahead),
    its two ends show what lies behind (the open floor, not red)."""
    from usarsim.config.catalog import ROBOTS_DIR

    text = (
        (ROBOTS_DIR / "P2AT.yaml")
        .read_text()
        .replace(
            "  - {type: Camera, name: Camera,",
            "  - {type: OmniCam, name: Omni, location: [0.0, 0.0, -0.3]}\n  - {type: Camera, name: Camera,",
        )
    )
    (tmp_path / "OmniBot.yaml").write_text(text.replace("class_name: P2AT", "class_name: OmniBot"))
    srv = server_factory(
        world=image_world,
        robot_dirs=(str(tmp_path),),
        image=__import__("usarsim.server.image", fromlist=["ImageSettings"]).ImageSettings(
            image_type=0, width=480, height=120
        ),
    )
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.OmniBot} {Name O} {Start Red}")
    c.step(1.0)
    c.send("SET {Type Camera} {Robot O} {Name Omni} {Client 127.0.0.1}")
    c.step(0.1)
    viewer = Viewer(srv.app.image.port)
    pano = viewer.picture()
    assert pano.shape == (120, 480, 3)
    assert colour_of(pano[40:80, 220:260]) == (1, 0, 0)  # straight ahead
    for edge in (pano[40:80, 0:20], pano[40:80, 460:480]):  # straight behind
        assert colour_of(edge) != (1, 0, 0)
    viewer.close()


def test_the_camera_bench_reports_served_and_bare_frame_rates():
    import json
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-m", "usarsim", "bench", "--cameras", "--sizes", "64x48", "--frames", "10", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    (row,) = json.loads(out.stdout)
    assert row["size"] == "64x48" and row["served_fps"] > 0 and row["bare_render_jpeg_fps"] > 0
    assert row["ratio"] == pytest.approx(row["served_fps"] / row["bare_render_jpeg_fps"], rel=0.01)
    # the same run serves the camera from the world in plain colours too, and says what textures cost
    assert row["served_plain_fps"] > 0
    assert row["textures_cost_percent"] == pytest.approx(
        100 * (1 - row["served_fps"] / row["served_plain_fps"]), abs=0.2
    )
    # and the same camera's depth, thermal and label pictures (PNG frames)
    assert all(row[f"served_{k}_fps"] > 0 for k in ("depth", "thermal", "label"))


def test_the_stereo_robot_renders_both_eyes(server_factory, image_world):
    """The StereoP2AT's two cameras, 0.12 m apart, see the stripe at different places."""
    srv = serve(server_factory, image_world, image_type=0, width=320, height=240)
    c = srv.connect()
    c.nfo()
    c.send("INIT {ClassName USARBot.StereoP2AT} {Name S} {Start Stripe}")
    c.step(1.0)
    v_left, v_right = Viewer(srv.app.image.port), Viewer(srv.app.image.port)
    c.send(f"SET {{Type Camera}} {{Robot S}} {{Name CameraLeft}} {{Client 127.0.0.1:{v_left.local_port}}}")
    c.send(f"SET {{Type Camera}} {{Robot S}} {{Name CameraRight}} {{Client 127.0.0.1:{v_right.local_port}}}")
    c.step(0.1)

    def stripe_column(img):
        red = (img[:, :, 0] > 120) & (img[:, :, 1] < 80)
        return float(np.nonzero(red.any(axis=0))[0].mean())

    left, right = stripe_column(v_left.picture()), stripe_column(v_right.picture())
    assert left > right + 5  # the left eye sees the stripe further right (parallax)
    v_left.close()
    v_right.close()


def test_the_headlight_lights_what_the_camera_sees(server_factory, tmp_path):
    from usarsim.config.world_file import load_world

    dim = IMAGE_WORLD.replace(
        "materials:",
        "ambient_light: [0.0, 0.0, 0.0]\nlights:\n"
        "  - {name: moon, type: directional, direction: [0.0, 0.0, 1.0], intensity: 0.05}\n"
        "materials:",
        1,
    )
    (tmp_path / "Dim.yaml").write_text(dim.replace("name: CameraRange", "name: Dim"))
    from usarsim.server.image import ImageSettings

    srv = server_factory(
        world=load_world(tmp_path / "Dim.yaml"), image=ImageSettings(image_type=0, width=160, height=120)
    )
    robot, viewer = bound_viewer(srv, "White")
    dark = viewer.picture()[40:80, 60:100].mean()
    robot.send("DRIVE {Light True}")
    robot.step(0.2)
    lit = viewer.picture()[40:80, 60:100].mean()
    assert lit > dark + 20, (dark, lit)
    viewer.close()
