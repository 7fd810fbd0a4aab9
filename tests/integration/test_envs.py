"""The reinforcement-learning environments (usarsim.envs) on real lock-step simulators:
Gymnasium's and PettingZoo's own API checkers, seeded determinism, the exploration reward,
the ends of an episode, and team messages that cross only the radio links the simulator's
ComServer says hold.  Every reset launches a simulator (about a second each)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

from helpers import same
from usarsim.client import launch
from usarsim.config.catalog import ROBOTS_DIR
from usarsim.envs import ExploreEnv, TeamExplore, parallel_env
from usarsim.envs.spec import DISCRETE_ACTIONS

FORWARD = np.array([0.8, 0.8], dtype=np.float32)
STOP = np.zeros(2, dtype=np.float32)
UPSIDE_DOWN_AT_START7 = ((-9.5, -8.0, -0.4), (math.pi, 0.0, 0.0))
NE_CORNER = ((4.8, 6.4, -0.25), (0.0, 0.0, 0.0))  # inside the arena, walls between it and the entrance


@pytest.mark.parametrize("env_id", ["usarsim/Explore-v0", "usarsim/ExploreDiscrete-v0"])
def test_gymnasium_check_env(env_id):
    env = gymnasium.make(env_id, time_limit_s=2.0)
    try:
        check_env(env.unwrapped)
        assert isinstance(env.unwrapped, ExploreEnv)
        if env_id.endswith("Discrete-v0"):
            assert env.action_space == gymnasium.spaces.Discrete(len(DISCRETE_ACTIONS))
        else:
            assert env.action_space == gymnasium.spaces.Box(-1.0, 1.0, (2,), np.float32)
        space = env.observation_space
        assert set(space.spaces) == {"laser", "sonar", "odometry", "battery", "victims"}
        assert space["laser"].shape == (30,) and space["laser"].high.max() == pytest.approx(20.0)
        assert space["sonar"].shape == (16,) and space["sonar"].high.max() == pytest.approx(5.0)
        assert all(
            s.dtype == np.float32 and np.all(np.isfinite(s.low)) and np.all(np.isfinite(s.high))
            for s in space.spaces.values()
        )
    finally:
        env.close()
    assert env.unwrapped.sim.server is None  # close() stopped the simulator


def test_made_by_module_path_with_chosen_observations():
    env = gymnasium.make("usarsim.envs:usarsim/ExploreDiscrete-v0", observations=["laser", "battery"], laser_beams=9)
    assert set(env.observation_space.spaces) == {"laser", "battery"}
    assert env.observation_space["laser"].shape == (9,)
    env.close()
    with pytest.raises(ValueError, match="unknown observation 'camera'"):
        ExploreEnv(observations=["laser", "camera"])
    with pytest.raises(ValueError, match="has the 'aerial' drive"):
        ExploreEnv(robot="AirRobot")
    with pytest.raises(ValueError, match="laser_beams must be 1..181"):
        ExploreEnv(laser_beams=500)


def test_the_environments_load_no_mujoco_or_simulation():
    """usarsim.envs is a client of the simulator: the spaces come from GETGEO and GETCONF."""
    code = (
        "import sys, usarsim.envs\n"
        "print(sorted(m for m in sys.modules if m == 'mujoco' or m.startswith(('usarsim.sim', 'usarsim.server'))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.strip() == "[]"


def test_same_seed_and_actions_give_the_same_episode_in_two_envs():
    actions = [FORWARD] * 8 + [np.array([-0.6, 0.6], np.float32)] * 6 + [FORWARD] * 8

    def episode(env, seed=None):
        obs, info = env.reset(seed=seed)
        return [(obs, 0.0, False, False, info)] + [env.step(a) for a in actions]

    a, b = ExploreEnv(time_limit_s=5.0), ExploreEnv(time_limit_s=5.0, prelaunch=False)
    try:
        a1 = episode(a, 7)
        assert a.sim._spares  # 20 steps in, the next episode's simulator is being launched
        a.prelaunch = False
        a2 = episode(a)  # in that simulator
        b1 = episode(b, 7)
    finally:
        a.close()
        b.close()
    assert same(a1, b1)
    assert a1[-1][0]["odometry"][0] > 0.5  # the robot went somewhere
    # the next episode's simulator has another seed: other sensor noise, other laser readings
    assert not all(np.array_equal(x[0]["laser"], y[0]["laser"]) for x, y in zip(a1, a2))
    assert a2[-1][0]["odometry"][0] > 0.5


def test_reward_grows_into_unseen_floor_and_the_episode_truncates_at_its_time_limit():
    env = ExploreEnv(time_limit_s=3.0, prelaunch=False)
    try:
        obs, info = env.reset(seed=1)
        start_area = info["explored_m2"]
        assert start_area > 10.0  # the first sweep from the start pose, not rewarded
        still = [env.step(STOP) for _ in range(5)]
        assert sum(r for _, r, *_ in still) <= 0.5
        moving, truncated, steps = [], False, 5
        while not truncated:
            obs, reward, terminated, truncated, info = env.step(FORWARD)
            moving.append(reward)
            steps += 1
            assert not terminated
        assert steps == 30 and info["time_s"] == pytest.approx(3.0)
        assert sum(moving) > 3.0 * (1 + sum(r for _, r, *_ in still))
        assert info["explored_m2"] >= start_area + sum(moving) - 1e-9  # no collision penalty on open floor
        assert obs["odometry"][0] > 1.0 and obs["battery"][0] < 1.0
    finally:
        env.close()


def test_a_victim_pays_once_when_first_detected():
    env = ExploreEnv(prelaunch=False)
    try:  # a metre in front of Carl, who sits in the arena's south-west room, facing him
        env.reset(seed=5, options={"start": ((-3.8, -3.5, -0.25), (0.0, 0.0, math.pi))})
        steps = [env.step(STOP) for _ in range(12)]
    finally:
        env.close()
    paid = [(r, info["new_victims"]) for _, r, _, _, info in steps if info["new_victims"]]
    assert paid == [(10.0, ["Carl"])]  # standing still, nothing else earns or costs
    obs, _, _, _, info = steps[-1]
    assert info["victims_found"] == 1 and sum(r for _, r, *_ in steps) == 10.0
    parts, bearing, distance = obs["victims"]
    assert parts >= 1 and abs(bearing) < 0.4 and 0.3 < distance < 1.5


@pytest.fixture(scope="module")
def short_battery_robots(tmp_path_factory) -> Path:
    """A robot folder with ShortP2AT: a P2AT whose battery lasts 1 s at rest."""
    d = tmp_path_factory.mktemp("robots")
    text = (ROBOTS_DIR / "P2AT.yaml").read_text()
    text = text.replace("class_name: P2AT", "class_name: ShortP2AT").replace("battery_s: 1200", "battery_s: 1")
    (d / "ShortP2AT.yaml").write_text(text)
    return d


def test_an_empty_battery_terminates(short_battery_robots):
    env = ExploreEnv(robot="ShortP2AT", robot_dirs=[str(short_battery_robots)], time_limit_s=10.0)
    try:
        obs, info = env.reset(seed=2)
        assert obs["battery"][0] == 1.0 and not info["battery_empty"]
        for _ in range(30):
            obs, _, terminated, truncated, info = env.step(FORWARD)
            if terminated:
                break
    finally:
        env.close()
    assert terminated and info["battery_empty"] and not info["flipped"] and not truncated
    assert obs["battery"][0] == 0.0 and info["time_s"] <= 1.5


def test_episodes_in_a_running_simulator():
    with launch(seed=1) as server:
        env = ExploreEnv(host=server.host, port=server.port, truth_port=server.ports["truth"])
        try:
            env.reset(seed=1)
            for _ in range(6):
                obs, *_ = env.step(FORWARD)
            assert obs["odometry"][0] > 0.1
            obs, info = env.reset()  # the robot leaves and is spawned again at its start
            assert obs["odometry"][0] == pytest.approx(0.0, abs=0.02) and info["explored_m2"] > 10.0
            with server.connect() as world:
                assert [o.name for o in world.truth(name="Explorer")] == ["Explorer"]
                env.close()
                assert world.truth(name="Explorer") == []
            assert server.proc.poll() is None  # not the environment's to stop
        finally:
            env.close()


def test_pettingzoo_parallel_api_and_shared_rewards():
    env = parallel_env(robots=2, message_size=2, time_limit_s=1.0)
    steps = []  # what each step the API test takes returns
    step = env.step

    def recording_step(actions):
        out = step(actions)
        steps.append(out)
        return out

    env.step = recording_step
    try:
        parallel_api_test(env, num_cycles=15)
    finally:
        env.close()
    assert len(steps) == 20  # two episodes of 1 s at 0.1 s (after a first reset with seed 0)
    total = 0.0
    for obs, rewards, _, _, infos in steps:
        assert set(rewards) == {"robot_0", "robot_1"}
        assert all(obs[a] in env.observation_space(a) for a in obs)
        own = [infos[a]["new_area_m2"] - (1.0 if infos[a]["collision"] else 0.0) for a in rewards]
        assert rewards["robot_0"] == rewards["robot_1"] == pytest.approx(sum(own))  # the team's total
        total += rewards["robot_0"]
    assert total > 0 and [i for i, s in enumerate(steps) if s[3]["robot_0"]] == [9, 19]


def test_messages_cross_only_links_the_radio_model_holds_and_a_flipped_robot_leaves(tmp_path):
    # a shorter-range radio (README: raise the cutoff): -75 dBm, which the 4 m and 8 m lines of
    # sight between start poses pass and the walls and 16 m to the arena's far corner do not;
    # robot_3 starts upside down
    ini = tmp_path / "radio.ini"
    ini.write_text("[USARBot.ComServer]\nModel=waf\neCutoff=-75\n")
    env = TeamExplore(
        robots=4,
        starts=["PlayerStart1", "PlayerStart2", NE_CORNER, UPSIDE_DOWN_AT_START7],
        message_size=3,
        wireless_config=str(ini),
        shared_reward=False,
        time_limit_s=2.0,
    )
    assert env.radio.cutoff_dbm == -75.0
    try:
        env.reset(seed=4)
        messages = {a: np.array([i / 4, -0.25, 1.0], np.float32) for i, a in enumerate(env.agents)}
        actions = {a: {"move": FORWARD, "message": m} for a, m in messages.items()}
        obs, rewards, terminations, truncations, infos = env.step(actions)
        ss = infos["robot_0"]["signal_dbm"]
        assert ss["robot_1"] > -75.0 > ss["robot_2"] and ss["robot_3"] > -75.0
        assert infos["robot_2"]["signal_dbm"]["robot_1"] < -75.0
        assert infos["robot_0"]["received_from"] == ["robot_1", "robot_3"]
        assert infos["robot_1"]["received_from"] == ["robot_0", "robot_3"]
        assert infos["robot_2"]["received_from"] == []
        np.testing.assert_array_equal(obs["robot_0"]["inbox"][1], messages["robot_1"])
        np.testing.assert_array_equal(obs["robot_1"]["inbox"][0], messages["robot_0"])
        np.testing.assert_array_equal(obs["robot_0"]["inbox_mask"], [0, 1, 0, 1])
        assert not obs["robot_2"]["inbox"].any() and not obs["robot_2"]["inbox_mask"].any()
        assert all(obs[a] in env.observation_space(a) for a in obs)
        for a in obs:  # individual rewards: each its own new floor (collisions cost 1)
            assert rewards[a] == pytest.approx(infos[a]["new_area_m2"] - (1.0 if infos[a]["collision"] else 0.0))
        # the flipped robot is done: it neither sends nor receives any more
        assert terminations == {"robot_0": False, "robot_1": False, "robot_2": False, "robot_3": True}
        assert infos["robot_3"]["flipped"] and not any(truncations.values())
        assert env.agents == ["robot_0", "robot_1", "robot_2"]
        obs, *_, infos = env.step({a: {"move": STOP, "message": np.zeros(3, np.float32)} for a in env.agents})
        assert set(obs) == {"robot_0", "robot_1", "robot_2"}
        assert infos["robot_0"]["received_from"] == ["robot_1"]  # this step's message only
        assert not obs["robot_0"]["inbox"].any() and obs["robot_0"]["inbox_mask"].tolist() == [0, 1, 0, 0]
    finally:
        env.close()


def test_team_messages_go_through_the_servers_channel_with_its_delay(tmp_path):
    # a channel of 0.25 s latency (docs/wireless.md): a message sent before step k (at t_k) is
    # judged at t_k+1 and delivered at the first evaluation past t_k + 0.25, t_k+3, which ends
    # step k + 2; over USARSim's ideal channel it is in the inbox at the end of its own step
    slow = tmp_path / "slow.yaml"
    slow.write_text("channel: {latency_s: 0.25}\n")
    inboxes = {}
    for name, config in (("ideal", None), ("slow", str(slow))):
        env = TeamExplore(robots=2, message_size=1, wireless_config=config, time_limit_s=2.0)
        try:
            env.reset(seed=1)
            got = []
            for k in range(6):
                actions = {a: {"move": STOP, "message": np.array([k / 10], np.float32)} for a in env.agents}
                obs, *_ = env.step(actions)
                got.append(float(obs["robot_0"]["inbox"][1][0]) if obs["robot_0"]["inbox_mask"][1] else None)
            inboxes[name] = got
        finally:
            env.close()
    assert inboxes["ideal"] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    assert inboxes["slow"][:2] == [None, None]
    assert inboxes["slow"][2:] == pytest.approx([0.0, 0.1, 0.2, 0.3])
