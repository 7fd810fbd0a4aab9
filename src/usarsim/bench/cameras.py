"""``usarsim bench --cameras``: frames per second a client gets through the image server,
beside bare MuJoCo rendering plus JPEG encoding of the same view, and what textures cost."""

from __future__ import annotations

import json
import os
import queue
import statistics
import threading
import time

from usarsim.bench.serving import ServedApp, fetch_picture, logging_quiet

ROUNDS = 5  # the camera bench alternates this many served and bare runs and takes the medians

BEYOND_COLOUR = ("depth", "thermal", "label")  # the pictures beyond colour (usarsim.sim.pictures)
# Robots in view: what robots' looks (tracks, hubs, pieces) cost a picture of a row of them
LINEUP = ("P2AT", "Kenaf", "Talon", "Kurt3D", "TeleMax", "P3AT")


class _ServedCamera:
    """A P2AT's camera (its physics running in real time) served by the image server of an
    Application of its own, its world built with or without textures; ``frame()`` asks for
    one JPEG picture and reads it whole.  The robot stands at its start pose, so that every
    picture compared (textured, plain, bare) shows the same view: a robot driving would
    bring a wall nearer, and what a picture costs changes with what fills it."""

    def __init__(self, world, w: int, h: int, textures: bool):
        import socket

        from usarsim.server.app import Application
        from usarsim.server.config import ServeConfig
        from usarsim.server.image import ImageSettings
        from usarsim.sim.settings import SimSettings

        self.app = Application(
            ServeConfig(
                world=world,
                sim=SimSettings(textures=textures),
                host="127.0.0.1",
                port=0,
                seed=0,
                speed=1.0,
                lockstep=False,
                truth_port=None,
                image_port=0,
                image=ImageSettings(image_type=3, width=w, height=h, max_fps=0.0),
                web_port=None,
            )
        )
        self.server = ServedApp(self.app)
        try:
            self.ctl = socket.create_connection(("127.0.0.1", self.app.control.port), timeout=30)
            pose = world.start_poses[0]
            self.ctl.sendall(
                f"INIT {{ClassName USARBot.P2AT}} {{Name Bench}} {{Start {pose.name}}}\r\n"
                "SET {Type Camera} {Robot Bench} {Name Camera} {Client 127.0.0.1}\r\n".encode()
            )
            sim = self.app.facade.sim
            deadline = time.monotonic() + 30
            while not sim.robots and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(0.5)
        except BaseException:
            self.close()  # the server's thread and sockets go with a failed start
            raise
        try:
            image = self.app.image
            assert image is not None  # image_port=0: the Application serves pictures
            self.viewer = socket.create_connection(("127.0.0.1", image.port), timeout=60)
            self.frame()  # the first picture opens the GL context
        except BaseException:
            self.close()
            raise

    def frame(self) -> None:
        fetch_picture(self.viewer)

    def fps(self, count: int) -> float:
        t0 = time.perf_counter()
        for _ in range(count):
            self.frame()
        return count / (time.perf_counter() - t0)

    def picture_kind(self, kind: str) -> None:
        """Make the camera's pictures colour, depth, thermal or label ones (SET {Opcode Picture})."""
        self.ctl.sendall(f"SET {{Type Camera}} {{Name Camera}} {{Opcode Picture}} {{Params {kind}}}\r\n".encode())
        time.sleep(0.2)  # carried out (real time); the next picture is of that kind
        self.frame()

    def close(self) -> None:
        for s in (getattr(self, "viewer", None), getattr(self, "ctl", None)):
            if s is not None:
                s.close()
        self.server.stop()


class _BareRenderer:
    """The served camera's view rendered and JPEG-encoded directly with MuJoCo's offscreen
    renderer, on a thread of its own (its own GL context), from a snapshot of the same scene,
    drawn the way the image server draws (no shadows or reflections, nearest mipmap)."""

    def __init__(self, served: _ServedCamera, w: int, h: int):
        self.snap = served.app.facade.call(lambda s: s.cameras.render_snapshot()).result(30)
        self.size = (w, h)
        self.jobs: queue.Queue[int | None] = queue.Queue()
        self.times: queue.Queue[float] = queue.Queue()
        self.thread = threading.Thread(target=self._run, name="bench-bare-render")
        self.thread.start()
        self.fps(1)  # its context is open

    def _run(self) -> None:
        from usarsim.server.image import encode_picture
        from usarsim.sim.render import camera_renderer
        from usarsim.sim.robotspec import camera_fovy_deg

        w, h = self.size
        snap = self.snap
        cam = next(iter(snap.cameras.values()))
        r = camera_renderer(snap.model, w, h, shadows=False)
        snap.model.cam_fovy[cam.cam_id] = camera_fovy_deg(cam.fov_rad, w, h)
        while (count := self.jobs.get()) is not None:
            t = time.perf_counter()
            for _ in range(count):
                r.update_scene(snap.data, camera=cam.cam_id)
                encode_picture(r.render(), 3)
            self.times.put(count / (time.perf_counter() - t))
        r.close()

    def fps(self, count: int) -> float:
        self.jobs.put(count)
        return self.times.get()

    def close(self) -> None:
        self.jobs.put(None)
        self.thread.join()


def run_camera_bench(args) -> int:
    """Frames per second a client gets through the image server (a P2AT's camera bound to
    it, physics running in real time beside it) against bare MuJoCo rendering plus JPEG
    encoding of the same view in the same process, at each picture size; and, in the same
    run, what the world's textures cost: the same camera served from the world built with
    plain colours.  The three are measured in alternate runs so that all see the same load."""
    from usarsim.config.catalog import resolve_world

    logging_quiet()
    world = resolve_world(args.world)
    results = []
    for size in args.sizes:
        row = camera_result(world, size, int(args.frames))
        results.append(row)
        if not args.json:
            print(
                f"camera {row['size']}: served {row['served_fps']:.1f} frames/s through the image server; bare "
                f"MuJoCo render + JPEG {row['bare_render_jpeg_fps']:.1f} frames/s; ratio {row['ratio']:.2f}; "
                f"plain colours served {row['served_plain_fps']:.1f} frames/s, textures cost "
                f"{row['textures_cost_percent']:.1f} %; the same camera's depth, thermal and label pictures served "
                f"{row['served_depth_fps']:.1f}, {row['served_thermal_fps']:.1f} and {row['served_label_fps']:.1f} "
                f"frames/s; {len(LINEUP)} robots in view {row['robots_look_fps']:.1f} frames/s with their looks, "
                f"{row['robots_plain_fps']:.1f} as solid pieces only (looks cost {row['look_cost_percent']:.1f} %)"
            )
    if args.json:
        print(json.dumps(results))
    return 0


def look_cost(w: int, h: int, frames: int) -> dict:
    """Render plus JPEG frames a second of a picture of LINEUP's robots in a row, filling it,
    drawn with their looks and as their solid pieces only (alternately, ROUNDS times; medians),
    the way the image server draws (no shadows)."""
    from usarsim.config.catalog import robot_files
    from usarsim.config.robot import load_robot
    from usarsim.server.image import encode_picture
    from usarsim.sim.gallery import robots_scene
    from usarsim.sim.render import SEEN, camera_renderer

    files = robot_files()
    robots = [load_robot(files[name]) for name in LINEUP]
    per_round = max(5, frames // ROUNDS)
    views = []
    for look in (True, False):
        m, d, middle = robots_scene(robots, look=look)
        cam = mujoco_camera(middle, distance=4.0)
        views.append((camera_renderer(m, w, h, shadows=False), d, cam))
    runs: list[list[float]] = [[], []]
    try:
        for _ in range(ROUNDS):
            for k, (r, d, cam) in enumerate(views):
                t = time.perf_counter()
                for _ in range(per_round):
                    r.update_scene(d, cam, SEEN)
                    encode_picture(r.render(), 3)
                runs[k].append(per_round / (time.perf_counter() - t))
    finally:
        for r, _, _ in views:
            r.close()
    dressed, plain = statistics.median(runs[0]), statistics.median(runs[1])
    return {
        "robots_look_fps": round(dressed, 2),
        "robots_plain_fps": round(plain, 2),
        "look_cost_percent": round(100.0 * (1.0 - dressed / plain), 1),
    }


def mujoco_camera(lookat, distance: float):
    """A free camera ``distance`` from ``lookat``, ahead of the row and a little above."""
    import mujoco

    cam = mujoco.MjvCamera()
    cam.lookat[:] = lookat
    cam.distance, cam.azimuth, cam.elevation = distance, 180.0, -15.0
    return cam


def camera_result(world, size: tuple[int, int], frames: int) -> dict:
    """One picture size of the camera bench (``frames`` a camera, at least 5): what
    ``usarsim bench --cameras --json`` prints for it."""
    w, h = size
    frames = max(5, int(frames))
    opened: list[_ServedCamera | _BareRenderer] = []
    try:
        textured = _ServedCamera(world, w, h, textures=True)
        opened.append(textured)
        plain = _ServedCamera(world, w, h, textures=False)
        opened.append(plain)
        bare = _BareRenderer(textured, w, h)
        opened.append(bare)
        served_runs, plain_runs, bare_runs = [], [], []
        kind_runs: dict[str, list[float]] = {k: [] for k in BEYOND_COLOUR}
        per_round = max(5, frames // ROUNDS)
        for _ in range(ROUNDS):
            served_runs.append(textured.fps(per_round))
            plain_runs.append(plain.fps(per_round))
            bare_runs.append(bare.fps(per_round))
            for kind in BEYOND_COLOUR:  # the same camera's pictures of the other kinds (PNG frames)
                textured.picture_kind(kind)
                kind_runs[kind].append(textured.fps(per_round))
            textured.picture_kind("colour")
    finally:
        for o in reversed(opened):
            o.close()
    served = statistics.median(served_runs)
    plain_fps = statistics.median(plain_runs)
    bare_fps = statistics.median(bare_runs)
    cost = 100.0 * (1.0 - served / plain_fps)
    return {
        "size": f"{w}x{h}",
        "served_fps": round(served, 2),
        "bare_render_jpeg_fps": round(bare_fps, 2),
        "ratio": round(served / bare_fps, 3),
        "served_plain_fps": round(plain_fps, 2),
        "textures_cost_percent": round(cost, 1),
        **{f"served_{k}_fps": round(statistics.median(kind_runs[k]), 2) for k in BEYOND_COLOUR},
        **look_cost(w, h, frames),
        "frames": frames,
        "world": world.name,
        "cpu_count": os.cpu_count(),
    }
