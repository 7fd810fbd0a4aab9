"""``usarsim bench --robots N --record``: what recording costs, in real-time factor and in
bytes per robot-minute."""

from __future__ import annotations

import json
import os
import statistics

from usarsim.bench.rtf import measure_rtf

RECORD_ROUNDS = 3  # bench --record alternates this many runs without and with a recording
CAMERA_ROBOTS = 4  # bench --record then records this many robots' cameras in real time ...
CAMERA_FPS = 5.0  # ... at this many pictures a simulated second


def run_record_bench(args, world, n: int, seconds: float, progress: bool) -> int:
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
        cams = measure_rtf(
            world,
            CAMERA_ROBOTS,
            seconds,
            record=os.path.join(tmp, "cameras.mcap"),
            speed=1.0,
            cameras_fps=CAMERA_FPS,
            progress=progress,
        )
        cam_size = os.path.getsize(os.path.join(tmp, "cameras.mcap")) / (CAMERA_ROBOTS * (cams["sim_seconds"] + 1) / 60)
    off, on = statistics.median(plain), statistics.median(recorded)
    cost = 100.0 * (1.0 - on / off)
    per = statistics.median(sizes)
    # pictures a camera per simulated second over the measured stretch (each P2AT has one camera)
    cam_rate = cams["pictures"] / (CAMERA_ROBOTS * (cams["sim_seconds"] + 1.0))
    result = {
        "robots": n,
        "sim_seconds": seconds,
        "rtf": off,
        "rtf_recording": on,
        "cost_percent": round(cost, 1),
        "bytes_per_robot_minute": round(per),
        "runs": {"plain": plain, "recording": recorded},
        "cameras": {
            "robots": CAMERA_ROBOTS,
            "fps_asked": CAMERA_FPS,
            "speed": cams["rtf"],
            "pictures_per_s": round(cam_rate, 2),
            "bytes_per_robot_minute": round(cam_size),
        },
        "world": world.name,
        "cpu_count": os.cpu_count(),
    }
    if args.json:
        print(json.dumps(result))
    else:
        print(
            f"robots {n}: real-time factor {off:.2f} without a recording, {on:.2f} recording every channel but "
            f"cameras ({cost:.1f} % less; medians of {RECORD_ROUNDS} runs each, alternately)"
        )
        print(f"recording size: {per / 1e6:.2f} MB per robot-minute of simulated time")
        print(
            f"{CAMERA_ROBOTS} robots in real time, every camera recorded at {CAMERA_FPS:g} pictures a simulated "
            f"second: the clock ran at {cams['rtf']:.2f}x real time; {cam_rate:.1f} pictures a camera per "
            f"simulated second; {cam_size / 1e6:.2f} MB per robot-minute"
        )
    return 0
