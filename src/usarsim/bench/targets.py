"""``usarsim bench --targets``: one sitting of every benchmark the scaling targets are judged
by, and a table of each target against every run of it.

The targets are those of a 2-core machine: the share of bare ``mj_step`` the whole simulator
keeps (``ratio``) at 16, 64 and 256 robots, the real-time factor of 256 robots, their peak
memory, lock-step round trips with no robot and with one P2AT, and the image server's frame
rate beside bare rendering plus JPEG.  A target is met when every run of the sitting meets
it.  The sitting runs each robot count, then the round trips, then the cameras, ``runs``
times over, in turn (16, 64, 256, round trips, cameras; 16, 64...), so that a machine whose
speed drifts through the sitting weighs on every figure alike; each is ``usarsim bench`` in a
process of its own, as a user runs it (the peak memory is then each run's own).  The machine
(processor, cores, memory, MuJoCo) and the time are printed with the table: figures from two
machines do not compare.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

ROBOT_COUNTS = (16, 64, 256)
RUNS = 3
BENCH_TIMEOUT_S = 1800.0  # one benchmark of the sitting (256 robots spawn in a minute or two)


@dataclass(frozen=True)
class Target:
    """A figure of the sitting (``figure(sitting)``: one value a run) and the least or most
    it may be."""

    label: str
    figure: Callable[[dict], list[float]]
    at_least: float | None = None
    at_most: float | None = None
    digits: int = 2

    def holds(self, value: float) -> bool:
        return (self.at_least is None or value >= self.at_least) and (self.at_most is None or value <= self.at_most)

    @property
    def bound(self) -> str:
        if self.at_least is not None:
            return f">= {self.at_least:,.{self.digits}f}"
        return f"<= {self.at_most:,.{self.digits}f}"


def _rtf(n: int, key: str) -> Callable[[dict], list[float]]:
    return lambda sitting: [r[key] for r in sitting["rtf"].get(str(n), [])]


def _round_trips(key: str) -> Callable[[dict], list[float]]:
    return lambda sitting: [r[key] for r in sitting["round_trips"]]


def _cameras(size: str) -> Callable[[dict], list[float]]:
    return lambda sitting: [row["ratio"] for rows in sitting["cameras"] for row in rows if row["size"] == size]


# The scaling targets of a 2-core machine (bare mj_step: one thread, on the same model).
TARGETS = (
    Target("ratio, 16 robots", _rtf(16, "ratio"), at_least=0.8),
    Target("ratio, 64 robots", _rtf(64, "ratio"), at_least=0.8),
    Target("ratio, 256 robots", _rtf(256, "ratio"), at_least=1.0),
    Target("real-time factor, 256 robots", _rtf(256, "rtf"), at_least=1.0),
    Target("peak memory MB, 256 robots", _rtf(256, "peak_rss_mb"), at_most=2000.0, digits=0),
    Target("round trips/s, no robot", _round_trips("no_robot"), at_least=15000.0, digits=0),
    Target("round trips/s, one P2AT", _round_trips("one_p2at"), at_least=10000.0, digits=0),
    Target("camera ratio, 320x240", _cameras("320x240"), at_least=0.85),
    Target("camera ratio, 640x480", _cameras("640x480"), at_least=0.85),
)


def evaluate(sitting: dict) -> list[dict]:
    """Each target with the values of its runs and whether it is met (every run meets it;
    None when the sitting did not measure it)."""
    rows = []
    for t in TARGETS:
        values = t.figure(sitting)
        rows.append(
            {
                "target": t.label,
                "bound": t.bound,
                "at_least": t.at_least,
                "at_most": t.at_most,
                "values": values,
                "met": all(t.holds(v) for v in values) if values else None,
            }
        )
    return rows


def machine() -> dict:
    """What the figures were measured on."""
    import mujoco

    cpu = platform.processor() or platform.machine()
    memory_gib = None
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu)
        with open("/proc/meminfo") as f:
            kib = next(int(line.split()[1]) for line in f if line.startswith("MemTotal:"))
            memory_gib = round(kib / 2**20, 1)
    except (OSError, StopIteration, ValueError):
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "memory_gib": memory_gib,
        "system": platform.platform(),
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "time_utc": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }


def _bench(*args: str) -> object:
    """``usarsim bench ARGS --json`` in a process of its own (as a user runs it: each run's
    memory is its own process's), its JSON."""
    out = subprocess.run(
        [sys.executable, "-m", "usarsim", "bench", *args, "--json"],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=BENCH_TIMEOUT_S,
    )
    if out.returncode != 0:
        raise SystemExit(
            f"usarsim bench {' '.join(args)} failed (exit code {out.returncode}): {out.stderr.strip()[-1000:]}"
        )
    return json.loads(out.stdout.strip().splitlines()[-1])


def sitting(
    world: str,
    *,
    counts=ROBOT_COUNTS,
    runs: int = RUNS,
    seconds: float = 10.0,
    count: int = 5000,
    sizes=((320, 240), (640, 480)),
    frames: int = 60,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Every benchmark of the targets, ``runs`` times in turn, each in a process of its own;
    ``progress(what)`` is called before each one."""
    out: dict = {
        "world": world,
        "runs": runs,
        "seconds": seconds,
        "counts": list(counts),
        "rtf": {},
        "round_trips": [],
        "cameras": [],
    }
    for k in range(runs):
        for n in counts:
            if progress:
                progress(f"{n} robots, run {k + 1} of {runs}")
            out["rtf"].setdefault(str(n), []).append(
                _bench("--world", world, "--robots", str(n), "--seconds", repr(float(seconds)))
            )
        if count > 0:
            if progress:
                progress(f"round trips, run {k + 1} of {runs}")
            out["round_trips"].append(_bench("--world", world, "--round-trips", "--count", str(count)))
        if sizes:
            if progress:
                progress(f"cameras, run {k + 1} of {runs}")
            out["cameras"].append(
                _bench(
                    "--world", world, "--cameras", "--frames", str(frames), "--sizes", *(f"{w}x{h}" for w, h in sizes)
                )
            )
    return out


def steps_of(counts, runs: int, count: int, sizes) -> int:
    return runs * (len(counts) + (count > 0) + bool(sizes))


def run_targets_bench(args) -> int:
    """``usarsim bench --targets``: the sitting, then the table (or one JSON object)."""
    from usarsim.config.catalog import resolve_world

    resolve_world(args.world)  # a world that is not there: a clear error now, not in the first benchmark
    world = str(args.world)
    counts = tuple(args.counts)
    runs, seconds = int(args.runs), float(args.seconds)
    if runs < 1 or not seconds > 0 or any(n < 1 for n in counts):
        print("usarsim bench: --runs and --counts must be >= 1 and --seconds > 0", file=sys.stderr)
        return 2
    show = sys.stderr.isatty() and not args.json
    kwargs: dict[str, Any] = dict(
        counts=counts,
        runs=runs,
        seconds=seconds,
        count=int(args.count),
        sizes=tuple(args.sizes),
        frames=int(args.frames),
    )
    info = machine()  # and the time the sitting started
    started = time.monotonic()
    if show:
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        total = steps_of(counts, runs, kwargs["count"], kwargs["sizes"])
        with Progress(
            TextColumn("{task.description:<28}"),
            BarColumn(),
            TextColumn("{task.completed}/{task.total}"),
            TimeElapsedColumn(),
            transient=True,
        ) as bar:
            task = bar.add_task("starting", total=total)
            first = [True]

            def note(what: str) -> None:
                if not first[0]:
                    bar.advance(task)
                first[0] = False
                bar.update(task, description=what)

            result = sitting(world, progress=note, **kwargs)
    else:
        result = sitting(world, **kwargs)
    result["machine"] = info
    result["wall_s"] = round(time.monotonic() - started, 1)
    result["targets"] = evaluate(result)
    if args.json:
        print(json.dumps(result))
    else:
        print_targets(result)
    return 0


def print_targets(result: dict) -> None:
    """The targets as a table: one column a run, and whether each is met."""
    from rich import box
    from rich.console import Console
    from rich.table import Table

    m = result["machine"]
    rows = result["targets"]
    measured = [r for r in rows if r["met"] is not None]
    met = sum(1 for r in measured if r["met"])
    print(
        f"{m['time_utc']}: {m['cpu']}, {m['cores']} cores, {m['memory_gib']} GiB, {m['system']}, Python "
        f"{m['python']}, MuJoCo {m['mujoco']}"
    )
    print(
        f"{result['world']}, {result['seconds']:g} simulated s a bench run, {result['runs']} runs of each in turn, "
        f"{result['wall_s']:.0f} s in all: {met} of {len(measured)} targets measured were met in every run"
    )
    t = Table(box=box.SIMPLE_HEAD)
    t.add_column("target")
    t.add_column("bound", justify="right")
    for k in range(result["runs"]):
        t.add_column(f"run {k + 1}", justify="right")
    t.add_column("met")
    for r, target in zip(rows, TARGETS, strict=True):
        values = r["values"]
        per_run = len(values) // result["runs"] if values else 0
        cells = []
        for k in range(result["runs"]):
            mine = values[k * per_run : (k + 1) * per_run] if per_run else []
            cells.append(", ".join(f"{v:,.{target.digits}f}" for v in mine) or "-")
        verdict = "not measured" if r["met"] is None else ("yes" if r["met"] else "[bold red]no[/]")
        t.add_row(r["target"], r["bound"], *cells, verdict)
    Console().print(t)
    print(
        "ratio: real-time factor / bare single-threaded mj_step on the same model; camera ratio: frames a "
        "second served / bare MuJoCo render + JPEG"
    )
    # what the machine allows, to read the targets against
    for n, runs in result["rtf"].items():
        rtf = " / ".join(f"{r['rtf']:.2f}" for r in runs)
        bare = " / ".join(f"{r['raw_mujoco_rtf']:.2f}" for r in runs)
        print(f"{n} robots: real-time factor {rtf}; bare mj_step {bare}")
    if result["round_trips"]:
        echo = " / ".join(f"{r['bare_echo']:,.0f}" for r in result["round_trips"])
        print(f"a bare echo server on the same event loop: {echo} round trips a second")
