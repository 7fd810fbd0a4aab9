"""``usarsim bench --ros2 --robots N``: what the ROS 2 bridge costs and delivers.

N P2ATs with their full kit in real time (speed 1), twice each way, alternately, with the
simulator's report phases spread (``serve --report-phases spread``: each robot reports on a phase
of its own) unless ``--report-phases grid`` says:

* **without** the bridge: an ordinary protocol client (``usarsim.bench``'s) spawns and drives
  them and reads every line;
* **with** it: ``usarsim ros2`` spawns them; a subscriber in a third process (real rclpy)
  subscribes to every topic of every robot and to ``/clock``, and drives each robot over
  ``cmd_vel`` in the same pattern.

The simulator runs in this process, so the wall time at which its clock reached each simulated
time is known (sampled every millisecond): a message's delay is the wall time the subscriber got
it less the wall time the simulator reached its stamp.  Per topic kind: messages a second per
robot, the share of readings missed (gaps in the stamps), and the delay's median, 95th percentile
and maximum.  Per run: the real-time factor reached, and the simulator's CPU seconds per
simulated second (this process: the server and the 1 ms sampler, the same both ways).
"""

from __future__ import annotations

import bisect
import importlib
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

SETTLE_S = 1.0  # after every topic has delivered, before the measured stretch
STEADY_LIMIT_S = 90.0  # the most the subscriber may take to hear every topic
DRAIN_S = 1.0  # after the measured stretch, for its last messages to arrive
QUIET_S = 2.0  # discovery is taken as done when no new topic came in this long
# the bench client's DRIVE pattern (usarsim.bench.clients), as Twists for a P2AT: m/s, rad/s
DRIVE_PATTERN = ((0.26, 0.0), (0.0, 0.55), (0.195, 0.0), (0.0, -0.55))
# published when something happens, not at a rate: no "missed" figure (clock: whenever the
# simulated time the bridge has seen advances; victims: while one is in view)
IRREGULAR = ("clock", "victims", "rfid")


def _message_class(type_name: str) -> Any:
    package, _, cls = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), cls)


def _kind(topic: str) -> str:
    """``/robot3/sonar/F1`` -> ``sonar``; ``/clock`` -> ``clock``."""
    parts = topic.strip("/").split("/")
    return parts[0] if len(parts) == 1 else parts[1]


def subscriber_main(n: int, limit_s: float, out: str) -> int:
    """Child process: subscribe to every topic of robot1..robotN and /clock and drive the robots
    over cmd_vel; print "steady" once every robot's topics are known and each has delivered,
    and when told "stop" on standard input (or after ``limit_s`` of wall time) write (topic,
    stamp, wall) of every message to ``out`` (JSON)."""
    from usarsim.ros2.setup import prepare

    prepare()
    import select

    import rclpy
    from geometry_msgs.msg import Twist
    from rclpy.experimental import EventsExecutor

    rclpy.init()
    node = rclpy.create_node("usarsim_bench_subscriber")
    # rclpy's events executor: a callback's cost does not grow with the hundreds of subscriptions
    # (the default executor's does, which would make the subscriber the bottleneck measured)
    executor = EventsExecutor()
    executor.add_node(node)
    got: list[tuple[str, float, float]] = []
    subs: set[str] = set()
    heard: set[str] = set()
    robots = [f"/robot{i + 1}" for i in range(n)]
    pubs = {r: node.create_publisher(Twist, f"{r}/cmd_vel", 10) for r in robots}

    import struct

    from rclpy.serialization import deserialize_message

    def keeper(topic: str, msg_type: Any) -> Any:
        # raw (serialised) messages: the subscriber's own Python costs stay out of the figures.
        # A stamped message's CDR starts with its 4-byte encapsulation, then the header's stamp
        # (int32 sec, uint32 nanosec); so does a Clock's; a MarkerArray's stamp is inside.
        stamped = topic == "/clock" or "header" in msg_type.get_fields_and_field_types()
        markers = hasattr(msg_type, "get_fields_and_field_types") and "markers" in msg_type.get_fields_and_field_types()

        def keep(raw: bytes) -> None:
            wall = time.time()
            heard.add(topic)
            if stamped:
                sec, nsec = struct.unpack_from("<iI", raw, 4)
                got.append((topic, sec + nsec * 1e-9, wall))
            elif markers:
                msg = deserialize_message(raw, msg_type)
                s = msg.markers[-1].header.stamp if msg.markers else None
                got.append((topic, -1.0 if s is None else s.sec + s.nanosec * 1e-9, wall))
            else:
                got.append((topic, -1.0, wall))

        return keep

    def discover() -> bool:
        """Subscribe to topics not seen before; True if there were any."""
        new = False
        for topic, types in node.get_topic_names_and_types():
            if topic in subs or not (topic == "/clock" or any(topic.startswith(r + "/") for r in robots)):
                continue
            if node.count_publishers(topic) == 0:  # the bridge's subscriptions (cmd_vel, joint_commands...)
                continue
            subs.add(topic)
            new = True
            cls = _message_class(types[0])
            node.create_subscription(cls, topic, keeper(topic, cls), 10, raw=True)
        return new

    import gc

    # the list of what arrived grows by thousands of tuples a second: the collector's full passes
    # over it would stall this process (the instrument) by tens of milliseconds, so it stays off
    gc.disable()
    start = time.monotonic()
    phase = -1
    print("subscriber: up", flush=True)
    next_discovery = start
    last_new = start
    steady = False
    while time.monotonic() - start < limit_s:
        now = time.monotonic()
        if now >= next_discovery:
            if discover():
                last_new = now
            next_discovery = now + (0.2 if not steady else 1.0)
        if not steady and now - last_new > QUIET_S:
            regular = {t for t in subs if _kind(t) not in IRREGULAR}
            # the robots are P2ATs with the same kit: the same topics each once discovery is done
            per_robot = {sum(t.startswith(r + "/") for t in regular) for r in robots}
            if heard >= regular and len(per_robot) == 1 and 0 not in per_robot:
                steady = True
                print(f"subscriber: steady, {len(subs)} topics", flush=True)
            elif now - start > STEADY_LIMIT_S:
                print(f"subscriber: not steady, {len(heard & regular)} of {len(regular)} topics heard", flush=True)
                break
        p = int((now - start) / 2.0)
        if p != phase:
            phase = p
            for i, r in enumerate(robots):
                m = Twist()
                m.linear.x, m.angular.z = DRIVE_PATTERN[(phase + i) % 4]
                pubs[r].publish(m)
        executor.spin_once(timeout_sec=0.01)
        if select.select([sys.stdin], [], [], 0)[0] and sys.stdin.readline().strip() in ("stop", ""):
            break
    Path(out).write_text(json.dumps({"topics": sorted(subs), "messages": got}))
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


class _ClockSampler:
    """(wall, simulated) pairs every millisecond, on a thread."""

    def __init__(self, sim: Any):
        self.sim = sim
        self.walls: list[float] = []
        self.sims: list[float] = []
        self._stop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        last = -1.0
        while not self._stop:
            t = self.sim.time
            if t != last:
                self.walls.append(time.time())
                self.sims.append(t)
                last = t
            time.sleep(0.001)

    def wall_at(self, sim_t: float) -> float | None:
        """The wall time the simulator's clock first reached ``sim_t``."""
        i = bisect.bisect_left(self.sims, sim_t - 1e-9)
        return self.walls[i] if i < len(self.walls) else None

    def stop(self) -> None:
        self._stop = True
        self.thread.join(2)


def _one_run(world: Any, spots: list, seconds: float, with_bridge: bool, domain: int, phases: str) -> dict:
    from usarsim.bench.serving import ServedApp, bench_app
    from usarsim.sim.settings import SimSettings

    n = len(spots)
    app = bench_app(
        world, speed=1.0, lockstep=False, max_connections=max(64, 2 * n), sim=SimSettings(report_phases=phases)
    )
    served = ServedApp(app)
    sim = app.facade.sim
    port = app.control.port
    procs: list[subprocess.Popen] = []
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    tmp = tempfile.TemporaryDirectory(prefix="usarsim-bench-ros2-")
    out = Path(tmp.name) / "received.json"
    try:
        if with_bridge:
            robots = Path(tmp.name) / "robots.yaml"
            robots.write_text(
                "".join(
                    f"- {{class: P2AT, name: robot{i + 1}, location: [{x:.3f}, {y:.3f}, {z:.3f}], yaw: {yaw:.4f}}}\n"
                    for i, (x, y, z, yaw) in enumerate(spots)
                )
            )
            bridge = subprocess.Popen(
                [sys.executable, "-m", "usarsim", "ros2", "--port", str(port), "--robots", str(robots)],
                env=env,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            procs.append(bridge)
            assert bridge.stdout is not None  # stdout=PIPE
            line = bridge.stdout.readline()
            if not line.startswith("usarsim ros2:"):
                why = bridge.communicate(timeout=30)[1][-2000:]
                raise SystemExit(f"usarsim bench: the bridge did not start: {why}")
        else:
            procs.append(
                subprocess.Popen(
                    [sys.executable, "-m", "usarsim.bench", "--client", str(port), json.dumps(spots), str(seconds)],
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                )
            )
        deadline = time.monotonic() + 120
        while len(sim.robots) < n:
            if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
                raise SystemExit(f"usarsim bench: only {len(sim.robots)} of {n} robots spawned")
            time.sleep(0.01)
        sampler = _ClockSampler(sim)
        if with_bridge:
            sub = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "usarsim.ros2.bench",
                    "--subscribe",
                    str(n),
                    str(STEADY_LIMIT_S + SETTLE_S + seconds + DRAIN_S + 30.0),
                    str(out),
                ],
                env=env,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                text=True,
            )
            procs.append(sub)
            assert sub.stdin is not None and sub.stdout is not None  # PIPE
            sub.stdout.readline()  # up
            steady = sub.stdout.readline()  # every topic heard (or the subscriber gave up)
            if not steady.startswith("subscriber: steady"):
                raise SystemExit(f"usarsim bench: the subscriber did not hear every robot's topics ({steady.strip()})")
        time.sleep(SETTLE_S if with_bridge else 2 * SETTLE_S)
        sim0, wall0, cpu0 = sim.time, time.perf_counter(), time.process_time()
        time.sleep(seconds)
        sim1, wall1, cpu1 = sim.time, time.perf_counter(), time.process_time()
        if with_bridge:
            time.sleep(DRAIN_S)  # the window's last messages on their way
            assert sub.stdin is not None  # PIPE
            sub.stdin.write("stop\n")
            sub.stdin.flush()
            sub.wait(60)
        sampler.stop()
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                p.terminate()
                try:
                    p.wait(20)
                except subprocess.TimeoutExpired:
                    p.kill()
        served.stop()
    result: dict[str, Any] = {
        "bridge": with_bridge,
        "rtf": (sim1 - sim0) / (wall1 - wall0),
        "cpu_per_sim_s": (cpu1 - cpu0) / max(1e-9, sim1 - sim0),
    }
    if with_bridge:
        data = json.loads(out.read_text())
        result["kinds"] = _topic_figures(data["messages"], sampler, sim0, sim1, n)
    tmp.cleanup()
    return result


def _topic_figures(messages: list, sampler: _ClockSampler, sim0: float, sim1: float, n: int) -> dict:
    """Per topic kind: messages a second per robot, share missed, delay percentiles (ms)."""
    by_topic: dict[str, list[tuple[float, float]]] = {}
    for topic, stamp, wall in messages:
        if sim0 <= stamp <= sim1:
            by_topic.setdefault(topic, []).append((stamp, wall))
    kinds: dict[str, dict[str, list[float]]] = {}
    for topic, rows in by_topic.items():
        k = kinds.setdefault(_kind(topic), {"rates": [], "missed": [], "delays": []})
        stamps = sorted({s for s, _ in rows})
        k["rates"].append(len(rows) / (sim1 - sim0))
        if len(stamps) >= 3 and _kind(topic) not in IRREGULAR:
            gaps = [b - a for a, b in zip(stamps, stamps[1:])]
            step = statistics.median(gaps)
            # the readings a topic at its rate has in the window, whatever its phase: gaps inside,
            # and a late start or an early end, count as missed
            expected = math.floor((sim1 - sim0) / step + 1e-6) if step > 0 else len(stamps)
            k["missed"].append(max(0, expected - len(stamps)) / max(1, expected))
        for stamp, wall in rows:
            at = sampler.wall_at(stamp)
            if at is not None:
                k["delays"].append((wall - at) * 1000.0)
    out = {}
    for kind, k in sorted(kinds.items()):
        d = sorted(k["delays"])
        out[kind] = {
            "topics": len(k["rates"]),
            "hz_per_topic": statistics.mean(k["rates"]),
            "missed": max(k["missed"]) if k["missed"] else None,
            "delay_ms_p50": d[len(d) // 2] if d else None,
            "delay_ms_p95": d[min(len(d) - 1, int(0.95 * len(d)))] if d else None,
            "delay_ms_max": d[-1] if d else None,
        }
    return out


def run_ros2_bench(args: Any) -> int:
    from usarsim.bench.serving import logging_quiet
    from usarsim.bench.spots import spread_spots
    from usarsim.config.catalog import resolve_world
    from usarsim.errors import UsarsimError
    from usarsim.extras import MissingExtraError, require

    try:
        require("ros2", "usarsim bench --ros2")
        from usarsim.ros2.setup import prepare
        from usarsim.ros2.tf2_build import ensure_tf2_msgs

        domain = prepare()
        ensure_tf2_msgs()
        world = resolve_world(args.world)
    except (MissingExtraError, UsarsimError) as exc:
        print(f"usarsim: error: {exc}", file=sys.stderr)
        return 1
    logging_quiet()
    n = max(1, args.robots)
    seconds = args.seconds
    spots = spread_spots(world, n)
    runs = []
    for i, with_bridge in enumerate((False, True) * max(1, args.runs)):
        if not args.json:
            print(
                f"  run {i + 1}: {n} P2ATs in real time for {seconds:g} s, "
                f"{'with' if with_bridge else 'without'} the ROS 2 bridge",
                file=sys.stderr,
                flush=True,
            )
        runs.append(_one_run(world, spots, seconds, with_bridge, domain, args.report_phases))
    plain = [r for r in runs if not r["bridge"]]
    bridged = [r for r in runs if r["bridge"]]
    summary = {
        "robots": n,
        "seconds": seconds,
        "world": world.name,
        "report_phases": args.report_phases,
        "runs": len(runs),
        "rtf_without": [round(r["rtf"], 4) for r in plain],
        "rtf_with": [round(r["rtf"], 4) for r in bridged],
        "cpu_per_sim_s_without": [round(r["cpu_per_sim_s"], 4) for r in plain],
        "cpu_per_sim_s_with": [round(r["cpu_per_sim_s"], 4) for r in bridged],
        "kinds": bridged[-1]["kinds"],
        "cpu_count": os.cpu_count(),
    }
    worst: dict[str, dict] = {}
    for r in bridged:
        for kind, f in r["kinds"].items():
            w = worst.setdefault(kind, dict(f))
            for key in ("delay_ms_p95", "delay_ms_max", "missed"):
                if f[key] is not None and (w[key] is None or f[key] > w[key]):
                    w[key] = f[key]
    summary["kinds"] = worst
    if args.json:
        print(json.dumps(summary))
        return 0
    drop = 1 - statistics.mean(summary["rtf_with"]) / statistics.mean(summary["rtf_without"])
    print(
        f"{n} P2ATs in real time ({world.name}, report phases: {args.report_phases}), {len(runs)} runs of "
        f"{seconds:g} s alternately without and with the ROS 2 bridge:"
    )
    print(
        f"  real-time factor reached: without {_range(summary['rtf_without'], 3)}, with "
        f"{_range(summary['rtf_with'], 3)} ({drop * 100:+.1f} % drop)"
    )
    print(
        f"  simulator CPU per simulated second: without {_range(summary['cpu_per_sim_s_without'], 3)} s, with "
        f"{_range(summary['cpu_per_sim_s_with'], 3)} s"
    )
    print(f"  {'topic':14s} {'topics':>6s} {'Hz each':>8s} {'missed':>7s} {'delay p50':>10s} {'p95':>8s} {'max':>8s}")
    for kind, f in sorted(summary["kinds"].items()):
        missed = "-" if f["missed"] is None else f"{f['missed'] * 100:.1f}%"
        print(
            f"  {kind:14s} {f['topics']:6d} {f['hz_per_topic']:8.2f} {missed:>7s} "
            f"{_ms(f['delay_ms_p50']):>10s} {_ms(f['delay_ms_p95']):>8s} {_ms(f['delay_ms_max']):>8s}"
        )
    print(
        "  (delay: from the simulator's clock reaching a reading's stamp to a subscriber in another process "
        "getting it; worst of the runs)"
    )
    return 0


def _range(values: list[float], digits: int) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:.{digits}f}" if lo == hi else f"{lo:.{digits}f} - {hi:.{digits}f}"


def _ms(v: float | None) -> str:
    return "-" if v is None else f"{v:.1f} ms"


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "--subscribe":
        sys.exit(subscriber_main(int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]))
    sys.exit("usage: python -m usarsim.ros2.bench --subscribe N LIMIT_SECONDS OUT (usarsim bench --ros2 runs it)")
