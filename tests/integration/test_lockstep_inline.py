"""Lock-step STEPs run at once on the thread that asks when the simulation thread has nothing
to do (usarsim.sim.runner), and everything still happens in the order it was asked for."""

from __future__ import annotations

import threading

import pytest

from usarsim.sim.api import when_done
from usarsim.sim.facade import SimFacade
from usarsim.sim.runner import SimulationRunner

WAIT_S = 30.0


@pytest.fixture
def facade(yellow_world):
    f = SimFacade(yellow_world, seed=0, lockstep=True)
    f.start()
    yield f
    f.stop()


def step(facade: SimFacade, seconds: float) -> float:
    """STEP and wait for its STEPPED time."""
    done = threading.Event()
    got: list[float] = []
    when_done(facade.step(seconds), lambda t, e: (got.append(t), done.set()))
    assert done.wait(WAIT_S), "no STEPPED"
    return got[0]


def ran_on(facade: SimFacade) -> list[str]:
    """The threads every advance of the clock runs on, from now on."""
    names: list[str] = []
    facade.sim.on_advance(lambda sim: names.append(threading.current_thread().name))
    return names


@pytest.mark.alone  # wall-clock pacing: run by itself (scripts/test.sh)
def test_a_short_step_runs_on_the_thread_that_asks_a_long_one_on_the_simulation_thread(facade):
    names = ran_on(facade)
    assert step(facade, 0.004) == pytest.approx(0.004)  # how long STEPs take is not known yet
    assert step(facade, 0.004) == pytest.approx(0.008)
    assert step(facade, 0.02) == pytest.approx(0.028)
    # 20 simulated seconds hold anything up far longer than INLINE_STEP_WALL_S
    assert 20.0 * facade.runner._wall_per_s > 4 * SimulationRunner.INLINE_STEP_WALL_S  # noqa: SLF001
    assert step(facade, 20.0) == pytest.approx(20.028)
    here = threading.current_thread().name
    assert names == ["usarsim-sim", here, here, "usarsim-sim"]


def test_requests_before_a_step_run_in_it_in_order_wherever_it_runs(facade):
    step(facade, 0.004)
    seen: list[tuple[str, float, str]] = []

    def note(what):
        return lambda sim: seen.append((what, round(sim.time, 6), threading.current_thread().name))

    here = threading.current_thread().name
    facade.call(note("a"), immediate=False)
    facade.call(note("b"), immediate=False)
    assert step(facade, 0.004) == pytest.approx(0.008)
    assert seen == [("a", 0.004, here), ("b", 0.004, here)]  # before the physics of that STEP


def test_a_request_after_a_queued_step_waits_for_the_next_one(facade):
    step(facade, 0.004)
    step(facade, 0.004)
    gate = threading.Event()
    facade.call(lambda sim: gate.wait(WAIT_S), immediate=True)  # the simulation thread is busy
    seen: list[float] = []
    first, second = threading.Event(), threading.Event()
    when_done(facade.step(0.004), lambda t, e: first.set())  # queued behind the busy request
    facade.call(lambda sim: seen.append(round(sim.time, 6)), immediate=False)  # after that STEP
    when_done(facade.step(0.004), lambda t, e: second.set())
    gate.set()
    assert first.wait(WAIT_S) and second.wait(WAIT_S)
    assert seen == [0.012]  # at the start of the second STEP, not the first
    assert facade.sim.time == pytest.approx(0.016)
