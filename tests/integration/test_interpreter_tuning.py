"""While a simulation thread runs, the heap it has built is kept out of the collector's full
collections once the model stands still, and the interpreter switches threads every 0.5 ms
(usarsim.sim.interpreter); a removed robot is still collected, and all of it is given back
when the thread stops."""

from __future__ import annotations

import gc
import sys
import weakref
from concurrent.futures import Future

from helpers import wait_for
from usarsim.config.catalog import resolve_robot
from usarsim.sim.facade import SimFacade
from usarsim.sim.interpreter import SWITCH_INTERVAL_S, InterpreterTuning

WAIT_S = 60.0


def _wait(answer: Future) -> object:
    """The facade's answer (it raises the error the request was refused with)."""
    return answer.result(WAIT_S)


def test_the_heap_is_frozen_while_it_runs_a_removed_robot_is_collected_and_all_is_given_back(yellow_world):
    before = sys.getswitchinterval()
    assert before != SWITCH_INTERVAL_S
    gc.unfreeze()
    facade = SimFacade(yellow_world, seed=0, speed=None)
    facade.start()
    try:
        p2at = resolve_robot("USARBot.P2AT")
        for uid, x in ((1, 0.0), (2, 2.0)):
            _wait(facade.spawn(uid, p2at, f"R{uid}", (x, 0.0, 0.5), (0, 0, 0), set_down=True))
        assert sys.getswitchinterval() == SWITCH_INTERVAL_S
        # once the model has stood still: the world, both robots and everything imported
        wait_for(lambda: gc.get_freeze_count() > 10_000, timeout=10 * InterpreterTuning.SETTLE_S)

        # a robot whose objects refer to each other, frozen with them: only a collection that
        # walks them frees them
        robot = facade.sim.robots[2]
        robot.__dict__["itself"] = robot
        gone = weakref.ref(robot)
        del robot
        frozen_with_two = gc.get_freeze_count()
        facade.remove(2)
        _wait(facade.barrier())
        assert gc.get_freeze_count() == 0  # thawed at once
        wait_for(lambda: gone() is None, timeout=10 * InterpreterTuning.SETTLE_S)
        wait_for(lambda: 10_000 < gc.get_freeze_count() < frozen_with_two, timeout=10 * InterpreterTuning.SETTLE_S)
        assert 1 in facade.sim.robots
        t = _wait(facade.barrier())
        assert t > 0.0  # it runs on
    finally:
        facade.stop()
    assert gc.get_freeze_count() == 0
    assert sys.getswitchinterval() == before
