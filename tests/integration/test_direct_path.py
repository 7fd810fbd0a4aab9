"""The direct path (usarsim.client.direct): an in-process simulator gives the episodes the
control port gives, to the last bit, and passes the environments' checkers."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

from helpers import same
from usarsim.client import ClientError, ClientTimeout, ServerError, launch
from usarsim.envs import ExploreEnv, TeamExplore


def episode(transport: str, seed: int, steps: int) -> list:
    """What ``steps`` random actions (drawn with ``seed``) give: every observation, reward,
    termination, truncation and info, resets included."""
    env = ExploreEnv(transport=transport, prelaunch=False, time_limit_s=12.0)
    env.action_space.seed(seed)
    try:
        out = [env.reset(seed=seed)]
        for _ in range(steps):
            step = env.step(env.action_space.sample())
            out.append(step)
            if step[2] or step[3]:
                out.append(env.reset())
    finally:
        env.close()
    return out


@pytest.mark.parametrize("seed", [3, 11])
def test_direct_and_tcp_paths_give_identical_episodes(seed):
    tcp = episode("tcp", seed, 200)
    direct = episode("inproc", seed, 200)
    assert len(tcp) == len(direct) == 202  # 200 steps, a truncation at 12 s and its reset
    assert same(tcp, direct)
    odometry = [s[0]["odometry"] for s in direct]
    assert max(float(np.hypot(o[0], o[1])) for o in odometry) > 0.3  # the robot went somewhere
    assert sum(s[1] for s in direct[1:] if len(s) == 5) > 0  # and saw new floor


def test_team_episodes_are_identical_on_both_paths():
    def run(transport: str) -> list:
        env = TeamExplore(robots=3, transport=transport, prelaunch=False, time_limit_s=3.0)
        try:
            out = [env.reset(seed=5)]
            rng = np.random.default_rng(5)
            while env.agents:
                out.append(env.step({a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}))
        finally:
            env.close()
        return out

    tcp, direct = run("tcp"), run("inproc")
    assert len(direct) == 31 and same(tcp, direct)


def test_gymnasium_and_pettingzoo_checkers_pass_on_the_direct_path():
    env = gymnasium.make("usarsim/Explore-v0", transport="inproc", time_limit_s=2.0)
    try:
        check_env(env.unwrapped)
    finally:
        env.close()
    team = TeamExplore(robots=2, transport="inproc", time_limit_s=1.0)
    try:
        parallel_api_test(team, num_cycles=15)
    finally:
        team.close()


def test_the_client_drives_an_in_process_simulator():
    with launch("DM-USAR_yellow", seed=2, transport="inproc") as server:
        world = server.connect()
        robot = world.spawn("P2AT", start="PlayerStart1")
        world.step(0.1)
        x0 = robot.odometry()
        for _ in range(20):
            robot.drive(left=2.0, right=2.0)
            world.step(0.1)
        assert world.time == pytest.approx(2.1)
        assert robot.odometry()[0] - x0[0] > 0.3  # it drove forwards
        assert robot.scan().ranges.shape == (181,)
        assert {o.name for o in world.truth(class_name="Victim")}  # the world's victims
        with pytest.raises(ServerError, match="unknown start pose"):
            world.spawn("P2AT", "Other", start="Nowhere")
        with pytest.raises(ClientTimeout, match="did not answer"):  # at once: nothing is in flight
            robot._conn.wait_for(lambda m: False, "a reply never asked for", None)
    with pytest.raises(ValueError, match="serves no port: image"):
        launch(transport="inproc", image=True)
    with pytest.raises(ValueError, match="lock-step only"):
        launch(transport="inproc", lockstep=False)
    with pytest.raises(ValueError, match="give no port"):
        ExploreEnv(transport="inproc", port=3000)


def test_a_vector_of_worlds_runs_each_as_a_single_env_with_its_seed_and_autoresets():
    from usarsim.envs import make_vector

    env = make_vector(3, workers=2, time_limit_s=1.0)
    rng = np.random.default_rng(9)
    actions = [rng.uniform(-1, 1, (3, 2)).astype(np.float32) for _ in range(12)]
    try:
        assert env.observation_space["laser"].shape == (3, 30) and env.action_space.shape == (3, 2)
        batch = [env.reset(seed=4)]
        batch += [env.step(a) for a in actions]
    finally:
        env.close()
    single = ExploreEnv(transport="inproc", time_limit_s=1.0, prelaunch=False)
    try:
        alone = [single.reset(seed=5)]  # world 1 of the vector: seed 4 + 1
        for a in actions:
            if alone[-1][-3:-1] in ((False, True), (True, False), (True, True)):  # next_step autoreset
                obs, info = single.reset()
                alone.append((obs, 0.0, False, False, info))
            else:
                alone.append(single.step(a[1]))
    finally:
        single.close()
    for k, (got, want) in enumerate(zip(batch, alone)):
        assert same({key: v[1] for key, v in got[0].items()}, want[0]), k  # world 1's observation
        if k:
            assert float(got[1][1]) == want[1] and bool(got[3][1]) == want[3], k
    truncated = [k for k in range(1, 13) if batch[k][3].all()]
    assert truncated == [10]  # 1 s at 0.1 s a step, every world; step 11 starts the next episodes
    assert not batch[11][3].any() and (batch[11][1] == 0.0).all()
    assert batch[12][4]["time_s"][0] == pytest.approx(0.1) and batch[12][4]["_time_s"].all()


def test_read_only_measures_the_sensors_named_and_leaves_their_readings_as_they_were():
    def sweeps(only: tuple[str, ...]) -> tuple[set[str], list]:
        with launch("DM-USAR_yellow", seed=4, transport="inproc") as server:
            world = server.connect()
            robot = world.spawn("P2AT", start="PlayerStart1")
            if only:
                robot.read_only(*only)
            out = []
            for _ in range(15):
                robot.drive(left=1.5, right=2.0)
                world.step(0.1)
                out += [m for m in robot.take_messages() if getattr(m, "reading", None) is not None]
            return {type(m.reading).__name__ for m in out}, [
                m for m in out if getattr(m.reading, "name", None) == "Scanner1"
            ]

    kinds_all, scans_all = sweeps(())
    kinds, scans = sweeps(("RangeScanner", "Odometry"))
    assert {"GpsReading", "RfidReading", "EncoderReading"} <= kinds_all
    assert kinds == {"RangeScanReading", "OdometryReading"}
    assert len(scans) == 8 and repr(scans) == repr(scans_all)  # every sweep, to the last bit
    with launch("DM-USAR_yellow", seed=4) as server, server.connect() as world:  # usarsim serve measures all
        robot = world.spawn("P2AT", start="PlayerStart1")
        with pytest.raises(ClientError, match="in-process"):
            robot.read_only("RangeScanner")
