"""Running brains: the loop that steps them (in real time or lock-step) and the command
line every brain module shares (``python -m usarsim.brains.<brain> --host ... --port ...``)."""

from __future__ import annotations

import argparse
import logging
import math
import re
import sys
from collections.abc import Callable, Iterable
from typing import Any

from usarsim.client import ClientError, connect

log = logging.getLogger("usarsim.brains")


def run(
    world: Any,
    brains: Iterable[Any],
    seconds: float,
    *,
    period: float = 0.1,
    on_step: Callable[[float], bool | None] | None = None,
    until_done: str = "all",
) -> float:
    """Step ``brains`` every ``period`` seconds of simulated time for ``seconds`` (or until
    they are done: ``until_done`` ``"all"``, ``"any"`` or ``"never"``).  In lock-step the
    loop advances the world itself (``world.step``); in real time it waits while the
    messages are read (``world.wait``).  ``on_step(time)`` is called after each period
    (return True to stop).  Returns the simulated time the loop ran."""
    brains = list(brains)
    if period <= 0:
        raise ValueError(f"period must be > 0, got {period}")
    if not world.lockstep:
        world.wait(period)  # the robots' latest messages: the world's time is now
    start = world.time
    while world.time - start < seconds - 1e-9:
        if world.lockstep:
            world.step(period)
        else:
            world.wait(period)
        for b in brains:
            b.step(period)
        if on_step is not None and on_step(world.time):
            break
        finished = [b.done for b in brains]
        if (until_done == "all" and all(finished)) or (until_done == "any" and any(finished)):
            break
    for b in brains:
        b.stop()
    if world.lockstep:
        world.step(period)  # the last DRIVE reaches the robots
    return world.time - start


def parser(description: str, *, seconds: float = 60.0) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--host", default="127.0.0.1", help="the simulator's address (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=3000, help="its control port (default 3000)")
    p.add_argument("--robot", default="P2AT", help="robot class to spawn (default P2AT)")
    p.add_argument("--name", default=None, help="the robot's name (default: the class and a number)")
    p.add_argument("--start", default=None, help="start pose name (default: the first start pose)")
    p.add_argument("--location", default=None, help="x,y,z to spawn at instead of a start pose (metres)")
    p.add_argument("--yaw", type=float, default=0.0, help="yaw at --location (radians, clockwise)")
    p.add_argument("--seconds", type=float, default=seconds, help=f"simulated seconds to run (default {seconds:g})")
    p.add_argument("--period", type=float, default=0.1, help="control period, simulated seconds (default 0.1)")
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="the server runs in lock-step (usarsim serve --lockstep): step it from here",
    )
    p.add_argument(
        "--pose",
        default="odometry",
        choices=("odometry", "ins", "truth"),
        help="where the brain's pose comes from (default odometry)",
    )
    p.add_argument("-v", "--verbose", action="store_true", help="log what the brain does")
    return p


def numbers_first(argv: list[str] | None) -> list[str]:
    """The arguments, with an option's value that starts with a minus sign joined to it
    (``--bounds -6,-7.2,6,7.2`` -> ``--bounds=-6,-7.2,6,7.2``): argparse would take the
    value for an option of its own."""
    argv = list(sys.argv[1:] if argv is None else argv)
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a.startswith("--") and "=" not in a and i + 1 < len(argv) and re.match(r"^-[\d.]", argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
        else:
            out.append(a)
            i += 1
    return out


def vector(text: str, n: int) -> tuple[float, ...]:
    parts = [float(v) for v in text.replace(" ", ",").split(",") if v]
    if len(parts) != n:
        raise ValueError(f"expected {n} numbers separated by commas, got {text!r}")
    return tuple(parts)


def spawn(
    world: Any, args: argparse.Namespace, name: str | None = None, start: str | None = None
) -> tuple[Any, tuple[float, float, float]]:
    """Spawn the robot the arguments ask for; returns it and the world pose it started at
    (x, y, yaw), the origin of its odometry."""
    start = start or args.start
    if args.location:
        loc = vector(args.location, 3)
        robot = world.spawn(args.robot, name or args.name, location=loc, rotation=(0.0, 0.0, args.yaw))
        return robot, (loc[0], loc[1], args.yaw)
    poses = world.start_poses
    if not poses:
        raise ClientError("the world has no start poses: give --location")
    pose = poses[0] if start is None else next((p for p in poses if p.name.lower() == start.lower()), None)
    if pose is None:
        raise ClientError(f"no start pose {start!r} (known: {', '.join(p.name for p in poses)})")
    robot = world.spawn(args.robot, name or args.name, start=pose.name)
    return robot, (pose.location[0], pose.location[1], pose.rotation[2])


def main_for(
    make: Callable[[Any, tuple[float, float, float], argparse.Namespace], Any],
    p: argparse.ArgumentParser,
    argv: list[str] | None = None,
    report: Callable[[Any], None] | None = None,
) -> int:
    """The body of every brain's ``main``: connect, spawn, run, report."""
    args = p.parse_args(numbers_first(argv))
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="%(asctime)s %(name)s: %(message)s"
    )
    try:
        with connect(args.host, args.port, lockstep=args.lockstep) as world:
            robot, origin = spawn(world, args)
            brain = make(robot, origin, args)
            if world.lockstep:
                world.step(args.period)  # the first readings
            ran = run(world, [brain], args.seconds if math.isfinite(args.seconds) else 1e12, period=args.period)
            print(f"{type(brain).__name__}: ran {ran:.1f} simulated seconds", flush=True)
            if report is not None:
                report(brain)
    except (ClientError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    return 0
