"""Every request to the simulation gets an answer, also when the simulation has stopped or
is stopping: it is answered with SimulationStopped instead of being dropped, so that nobody
waits for it (a camera recording's render thread waited 30 s for a snapshot the stopped
simulation would never take, once in a few stops)."""

from __future__ import annotations

import threading
import time

import pytest

from helpers import broken_advance
from usarsim.errors import SimulationStopped
from usarsim.sim.api import when_done
from usarsim.sim.facade import SimFacade

WAIT_S = 10.0


def answer(facade: SimFacade, fn, immediate: bool = True):
    """Ask ``fn`` of the simulation; its (result, error), or fail if none comes."""
    done = threading.Event()
    box: list = []
    when_done(facade.call(fn, immediate=immediate), lambda r, e: (box.append((r, e)), done.set()))
    assert done.wait(WAIT_S), "the request was never answered"
    return box[0]


@pytest.mark.parametrize("lockstep", [False, True])
def test_a_request_after_the_stop_is_answered_at_once(yellow_world, lockstep):
    facade = SimFacade(yellow_world, seed=0, lockstep=lockstep)
    facade.start()
    assert answer(facade, lambda sim: sim.time) == (pytest.approx(0.0, abs=1.0), None)
    facade.stop()
    t0 = time.monotonic()
    result, error = answer(facade, lambda sim: sim.time)
    assert result is None and isinstance(error, SimulationStopped)
    assert "stopped" in str(error)
    assert time.monotonic() - t0 < 1.0


def test_requests_waiting_for_a_step_that_never_comes_are_answered_at_the_stop(yellow_world):
    facade = SimFacade(yellow_world, seed=0, lockstep=True)
    facade.start()
    answers: list = []
    done = threading.Event()
    for _ in range(3):  # lock-step: these wait for the next STEP
        when_done(
            facade.call(lambda sim: sim.time, immediate=False),
            lambda r, e: (answers.append((r, e)), len(answers) == 3 and done.set()),
        )
    time.sleep(0.1)
    assert answers == []  # no STEP yet: nothing ran
    facade.stop()
    assert done.wait(WAIT_S)
    assert all(r is None and isinstance(e, SimulationStopped) for r, e in answers)


def test_requests_queued_behind_a_long_one_are_answered_when_the_stop_drops_them(yellow_world):
    facade = SimFacade(yellow_world, seed=0, lockstep=False)
    facade.start()
    started = threading.Event()
    answers: list = []

    def slow(sim):
        started.set()
        time.sleep(0.5)
        return "slow"

    when_done(facade.call(slow), lambda r, e: answers.append(("slow", r, e)))
    assert started.wait(WAIT_S)
    for k in range(5):  # queued behind it; the stop comes before they run
        when_done(facade.call(lambda sim, k=k: k), lambda r, e, k=k: answers.append((k, r, e)))
    facade.stop()
    assert answers[0] == ("slow", "slow", None)  # the one running finishes
    assert sorted(a[0] for a in answers[1:]) == [0, 1, 2, 3, 4]
    assert all(r is None and isinstance(e, SimulationStopped) for _, r, e in answers[1:])


def test_the_render_service_stops_at_once_after_the_simulation(yellow_world):
    facade = SimFacade(yellow_world, seed=0, lockstep=False)
    facade.start()
    service = facade.render_service(max_fps=0.0)
    facade.stop()  # as a server stops: the simulation first, then the recorder's renderer
    fut = service.render(64, 48, ())
    t0 = time.monotonic()
    with pytest.raises(SimulationStopped):
        fut.result(WAIT_S)
    service.stop()
    assert time.monotonic() - t0 < 2.0


def step(facade: SimFacade, seconds: float) -> tuple[str, object]:
    """A lock-step STEP: ("stepped", time) or ("refused", error); fail if neither comes."""
    done = threading.Event()
    box: list = []
    when_done(
        facade.step(seconds),
        lambda t, e: (box.append(("stepped", t) if e is None else ("refused", e)), done.set()),
    )
    assert done.wait(WAIT_S), "the STEP was never answered"
    return box[0]


def test_a_step_after_the_stop_is_refused_at_once(yellow_world):
    facade = SimFacade(yellow_world, seed=0, lockstep=True)
    failed: list = []
    facade.when_failed(failed.append)
    facade.start()
    assert step(facade, 0.02) == ("stepped", pytest.approx(0.02))
    facade.stop()
    kind, error = step(facade, 0.02)
    assert kind == "refused" and isinstance(error, SimulationStopped) and "not advanced" in str(error)
    assert failed == [] and facade.failure is None  # a stop is no failure


def test_a_step_the_simulation_stops_on_is_refused_and_so_are_the_next(yellow_world, caplog):
    """A STEP whose physics raises (a bug): the simulation thread ends on the error, logged,
    and that STEP and every later one are refused instead of waiting for ever."""
    facade = SimFacade(yellow_world, seed=0, lockstep=True)
    failed: list[BaseException] = []
    ended = threading.Event()
    facade.when_failed(lambda exc: (failed.append(exc), ended.set()))  # the server stops on it (cli serve)
    facade.start()
    try:
        facade.sim.advance = broken_advance  # the first STEP's wall time is unknown: it runs on the simulation thread
        kind, error = step(facade, 0.02)
        assert kind == "refused" and isinstance(error, SimulationStopped)
        assert ended.wait(WAIT_S) and isinstance(failed[0], RuntimeError) and facade.failure is failed[0]
        assert "a physics bug" in caplog.text  # logged before the thread ends
        assert step(facade, 0.02)[0] == "refused"
    finally:
        facade.stop()
