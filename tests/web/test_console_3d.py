"""The console's 3-D view and plots: the world rendered by the simulator from a free camera
that the page moves (left-drag orbits, right-drag pans, the wheel zooms, Follow keeps the
attached robot in the middle), and small plots of the attached robot's speed, battery and
nearest obstacle over the last 60 s of simulated time.

The render path is also tested without a browser: the render thread's free camera, and the
console's ``/api/view3d`` endpoint.  Screenshots go to tests/artifacts/; with
``USARSIM_DOCS_IMAGES=1`` the 3-D view with a robot in it is also saved as
docs/images/console-3d.png."""

from __future__ import annotations

import colorsys
import io
import json
import math
import os
import threading
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from helpers import DEFAULT_TIMEOUT, wait_for
from webtools import gl_problem, truth

ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = ROOT / "tests" / "artifacts"
DOCS_IMAGE = ROOT / "docs" / "images" / "console-3d.png"
DOCS_IMAGE_MAX_BYTES = 150_000
DEG_PER_PX = 0.3  # view3d.js: degrees of azimuth per pixel dragged

needs_gl = pytest.mark.skipif(bool(gl_problem()), reason="pictures need an OpenGL context (MUJOCO_GL=egl)")


def picture(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)


def azimuth_change(a: float, b: float) -> float:
    """b - a in degrees, within -180..180."""
    return math.remainder(b - a, 360.0)


def eye(cam: dict) -> np.ndarray:
    """Where MuJoCo's free camera is (its frame): ``distance`` back from the point it looks at."""
    az, el = math.radians(cam["azimuth"]), math.radians(cam["elevation"])
    fwd = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    return np.asarray(cam["lookat"], dtype=float) - cam["distance"] * fwd


def yellow(img: np.ndarray) -> np.ndarray:
    """The pixels of DM-USAR_yellow's yellow walls."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 100) & (g > 90) & (b < 0.75 * np.minimum(r, g))


def red(img: np.ndarray) -> np.ndarray:
    """The pixels of a P2AT's red body."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 90) & (r > 2 * g) & (r > 2 * b)


def wait_for_frame_after(page, frames: int) -> dict:
    """The camera of the first 3-D view picture after ``frames`` pictures, once no other is asked for."""
    page.wait_for_function(
        """(n) => { const v = window.usarsimConsole.view3d;
        return v.frames > n && !v.busy && !v.wanted && !v.drag; }""",
        arg=frames,
    )
    return page.evaluate("({ ...window.usarsimConsole.view3d.shown, frames: window.usarsimConsole.view3d.frames })")


# the browser ---------------------------------------------------------------------------------


@needs_gl
def test_the_3d_view_shows_the_arena_and_a_drag_orbits_the_camera(console_page, console_server):
    page = console_page.open().page
    view = page.locator("#view3d")
    page.wait_for_function("(document.getElementById('view3d').dataset.frames | 0) >= 1", timeout=30000)
    first = wait_for_frame_after(page, 0)
    # the default: the arena from above at an angle, seen along +X as the map shows it
    assert first["azimuth"] == 0 and -80 < first["elevation"] < -30 and first["distance"] > 10, first
    assert first["follow"] is None and first["width"] >= 200 and first["height"] >= 200, first
    # framed: the arena (the outer walls, 12.1 m by 14.5 m, on a floor of 28 m by 22 m) is
    # in the middle, the camera about as far from it as it is wide
    static = page.evaluate("window.usarsimConsole.world.objects.filter((o) => !o.movable).flatMap((o) => o.poly)")
    xs, ys = [p[0] for p in static], [p[1] for p in static]
    centre = np.array([(min(xs) + max(xs)) / 2, -(min(ys) + max(ys)) / 2, 0.0])  # MuJoCo's frame
    size = math.hypot(max(xs) - min(xs), max(ys) - min(ys))
    assert size == pytest.approx(math.hypot(12.1, 14.5), abs=0.1)
    assert math.dist(first["lookat"][:2], centre[:2]) < 0.15 * size, (first, centre)
    assert 0.5 * size < np.linalg.norm(eye(first) - centre) < 1.4 * size, (first, size)
    ARTIFACTS.mkdir(exist_ok=True)
    before_png = view.screenshot(path=str(ARTIFACTS / "console-3d-before-orbit.png"))
    before = picture(before_png)
    assert before.std() > 15, "the 3-D view is a uniform field, not a picture of the world"
    # the walls span most of the picture's width, and a good share of it is wall
    walls = yellow(before)
    cols, rows = walls.any(axis=0).nonzero()[0], walls.any(axis=1).nonzero()[0]
    assert (cols.max() - cols.min()) > 0.75 * before.shape[1], (cols.min(), cols.max(), before.shape)
    assert (rows.max() - rows.min()) > 0.4 * before.shape[0], (rows.min(), rows.max(), before.shape)
    assert walls.mean() > 0.08, walls.mean()
    assert page.text_content("#view3d-info").startswith("az 0° · el ")
    # left-drag 200 pixels to the right: the camera orbits, 60 degrees of azimuth
    box = view.bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x - 100, y)
    page.mouse.down()
    page.mouse.move(x + 100, y, steps=10)
    page.mouse.up()
    page.wait_for_function("Math.abs(window.usarsimConsole.view3d.shown.azimuth) > 30")
    after_cam = wait_for_frame_after(page, first["frames"])
    while abs(after_cam["azimuth"] - page.evaluate("window.usarsimConsole.view3d.camera.azimuth")) > 1e-3:
        after_cam = wait_for_frame_after(page, after_cam["frames"])  # the last view asked for is the one shown
    turned = azimuth_change(first["azimuth"], after_cam["azimuth"])
    assert turned == pytest.approx(-200 * DEG_PER_PX, abs=3), after_cam
    assert after_cam["elevation"] == pytest.approx(first["elevation"], abs=1)  # a level drag keeps the elevation
    assert after_cam["distance"] == pytest.approx(first["distance"], rel=1e-3)
    assert after_cam["lookat"] == pytest.approx(first["lookat"], abs=1e-3)  # orbiting keeps the point looked at
    assert float(view.get_attribute("data-azimuth")) == pytest.approx(after_cam["azimuth"], abs=0.01)
    after = picture(view.screenshot(path=str(ARTIFACTS / "console-3d-after-orbit.png")))
    assert after.shape == before.shape
    diff = np.abs(after - before).sum(axis=2)
    # the arena seen from 60 degrees round: much of the picture is another one (the sky above it stays)
    assert diff.mean() > 25 and (diff > 60).mean() > 0.15, (diff.mean(), (diff > 60).mean())
    assert after.std() > 15
    # the wheel zooms in: a nearer camera, the same angles
    page.mouse.move(x, y)
    page.mouse.wheel(0, -400)
    zoomed = wait_for_frame_after(page, after_cam["frames"])
    while zoomed["distance"] != pytest.approx(page.evaluate("window.usarsimConsole.view3d.camera.distance"), rel=1e-4):
        zoomed = wait_for_frame_after(page, zoomed["frames"])
    assert zoomed["distance"] < 0.7 * after_cam["distance"]
    assert zoomed["azimuth"] == pytest.approx(after_cam["azimuth"], abs=0.01)
    # a right-drag pans: the point looked at moves, the angles stay
    page.mouse.move(x, y)
    page.mouse.down(button="right")
    page.mouse.move(x + 60, y + 40, steps=5)
    page.mouse.up(button="right")
    panned = wait_for_frame_after(page, zoomed["frames"])
    while panned["lookat"] != pytest.approx(page.evaluate("window.usarsimConsole.view3d.camera.lookat"), abs=1e-3):
        panned = wait_for_frame_after(page, panned["frames"])
    moved = math.dist(panned["lookat"][:2], zoomed["lookat"][:2])
    assert moved > 1.0 and panned["lookat"][2] == pytest.approx(zoomed["lookat"][2], abs=1e-6), (zoomed, panned)
    assert panned["azimuth"] == pytest.approx(zoomed["azimuth"], abs=0.01)
    # Arena: back to the arena
    page.click("#view3d-arena")
    again = wait_for_frame_after(page, panned["frames"])
    while again["azimuth"] != 0:
        again = wait_for_frame_after(page, again["frames"])
    assert again["distance"] == pytest.approx(first["distance"], rel=1e-3)
    assert again["lookat"] == pytest.approx(first["lookat"], abs=1e-3)
    # the view made wide: the arena is framed again, for the wider picture
    page.click("#view3d-wide")
    page.wait_for_selector("#world-view", state="hidden")
    page.wait_for_function("""() => { const v = window.usarsimConsole.view3d;
        return v.shown.width > 1.5 * v.shown.height && !v.busy && !v.wanted; }""")
    wide = wait_for_frame_after(page, page.evaluate("window.usarsimConsole.view3d.frames") - 1)
    assert wide["azimuth"] == 0 and wide["distance"] < 0.9 * first["distance"], (first, wide)
    assert math.dist(wide["lookat"][:2], centre[:2]) < 0.15 * size, (wide, centre)
    walls = yellow(picture(page.locator("#view3d").screenshot(path=str(ARTIFACTS / "console-3d-wide.png"))))
    cols, rows = walls.any(axis=0).nonzero()[0], walls.any(axis=1).nonzero()[0]
    # the taller of its sides now fills the picture's height
    assert (rows.max() - rows.min()) > 0.75 * walls.shape[0], (rows.min(), rows.max(), walls.shape)
    assert (cols.max() - cols.min()) > 0.4 * walls.shape[1], (cols.min(), cols.max(), walls.shape)
    page.click("#view3d-wide")
    assert console_page.errors == []


@needs_gl
def test_the_3d_view_follows_the_attached_robot(console_page, console_server):
    page = console_page.open().page
    console_page.spawn("P2AT", "PlayerStart5", "Web3D")
    page.click("#view3d-follow")
    assert page.get_attribute("#view3d-follow", "aria-pressed") == "true"
    page.wait_for_function(
        "window.usarsimConsole.view3d.shown && window.usarsimConsole.view3d.shown.follow === 'Web3D'", timeout=30000
    )
    shown = wait_for_frame_after(page, 0)
    while shown["elevation"] != page.evaluate("window.usarsimConsole.view3d.camera.elevation"):
        shown = wait_for_frame_after(page, shown["frames"])  # the chase view asked for is the one shown
    [row] = truth(console_server.app.truth.port, "Web3D")
    x, y, z = row["location"]
    # the camera looks at the robot's chassis (MuJoCo's frame: Y left, Z up)
    assert shown["lookat"] == pytest.approx([x, -y, -z], abs=0.15), (shown, row)
    # from a few metres behind it (looking where it heads) and above it
    assert 2.0 <= shown["distance"] <= 5.0, shown
    assert -40 <= shown["elevation"] <= -15, shown
    assert abs(azimuth_change(-math.degrees(row["rotation"][2]), shown["azimuth"])) < 5, (shown, row)
    cam = eye(shown)
    assert 0.8 < cam[2] - (-z) < 3.0 and cam[0] < x - 1.5, (cam, row)  # above, and behind (it faces +X)
    assert page.text_content("#view3d-info").endswith("following Web3D")
    # the robot is big in the middle of the picture
    ARTIFACTS.mkdir(exist_ok=True)
    img = picture(page.locator("#view3d").screenshot(path=str(ARTIFACTS / "console-3d-follow.png")))
    body = red(img)
    h, w = body.shape
    assert body.sum() > 0.02 * h * w, (body.sum(), h * w)
    rows, cols = body.nonzero()
    assert abs(cols.mean() - w / 2) < 0.15 * w and abs(rows.mean() - h / 2) < 0.2 * h, (cols.mean(), rows.mean(), w, h)
    # it drives forward: the pictures follow it, a few a second
    page.fill("#command", "DRIVE {Left 4} {Right 4}")
    page.press("#command", "Enter")
    wait_for(
        lambda: truth(console_server.app.truth.port, "Web3D")[0]["location"][0] > x + 0.5,
        timeout=20,
        interval=0.1,
        what="the robot to drive 0.5 m",
    )
    page.wait_for_function(f"window.usarsimConsole.view3d.shown.lookat[0] > {x + 0.4}")
    frames = page.evaluate("window.usarsimConsole.view3d.frames")
    # about 5 pictures a second while it moves (fewer on a loaded machine: waited for, not timed)
    page.wait_for_function("(n) => window.usarsimConsole.view3d.frames >= n + 3", arg=frames, timeout=15000)
    page.fill("#command", "DRIVE {Left 0} {Right 0}")
    page.press("#command", "Enter")
    # the 3-D view alone, wide, on a larger screen, from behind and above the robot: the picture of the docs
    page.set_viewport_size({"width": 1920, "height": 1080})
    page.click("#view3d-wide")
    page.wait_for_selector("#world-view", state="hidden")
    page.evaluate(
        "() => { const v = window.usarsimConsole.view3d; v.camera.azimuth = 20; v.camera.elevation = -28;"
        " v.camera.distance = 6; v.request(); }"
    )
    page.wait_for_function("""() => { const v = window.usarsimConsole.view3d;
        return v.shown.azimuth === 20 && v.shown.distance === 6 && v.shown.width > 800 && !v.busy && !v.wanted; }""")
    shot = page.locator("#view3d-panel").screenshot()  # with its buttons and the plots
    ARTIFACTS.mkdir(exist_ok=True)
    (ARTIFACTS / "console-3d.png").write_bytes(shot)
    if os.environ.get("USARSIM_DOCS_IMAGES"):
        save_docs_image(shot)
    # a right-drag pans away from the robot: following stops
    box = page.locator("#view3d").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down(button="right")
    page.mouse.move(cx - 50, cy, steps=4)
    page.mouse.up(button="right")
    assert page.get_attribute("#view3d-follow", "aria-pressed") == "false"
    last = wait_for_frame_after(page, page.evaluate("window.usarsimConsole.view3d.frames"))
    assert last["follow"] is None
    page.click("#view3d-wide")
    assert page.is_visible("#world-view")
    assert console_page.errors == []


def save_docs_image(png: bytes) -> None:
    """The screenshot as docs/images/console-3d.png: at most 960 x 540, under
    DOCS_IMAGE_MAX_BYTES (in 256 colours when the full colours are larger)."""
    from PIL import Image

    img = Image.open(io.BytesIO(png)).convert("RGB")
    img.thumbnail((960, 540))
    DOCS_IMAGE.parent.mkdir(parents=True, exist_ok=True)
    for colours in (None, 256, 128, 64):
        out = io.BytesIO()
        (img if colours is None else img.quantize(colors=colours, dither=Image.Dither.NONE)).save(
            out, "PNG", optimize=True
        )
        if out.tell() <= DOCS_IMAGE_MAX_BYTES:
            break
    DOCS_IMAGE.write_bytes(out.getvalue())


def test_the_plots_draw_the_attached_robots_speed_battery_and_nearest_obstacle(console_page, console_server):
    page = console_page.open().page
    # no robot: nothing drawn
    page.wait_for_function("document.getElementById('plot-speed').dataset.points === '0'")
    console_page.spawn("P2AT", "PlayerStart5", "WebPlotted")  # 4 m of open floor ahead
    page.fill("#command", "DRIVE {Left 3} {Right 3}")  # 0.39 m/s: 3 rad/s on wheels of 0.13 m radius
    page.press("#command", "Enter")
    page.wait_for_function("(Number(document.getElementById('plot-speed').dataset.latest) || 0) > 0.2", timeout=20000)
    # five simulated seconds of each: lines some pixels long
    page.wait_for_function(
        """() => { const t = window.usarsimConsole.selected.track;
        return [t.speed, t.battery, t.obstacle].every((s) => s.t.length > 1 && s.t[s.t.length - 1] - s.t[0] >= 5); }""",
        timeout=20000,
    )
    page.wait_for_timeout(300)  # drawn again
    latest = page.evaluate("""() => { const p = window.usarsimConsole.plots;
        return { speed: p.speed.latest, battery: p.battery.latest, obstacle: p.obstacle.latest,
                 points: [p.speed.points, p.battery.points, p.obstacle.points] }; }""")
    assert 0.2 < latest["speed"] < 0.6, latest
    assert 0 < latest["battery"] <= 20000, latest  # seconds of charge left (STA's Battery)
    conf = page.evaluate("window.usarsimConsole.selected.conf.RangeScanner")
    max_range = float(next(iter(conf.values()))["MaxRange"]) if conf else 20.0
    assert 0 < latest["obstacle"] <= max_range + 1e-6, latest
    assert all(n >= 2 for n in latest["points"]), latest
    # the nearest obstacle is the least range of the laser's last sweep
    least = page.evaluate("""() => { const r = window.usarsimConsole.selected.latest('RangeScanner');
        const f = Object.fromEntries([...r.named.values()][0]);
        return Math.min(...f.Range.split(',').map(Number)); }""")
    assert latest["obstacle"] == pytest.approx(least, abs=0.5)
    # each plot is drawn: its line's colour is on its canvas
    drawn = page.evaluate("""() => ['plot-speed', 'plot-battery', 'plot-obstacle'].map((id) => {
        const c = document.getElementById(id);
        const d = c.getContext('2d').getImageData(0, 14, c.width, c.height - 14).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (Math.max(d[i], d[i + 1], d[i + 2]) - Math.min(d[i], d[i + 1], d[i + 2]) > 80) n++;
        return n; })""")
    assert all(n > 3 for n in drawn), drawn
    page.fill("#command", "DRIVE {Left 0} {Right 0}")
    page.press("#command", "Enter")
    page.wait_for_function(
        """() => { const v = document.getElementById('plot-speed').dataset.latest;
        return v !== '' && Number(v) < 0.05; }""",
        timeout=20000,
    )
    assert console_page.errors == []


# the render path, without a browser ------------------------------------------------------------

GREEN_FLOOR_WORLD = """\
name: GreenFloor
description: a green floor with one red block (tests only); the default light, 10 m above the floor's centre, is far from the origin
floor:
  center: [30.0, 0.0]
  size: [80.0, 80.0]
materials:
  floor: {rgba: [0.2, 0.6, 0.25, 1.0]}
  block: {rgba: [0.8, 0.15, 0.1, 1.0]}
objects:
  - {name: block, shape: box, center: [4.0, 2.0, -0.5], size: [1.0, 1.0, 1.0], material: block}
start_poses:
  - {name: Middle, location: [0.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""


@pytest.fixture(scope="module")
def free_camera(tmp_path_factory):
    """The render thread of a simulation of GreenFloor, and a function that renders one
    free-camera picture with it."""
    from usarsim.config.catalog import resolve_world
    from usarsim.sim.facade import SimFacade

    path = tmp_path_factory.mktemp("worlds") / "GreenFloor.yaml"
    path.write_text(GREEN_FLOOR_WORLD)
    facade = SimFacade(resolve_world(str(path)), lockstep=True)
    facade.start()
    renderer = facade.render_service(0)

    def render(width=160, height=120, **camera):
        return renderer.render_free(width, height, **camera).result(60)

    yield render
    renderer.stop()
    facade.stop()


@needs_gl
def test_the_free_camera_sees_the_world_from_the_angle_asked(free_camera):
    at = {"lookat": (0.0, 0.0, 0.0), "elevation": -35.0, "distance": 12.0}
    a, cam_a = free_camera(azimuth=0.0, **at)
    b, cam_b = free_camera(azimuth=180.0, **at)
    assert a.shape == b.shape == (120, 160, 3) and a.dtype == np.uint8
    assert cam_a["azimuth"] == 0.0 and cam_b["azimuth"] == 180.0 and cam_a["fovy"] > 0
    assert cam_a["lookat"] == [0.0, 0.0, 0.0] and cam_a["follow"] is None
    diff = np.abs(a.astype(int) - b.astype(int)).sum(axis=2)
    assert (diff > 60).mean() > 0.02, "two azimuths gave the same picture"
    # the red block (x 4, y 2 in USARSim's frame: right of the line of sight along +X) is seen
    # right of the middle looking along +X, left of it from the other side
    red = [((p[:, :, 0] > 40) & (p[:, :, 0] > 2 * p[:, :, 1].astype(int))).nonzero()[1] for p in (a, b)]
    assert len(red[0]) > 20 and len(red[1]) > 20, "the red block is not in the pictures"
    assert red[0].mean() > 85 and red[1].mean() < 75, (red[0].mean(), red[1].mean())


@needs_gl
def test_the_free_camera_straight_above_sees_the_floors_colour_in_the_middle(free_camera):
    top, cam = free_camera(lookat=(0.0, 0.0, 0.0), azimuth=0.0, elevation=-90.0, distance=5.0)
    middle = top[50:70, 70:90].reshape(-1, 3).mean(axis=0) / 255
    # lit, not painted: darker or brighter, whitened by the light's reflection, but the floor's hue
    hue, _, saturation = colorsys.rgb_to_hls(*middle)
    floor_hue = colorsys.rgb_to_hls(0.2, 0.6, 0.25)[0]
    assert abs(math.remainder(hue - floor_hue, 1.0)) * 360 < 8 and saturation > 0.2, (middle * 255, hue * 360)
    assert cam["elevation"] == -90.0
    # following a robot that is not in the world: the point given is kept
    _, cam = free_camera(lookat=(1.0, 2.0, 0.0), azimuth=0.0, elevation=-90.0, distance=5.0, follow="Nobody")
    assert cam["lookat"] == [1.0, 2.0, 0.0] and cam["follow"] is None


def fetch(url: str) -> tuple[int, dict, bytes]:
    try:
        with urllib.request.urlopen(url, timeout=DEFAULT_TIMEOUT * 3) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as exc:
        return exc.code, dict(exc.headers), exc.read()


@needs_gl
def test_the_view3d_endpoint_answers_a_jpeg_of_the_camera_asked(console_server):
    base = f"http://127.0.0.1:{console_server.app.web.port}/api/view3d"
    status, headers, body = fetch(f"{base}?lookat=5,0,0&azimuth=400&elevation=-120&distance=30&width=320&height=240")
    assert status == 200 and headers["Content-Type"] == "image/jpeg", (status, headers, body[:200])
    assert body[:3] == b"\xff\xd8\xff"  # a JPEG file
    view = json.loads(headers["X-View"])
    # what was rendered: the azimuth within -180..180, the elevation within -90..90
    assert view["azimuth"] == pytest.approx(40.0) and view["elevation"] == -90.0 and view["distance"] == 30.0
    assert view["lookat"] == [5.0, 0.0, 0.0] and (view["width"], view["height"]) == (320, 240)
    assert view["time"] >= 0 and view["follow"] is None
    img = picture(body)
    assert img.shape == (240, 320, 3) and img.std() > 5
    for bad in (
        "lookat=1,2&azimuth=0&elevation=0&distance=1&width=32&height=32",
        "lookat=0,0,0&azimuth=nan&elevation=0&distance=1&width=32&height=32",
        "lookat=0,0,0&azimuth=0&elevation=0&distance=1&width=99999&height=32",
        "lookat=0,0,0&azimuth=0&elevation=0&distance=1&width=32&height=32&follow=a%20b",
        "lookat=0,0,0&elevation=0&distance=1&width=32&height=32",
    ):
        status, _, body = fetch(f"{base}?{bad}")
        assert status == 400 and json.loads(body)["error"], bad


@needs_gl
def test_the_view3d_endpoint_never_holds_the_clock(console_server):
    """Pictures asked for one after another while the world runs in real time: the
    simulated clock goes on meanwhile (rendering works on snapshots)."""
    base = f"http://127.0.0.1:{console_server.app.web.port}/api/view3d"
    facade = console_server.app.facade
    stop = threading.Event()
    served = []

    def ask() -> None:
        while not stop.is_set():
            served.append(
                fetch(f"{base}?lookat=0,0,0&azimuth={len(served) * 7}&elevation=-45&distance=25&width=480&height=360")[
                    0
                ]
            )

    t0 = facade.time
    worker = threading.Thread(target=ask)
    worker.start()
    try:
        wait_for(
            lambda: facade.time > t0 + 1.0,
            timeout=DEFAULT_TIMEOUT,
            interval=0.05,
            what="the clock to go on while pictures are made",
        )
    finally:
        stop.set()
        worker.join(DEFAULT_TIMEOUT * 3)
    assert served and all(s == 200 for s in served), served
