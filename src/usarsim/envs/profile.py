"""Where an environment step's time goes (``usarsim bench --env --profile``).

An environment step sends its robots' commands, asks the lock-step simulator for one control
period and reads every line the robots got.  Over the same timed steps as
:func:`usarsim.envs.bench_env`, this measures the wall time of a step, the processor time
the environment's own process spent in it (the client: formatting commands, parsing the
readings, building the observation), the processor time of the simulator's process (its
event loop, the session, the physics, the sensors, formatting the readings) and, beside
them, what bare ``mj_step`` of the same robots at the same start poses takes for one control
period: the physics a step cannot do without, timed after each stretch of steps.  The
simulator's processor time is read from ``/proc`` (Linux); elsewhere it is left out.
"""

from __future__ import annotations

import os
import statistics
import time
from typing import Any

# Stretches of steps a profile is timed in, each followed by bare physics (env_profile).
BLOCKS = 5
# Simulated seconds of each run of bare physics after a stretch (three runs, the median).
BARE_SECONDS = 2.0
TICKS = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def process_cpu_s(pid: int) -> float | None:
    """User and system processor seconds of process ``pid`` so far (None: not readable)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return (int(fields[11]) + int(fields[12])) / TICKS  # utime, stime (proc(5), fields 14 and 15)


class BarePhysics:
    """Bare ``mj_step`` (one thread) of ``robot`` at each of ``starts`` (start pose names, or
    (location, rotation)) in ``world``, settled on the floor as an environment's robots are
    after a reset: :meth:`ms` times one control period of it."""

    def __init__(self, world: str, robot: str, starts: list[Any]):
        from usarsim.config.catalog import resolve_robot, resolve_world
        from usarsim.sim.simulation import Simulation

        w = resolve_world(world)
        cfg = resolve_robot(robot)
        sim = Simulation(w, seed=0)
        for uid, start in enumerate(starts, 1):
            if isinstance(start, str):
                pose = w.start_pose(start)
                if pose is None:
                    raise ValueError(f"{world} has no start pose {start!r}")
                sim.spawn(uid, cfg, f"r{uid}", pose.location, pose.rotation, set_down=True)
            else:
                location, rotation = start
                sim.spawn(uid, cfg, f"r{uid}", tuple(location), tuple(rotation))
        sim.advance(0.5)  # settled on the floor, as the environment's robots are after a reset
        self.model = sim.model

    def ms(self, period_s: float, seconds: float = 4.0) -> float:
        """Milliseconds of bare ``mj_step`` for one control period of ``period_s``, from the
        median of a few runs of ``seconds`` (:func:`usarsim.bench.rtf.raw_mujoco_rtf`)."""
        from usarsim.bench.rtf import raw_mujoco_rtf

        return period_s / raw_mujoco_rtf(self.model, seconds) * 1000.0


def env_profile(
    steps: int = 200, team: int = 0, *, seed: int = 0, blocks: int = BLOCKS, **kwargs: Any
) -> dict[str, Any]:
    """Per step of :class:`~usarsim.envs.ExploreEnv` (``team`` 0) or of a
    :class:`~usarsim.envs.TeamExplore` of ``team`` robots, with random actions seeded with
    ``seed``: steps a second, wall, environment and simulator processor milliseconds, and bare
    physics milliseconds (see the module's text).  The steps are timed in ``blocks`` stretches,
    each followed by bare ``mj_step`` of the same robots, so that both see the machine at the
    same speed (on a shared machine it changes by half within a minute): ``share`` is the
    steps a second as a fraction of what bare physics allows, the median over the stretches.
    ``kwargs`` go to the environment."""
    from .bench import timed
    from .explore import ExploreEnv
    from .team import TeamExplore

    kwargs = timed(steps, kwargs)
    period = float(kwargs.get("control_period_s", 0.1))
    env: Any = TeamExplore(robots=team, **kwargs) if team else ExploreEnv(**kwargs)
    wall = cpu = 0.0
    stretches: list[tuple[float, float]] = []  # (wall ms a step, bare physics ms a step) of each
    blocks = max(1, min(int(blocks), steps))
    try:
        env.reset(seed=seed)
        if team:
            for i, a in enumerate(env.possible_agents):
                env.action_space(a).seed(seed + i)
        else:
            env.action_space.seed(seed)
        # the simulator's processor time over all the steps (it works only when a step asks,
        # and /proc counts in ticks of 10 ms): None when a reset launched another one
        server = env.sim.server
        proc = getattr(server, "proc", None)  # None: an in-process simulator (its time is the env's)
        pid = proc.pid if proc is not None else None
        s0 = process_cpu_s(pid) if pid is not None else None
        bare = BarePhysics(env.world_config.name, env.spec_robot.class_name, list(env.starts) if team else [env.start])
        block_wall, block_steps = 0.0, 0
        for i in range(steps):
            if team:
                if not env.agents:
                    env.reset()
                action: Any = {a: env.action_space(a).sample() for a in env.agents}
            else:
                action = env.action_space.sample()
            c0, t0 = time.process_time(), time.perf_counter()
            out = env.step(action)
            took = time.perf_counter() - t0
            wall += took
            cpu += time.process_time() - c0
            block_wall += took
            block_steps += 1
            if not team and (out[2] or out[3]):
                env.reset()
            if (i + 1) * blocks // steps > len(stretches):  # a stretch done: bare physics now
                stretches.append((block_wall / block_steps * 1000.0, bare.ms(period, BARE_SECONDS)))
                block_wall, block_steps = 0.0, 0
        same = env.sim.server is server
        s1 = process_cpu_s(pid) if pid is not None and same else None
        server_s = None if s0 is None or s1 is None else s1 - s0
    finally:
        env.close()
    return {
        "transport": kwargs.get("transport", "tcp"),
        "robots": max(1, team),
        "control_period_s": period,
        "steps_per_s": steps / wall,
        "wall_ms": wall / steps * 1000.0,
        "env_cpu_ms": cpu / steps * 1000.0,
        "sim_cpu_ms": None if server_s is None else server_s / steps * 1000.0,
        "physics_ms": statistics.mean(b for _, b in stretches),
        "share": statistics.median(b / w for w, b in stretches),
        "stretches": [{"wall_ms": round(w, 4), "physics_ms": round(b, 4)} for w, b in stretches],
    }


def print_profile(p: dict[str, Any]) -> None:
    """The profile as a few lines of text."""
    limit = 1000.0 / p["physics_ms"]
    inproc = p.get("transport") == "inproc"
    shares = [s["physics_ms"] / s["wall_ms"] for s in p.get("stretches", ())]
    spread = f", stretches {min(shares):.0%} - {max(shares):.0%}" if len(shares) > 1 else ""
    print(
        f"  {p['robots']} robot(s), {p['control_period_s']:g} s a step, {'in-process' if inproc else 'over TCP'}: "
        f"{p['steps_per_s']:.0f} steps/s ({p['wall_ms']:.2f} ms each), "
        f"{p['share']:.0%} of what bare mj_step allows (about {limit:.0f}; the median of "
        f"{len(shares)} stretches, each timed beside bare physics{spread})"
    )
    if inproc:
        print(
            f"    a step's processor time: {p['env_cpu_ms']:.2f} ms in the one process (environment and simulator), "
            f"beside bare physics of {p['physics_ms']:.2f} ms"
        )
        return
    sim = "-" if p["sim_cpu_ms"] is None else f"{p['sim_cpu_ms']:.2f} ms"
    print(
        f"    a step's processor time: environment process {p['env_cpu_ms']:.2f} ms, simulator process {sim}, "
        f"of which bare physics {p['physics_ms']:.2f} ms"
    )
