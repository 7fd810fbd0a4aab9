"""What a sweep costs beyond the simulation itself, and how many runs an hour it gets through
with 1 and with 2 workers (usarsim sweep on a local Ray).

    python tools/bench_sweep.py                     # 8 runs of 10 simulated s, 1 then 2 workers
    python tools/bench_sweep.py --runs 16 --duration 30 --workers 1 2 4

Each run is one P2AT wandering DM-USAR_yellow in lock-step (a seed each).  Per run it prints
the sweep's own overhead, phase by phase: start (the simulator started and listening),
connect (client connected, robot spawned, brain made, first step), score (SIGTERM, the
score file written and read), collect (the row from the finished task to the results
table) and idle (workers waiting on Ray between runs: workers x elapsed - the runs' wall
time, per run); then the controller's own time (the simulated duration) and runs per hour.
Ray's start-up is timed apart: it is paid once per sweep.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path


def bench(workers: int, runs: int, duration: float, world: str, controller: str) -> dict:
    import ray

    from usarsim.sweep.experiment import load_experiment
    from usarsim.sweep.runner import run_sweep, start_ray

    with tempfile.TemporaryDirectory(prefix="usarsim-bench-sweep-") as tmp:
        path = Path(tmp) / "bench.yaml"
        path.write_text(
            f"name: bench\nworld: {world}\nseeds: {runs}\nteam: P2AT\nduration: {duration}\n"
            f"clock: lockstep\ncontroller: {controller}\n",
            encoding="utf-8",
        )
        exp = load_experiment(path)
        t0 = time.monotonic()
        start_ray(workers, None)
        ray_start = time.monotonic() - t0
        try:
            out = run_sweep(exp, Path(tmp) / "out", workers=workers, progress=False)
        finally:
            ray.shutdown()
    rows = out.rows
    failed = [r["error"] for r in rows if r.get("error")]
    if failed:
        raise SystemExit(f"{len(failed)} runs failed, e.g.: {failed[0]}")
    elapsed = out.elapsed_s - out.ray_start_s  # the runs only: Ray was started before
    mean = statistics.fmean
    idle = max(0.0, workers * elapsed - sum(r["wall_s"] for r in rows)) / len(rows)
    phases = {
        "start_s": mean(r["start_s"] for r in rows),
        "connect_s": mean(r["setup_s"] for r in rows),
        "score_s": mean(r["stop_s"] for r in rows),
        "collect_s": mean(out.collect_s) if out.collect_s else 0.0,
        "idle_s": idle,
    }
    return {
        "workers": workers,
        "runs": len(rows),
        "duration_s": duration,
        "ray_start_s": round(ray_start, 2),
        "elapsed_s": round(elapsed, 2),
        "runs_per_hour": round(len(rows) / elapsed * 3600.0),
        "control_s": round(mean(r["control_s"] for r in rows), 3),
        "overhead_s": round(sum(phases.values()), 3),
        **{k: round(v, 3) for k, v in phases.items()},
        "cpu_count": os.cpu_count(),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=8, help="runs per measurement (default: %(default)s)")
    p.add_argument("--duration", type=float, default=10.0, help="simulated seconds per run (default: %(default)s)")
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts (default: 1 2)")
    p.add_argument("--world", default="DM-USAR_yellow", help="world (default: %(default)s)")
    p.add_argument("--controller", default="usarsim.brains.wander:Wander", help="brain (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="one JSON object per measurement")
    args = p.parse_args(argv)
    os.environ.setdefault("MUJOCO_GL", "egl")
    results = [bench(w, args.runs, args.duration, args.world, args.controller) for w in args.workers]
    if args.json:
        for r in results:
            print(json.dumps(r))
        return 0
    print(
        f"{args.runs} runs of {args.duration:g} simulated s ({args.world}, one P2AT, lock-step, "
        f"{args.controller}) on {os.cpu_count()} CPUs"
    )
    print(
        f"{'workers':>7} {'Ray start':>9} {'start':>6} {'connect':>7} {'score':>6} {'collect':>7} {'idle':>6} "
        f"{'overhead':>8} {'control':>7} {'elapsed':>7} {'runs/hour':>9}"
    )
    for r in results:
        print(
            f"{r['workers']:>7} {r['ray_start_s']:>8.2f}s {r['start_s']:>5.2f}s {r['connect_s']:>6.2f}s "
            f"{r['score_s']:>5.2f}s {r['collect_s']:>6.3f}s {r['idle_s']:>5.2f}s {r['overhead_s']:>7.2f}s "
            f"{r['control_s']:>6.2f}s {r['elapsed_s']:>6.1f}s {r['runs_per_hour']:>9}"
        )
    print(
        "overhead per run = start + connect + score + collect + idle (the sweep's own cost); control: the "
        "controller's simulated duration"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
