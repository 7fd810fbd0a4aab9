"""How fast the environments step (``usarsim bench --env``)."""

from __future__ import annotations

import time
from typing import Any


def timed(steps: int, kwargs: dict[str, Any]) -> dict[str, Any]:
    """An environment's arguments for ``steps`` timed steps: a time limit long enough for every
    one unless given, and no simulator launched ahead (it would compete with the steps timed)."""
    if steps < 1:
        raise ValueError(f"steps must be at least 1, got {steps!r}")
    period = float(kwargs.get("control_period_s", 0.1))
    return {"time_limit_s": period * (steps + 10), "prelaunch": False, **kwargs}


def bench_env(steps: int = 200, team: int = 0, *, seed: int = 0, **kwargs: Any) -> float:
    """Environment steps per second over ``steps`` steps with random actions (seeded with
    ``seed``): of :class:`~usarsim.envs.ExploreEnv` when ``team`` is 0, else of a
    :class:`~usarsim.envs.TeamExplore` of ``team`` robots (one step moves them all).
    ``kwargs`` go to the environment (``control_period_s``, ``message_size``, ...); the
    time limit defaults to one long enough for every step, and no simulator is launched
    ahead.  Resets (a simulator launch each) are not counted."""
    from .explore import ExploreEnv
    from .team import TeamExplore

    kwargs = timed(steps, kwargs)
    if team:
        env = TeamExplore(robots=team, **kwargs)
        try:
            env.reset(seed=seed)
            for i, a in enumerate(env.possible_agents):
                env.action_space(a).seed(seed + i)
            elapsed = 0.0
            for _ in range(steps):
                if not env.agents:
                    env.reset()
                actions = {a: env.action_space(a).sample() for a in env.agents}
                t = time.perf_counter()
                env.step(actions)
                elapsed += time.perf_counter() - t
        finally:
            env.close()
        return steps / elapsed
    single = ExploreEnv(**kwargs)
    try:
        single.reset(seed=seed)
        single.action_space.seed(seed)
        elapsed = _single_steps(single, steps)
    finally:
        single.close()
    return steps / elapsed


def _single_steps(env: Any, steps: int) -> float:
    """Seconds ``steps`` random steps of one world take (sampling and resets not counted)."""
    elapsed = 0.0
    for _ in range(steps):
        action = env.action_space.sample()
        t = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(action)
        elapsed += time.perf_counter() - t
        if terminated or truncated:
            env.reset()
    return elapsed


# Untimed steps that start each stretch of bench_one_and_vector: the side that waited while
# the other was timed starts from cold caches, its workers asleep.
WARM_STEPS = 2


def bench_one_and_vector(
    steps: int = 400, worlds: int = 4, *, seed: int = 0, blocks: int = 5, **kwargs: Any
) -> dict[str, Any]:
    """One world's env steps a second (:class:`~usarsim.envs.ExploreEnv` on the direct path)
    and those of an :class:`~usarsim.envs.ExploreVectorEnv` of ``worlds`` worlds (every world's
    steps counted), timed in ``blocks`` alternating stretches (``steps`` steps of the one world
    in all, as many world steps of the vector) so that both see the machine at the same speed:
    on a shared machine it changes by half within a minute, and two runs one after the other
    gave ratios from 1.1 to 1.6.  Returns ``one`` and ``vector`` (steps a second over all their
    stretches) and ``times_one``, the median of the stretches' ratios.  Sampling the actions
    and resets are not timed; ``kwargs`` as :func:`bench_env`'s."""
    import statistics

    from .explore import ExploreEnv
    from .vector import make_vector

    blocks = max(1, min(int(blocks), steps))
    per_block = max(1, steps // blocks)
    vector_block = max(1, per_block // worlds)  # vector steps a stretch: as many world steps
    kwargs = timed((per_block + WARM_STEPS) * blocks, {"transport": "inproc", **kwargs})
    single = ExploreEnv(**kwargs)
    vector = make_vector(worlds, **kwargs)
    one_s = vec_s = 0.0
    ratios = []
    try:
        single.reset(seed=seed)
        single.action_space.seed(seed)
        vector.reset(seed=seed)
        vector.action_space.seed(seed)
        for _ in range(blocks):
            _single_steps(single, WARM_STEPS)  # each stretch starts warm (not timed)
            a, b = _single_steps(single, per_block), 0.0
            for k in range(WARM_STEPS + vector_block):
                actions = vector.action_space.sample()
                t = time.perf_counter()
                vector.step(actions)
                if k >= WARM_STEPS:
                    b += time.perf_counter() - t
            one_s += a
            vec_s += b
            ratios.append((vector_block * worlds / b) / (per_block / a))
    finally:
        single.close()
        vector.close()
    return {
        "one": blocks * per_block / one_s,
        "vector": blocks * vector_block * worlds / vec_s,
        "times_one": statistics.median(ratios),
        "blocks": [round(r, 3) for r in ratios],
    }
