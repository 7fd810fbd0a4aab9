"""``usarsim bench --robots N`` and its variants (``--record``, ``--profile``): the command
that picks the measurement and prints it."""

from __future__ import annotations

import json
import math
import sys

from usarsim.bench.record import run_record_bench
from usarsim.bench.rtf import rtf_result, run_profile_bench
from usarsim.bench.serving import logging_quiet


def run_bench(args) -> int:
    """``usarsim bench --robots N``: the real-time factor (``--record``: with and without a
    recording; ``--profile``: where the time goes)."""
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
        return run_record_bench(args, world, n, seconds, progress)
    if getattr(args, "profile", False):
        return run_profile_bench(args, world, n, seconds, progress)
    result = rtf_result(world, n, seconds, progress=progress)
    if args.json:
        print(json.dumps(result))
    else:
        print(
            f"robots {n}: {result['sim_seconds']:.1f} simulated s in {result['wall_seconds']:.2f} s wall -> "
            f"real-time factor {result['rtf']:.2f}; bare mj_step {result['raw_mujoco_rtf']:.2f}; ratio "
            f"{result['ratio']:.2f}; memory {result['peak_rss_mb']:.0f} MB at the peak, "
            f"{result['rss_per_robot_mb']:.1f} MB a robot"
        )
    return 0
