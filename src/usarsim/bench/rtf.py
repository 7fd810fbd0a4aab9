"""``usarsim bench --robots N``: the real-time factor of the whole simulator with N robots.

N P2ATs with their full sensor kit are spawned in the world, each by its own TCP
client over loopback (a separate process reads every line they are sent and
drives them); the simulator runs as fast as it can (``--speed max``) for S
simulated seconds.  Beside it, bare ``mj_step`` on the same compiled model, timed
from the scenes at the start, middle and end of the run, gives the physics-only
real-time factor; ``ratio`` = ``rtf`` / ``raw_mujoco_rtf`` is the share of the
machine that stays with physics."""

from __future__ import annotations

import gc
import json
import os
import statistics
import subprocess
import sys
import threading
import time

import numpy as np

from usarsim.bench.serving import ServedApp, bench_app, peak_rss_mb, rss_mb
from usarsim.bench.spots import spread_spots


def measure_rtf(
    world,
    n: int,
    seconds: float,
    *,
    record: str | None = None,
    progress: bool = False,
    speed: float | None = None,
    cameras_fps: float = 0.0,
    window=None,
) -> dict:
    """One run: N P2ATs driven over loopback at ``speed`` (None: as fast as it goes) for
    ``seconds`` of simulated time; with ``record``, recorded to that MCAP file, with every
    camera's picture ``cameras_fps`` times a simulated second (the time the recorder takes to
    write what was still queued at the end is counted in the wall time).  ``window``: an
    object whose ``start(app)`` and ``stop(app)`` are called as the measured stretch begins
    and ends (``usarsim bench --profile``).  The server runs in this process (its client in
    another): the memory figures are the simulator's."""
    result = _measure_rtf(
        world, n, seconds, record=record, progress=progress, speed=speed, cameras_fps=cameras_fps, window=window
    )
    # The stopped server is garbage in reference cycles, which only a full collection frees: the
    # next run in this process (bench --record runs six) would otherwise be built beside it
    # (three runs of 128 robots in one process peaked at 1.0 GB without this, 0.69 GB with it).
    gc.collect()
    return result


def _measure_rtf(
    world,
    n: int,
    seconds: float,
    *,
    record: str | None,
    progress: bool,
    speed: float | None,
    cameras_fps: float,
    window,
) -> dict:

    poses = spread_spots(world, n)
    app = bench_app(
        world,
        speed=speed,
        lockstep=False,
        max_connections=max(64, n),
        record=record,
        record_cameras_fps=cameras_fps,
    )
    served = ServedApp(app)
    rss_before = rss_mb()  # the world built, no robot yet
    port = app.control.port
    client = subprocess.Popen(
        [sys.executable, "-m", "usarsim.bench", "--client", str(port), json.dumps(poses), str(seconds)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
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
                print(
                    f"\r  {done:7.1f} / {seconds:g} simulated s{' (recording)' if record else ''}",
                    end="",
                    file=sys.stderr,
                    flush=True,
                )
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
    result = {
        "sim_seconds": round(sim_s, 3),
        "wall_seconds": round(wall_s, 3),
        "rtf": round(sim_s / wall_s, 3),
        "model": model,
        "state": state,
        "states": states,
        "physics_resets": sim.resets,
        "pictures": app.recorder.pictures if app.recorder is not None else 0,
        "peak_rss_mb": round(peak_rss_mb(), 1),
        "rss_per_robot_mb": round((rss_after - rss_before) / n, 2),
    }
    return result


def rtf_result(world, n: int, seconds: float, progress: bool = False) -> dict:
    """One bench run of ``n`` robots for ``seconds`` (:func:`measure_rtf`) beside bare
    ``mj_step`` on its scenes: what ``usarsim bench --json`` prints."""
    run = measure_rtf(world, n, seconds, progress=progress)
    model = run["model"]
    rtf = run["rtf"]
    raw = raw_mujoco_rtf_over(model, min(seconds, 5.0), run["states"])
    return {
        "robots": n,
        "sim_seconds": run["sim_seconds"],
        "wall_seconds": run["wall_seconds"],
        "rtf": rtf,
        "raw_mujoco_rtf": round(raw, 3),
        "ratio": round(rtf / raw, 3),
        "timestep_s": model.opt.timestep,
        "world": world.name,
        "cpu_count": os.cpu_count(),
        "physics_resets": run["physics_resets"],
        "peak_rss_mb": run["peak_rss_mb"],
        "rss_per_robot_mb": run["rss_per_robot_mb"],
    }


def run_profile_bench(args, world, n: int, seconds: float, progress: bool) -> int:
    """``bench --profile``: one run with both threads profiled; the breakdown."""
    from usarsim.bench.profile import Profiler, breakdown, format_breakdown

    prof = Profiler()
    run = measure_rtf(world, n, seconds, progress=progress, window=prof)
    b = breakdown(prof)
    if args.json:
        print(
            json.dumps(
                {
                    "robots": n,
                    "sim_seconds": run["sim_seconds"],
                    "rtf_profiled": run["rtf"],
                    "sim_wall_s": round(b["sim_wall_s"], 3),
                    "sim_cpu_s": round(b["sim_cpu_s"], 3),
                    "loop_wall_s": round(b["loop_wall_s"], 3),
                    "loop_cpu_s": round(b["loop_cpu_s"], 3),
                    "sensors_wall_s": round(b["sensors_wall_s"], 3),
                    "sensors_cpu_s": round(b["sensors_cpu_s"], 3),
                    "sim": {k: round(v, 4) for k, v in b["sim"]},
                    "sensors": {k: round(v, 4) for k, v in b["sensors"]},
                    "loop": {k: round(v, 4) for k, v in b["loop"]},
                    "contacts": dict(zip(("contacts", "constraint_rows", "islands"), b["contacts"] or ())),
                    "peak_rss_mb": run["peak_rss_mb"],
                    "rss_per_robot_mb": run["rss_per_robot_mb"],
                }
            )
        )
    else:
        print(
            f"robots {n}: {run['sim_seconds']:.1f} simulated s in {run['wall_seconds']:.2f} s wall under the "
            f"profiler (real-time factor {run['rtf']:.2f}; without it, run 'usarsim bench')"
        )
        print(format_breakdown(b, run["sim_seconds"]))
    return 0


def snapshot_state(sim, runner=None) -> np.ndarray | None:
    """The full physics state (with the controls) of the running simulation, taken
    from its own thread so that it is consistent (None when that thread did not take it
    within 10 s: the bare ``mj_step`` timings then start from the initial state)."""
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
        # concurrent: it reads the live state only, so it need not wait for the readings in flight
        runner.submit(Request(take, immediate=True, concurrent=True, on_done=lambda result, error: done.set()))
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
