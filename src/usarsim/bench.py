"""``usarsim bench``: the real-time factor of the whole simulator with N robots.

N P2ATs with their full sensor kit are spawned in the world, each by its own TCP
client over loopback (a separate process reads every line they are sent and
drives them); the simulator runs as fast as it can (``--speed max``) for S
simulated seconds.  Beside it, bare ``mj_step`` on the same compiled model, timed
from the scenes at the start, middle and end of the run, gives the physics-only
real-time factor; ``ratio`` = ``rtf`` / ``raw_mujoco_rtf`` is the share of the
machine that stays with physics.
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import queue
import statistics
import subprocess
import sys
import threading
import time

import numpy as np

Spot = tuple[float, float, float, float]  # x, y, z, yaw


def free_spots(world, n: int, clearance: float = 0.4, spacing: float = 0.7) -> list[Spot]:
    """Start poses first, then points of a grid ``spacing`` apart at least ``clearance`` from
    every static object and ``spacing`` from every start pose."""
    spots = _spots(world, clearance, spacing, limit=None)
    if len(spots) < n:
        raise SystemExit(f"usarsim bench: the world has room for {len(spots)} robots, {n} asked")
    return spots[:n]


def spread_spots(world, n: int, clearance: float = 0.4, spacing: float = 0.7) -> list[Spot]:
    """``n`` spots as far apart as the world's free floor allows: the start poses, then a grid
    of the widest spacing (at least ``spacing``, to the centimetre) that still has room for
    ``n``.  Robots started on a tight grid in one corner of an arena jam into each other as they
    turn; the bench measures robots that meet now and then, not one pile-up."""
    if len(_spots(world, clearance, spacing, limit=n)) < n:
        raise SystemExit(f"usarsim bench: the world has room for {len(_spots(world, clearance, spacing))} "
                         f"robots, {n} asked")
    lo, hi = spacing, spacing * 2
    while len(_spots(world, clearance, hi, limit=n)) >= n and hi < 1e3:
        lo, hi = hi, hi * 2
    while hi - lo > 0.01:  # the room for n shrinks (roughly) as the spacing grows: bisect
        mid = (lo + hi) / 2
        if len(_spots(world, clearance, mid, limit=n)) >= n:
            lo = mid
        else:
            hi = mid
    return _spots(world, clearance, lo, limit=n)


def _spots(world, clearance: float, spacing: float, limit: int | None = None) -> list[Spot]:
    """Free spots (x, y, z, yaw): the start poses, then grid points; at most ``limit``."""
    from usarsim.sim.frames import euler_to_mat

    spots = [tuple(p.location) + (p.rotation[2],) for p in world.start_poses]
    centers, halves = [], []
    for o in world.objects:
        if o.shape == "box":
            half = np.abs(euler_to_mat(*o.rotation)) @ (np.array(o.size) / 2.0)
        else:
            half = np.abs(euler_to_mat(*o.rotation)) @ np.array([o.radius_m, o.radius_m, o.length_m / 2.0])
        center = np.array(o.center)
        if center[2] - half[2] < -0.02:  # objects lower than 2 cm (plates, ramps' feet) do not block
            centers.append(center[:2])
            halves.append(half[:2])
    fl = world.floor
    xs = np.arange(fl.center[0] - fl.size[0] / 2 + 1.0, fl.center[0] + fl.size[0] / 2 - 1.0, spacing)
    ys = np.arange(fl.center[1] - fl.size[1] / 2 + 1.0, fl.center[1] + fl.size[1] / 2 - 1.0, spacing)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    grid = np.stack([gx.ravel(), gy.ravel()], axis=1)
    free = np.ones(len(grid), dtype=bool)
    if centers:  # outside every object's footprint grown by the clearance, along x or along y
        c, h = np.array(centers), np.array(halves) + clearance
        free = ~np.any(np.all(np.abs(grid[:, None, :] - c[None, :, :]) <= h[None, :, :], axis=2), axis=1)
    if spots:  # grid points lie ``spacing`` apart already; keep them as far from the start poses
        starts = np.array([sp[:2] for sp in spots])
        free &= np.all(np.linalg.norm(grid[:, None, :] - starts[None, :, :], axis=2) >= spacing * 0.99, axis=1)
    for x, y in grid[free]:
        if limit is not None and len(spots) >= limit:
            break
        spots.append((float(x), float(y), -0.25, 0.0))
    return spots if limit is None else spots[:limit]


async def _client_main(port: int, poses: list, seconds_hint: float) -> None:
    """Child process: one connection per robot, INIT, then drive and read everything."""
    conns = []
    for i, (x, y, z, yaw) in enumerate(poses):
        r, w = await asyncio.open_connection("127.0.0.1", port, limit=1 << 20)
        w.write(f"INIT {{ClassName USARBot.P2AT}} {{Name Bench{i + 1}}} {{Location {x:.2f},{y:.2f},{z:.2f}}} "
                f"{{Rotation 0,0,{yaw:.4f}}}\r\n".encode())
        conns.append((r, w))

    async def drive(i, r, w):
        lines = 0
        phase = 0
        last_t = -1.0
        try:
            while True:
                line = await r.readline()
                if not line:
                    return
                lines += 1
                if line.startswith(b"STA"):
                    t = float(line.split(b"{Time ", 1)[1].split(b"}", 1)[0])
                    if t - last_t >= 2.0:
                        last_t = t
                        phase += 1
                        left, right = ((2.0, 2.0), (-1.0, 1.0), (1.5, 1.5), (1.0, -1.0))[(phase + i) % 4]
                        w.write(f"DRIVE {{Left {left}}} {{Right {right}}}\r\n".encode())
        except (ConnectionError, OSError):
            return

    await asyncio.gather(*(drive(i, r, w) for i, (r, w) in enumerate(conns)))


class _LoopThread:
    """An event loop on a thread of its own (polling as a lock-step server's does, with
    ``lockstep``), running from once ``start()`` has run on it until ``stop_loop()``."""

    def __init__(self, lockstep: bool, name: str, start) -> None:
        from usarsim.server.polling import new_event_loop, poll_seconds

        self.loop = new_event_loop(poll_seconds(lockstep))  # as `serve` makes it
        ready = threading.Event()

        def serve():
            asyncio.set_event_loop(self.loop)
            self.loop.run_until_complete(start())
            ready.set()
            self.loop.run_forever()

        self.thread = threading.Thread(target=serve, name=name, daemon=True)
        self.thread.start()
        ready.wait(30)

    def stop_loop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(5)
        self.loop.close()


class _ServedApp(_LoopThread):
    """An Application served by its own event loop on a thread, until ``stop()``."""

    def __init__(self, app):
        self.app = app
        super().__init__(app.facade.lockstep, "bench-server", app.start)

    def stop(self) -> None:
        asyncio.run_coroutine_threadsafe(self.app.stop(), self.loop).result(120)
        self.stop_loop()


def rss_mb() -> float:
    """This process's resident memory now (MB; Linux /proc, else the peak so far)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6
    except (OSError, ValueError, IndexError):
        return peak_rss_mb()


def peak_rss_mb() -> float:
    """This process's peak resident memory so far (MB)."""
    import resource

    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return kb / 1e3 if sys.platform != "darwin" else kb / 1e6


def measure_rtf(world, n: int, seconds: float, *, record: str | None = None, progress: bool = False,
                speed: float | None = None, cameras_fps: float = 0.0, window=None) -> dict:
    """One run: N P2ATs driven over loopback at ``speed`` (None: as fast as it goes) for
    ``seconds`` of simulated time; with ``record``, recorded to that MCAP file, with every
    camera's picture ``cameras_fps`` times a simulated second (the time the recorder takes to
    write what was still queued at the end is counted in the wall time).  ``window``: an
    object whose ``start(app)`` and ``stop(app)`` are called as the measured stretch begins
    and ends (``usarsim bench --profile``).  The server runs in this process (its client in
    another): the memory figures are the simulator's."""
    from usarsim.server.app import Application

    poses = spread_spots(world, n)
    app = Application(world, host="127.0.0.1", port=0, seed=0, speed=speed, lockstep=False, max_connections=max(64, n),
                      truth_port=None, image_port=None, web_port=None, record=record, record_cameras_fps=cameras_fps)
    served = _ServedApp(app)
    rss_before = rss_mb()  # the world built, no robot yet
    port = app.control.port
    client = subprocess.Popen([sys.executable, "-m", "usarsim.bench", "--client", str(port), json.dumps(poses),
                               str(seconds)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    sim = app.facade.sim
    runner = app.facade.runner

    def running() -> None:
        if runner.error is not None:  # logged where it happened
            raise SystemExit(f"usarsim bench: the simulation stopped on an error: {runner.error!r}")

    try:
        deadline = time.monotonic() + 120
        while len(sim.robots) < n:
            if time.monotonic() > deadline or client.poll() is not None:
                raise SystemExit(f"usarsim bench: only {len(sim.robots)} of {n} robots spawned")
            running()
            time.sleep(0.01)
        # let every robot land and its client start driving
        t_settle = sim.time + 1.0
        while sim.time < t_settle:
            running()
            time.sleep(0.01)

        if window is not None:
            window.start(app)
        sim_start, wall_start = sim.time, time.perf_counter()
        states = [snapshot_state(sim, app.facade.runner)]  # the scenes bare mj_step is timed from
        while sim.time - sim_start < seconds:
            running()
            time.sleep(0.005)
            if len(states) == 1 and sim.time - sim_start >= seconds / 2:
                states.append(snapshot_state(sim, app.facade.runner))
            if progress:
                done = sim.time - sim_start
                print(f"\r  {done:7.1f} / {seconds:g} simulated s{' (recording)' if record else ''}", end="",
                      file=sys.stderr, flush=True)
        sim_end, wall_end = sim.time, time.perf_counter()
        if window is not None:
            window.stop(app)
        rss_after = rss_mb()
        if app.recorder is not None:  # what the recorder still has to write is part of the cost
            mark = app.recorder.mark()
            while app.recorder.written() < mark - 1 and time.perf_counter() - wall_end < 120:
                time.sleep(0.002)
            wall_end = time.perf_counter()
        if progress:
            print(file=sys.stderr)
        model = sim.model
        state = snapshot_state(sim, app.facade.runner)
        states.append(state)
    finally:
        client.terminate()
        client.wait(10)
        served.stop()
    sim_s = sim_end - sim_start
    wall_s = wall_end - wall_start
    return {"sim_seconds": round(sim_s, 3), "wall_seconds": round(wall_s, 3), "rtf": round(sim_s / wall_s, 3),
            "model": model, "state": state, "states": states, "physics_resets": sim.resets,
            "pictures": app.recorder.pictures if app.recorder is not None else 0,
            "peak_rss_mb": round(peak_rss_mb(), 1), "rss_per_robot_mb": round((rss_after - rss_before) / n, 2)}


def run_bench(args) -> int:
    from usarsim.config.catalog import resolve_world

    logging_quiet()
    world = resolve_world(args.world)
    n = int(args.robots)
    seconds = float(args.seconds)
    if n < 1 or not (seconds > 0 and math.isfinite(seconds)):
        print("usarsim bench: --robots must be >= 1 and --seconds > 0", file=sys.stderr)
        return 2
    progress = sys.stderr.isatty() and not args.json
    if getattr(args, "record", False):
        return _record_bench(args, world, n, seconds, progress)
    if getattr(args, "profile", False):
        return _profile_bench(args, world, n, seconds, progress)
    run = measure_rtf(world, n, seconds, progress=progress)
    model = run["model"]
    sim_s, wall_s, rtf = run["sim_seconds"], run["wall_seconds"], run["rtf"]
    raw = raw_mujoco_rtf_over(model, min(seconds, 5.0), run["states"])
    result = {"robots": n, "sim_seconds": sim_s, "wall_seconds": wall_s, "rtf": rtf,
              "raw_mujoco_rtf": round(raw, 3), "ratio": round(rtf / raw, 3), "timestep_s": model.opt.timestep,
              "world": world.name, "cpu_count": os.cpu_count(), "physics_resets": run["physics_resets"],
              "peak_rss_mb": run["peak_rss_mb"], "rss_per_robot_mb": run["rss_per_robot_mb"]}
    if args.json:
        print(json.dumps(result))
    else:
        print(f"robots {n}: {sim_s:.1f} simulated s in {wall_s:.2f} s wall -> real-time factor {rtf:.2f}; "
              f"bare mj_step {raw:.2f}; ratio {rtf / raw:.2f}; memory {run['peak_rss_mb']:.0f} MB at the peak, "
              f"{run['rss_per_robot_mb']:.1f} MB a robot")
    return 0


def _profile_bench(args, world, n: int, seconds: float, progress: bool) -> int:
    """``bench --profile``: one run with both threads profiled; the breakdown."""
    from usarsim.benchprofile import Profiler, breakdown, format_breakdown

    prof = Profiler()
    run = measure_rtf(world, n, seconds, progress=progress, window=prof)
    b = breakdown(prof)
    if args.json:
        print(json.dumps({"robots": n, "sim_seconds": run["sim_seconds"], "rtf_profiled": run["rtf"],
                          "sim_wall_s": round(b["sim_wall_s"], 3), "sim_cpu_s": round(b["sim_cpu_s"], 3),
                          "loop_wall_s": round(b["loop_wall_s"], 3), "loop_cpu_s": round(b["loop_cpu_s"], 3),
                          "sensors_wall_s": round(b["sensors_wall_s"], 3),
                          "sensors_cpu_s": round(b["sensors_cpu_s"], 3),
                          "sim": {k: round(v, 4) for k, v in b["sim"]},
                          "sensors": {k: round(v, 4) for k, v in b["sensors"]},
                          "loop": {k: round(v, 4) for k, v in b["loop"]},
                          "peak_rss_mb": run["peak_rss_mb"], "rss_per_robot_mb": run["rss_per_robot_mb"]}))
    else:
        print(f"robots {n}: {run['sim_seconds']:.1f} simulated s in {run['wall_seconds']:.2f} s wall under the "
              f"profiler (real-time factor {run['rtf']:.2f}; without it, run 'usarsim bench')")
        print(format_breakdown(b, run["sim_seconds"]))
    return 0


RECORD_ROUNDS = 3  # bench --record alternates this many runs without and with a recording
CAMERA_ROBOTS = 4  # bench --record then records this many robots' cameras in real time ...
CAMERA_FPS = 5.0  # ... at this many pictures a simulated second


def _record_bench(args, world, n: int, seconds: float, progress: bool) -> int:
    """``bench --record``: runs without and with a recording, alternately in one sitting; the
    cost in real-time factor and the recording's size per robot-minute."""
    import tempfile

    plain, recorded, sizes = [], [], []
    with tempfile.TemporaryDirectory(prefix="usarsim-bench-") as tmp:
        for k in range(RECORD_ROUNDS):
            plain.append(measure_rtf(world, n, seconds, progress=progress)["rtf"])
            path = os.path.join(tmp, f"run{k}.mcap")
            run = measure_rtf(world, n, seconds, record=path, progress=progress)
            recorded.append(run["rtf"])
            # the file holds the settling second and the spawns too: its size over all the
            # simulated time it covers
            minutes = (run["sim_seconds"] + 1.0) / 60.0
            sizes.append(os.path.getsize(path) / (n * minutes))
        # cameras: 4 robots in real time, every camera recorded at 5 pictures a simulated second
        cams = measure_rtf(world, CAMERA_ROBOTS, seconds, record=os.path.join(tmp, "cameras.mcap"), speed=1.0,
                           cameras_fps=CAMERA_FPS, progress=progress)
        cam_size = os.path.getsize(os.path.join(tmp, "cameras.mcap")) / (CAMERA_ROBOTS * (cams["sim_seconds"] + 1) / 60)
    off, on = statistics.median(plain), statistics.median(recorded)
    cost = 100.0 * (1.0 - on / off)
    per = statistics.median(sizes)
    # pictures a camera per simulated second over the measured stretch (each P2AT has one camera)
    cam_rate = cams["pictures"] / (CAMERA_ROBOTS * (cams["sim_seconds"] + 1.0))
    result = {"robots": n, "sim_seconds": seconds, "rtf": off, "rtf_recording": on, "cost_percent": round(cost, 1),
              "bytes_per_robot_minute": round(per), "runs": {"plain": plain, "recording": recorded},
              "cameras": {"robots": CAMERA_ROBOTS, "fps_asked": CAMERA_FPS, "speed": cams["rtf"],
                          "pictures_per_s": round(cam_rate, 2), "bytes_per_robot_minute": round(cam_size)},
              "world": world.name, "cpu_count": os.cpu_count()}
    if args.json:
        print(json.dumps(result))
    else:
        print(f"robots {n}: real-time factor {off:.2f} without a recording, {on:.2f} recording every channel but "
              f"cameras ({cost:.1f} % less; medians of {RECORD_ROUNDS} runs each, alternately)")
        print(f"recording size: {per / 1e6:.2f} MB per robot-minute of simulated time")
        print(f"{CAMERA_ROBOTS} robots in real time, every camera recorded at {CAMERA_FPS:g} pictures a simulated "
              f"second: the clock ran at {cams['rtf']:.2f}x real time; {cam_rate:.1f} pictures a camera per "
              f"simulated second; {cam_size / 1e6:.2f} MB per robot-minute")
    return 0


ROUNDS = 5  # the camera bench alternates this many served and bare runs and takes the medians


class _ServedCamera:
    """A P2AT's camera (its physics running in real time) served by the image server of an
    Application of its own, its world built with or without textures; ``frame()`` asks for
    one JPEG picture and reads it whole.  The robot stands at its start pose, so that every
    picture compared (textured, plain, bare) shows the same view: a robot driving would
    bring a wall nearer, and what a picture costs changes with what fills it."""

    def __init__(self, world, w: int, h: int, textures: bool):
        import socket

        from usarsim.server.app import Application
        from usarsim.server.image import ImageSettings
        from usarsim.sim.builder import TEXTURES_ENV

        before = os.environ.get(TEXTURES_ENV)
        os.environ[TEXTURES_ENV] = "1" if textures else "0"  # read while the world is built
        try:
            self.app = Application(world, host="127.0.0.1", port=0, seed=0, speed=1.0, lockstep=False,
                                   truth_port=None, image_port=0,
                                   image=ImageSettings(image_type=3, width=w, height=h, max_fps=0.0), web_port=None)
            self.server = _ServedApp(self.app)
            try:
                self.ctl = socket.create_connection(("127.0.0.1", self.app.control.port), timeout=30)
                pose = world.start_poses[0]
                self.ctl.sendall(f"INIT {{ClassName USARBot.P2AT}} {{Name Bench}} {{Start {pose.name}}}\r\n"
                                 "SET {Type Camera} {Robot Bench} {Name Camera} {Client 127.0.0.1}\r\n".encode())
                sim = self.app.facade.sim
                deadline = time.monotonic() + 30
                while not sim.robots and time.monotonic() < deadline:
                    time.sleep(0.01)
                time.sleep(0.5)
            except BaseException:
                self.close()  # the server's thread and sockets go with a failed start
                raise
        finally:
            if before is None:
                os.environ.pop(TEXTURES_ENV, None)
            else:
                os.environ[TEXTURES_ENV] = before
        try:
            self.viewer = socket.create_connection(("127.0.0.1", self.app.image.port), timeout=60)
            self.frame()  # the first picture opens the GL context
        except BaseException:
            self.close()
            raise

    def frame(self) -> None:
        import struct

        self.viewer.sendall(b"OK")
        head = b""
        while len(head) < 5:
            head += self.viewer.recv(5 - len(head))
        n = struct.unpack(">I", head[1:5])[0]
        got = 0
        while got < n:
            got += len(self.viewer.recv(min(1 << 20, n - got)))

    def fps(self, count: int) -> float:
        t0 = time.perf_counter()
        for _ in range(count):
            self.frame()
        return count / (time.perf_counter() - t0)

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
        box = {}
        done = threading.Event()
        served.app.facade.call(lambda s: s.cameras.render_snapshot(),
                               on_done=lambda r, e: (box.update(r=r), done.set()))
        done.wait(30)
        self.snap = box["r"]
        self.size = (w, h)
        self.jobs: queue.Queue[int | None] = queue.Queue()
        self.times: queue.Queue[float] = queue.Queue()
        self.thread = threading.Thread(target=self._run, name="bench-bare-render")
        self.thread.start()
        self.fps(1)  # its context is open

    def _run(self) -> None:
        from usarsim.server.image import encode_picture
        from usarsim.sim.builder import camera_fovy_deg
        from usarsim.sim.render import camera_renderer

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
    frames = max(5, int(args.frames))
    results = []
    for size in args.sizes:
        w, h = size
        opened = []
        try:
            textured = _ServedCamera(world, w, h, textures=True)
            opened.append(textured)
            plain = _ServedCamera(world, w, h, textures=False)
            opened.append(plain)
            bare = _BareRenderer(textured, w, h)
            opened.append(bare)
            served_runs, plain_runs, bare_runs = [], [], []
            per_round = max(5, frames // ROUNDS)
            for _ in range(ROUNDS):
                served_runs.append(textured.fps(per_round))
                plain_runs.append(plain.fps(per_round))
                bare_runs.append(bare.fps(per_round))
        finally:
            for o in reversed(opened):
                o.close()
        served = statistics.median(served_runs)
        plain_fps = statistics.median(plain_runs)
        bare_fps = statistics.median(bare_runs)
        cost = 100.0 * (1.0 - served / plain_fps)
        row = {"size": f"{w}x{h}", "served_fps": round(served, 2), "bare_render_jpeg_fps": round(bare_fps, 2),
               "ratio": round(served / bare_fps, 3), "served_plain_fps": round(plain_fps, 2),
               "textures_cost_percent": round(cost, 1), "frames": frames, "world": world.name,
               "cpu_count": os.cpu_count()}
        results.append(row)
        if not args.json:
            print(f"camera {w}x{h}: served {served:.1f} frames/s through the image server; bare MuJoCo render + "
                  f"JPEG {bare_fps:.1f} frames/s; ratio {served / bare_fps:.2f}; plain colours served "
                  f"{plain_fps:.1f} frames/s, textures cost {cost:.1f} %")
    if args.json:
        print(json.dumps(results))
    return 0


def snapshot_state(sim, runner=None) -> np.ndarray:
    """The full physics state (with the controls) of the running simulation, taken
    from its own thread so that it is consistent."""
    import mujoco

    from usarsim.sim.runner import Request

    done = threading.Event()
    box = {}

    def take(s):
        spec = int(mujoco.mjtState.mjSTATE_FULLPHYSICS) | int(mujoco.mjtState.mjSTATE_CTRL)
        buf = np.empty(mujoco.mj_stateSize(s.model, spec))
        mujoco.mj_getState(s.model, s.data, buf, spec)
        box["state"] = buf

    if runner is None or not runner.alive:
        take(sim)
    else:
        runner.submit(Request(take, immediate=True, on_done=lambda result, error: done.set()))
        done.wait(10)
    return box.get("state")


RAW_REPEATS = 3  # bare mj_step is timed this many times from the same state; the median counts


def raw_mujoco_rtf(model, seconds: float, state: np.ndarray | None = None) -> float:
    """Real-time factor of bare ``mj_step`` on ``model`` (one thread), from ``state`` (the
    scene the benchmark ended with, robots driving as they were) or, without it, from the
    initial state with every wheel turning: the median of RAW_REPEATS runs of ``seconds``
    each from that same state (a single short run of a few robots varied by 20 %)."""
    import mujoco

    spec = int(mujoco.mjtState.mjSTATE_FULLPHYSICS) | int(mujoco.mjtState.mjSTATE_CTRL)
    d = mujoco.MjData(model)
    if state is None or state.size != mujoco.mj_stateSize(model, spec):
        d.ctrl[:] = 2.0
        state = np.empty(mujoco.mj_stateSize(model, spec))
        mujoco.mj_getState(model, d, state, spec)
    steps = max(1, int(round(seconds / model.opt.timestep)))
    rates = []
    for _ in range(RAW_REPEATS):
        mujoco.mj_setState(model, d, state, spec)
        mujoco.mj_forward(model, d)
        mujoco.mj_step(model, d, min(steps, 50))  # warm up
        mujoco.mj_setState(model, d, state, spec)
        mujoco.mj_forward(model, d)
        t0 = time.perf_counter()
        mujoco.mj_step(model, d, steps)
        rates.append(steps * model.opt.timestep / (time.perf_counter() - t0))
    return statistics.median(rates)


def raw_mujoco_rtf_over(model, seconds: float, states: list) -> float:
    """Bare ``mj_step``'s real-time factor over the scenes of a run (its start, middle and
    end): each timed for a share of ``seconds`` (:func:`raw_mujoco_rtf`), their mean time
    per simulated second.  The physics of a run costs more as robots meet walls and each
    other; timed from the end alone, a long run of 16 robots made bare ``mj_step`` 10 %
    slower than a short one, and the ratio to it as much better."""
    states = [s for s in states if s is not None] or [None]
    share = seconds / len(states)
    return 1.0 / statistics.mean(1.0 / raw_mujoco_rtf(model, share, s) for s in states)


def logging_quiet() -> None:
    import logging

    logging.getLogger("usarsim").setLevel(logging.WARNING)


ROUND_TRIP_STEP_S = 0.004  # one physics step of the shipped worlds (their timestep_s)


def _round_trip_client(port: int, robot: bool, count: int) -> None:
    """Child process: optionally spawn a P2AT, then ``count`` STEP/STEPPED round trips, one at
    a time, as a lock-step controller does; prints the round trips a second."""
    import socket

    s = socket.create_connection(("127.0.0.1", port))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    f = s.makefile("rb")
    f.readline()  # NFO
    if robot:
        s.sendall(b"INIT {ClassName USARBot.P2AT} {Name R1}\r\nPING {Id spawned}\r\n")
        while not f.readline().startswith(b"PONG"):
            pass
    line = b"STEP {Time %g}\r\n" % ROUND_TRIP_STEP_S
    for _ in range(min(200, count // 10)):  # warm up
        s.sendall(line)
        while not f.readline().startswith(b"STEPPED"):
            pass
    t0 = time.perf_counter()
    for _ in range(count):
        s.sendall(line)
        while not f.readline().startswith(b"STEPPED"):
            pass
    print(json.dumps({"round_trips_per_s": count / (time.perf_counter() - t0)}), flush=True)


class _EchoServer(_LoopThread):
    """The least a lock-step server does, on the event loop a lock-step server runs: it
    greets a client with one line and answers each line with a fixed STEPPED line (no
    parsing, no simulation).  Its round trips are what the machine and the client allow."""

    REPLY = b"STEPPED {Time 0.004}\r\n"

    def __init__(self) -> None:
        self.port = 0
        self._server: asyncio.base_events.Server | None = None
        super().__init__(True, "bench-echo", self._start)

    async def _start(self) -> None:
        async def handle(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            writer.write(b"NFO {Gametype BotDeathMatch} {Level echo} {TimeLimit 0}\r\n")
            while await reader.readline():
                writer.write(self.REPLY)
            writer.close()

        self._server = await asyncio.start_server(handle, "127.0.0.1", 0)
        self.port = self._server.sockets[0].getsockname()[1]

    def stop(self) -> None:
        if self._server is not None:
            self.loop.call_soon_threadsafe(self._server.close)
        self.stop_loop()


def _round_trips(port: int, robot: bool, count: int) -> float | None:
    """Round trips a second of :func:`_round_trip_client` against ``port`` (None: it failed)."""
    out = subprocess.run([sys.executable, "-m", "usarsim.bench", "--round-trip-client", str(port),
                          "1" if robot else "0", str(count)], capture_output=True, text=True, timeout=600)
    if out.returncode != 0:
        print(f"usarsim bench: the client failed: {out.stderr.strip()[-500:]}", file=sys.stderr)
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])["round_trips_per_s"]


def run_round_trip_bench(args) -> int:
    """``bench --round-trips``: lock-step STEP/STEPPED round trips per second of a client in
    another process over loopback, with no robot and with one P2AT (4 ms steps), and of the
    same client against a bare echo server on the same event loop (:class:`_EchoServer`):
    what the machine allows, to read the others against."""
    from usarsim.config.catalog import resolve_world
    from usarsim.server.app import Application

    logging_quiet()
    world = resolve_world(args.world)
    count = max(100, int(args.count))
    result = {"world": world.name, "step_s": ROUND_TRIP_STEP_S, "count": count, "cpu_count": os.cpu_count()}
    for robot in (False, True):
        app = Application(world, host="127.0.0.1", port=0, seed=0, lockstep=True, truth_port=None, image_port=None,
                          web_port=None)
        served = _ServedApp(app)
        try:
            rate = _round_trips(app.control.port, robot, count)
        finally:
            served.stop()
        if rate is None:
            return 1
        result["one_p2at" if robot else "no_robot"] = round(rate, 1)
    echo = _EchoServer()
    try:
        rate = _round_trips(echo.port, False, count)
    finally:
        echo.stop()
    if rate is None:
        return 1
    result["bare_echo"] = round(rate, 1)
    if args.json:
        print(json.dumps(result))
    else:
        print(f"lock-step STEP/STEPPED round trips of {ROUND_TRIP_STEP_S * 1000:g} ms, one client in another "
              f"process: {result['no_robot']:.0f} a second with no robot, {result['one_p2at']:.0f} with one P2AT; "
              f"a bare echo server on the same event loop: {result['bare_echo']:.0f}")
    return 0


if __name__ == "__main__" and len(sys.argv) > 1 and sys.argv[1] == "--client":
    asyncio.run(_client_main(int(sys.argv[2]), json.loads(sys.argv[3]), float(sys.argv[4])))
elif __name__ == "__main__" and len(sys.argv) > 1 and sys.argv[1] == "--round-trip-client":
    _round_trip_client(int(sys.argv[2]), sys.argv[3] == "1", int(sys.argv[4]))
