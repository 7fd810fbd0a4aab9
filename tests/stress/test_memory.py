"""Robots with their full sensor kits run for a long stretch of simulated time with flat
memory (issue: reliability): what the server holds does not grow with time.  Reduced: 8
P2ATs for 120 simulated seconds; full (USARSIM_STRESS=full): 64 P2ATs for 10 simulated
minutes."""

from __future__ import annotations

import json
import subprocess
import sys
import time

from stress_scale import scaled
from test_load import rss_mb


def test_many_robots_run_long_with_flat_memory(server_factory, caplog):
    from usarsim.bench import free_spots

    n = scaled(8, 64)
    seconds = float(scaled(120, 600))
    srv = server_factory(lockstep=False, speed=None, seed=6, max_connections=n + 1)
    poses = free_spots(srv.app.world, n)
    client = subprocess.Popen(
        [sys.executable, "-m", "usarsim.bench", "--client", str(srv.port), json.dumps(poses), str(seconds)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 60
        while srv.on_sim(lambda sim: len(sim.robots)) < n:
            assert time.monotonic() < deadline and client.poll() is None
            time.sleep(0.05)
        samples = []  # (simulated s, resident MB)
        t0 = srv.on_sim(lambda sim: sim.time)
        wall_limit = time.monotonic() + scaled(120, 3000)
        while True:
            t = srv.on_sim(lambda sim: sim.time) - t0
            samples.append((t, rss_mb()))
            if t >= seconds or time.monotonic() > wall_limit:
                break
            time.sleep(0.5)
    finally:
        client.terminate()
        client.wait(10)
    t_end = samples[-1][0]
    assert t_end >= 0.5 * seconds, f"only {t_end:.0f} of {seconds:.0f} simulated s in the time allowed"
    quarter = [m for t, m in samples if t >= 0.25 * t_end]
    print(
        f"\n{n} robots, {t_end:.0f} simulated s: resident memory {quarter[0]:.0f} MB after a quarter, "
        f"{max(quarter):.0f} MB at most, {samples[-1][1]:.0f} MB at the end; "
        f"robots reset by the blow-up guard: "
        f"{srv.on_sim(lambda sim: {r.name: r.resets for r in sim.robots.values() if r.resets}) or 'none'}"
    )
    for line in [r.getMessage() for r in caplog.records if "unstable" in r.getMessage()][:5]:
        print("  " + line)
    assert max(quarter) - quarter[0] < 30.0  # flat after the first quarter
