"""``usarsim bench --radio-load``: what the radio channel costs the simulation.  N P2ATs with
their full kit drive about (``python -m usarsim.bench --client``) while every robot sends each
teammate RATE messages a simulated second through the ComServer (a process of their own:
``--radio-client``), once under USARSim's ideal channel and once under a SubT-like channel
(capacity, shadowing, fading and loss: the figures of examples/subt_radio.yaml), alternately;
the real-time factor of each, their ratio, and what the channel delivered and lost."""

from __future__ import annotations

import dataclasses
import json
import multiprocessing as mp
import os
import statistics
import subprocess
import sys
import time

from usarsim.bench.serving import ServedApp, bench_app, logging_quiet
from usarsim.bench.spots import spread_spots
from usarsim.config.channel import ChannelConfig
from usarsim.config.world import WirelessConfig

# The SubT-like channel (examples/subt_radio.yaml gives the same figures and their sources)
SUBT_CHANNEL = ChannelConfig(
    shadowing_db=4.0,
    shadowing_wall_db=3.0,
    shadowing_distance_m=2.0,
    fading="rayleigh",
    loss="signal",
    link_bytes_per_s=125_000.0,
    radio_bytes_per_s=125_000.0,
    queue_bytes=1_000_000,
    latency_s=0.002,
    jitter_s=0.002,
)
MESSAGE = bytes(range(64))  # a message: 64 bytes (a pose and a few numbers)


def radio_client(port: int, names: list[str], rate_hz: float, clock, ready, stop) -> None:
    """Register ``names`` with the ComServer at ``port`` and link every pair that the radio lets
    through; set ``ready``; then until ``stop`` is set send each teammate ``rate_hz`` messages a
    simulated second (``clock``: the simulated time, shared with the bench), reading what
    arrives."""
    from usarsim.client.radio import Radio, link

    radios = [Radio("127.0.0.1", port, n, timeout=30.0) for n in names]
    try:
        for i, a in enumerate(radios):
            for b in radios[i + 1 :]:
                link(a, b)
        ready.value = sum(len(r.links) for r in radios) // 2
        period = 1.0 / rate_hz
        due = clock.value
        while not stop.is_set():
            now = clock.value
            while due <= now:
                for r in radios:
                    r.broadcast(MESSAGE)
                due += period
            for r in radios:
                r.poll()
            time.sleep(0.002)
    finally:
        for r in radios:
            r.close()


def process_cpu_s() -> float:
    """The CPU time this process (the server) has used, user and system, in seconds."""
    t = os.times()
    return t.user + t.system


def radio_rtf(world, n: int, seconds: float, channel: ChannelConfig | None, rate_hz: float) -> dict:
    """One run: the real-time factor with the radio load under ``channel`` (None: USARSim's)."""
    from usarsim.server.wireless import WirelessOptions

    if channel is not None:
        base = world.wireless or WirelessConfig()
        world = dataclasses.replace(world, wireless=dataclasses.replace(base, channel=channel))
    poses = spread_spots(world, n)
    app = bench_app(
        world,
        speed=None,
        lockstep=False,
        max_connections=max(64, n),
        wireless=WirelessOptions(wcs_port=0, wss_port=0, interface_port=0, max_connections=max(64, 2 * n)),
    )
    served = ServedApp(app)
    ctx = mp.get_context("spawn")
    clock, ready, stop = ctx.Value("d", 0.0), ctx.Value("i", -1), ctx.Event()
    driver = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "usarsim.bench",
            "--client",
            str(app.control.port),
            json.dumps(poses),
            str(seconds + 30),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    sim = app.facade.sim
    talker = None
    try:
        deadline = time.monotonic() + 120
        while len(sim.robots) < n:
            if time.monotonic() > deadline or driver.poll() is not None:
                raise SystemExit(f"usarsim bench: only {len(sim.robots)} of {n} robots spawned")
            time.sleep(0.01)
        names = sorted(r.name for r in sim.robots.values())
        assert app.wireless is not None
        clock.value = sim.time
        talker = ctx.Process(
            target=radio_client, args=(app.wireless.comserver.port, names, rate_hz, clock, ready, stop), daemon=True
        )
        talker.start()
        deadline = time.monotonic() + 120
        while ready.value < 0:  # every link open
            if time.monotonic() > deadline or not talker.is_alive():
                raise SystemExit("usarsim bench: the radio client did not link the robots")
            clock.value = sim.time
            time.sleep(0.005)
        t_settle = sim.time + 1.0  # messages flowing
        while sim.time < t_settle:
            clock.value = sim.time
            time.sleep(0.005)
        start, wall, cpu = sim.time, time.perf_counter(), process_cpu_s()
        while sim.time - start < seconds:
            clock.value = sim.time
            time.sleep(0.005)
        sim_s, wall_s, cpu_s = sim.time - start, time.perf_counter() - wall, process_cpu_s() - cpu
        net = app.facade.radio_net
        counts = list(net.counts().values()) if net is not None else []
    finally:
        stop.set()
        if talker is not None:
            talker.join(30)
        driver.terminate()
        driver.wait(10)
        served.stop()
    return {
        "rtf": round(sim_s / wall_s, 3),
        "server_cpu_ms_per_sim_s": round(1000.0 * cpu_s / sim_s, 1),
        "links": int(ready.value),
        "delivered": sum(c.delivered for c in counts),
        "lost": sum(sum(c.dropped.values()) for c in counts),
    }


def run_radio_bench(args) -> int:
    """Alternate runs with USARSim's channel and the SubT-like one (``--runs`` pairs)."""
    from usarsim.config.catalog import resolve_world

    logging_quiet()
    world = resolve_world(args.world)
    n = int(args.robots) if int(args.robots) > 1 else 16
    seconds = float(args.seconds)
    rate = float(args.radio_rate)
    runs: dict[str, list[dict]] = {"ideal": [], "subt": []}
    for k in range(max(1, int(args.runs))):
        for name, channel in (
            (("ideal", None), ("subt", SUBT_CHANNEL)) if k % 2 == 0 else (("subt", SUBT_CHANNEL), ("ideal", None))
        ):
            r = radio_rtf(world, n, seconds, channel, rate)
            runs[name].append(r)
            if not args.json:
                print(f"  {name:5s}: real-time factor {r['rtf']:.3f}", file=sys.stderr, flush=True)
    ideal = statistics.median(r["rtf"] for r in runs["ideal"])
    subt = statistics.median(r["rtf"] for r in runs["subt"])
    result = {
        "robots": n,
        "messages_per_s_to_each_teammate": rate,
        "sim_seconds": seconds,
        "rtf_ideal": [r["rtf"] for r in runs["ideal"]],
        "rtf_subt": [r["rtf"] for r in runs["subt"]],
        "cost_percent": round(100.0 * (1.0 - subt / ideal), 1),
        "server_cpu_ms_per_sim_s_ideal": [r["server_cpu_ms_per_sim_s"] for r in runs["ideal"]],
        "server_cpu_ms_per_sim_s_subt": [r["server_cpu_ms_per_sim_s"] for r in runs["subt"]],
        "subt_delivered": [r["delivered"] for r in runs["subt"]],
        "subt_lost": [r["lost"] for r in runs["subt"]],
        "links": [r["links"] for r in runs["ideal"] + runs["subt"]],
    }
    cpu_ideal = statistics.median(result["server_cpu_ms_per_sim_s_ideal"])
    cpu_subt = statistics.median(result["server_cpu_ms_per_sim_s_subt"])
    result["server_cpu_percent_more"] = round(100.0 * (cpu_subt / cpu_ideal - 1.0), 1)
    if args.json:
        print(json.dumps(result))
    else:
        print(
            f"radio load, {n} robots each sending every teammate {rate:g} messages a simulated second: real-time "
            f"factor {ideal:.3f} with USARSim's channel, {subt:.3f} with the SubT-like one (median of "
            f"{len(runs['ideal'])}); the channel costs {result['cost_percent']:.1f} %; the server used "
            f"{cpu_ideal:.0f} and {cpu_subt:.0f} ms of CPU a simulated second "
            f"({result['server_cpu_percent_more']:+.1f} %); it delivered "
            f"{result['subt_delivered']} and lost {result['subt_lost']} messages on {result['links']} links"
        )
    return 0
