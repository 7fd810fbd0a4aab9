"""``usarsim/Explore-v0`` and ``usarsim/ExploreDiscrete-v0``: one robot explores a world.

Each episode runs in a lock-step simulator launched for it with a seed drawn from the
environment's generator, so that ``reset(seed=s)`` followed by the same actions gives the
same observations, rewards and ends, run after run.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from typing import Any

import gymnasium as gym

from usarsim.config.catalog import resolve_world
from usarsim.coverage import CoverageGrid

from .explorer import Explorer, Outcome, Rewards
from .session import PRELAUNCH_AFTER_STEPS, SEED_RANGE, Pose, Simulator, next_seed, spawn_at
from .spec import action_space, check_robot, observation_space, robot_config, world_bounds


def rewards_of(rewards: Rewards | dict | None) -> Rewards:
    """:class:`Rewards` from itself, from a dict of its fields, or the defaults."""
    if rewards is None:
        return Rewards()
    if isinstance(rewards, Rewards):
        return rewards
    return Rewards(**dict(rewards))


def check_common(control_period_s: float, time_limit_s: float, laser_beams: int, spec) -> None:
    if not (math.isfinite(control_period_s) and control_period_s > 0):
        raise ValueError(f"control_period_s must be > 0 (simulated seconds per step), got {control_period_s!r}")
    if not time_limit_s > 0:
        raise ValueError(f"time_limit_s must be > 0 (simulated seconds per episode), got {time_limit_s!r}")
    if spec.laser is not None and not 1 <= laser_beams <= spec.laser.beams:
        raise ValueError(
            f"laser_beams must be 1..{spec.laser.beams} (the beams of {spec.class_name}'s "
            f"{spec.laser.name}), got {laser_beams!r}"
        )


class ExploreEnv(gym.Env):
    """One robot (a P2AT by default) explores a world: rewarded per square metre of floor its
    laser sees for the first time and per victim its victim sensor detects for the first
    time, penalised per step in collision; terminated when its battery is empty or it has
    flipped, truncated after ``time_limit_s`` simulated seconds.

    Observation: a Dict of float32 Boxes (``observations`` chooses among ``laser``,
    ``sonar``, ``odometry``, ``battery`` and ``victims``; default: every one the robot has
    a sensor for); see :func:`usarsim.envs.spec.observation_space`.  Action: the left and
    right side speeds in [-1, 1] (fractions of the top speed), or with ``discrete`` one of
    forward, left, right, back, stop.  Each step is ``control_period_s`` of simulated time.

    With ``port`` None every reset launches a lock-step simulator of ``world`` (stopped at
    the next reset and by :meth:`close`); with ``host``/``port`` the episodes run in that
    lock-step simulator, whose seed is its own, and each reset spawns the robot again (the
    rest of the world is not reset, so episodes are not reproducible there).  With
    ``variants`` (a range or list of the world's variants, ``usarsim serve --variant``) an
    episode of seed s plays variant ``variants[s % len(variants)]``, its victims, tags and
    debris placed anew: train on ``range(0, 800)`` and test on ``range(800, 1000)``, and no
    policy can learn where a victim lies.  With
    ``prelaunch``, once an episode has run a few steps, the simulator the next reset
    without a seed will need (with the next seed the generator will draw) is launched in
    the background, so that such a reset after a long episode takes a fraction of a second.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        *,
        world: str = "DM-USAR_yellow",
        robot: str = "P2AT",
        start: Pose = "PlayerStart1",
        control_period_s: float = 0.1,
        time_limit_s: float = 120.0,
        observations: tuple[str, ...] | list[str] | None = None,
        laser_beams: int = 30,
        discrete: bool = False,
        rewards: Rewards | dict | None = None,
        robot_name: str = "Explorer",
        host: str = "127.0.0.1",
        port: int | None = None,
        truth_port: int | None = None,
        robot_dirs: tuple[str, ...] | list[str] = (),
        timeout_s: float = 10.0,
        prelaunch: bool = True,
        render_mode: str | None = None,
        transport: str = "tcp",
        variants: Sequence[int] | None = None,
    ):
        if render_mode is not None:
            raise ValueError(f"ExploreEnv renders nothing (render_modes: []), got render_mode={render_mode!r}")
        self.world_config = resolve_world(world)
        cfg = robot_config(robot, tuple(robot_dirs))
        self.sim = Simulator(
            world=world,
            host=host,
            port=port,
            truth_port=truth_port,
            robot_dirs=tuple(robot_dirs),
            timeout=timeout_s,
            transport=transport,
            variants=variants,
        )
        self._finalizer = weakref.finalize(self, self.sim.stop)
        self.spec_robot = self.sim.describe(cfg, start)
        self.keys = check_robot(self.spec_robot, None if observations is None else tuple(observations))
        check_common(control_period_s, time_limit_s, laser_beams, self.spec_robot)
        self.start = start
        self.control_period_s = float(control_period_s)
        self.time_limit_s = float(time_limit_s)
        self.laser_beams = int(laser_beams)
        self.discrete = bool(discrete)
        self.rewards = rewards_of(rewards)
        self.robot_name = robot_name
        self.bounds = world_bounds(self.world_config)
        self.observation_space = observation_space(self.spec_robot, self.keys, self.laser_beams, self.world_config)
        self.action_space = action_space(self.discrete)
        self.coverage = CoverageGrid(self.bounds, self.rewards.cell_m)
        self.explorer: Explorer | None = None
        self.prelaunch = bool(prelaunch)
        self._steps = 0
        self._t0 = 0.0

    # gymnasium ---------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """A new episode: a fresh simulator seeded from the environment's generator (or the
        robot spawned again in the given one), the robot at ``start`` (``options={"start":
        ...}`` for this episode only), one control period run to fill its sensors."""
        super().reset(seed=seed)
        options = dict(options or {})
        start = options.pop("start", self.start)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; known: start")
        world = self.sim.start(int(self.np_random.integers(0, SEED_RANGE)))
        victims = {o.name: (o.location[0], o.location[1]) for o in world.truth(class_name="Victim")}
        robot = spawn_at(world, self.spec_robot.class_name, self.robot_name, start)
        self.coverage.clear()
        self.explorer = Explorer(
            robot,
            self.spec_robot,
            self.keys,
            self.laser_beams,
            self.rewards,
            self.bounds,
            self.coverage,
            victims,
            set(),
        )
        if self.sim.transport == "inproc":  # the sensors nobody reads are not measured
            robot.read_only(*self.explorer.readings_used())
        self.sim.step(self.control_period_s)
        self._t0 = world.time
        out = self.explorer.update()  # the first sweep's floor is where the robot starts: no reward
        self._steps = 0
        return self.explorer.observation(), self._info(out)

    def step(self, action):
        if self.explorer is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        self.explorer.drive(action, self.discrete)
        self.sim.step(self.control_period_s, self.explorer.take_sent())
        out = self.explorer.update()
        reward = self.explorer.reward(out)
        terminated = out.flipped or out.battery_empty
        truncated = self.elapsed_s >= self.time_limit_s - 1e-6
        self._steps += 1
        if self.prelaunch and self._steps == PRELAUNCH_AFTER_STEPS:
            self.sim.prelaunch([next_seed(self.np_random)])
        return self.explorer.observation(), float(reward), bool(terminated), bool(truncated), self._info(out)

    def close(self) -> None:
        self.explorer = None
        self.sim.stop()

    # ------------------------------------------------------------------------------------
    @property
    def elapsed_s(self) -> float:
        """Simulated seconds since the episode began."""
        return 0.0 if self.sim.world is None else self.sim.world.time - self._t0

    def _info(self, out: Outcome) -> dict[str, Any]:
        variant = {"variant": self.sim.variant} if self.sim.variants else {}
        return variant | {
            "time_s": round(self.elapsed_s, 6),
            "new_area_m2": len(out.new_cells) * self.coverage.cell_area_m2,
            "explored_m2": self.coverage.seen_m2,
            "new_victims": list(out.new_victims),
            "victims_found": len(self.explorer.found) if self.explorer is not None else 0,
            "collision": out.collision,
            "flipped": out.flipped,
            "battery_empty": out.battery_empty,
        }
