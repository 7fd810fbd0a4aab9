"""``TeamExplore`` (PettingZoo ParallelEnv): a team of robots explores one world together.

Each robot observes, acts and earns as the robot of :class:`~usarsim.envs.ExploreEnv`
does, on a coverage grid and a list of victims shared by the team (a cell or a victim pays
once, to the first robot that sees it).  With ``message_size`` > 0 every robot also sends
a small vector each step, through the simulator's ComServer as any robot's messages go: on
the links the ComServer opens while the radio model says they hold (the signal at or above
the cutoff, asked with ``GETSS`` before each step), and through the server's channel
(capacity, loss and delay: ``--wireless-config``).  A message is in its receiver's inbox at
the end of the step in which it arrives.
"""

from __future__ import annotations

import copy
import dataclasses
import weakref
from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from usarsim.config.catalog import resolve_world
from usarsim.coverage import CoverageGrid

from .explore import check_common, rewards_of
from .explorer import Explorer, Outcome, Rewards
from .radio import TeamRadio, radio_model
from .session import PRELAUNCH_AFTER_STEPS, SEED_RANGE, Pose, Simulator, next_seed, spawn_at
from .spec import action_space, check_robot, observation_space, robot_config, world_bounds


def parallel_env(**kwargs: Any) -> TeamExplore:
    """A :class:`TeamExplore` (PettingZoo's factory name)."""
    return TeamExplore(**kwargs)


class TeamExplore(ParallelEnv):
    """``robots`` robots of class ``robot`` (agents ``robot_0``, ``robot_1``, ...; also their
    names in the simulator) at ``starts`` (start pose names or (location, rotation); default
    the world's first start poses in order).

    Spaces: each agent's observation and action are those of ExploreEnv; with
    ``message_size`` > 0 the action is a Dict of ``move`` (that action) and ``message`` (a
    float32 vector in [-1, 1]), and the observation adds ``inbox`` (one row per agent: the
    message from that agent delivered this step, zeros otherwise) and ``inbox_mask`` (1
    where a message was delivered).  Rewards: each agent's own (``shared_reward`` False)
    or the team's total, given to every agent (True, the default).

    The radio model is the simulator's: the world's ``wireless`` section, ``wireless_model``
    (``--wireless-model``) and ``wireless_config`` (``--wireless-config``), which a launched
    simulator is started with and which give the cutoff; with ``host``/``port``, give
    ``comserver_port`` and, if the running simulator uses another model, ``cutoff_dbm``.
    Episodes run as ExploreEnv's do (``prelaunch`` and ``variants`` likewise).
    """

    metadata = {"name": "usarsim_team_explore_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(
        self,
        *,
        robots: int = 2,
        world: str = "DM-USAR_yellow",
        robot: str = "P2AT",
        starts: Sequence[Pose] | None = None,
        control_period_s: float = 0.1,
        time_limit_s: float = 120.0,
        observations: tuple[str, ...] | list[str] | None = None,
        laser_beams: int = 30,
        discrete: bool = False,
        rewards: Rewards | dict | None = None,
        shared_reward: bool = True,
        message_size: int = 0,
        wireless_model: str | None = None,
        wireless_config: str | None = None,
        cutoff_dbm: float | None = None,
        host: str = "127.0.0.1",
        port: int | None = None,
        truth_port: int | None = None,
        comserver_port: int | None = None,
        robot_dirs: tuple[str, ...] | list[str] = (),
        timeout_s: float = 10.0,
        prelaunch: bool = True,
        render_mode: str | None = None,
        transport: str = "tcp",
        variants: Sequence[int] | None = None,
    ):
        if render_mode is not None:
            raise ValueError(f"TeamExplore renders nothing (render_modes: []), got render_mode={render_mode!r}")
        if int(robots) < 1:
            raise ValueError(f"robots must be at least 1, got {robots!r}")
        if int(message_size) < 0:
            raise ValueError(f"message_size must be >= 0 (0: no messages), got {message_size!r}")
        self.world_config = resolve_world(world)
        cfg = robot_config(robot, tuple(robot_dirs))
        n = int(robots)
        if starts is None:
            poses = self.world_config.start_poses
            if n > len(poses):
                raise ValueError(
                    f"{world} has {len(poses)} start poses for {n} robots: give starts (start pose "
                    "names or (location, rotation) pairs)"
                )
            starts = [p.name for p in poses[:n]]
        if len(starts) != n:
            raise ValueError(f"starts has {len(starts)} poses for {n} robots")
        self.starts = list(starts)
        self.message_size = int(message_size)
        self.sim = Simulator(
            world=world,
            host=host,
            port=port,
            truth_port=truth_port,
            comserver_port=comserver_port,
            wireless=self.message_size > 0,
            wireless_model=wireless_model,
            wireless_config=wireless_config,
            robot_dirs=tuple(robot_dirs),
            timeout=timeout_s,
            transport=transport,
            variants=variants,
        )
        self._finalizer = weakref.finalize(self, self.sim.stop)
        self.spec_robot = self.sim.describe(cfg, self.starts[0])
        self.keys = check_robot(self.spec_robot, None if observations is None else tuple(observations))
        check_common(control_period_s, time_limit_s, laser_beams, self.spec_robot)
        self.control_period_s = float(control_period_s)
        self.time_limit_s = float(time_limit_s)
        self.laser_beams = int(laser_beams)
        self.discrete = bool(discrete)
        self.rewards = rewards_of(rewards)
        self.shared_reward = bool(shared_reward)
        self.radio = None  # the simulator's radio model, when messages are sent
        if self.message_size:
            self.radio = radio_model(self.world_config.wireless, wireless_model, wireless_config)
            if cutoff_dbm is not None:
                self.radio = dataclasses.replace(self.radio, cutoff_dbm=float(cutoff_dbm))
        self.bounds = world_bounds(self.world_config)
        self.possible_agents = [f"robot_{i}" for i in range(n)]
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        base = observation_space(self.spec_robot, self.keys, self.laser_beams, self.world_config)
        move = action_space(self.discrete)
        if self.message_size:
            obs_space = spaces.Dict(
                {
                    **base.spaces,
                    "inbox": spaces.Box(-1.0, 1.0, (n, self.message_size), np.float32),
                    "inbox_mask": spaces.Box(0.0, 1.0, (n,), np.float32),
                }
            )
            act_space: spaces.Space = spaces.Dict(
                {"move": move, "message": spaces.Box(-1.0, 1.0, (self.message_size,), np.float32)}
            )
        else:
            obs_space, act_space = base, move
        self.observation_spaces = {
            a: obs_space if i == 0 else _copy_space(obs_space) for i, a in enumerate(self.possible_agents)
        }
        self.action_spaces = {
            a: act_space if i == 0 else _copy_space(act_space) for i, a in enumerate(self.possible_agents)
        }
        self.coverage = CoverageGrid(self.bounds, self.rewards.cell_m)
        self.explorers: dict[str, Explorer] = {}
        self.team_radio: TeamRadio | None = None
        self._rng: np.random.Generator | None = None
        self.prelaunch = bool(prelaunch)
        self._steps = 0
        self._t0 = 0.0
        self._inbox = np.zeros((n, n, max(1, self.message_size)), np.float32)  # receiver, sender, vector
        self._mask = np.zeros((n, n), np.float32)
        self._signals: dict[tuple[str, str], float | None] = {}

    # pettingzoo ---------------------------------------------------------------------------
    def observation_space(self, agent: str) -> spaces.Space:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self.action_spaces[agent]

    def reset(self, seed: int | None = None, options: dict | None = None):
        """A new episode in a fresh simulator seeded from the environment's generator
        (``seed`` reseeds it), every robot at its start, one control period run.
        ``options`` are not used."""
        if seed is not None or self._rng is None:
            self._rng = np.random.default_rng(seed)
        self._close_radio()
        world = self.sim.start(int(self._rng.integers(0, SEED_RANGE)))
        victims = {o.name: (o.location[0], o.location[1]) for o in world.truth(class_name="Victim")}
        self.coverage.clear()
        found: set[str] = set()
        self.explorers = {}
        for agent, start in zip(self.possible_agents, self.starts):
            robot = spawn_at(world, self.spec_robot.class_name, agent, start)
            self.explorers[agent] = Explorer(
                robot,
                self.spec_robot,
                self.keys,
                self.laser_beams,
                self.rewards,
                self.bounds,
                self.coverage,
                victims,
                found,
            )
            if self.sim.transport == "inproc":  # the sensors nobody reads are not measured
                robot.read_only(*self.explorers[agent].readings_used())
        if self.message_size:
            self.team_radio = TeamRadio(
                self.sim.address, self.sim.comserver_port, self.possible_agents, self.sim.timeout
            )
        self.sim.step(self.control_period_s)
        self._t0 = world.time
        self.agents = list(self.possible_agents)
        if self.team_radio is not None and self.radio is not None:  # the links of the first step
            self.team_radio.link_up(self.team_radio.signals(self.agents), self.radio.holds)
        outs = {a: self.explorers[a].update() for a in self.agents}
        self._clear_inbox()
        self._signals = {}
        self._steps = 0
        return ({a: self._observe(a) for a in self.agents}, {a: self._info(a, outs[a]) for a in self.agents})

    def step(self, actions: dict[str, Any]):
        if not self.explorers:
            raise RuntimeError("call reset() before step()")
        sent: dict[str, np.ndarray] = {}
        for agent in self.agents:
            action = actions.get(agent)
            if self.message_size:
                move = None if action is None else action["move"]
                if action is not None:
                    msg = np.asarray(action["message"], dtype=np.float32).reshape(-1)
                    if msg.shape != (self.message_size,) or not np.all(np.isfinite(msg)):
                        raise ValueError(
                            f"{agent}: a message is {self.message_size} finite numbers in [-1, 1], "
                            f"got {action['message']!r}"
                        )
                    sent[agent] = np.clip(msg, -1.0, 1.0)
            else:
                move = action
            if move is None:  # no action for a live agent: it stands still
                move = 4 if self.discrete else np.zeros(2, np.float32)
            self.explorers[agent].drive(move, self.discrete)
        self._send(sent)
        t = self.sim.step(self.control_period_s, [r for e in self.explorers.values() for r in e.take_sent()])
        outs = {a: self.explorers[a].update() for a in self.agents}  # in agent order: first seen, first paid
        self._deliver()
        own = {a: self.explorers[a].reward(outs[a]) for a in self.agents}
        total = float(sum(own.values()))
        rewards = {a: total if self.shared_reward else float(own[a]) for a in self.agents}
        terminations = {a: bool(outs[a].flipped or outs[a].battery_empty) for a in self.agents}
        over = t - self._t0 >= self.time_limit_s - 1e-6
        truncations = dict.fromkeys(self.agents, bool(over))
        self._steps += 1
        if self.prelaunch and self._steps == PRELAUNCH_AFTER_STEPS and self._rng is not None:
            self.sim.prelaunch([next_seed(self._rng)])
        observations = {a: self._observe(a) for a in self.agents}
        infos = {a: self._info(a, outs[a]) for a in self.agents}
        for a in self.agents:
            if terminations[a] and not truncations[a]:
                self.explorers[a].drive(4 if self.discrete else np.zeros(2, np.float32), self.discrete)
        self.agents = [a for a in self.agents if not (terminations[a] or truncations[a])]
        if self.team_radio is not None:
            for a in sorted((set(self.possible_agents) - set(self.agents)) & set(self.team_radio.radios)):
                self.team_radio.leave(a)  # done: it neither sends nor receives any more
        return observations, rewards, terminations, truncations, infos

    def render(self) -> None:
        return None

    def close(self) -> None:
        self._close_radio()
        self.explorers = {}
        self.agents = []
        self.sim.stop()

    # ------------------------------------------------------------------------------------
    def _close_radio(self) -> None:
        if self.team_radio is not None:
            self.team_radio.close()
            self.team_radio = None

    def _clear_inbox(self) -> None:
        self._inbox[:] = 0.0
        self._mask[:] = 0.0

    def _send(self, sent: dict[str, np.ndarray]) -> None:
        """Each message on its sender's open links; then the signal of every pair, asked of
        the ComServer (the answers also say the messages are in its hands before the STEP),
        and a link opened for each pair that holds and has none."""
        self._signals = {}
        if self.radio is None or self.team_radio is None or len(self.agents) < 2:
            return
        for src, msg in sent.items():
            self.team_radio.send(src, msg.astype(np.float32).tobytes())
        self._signals = self.team_radio.signals(self.agents)
        self.team_radio.link_up(self._signals, self.radio.holds)

    def _deliver(self) -> None:
        """What arrived during the step: each sender's latest message in its receiver's inbox."""
        self._clear_inbox()
        if self.team_radio is None:
            return
        for dst, messages in self.team_radio.receive(self.agents).items():
            j = self._index[dst]
            for src, payload in messages:
                vec = np.frombuffer(payload, np.float32)
                if src in self._index and vec.shape == (self.message_size,):
                    i = self._index[src]
                    self._inbox[j, i] = vec
                    self._mask[j, i] = 1.0

    def _observe(self, agent: str) -> dict[str, np.ndarray]:
        obs = self.explorers[agent].observation()
        if self.message_size:
            j = self._index[agent]
            obs["inbox"] = self._inbox[j, :, : self.message_size].copy()
            obs["inbox_mask"] = self._mask[j].copy()
        return obs

    def _info(self, agent: str, out: Outcome) -> dict[str, Any]:
        info: dict[str, Any] = {
            "time_s": round(self.sim.world.time - self._t0, 6) if self.sim.world is not None else 0.0,
            "new_area_m2": len(out.new_cells) * self.coverage.cell_area_m2,
            "explored_m2": self.coverage.seen_m2,
            "new_victims": list(out.new_victims),
            "victims_found": len(self.explorers[agent].found),
            "collision": out.collision,
            "flipped": out.flipped,
            "battery_empty": out.battery_empty,
        }
        if self.message_size:
            j = self._index[agent]
            info["received_from"] = [a for a in self.possible_agents if self._mask[j, self._index[a]]]
            info["signal_dbm"] = {
                (b if a == agent else a): dbm for (a, b), dbm in self._signals.items() if agent in (a, b)
            }
        return info


def _copy_space(space: spaces.Space) -> spaces.Space:
    """An equal space of its own (each agent's space is seeded on its own)."""
    return copy.deepcopy(space)
