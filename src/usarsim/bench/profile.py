"""``usarsim bench --profile``: where the time of the simulation thread, of the measuring
thread (sensor readings, usarsim.sim.measuring) and of the server's event loop goes during
the bench's measured stretch.

The threads are profiled with ``cProfile`` (deterministic profiling: it slows Python code
down, native code such as MuJoCo's step and the ray-cast kernel not, so the shares of Python
work come out somewhat high; compare runs with each other, not with the bench's plain real-time
factor).  The simulation thread's time is split by entry point: the physics (the guarded
``mj_step`` calls, split by MuJoCo's own timers into collision, making and solving the
constraints and the rest of its step), each sensor type's measurement (its ray casting
included, which is also given on its own line), report scheduling, the rest of building the
outputs, world systems, handing the outputs to the server and the rest; with a measuring
thread, the sensors' lines are that thread's, and the simulation thread's own line is handing
each instant over to it (copying the world's state, waiting for a free copy).  Its CPU time
beside its wall time tells how long it waited for the interpreter lock (the GIL) or slept.  The
event loop's time is split into formatting lines, socket writes, reading clients' lines and the
rest (mostly waiting).
"""

from __future__ import annotations

import concurrent.futures
import cProfile
import inspect
import pstats
import threading
import time
from dataclasses import dataclass, field

# MuJoCo's own timers of its step (mjData.timer), summed into the parts of the physics that
# the profile shows: (what, the timers)
PHYSICS_PARTS = (
    ("collision, broad phase", ("mjTIMER_COL_BROAD",)),
    ("collision, narrow phase", ("mjTIMER_COL_NARROW",)),
    ("making constraints", ("mjTIMER_POS_MAKE", "mjTIMER_POS_PROJECT")),
    ("solving constraints", ("mjTIMER_CONSTRAINT",)),
    ("kinematics, inertia", ("mjTIMER_POS_KINEMATICS", "mjTIMER_POS_INERTIA")),
    ("the rest of its step", ("mjTIMER_VELOCITY", "mjTIMER_ACTUATION", "mjTIMER_ADVANCE")),
)


def physics_timers(d) -> dict[str, tuple[float, int]]:
    """MuJoCo's step timers of ``d`` so far: {timer: (seconds, count)}."""
    import mujoco

    out = {}
    for name, t in mujoco.mjtTimer.__members__.items():
        i = int(t)
        if name.startswith("mjTIMER_") and i < len(d.timer):
            out[name] = (float(d.timer[i].duration), int(d.timer[i].number))
    return out


def physics_parts(before: dict, after: dict) -> list[tuple[str, float]]:
    """The physics' parts between two readings of :func:`physics_timers`, in seconds (MuJoCo
    times them in seconds of wall clock)."""

    def spent(names) -> float:
        return sum(after.get(n, (0.0, 0))[0] - before.get(n, (0.0, 0))[0] for n in names)

    return [(what, max(0.0, spent(names))) for what, names in PHYSICS_PARTS]


@dataclass
class ThreadProfile:
    """What the profile measured of one thread over the bench's measured stretch: its ``cProfile`` statistics, its
    wall time and its CPU time in seconds (the difference is time spent waiting for the GIL or asleep)."""

    stats: pstats.Stats | None = None
    wall_s: float = 0.0
    cpu_s: float = 0.0


@dataclass
class Profiler:
    """The bench's window hooks (``measure_rtf(window=...)``): profiling starts and stops
    inside the simulation thread and the event loop's thread themselves."""

    sim: ThreadProfile = field(default_factory=ThreadProfile)
    loop: ThreadProfile = field(default_factory=ThreadProfile)
    sensors: ThreadProfile = field(default_factory=ThreadProfile)  # the measuring thread, when there is one

    def __post_init__(self) -> None:
        self._sim_prof = cProfile.Profile()
        self._loop_prof = cProfile.Profile()
        self._sensors_prof = cProfile.Profile()
        self._marks: dict[str, float] = {}
        self._measurer = None
        self._timers: list[dict] = []  # MuJoCo's step timers as the window starts and ends
        self.physics: list[tuple[str, float]] = []  # the physics' parts (seconds)
        self.contacts: tuple[int, int, int] | None = None  # contacts, constraint rows, islands at the end

    def _on_sim(self, fn) -> None:
        concurrent.futures.wait([self._facade.call(lambda sim: fn())], timeout=60)

    def _on_loop(self, app, fn) -> None:
        done = threading.Event()

        def run():
            fn()
            done.set()

        app.control.loop.call_soon_threadsafe(run)
        done.wait(60)

    def start(self, app) -> None:
        self._facade = app.facade

        def sim_start():
            self._timers = [physics_timers(app.facade.sim.data)]
            self._marks["sim_wall"], self._marks["sim_cpu"] = time.perf_counter(), time.thread_time()
            self._sim_prof.enable()

        def loop_start():
            self._marks["loop_wall"], self._marks["loop_cpu"] = time.perf_counter(), time.thread_time()
            self._loop_prof.enable()

        def sensors_start():
            self._marks["sensors_wall"], self._marks["sensors_cpu"] = time.perf_counter(), time.thread_time()
            self._sensors_prof.enable()

        self._on_loop(app, loop_start)
        self._measurer = app.facade.sim.measurer
        if self._measurer is not None:
            self._measurer.call(sensors_start).result(60)
        self._on_sim(sim_start)

    def stop(self, app) -> None:
        def sim_stop():
            self._sim_prof.disable()
            self.sim.wall_s = time.perf_counter() - self._marks["sim_wall"]
            self.sim.cpu_s = time.thread_time() - self._marks["sim_cpu"]
            d = app.facade.sim.data
            self._timers.append(physics_timers(d))
            self.physics = physics_parts(*self._timers)
            self.contacts = (int(d.ncon), int(d.nefc), int(d.nisland))

        def loop_stop():
            self._loop_prof.disable()
            self.loop.wall_s = time.perf_counter() - self._marks["loop_wall"]
            self.loop.cpu_s = time.thread_time() - self._marks["loop_cpu"]

        def sensors_stop():
            self._sensors_prof.disable()
            self.sensors.wall_s = time.perf_counter() - self._marks["sensors_wall"]
            self.sensors.cpu_s = time.thread_time() - self._marks["sensors_cpu"]

        self._on_sim(sim_stop)
        if self._measurer is not None:
            self._measurer.call(sensors_stop).result(60)
            self.sensors.stats = pstats.Stats(self._sensors_prof)
        self._on_loop(app, loop_stop)
        self.sim.stats = pstats.Stats(self._sim_prof)
        self.loop.stats = pstats.Stats(self._loop_prof)


def _where(fn) -> tuple[str, int, str]:
    code = inspect.unwrap(fn).__code__
    return code.co_filename, code.co_firstlineno, code.co_name


def _cum(stats: pstats.Stats, keys) -> float:
    """Cumulative time of the functions ``keys`` (file, line, name); recursion counted once."""
    total = 0.0
    for k in keys:
        entry = stats.stats.get(k)  # type: ignore[attr-defined]  # set by Stats(), not in typeshed
        if entry is not None:
            total += entry[3]
    return total


def _matching(stats: pstats.Stats, pred) -> list[tuple]:
    return [k for k in stats.stats if pred(k)]  # type: ignore[attr-defined]  # set by Stats(), not in typeshed


def _sensor_rows(s: pstats.Stats) -> tuple[list[tuple[str, float]], float]:
    """Each sensor type's measurements and the robots' statuses (largest first), then the ray
    casting among them; and their total."""
    from usarsim.sensors import SENSORS
    from usarsim.sim import raycaster, status

    total = 0.0
    per_type = []
    seen = set()
    for name in SENSORS.names():
        cls = SENSORS.get(name)
        if cls in seen:
            continue
        seen.add(cls)
        # a sensor's own measurement: measure (or sense and reading, with the framework's noise
        # between them, counted on its own row below)
        keys = {_where(getattr(cls, m)) for m in ("measure", "measure_group", "sense", "reading") if m in cls.__dict__}
        t = _cum(s, keys)
        if t > 0:
            per_type.append((f"sensor {cls.__name__}", t))
            total += t
    from usarsim.sensors.noise import Noise

    noise = _cum(s, [_where(cls.apply) for cls in Noise.__subclasses__()])
    if noise > 0:
        per_type.append(("sensor noise (declared, applied by the framework)", noise))
        total += noise
    statuses = _cum(s, [_where(status.status_output)])  # made where the sensors are read
    if statuses > 0:
        per_type.append(("statuses (STA, MISSTA)", statuses))
        total += statuses
    per_type.sort(key=lambda r: -r[1])
    cast_keys = _matching(s, lambda k: k[0] == raycaster.__file__ and k[2] in ("cast", "cast_from", "count_walls"))
    return per_type + [("  of which ray casting (all sensors)", _cum(s, cast_keys))], total


def breakdown(p: Profiler) -> dict:
    """The shares: {"sim": [(what, seconds)], "sensors": [...], "loop": [...], "sim_wall_s", ...}
    ("sensors": the measuring thread's, empty without one)."""
    from usarsim.sim import health, measuring, reports, runner
    from usarsim.sim.simulation import Simulation

    s = p.sim.stats
    assert s is not None, "the profiler has not stopped"
    rows: list[tuple[str, float]] = []
    physics = _cum(s, [_where(health.BlowUpGuard.step)])
    rows.append(("physics (MuJoCo steps)", physics))
    parts = [(f"  of which {what}", t) for what, t in p.physics]
    sensor_rows, sensor_total = _sensor_rows(s)
    rows += [r for r in sensor_rows if r[1] > 0]
    handing = _cum(s, [_where(measuring.Measurer.submit)])
    if handing > 0:
        rows.append(("handing instants to the measuring thread", handing))
    taking = ("take_due", "take_due_plans", "next_due")
    sched = _cum(s, _matching(s, lambda k: k[0] == reports.__file__ and k[2] in taking))
    rows.append(("report scheduling", sched))
    fire = _cum(s, [_where(Simulation._fire_due)])
    building = max(0.0, fire - sensor_total - sched - handing)
    rows.append(("building readings, besides the sensors", building))
    systems = _cum(s, _matching(s, lambda k: k[2] == "pre_step" and "/sim/systems/" in k[0]))
    rows.append(("world systems", systems))
    flush = _cum(s, [_where(runner.SimulationRunner._flush)])
    rows.append(("handing outputs to the server", flush))
    accounted = physics + sensor_total + handing + sched + building + systems + flush
    rows.append(("the rest (requests, clock)", max(0.0, p.sim.wall_s - accounted)))
    rows[1:1] = parts  # under the physics line, not counted twice

    sensors: list[tuple[str, float]] = []
    if p.sensors.stats is not None:
        sensor_rows, sensor_total = _sensor_rows(p.sensors.stats)
        sensors = sensor_rows + [("waiting for instants (idle)", max(0.0, p.sensors.wall_s - sensor_total))]

    lp = p.loop.stats
    assert lp is not None, "the profiler has not stopped"
    from usarsim.protocol import messages

    loop_rows = []
    fmt = _cum(lp, [_where(messages.format_message)])
    loop_rows.append(("formatting lines", fmt))
    writes = _cum(lp, _matching(lp, lambda k: k[2] == "write" and k[0].endswith("selector_events.py")))
    loop_rows.append(("socket writes", writes))
    reads = _cum(lp, _matching(lp, lambda k: k[2] == "data_received" and "/usarsim/server/" in k[0]))
    loop_rows.append(("reading and handling clients' lines", reads))
    waiting = _cum(lp, _matching(lp, lambda k: k[2] == "select" and k[0].endswith("selectors.py")))
    loop_rows.append(("waiting for sockets (idle)", waiting))
    loop_rows.append(("the rest", max(0.0, p.loop.wall_s - fmt - writes - reads - waiting)))
    return {
        "sim": rows,
        "sensors": sensors,
        "loop": loop_rows,
        "contacts": p.contacts,
        "sim_wall_s": p.sim.wall_s,
        "sim_cpu_s": p.sim.cpu_s,
        "sensors_wall_s": p.sensors.wall_s,
        "sensors_cpu_s": p.sensors.cpu_s,
        "loop_wall_s": p.loop.wall_s,
        "loop_cpu_s": p.loop.cpu_s,
    }


def format_breakdown(b: dict, sim_seconds: float) -> str:
    """The breakdown as a table: milliseconds of wall time per simulated second and shares."""
    out = []
    sw = b["sim_wall_s"] or 1e-9
    out.append(
        f"simulation thread: {sw:.2f} s wall, {b['sim_cpu_s']:.2f} s CPU "
        f"(waiting for the interpreter lock or sleeping: {100 * (1 - b['sim_cpu_s'] / sw):.0f} %)"
    )
    physics_parts_end = 1  # the physics line, then its parts (the lines right after it)
    while physics_parts_end < len(b["sim"]) and b["sim"][physics_parts_end][0].startswith("  of which"):
        physics_parts_end += 1
    for i, (what, t) in enumerate(b["sim"]):
        out.append(f"  {what:<42} {1000 * t / sim_seconds:8.1f} ms per simulated s  {100 * t / sw:5.1f} %")
        if i + 1 == physics_parts_end and b.get("contacts"):
            ncon, nefc, nisland = b["contacts"]
            out.append(
                f"    (the parts by MuJoCo's own timers; at the end {ncon:,} contacts, {nefc:,} constraint "
                f"rows, {nisland:,} islands)"
            )
    if b.get("sensors"):
        mw = b["sensors_wall_s"] or 1e-9
        out.append(f"measuring thread (sensor readings): {mw:.2f} s wall, {b['sensors_cpu_s']:.2f} s CPU")
        for what, t in b["sensors"]:
            out.append(f"  {what:<42} {1000 * t / sim_seconds:8.1f} ms per simulated s  {100 * t / mw:5.1f} %")
    lw = b["loop_wall_s"] or 1e-9
    out.append(f"event loop (server): {lw:.2f} s wall, {b['loop_cpu_s']:.2f} s CPU")
    for what, t in b["loop"]:
        out.append(f"  {what:<42} {1000 * t / sim_seconds:8.1f} ms per simulated s  {100 * t / lw:5.1f} %")
    return "\n".join(out)
