"""``usarsim bench --league``: the RoboCup Rescue virtual robot league's sensor load on this machine.

The league ran four robots a team, each with a 320x240 colour camera at 30 frames a second, a
160x120 thermal camera at 10 and a laser of 1,040 beams at 30 sweeps a second, beside the rest
of the competition kit.  This runs four such P2ATs (``P2ATLeague``: a P2AT whose SICK gives way
to that laser, with a FLIR Lepton-sized thermal camera beside its colour one) in a ``usarsim
serve`` process in real time, asks each camera for pictures through the image server at its
rate from a client of its own (as the league's operator stations did, each on its own
connection) and reads every robot's lines; then reports the real-time factor the simulator
kept, the pictures each camera delivered a second and the sweeps each laser delivered.
"""

from __future__ import annotations

import json
import math
import re
import socket
import statistics
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from usarsim.bench.serving import fetch_picture

LEAGUE_CLASS = "P2ATLeague"
ROBOTS = 4
COLOUR_FPS = 30.0  # the league's colour camera: 320 x 240 at 30 frames a second
COLOUR_SIZE = "320x240"
THERMAL_FPS = 10.0  # and its thermal camera: 160 x 120 at 10
LASER_HZ = 30.0  # its laser: 1,040 beams at 30 sweeps a second
LASER_BEAMS = 1040
LASER_RESOLUTION_RAD = math.radians(0.25)  # 0.25 degree steps (as a Hokuyo UTM-30LX's)
_TIME = re.compile(rb"SEN \{Time ([0-9.]+)\} \{Type RangeScanner\} \{Name Scanner1\}")


def league_robot_file(directory: Path) -> Path:
    """``P2ATLeague.yaml`` in ``directory``: the shipped P2AT with the league's laser in place of
    its SICK (1,040 beams 0.25 degrees apart, 30 m, 30 sweeps a second) and a thermal camera
    (160 x 120, usarsim.sensors.camera.ThermalCamera) beside its camera."""
    import yaml  # type: ignore[import-untyped]  # PyYAML ships no type information

    from usarsim.config.catalog import robot_files

    robot = yaml.safe_load(robot_files()["P2AT"].read_text(encoding="utf-8"))
    robot["class_name"] = LEAGUE_CLASS
    robot["description"] = "P2AT with the RoboCup Rescue virtual robot league's sensor load (usarsim bench --league)"
    for section in ("chassis", "sensors"):
        items = robot.get(section) or []
        for i, item in enumerate(list(items)):
            if item.get("type") == "RangeScanner":
                items[i] = {
                    "type": "RangeScanner",
                    "name": item["name"],
                    "location": item["location"],
                    "orientation": item.get("orientation", [0, 0, 0]),
                    "max_range_m": 30.0,
                    "min_range_m": 0.1,
                    "resolution_rad": LASER_RESOLUTION_RAD,
                    "fov_rad": (LASER_BEAMS - 1) * LASER_RESOLUTION_RAD,
                    "scan_interval_s": 1.0 / LASER_HZ,
                }
            if item.get("type") == "Camera":
                items.insert(i + 1, {**item, "type": "ThermalCamera", "name": "Thermal"})
    path = directory / f"{LEAGUE_CLASS}.yaml"
    path.write_text(yaml.safe_dump(robot, sort_keys=False), encoding="utf-8")
    return path


class _Laser(threading.Thread):
    """A robot's control connection, read to the end: its laser's sweeps counted, with the
    simulated time of each."""

    def __init__(self, sock: socket.socket):
        super().__init__(daemon=True, name="league-laser")
        self.sock = sock
        self.times: list[tuple[float, float]] = []  # (wall, simulated) of each sweep

    def run(self) -> None:
        buf = b""
        try:
            while True:
                data = self.sock.recv(1 << 20)
                if not data:
                    return
                buf += data
                lines = buf.split(b"\r\n")
                buf = lines.pop()
                now = time.perf_counter()
                for line in lines:
                    m = _TIME.match(line)
                    if m:
                        self.times.append((now, float(m.group(1))))
        except OSError:
            return


class _Viewer(threading.Thread):
    """A client of the image server bound to one camera, asking for a picture every
    1/``fps`` seconds of wall time (never two at once, never catching up in a burst)."""

    def __init__(self, port: int, fps: float, stop: threading.Event):
        super().__init__(daemon=True, name="league-viewer")
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=60)
        self.fps, self.stop = fps, stop
        self.frames: list[float] = []  # wall time of each picture received

    @property
    def local_port(self) -> int:
        return int(self.sock.getsockname()[1])

    def run(self) -> None:
        period = 1.0 / self.fps
        due = time.perf_counter()
        try:
            while not self.stop.is_set():
                fetch_picture(self.sock)
                now = time.perf_counter()
                self.frames.append(now)
                due = max(due + period, now)  # late: the next one at once, not a burst
                if due > now:
                    time.sleep(due - now)
        except OSError:
            return


def rate(stamps: list[float], t0: float, t1: float) -> float:
    """Events a second within [t0, t1]."""
    return sum(1 for t in stamps if t0 <= t <= t1) / (t1 - t0)


def league_run(
    world: str = "DM-USAR_yellow", seconds: float = 20.0, warmup_s: float = 4.0, antialias: int = 4
) -> dict[str, Any]:
    """One run of the league's load (see the module's text): the real-time factor, each
    camera's pictures a second and each laser's sweeps a second over ``seconds`` of wall time,
    after ``warmup_s``; ``antialias``: the simulator's multisampling (serve --antialias)."""
    from usarsim.client.launch import launch

    with tempfile.TemporaryDirectory(prefix="usarsim-league-") as tmp:
        league_robot_file(Path(tmp))
        server = launch(
            world,
            lockstep=False,
            speed=1.0,
            image=True,
            robot_dirs=(tmp,),
            extra_args=(
                *("--image-size", COLOUR_SIZE, "--max-fps", "0", "--image-type", "normal"),
                *("--antialias", str(int(antialias))),
            ),
            timeout=60.0,
        )
        stop = threading.Event()
        socks: list[socket.socket] = []
        viewers: list[tuple[str, int, _Viewer]] = []
        lasers: list[_Laser] = []
        try:
            image_port = server.ports["image"]
            for k in range(ROBOTS):
                sock = socket.create_connection((server.host, server.port), timeout=60)
                socks.append(sock)
                name = f"League{k + 1}"
                init = f"INIT {{ClassName USARBot.{LEAGUE_CLASS}}} {{Name {name}}} {{Start PlayerStart{k + 1}}}\r\n"
                sock.sendall(init.encode())
                for camera, fps in (("Camera", COLOUR_FPS), ("Thermal", THERMAL_FPS)):
                    viewer = _Viewer(image_port, fps, stop)
                    sock.sendall(
                        f"SET {{Type Camera}} {{Robot {name}}} {{Name {camera}}} "
                        f"{{Client 127.0.0.1:{viewer.local_port}}}\r\n".encode()
                    )
                    viewers.append((name, k, viewer))
                laser = _Laser(sock)
                laser.start()
                lasers.append(laser)
            time.sleep(1.0)  # the robots stand and the bindings are in place
            for _, _, viewer in viewers:
                viewer.start()
            time.sleep(warmup_s)
            t0 = time.perf_counter()
            time.sleep(seconds)
            t1 = time.perf_counter()
            stop.set()
        finally:
            stop.set()
            for _, _, viewer in viewers:
                viewer.sock.close()
            for sock in socks:
                sock.close()
            server.close()
    sims = [[s for w, s in laser.times if t0 <= w <= t1] for laser in lasers]
    rtf = statistics.median((s[-1] - s[0]) / (t1 - t0) for s in sims if len(s) > 1) if any(sims) else 0.0
    colour = [rate(v.frames, t0, t1) for _, _, v in viewers if v.fps == COLOUR_FPS]
    thermal = [rate(v.frames, t0, t1) for _, _, v in viewers if v.fps == THERMAL_FPS]
    laser_hz = [rate([w for w, _ in laser.times], t0, t1) for laser in lasers]
    return {
        "robots": ROBOTS,
        "seconds": seconds,
        "antialias": antialias,
        "rtf": round(rtf, 3),
        "colour_fps": [round(x, 1) for x in colour],
        "thermal_fps": [round(x, 1) for x in thermal],
        "laser_hz": [round(x, 1) for x in laser_hz],
        "at_rate": rtf >= 0.99
        and min(colour) >= 0.95 * COLOUR_FPS
        and min(thermal) >= 0.95 * THERMAL_FPS
        and min(laser_hz) >= 0.95 * LASER_HZ,
    }


def run_league_bench(args) -> int:
    """``usarsim bench --league``: ``--runs`` runs of ``--seconds`` wall seconds each."""
    runs = []
    for i in range(max(1, int(getattr(args, "runs", 1)))):
        r = league_run(args.world, seconds=float(args.seconds), antialias=int(getattr(args, "antialias", 4)))
        runs.append(r)
        if not args.json:
            print(
                f"run {i + 1}: {r['robots']} robots, real-time factor {r['rtf']:.3f}; colour 320x240 "
                f"(asked {COLOUR_FPS:g}/s): {', '.join(f'{x:.1f}' for x in r['colour_fps'])} frames/s; thermal "
                f"160x120 (asked {THERMAL_FPS:g}/s): {', '.join(f'{x:.1f}' for x in r['thermal_fps'])}; laser "
                f"{LASER_BEAMS} beams (at {LASER_HZ:g}/s): {', '.join(f'{x:.1f}' for x in r['laser_hz'])} sweeps/s; "
                f"{'every sensor at its rate' if r['at_rate'] else 'NOT every sensor at its rate'}",
                flush=True,
            )
    if args.json:
        print(json.dumps(runs))
    return 0
