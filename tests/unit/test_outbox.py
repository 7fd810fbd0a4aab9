"""The simulation's ordered outbox (usarsim.sim.measuring.OrderedOutbox): outputs come out
in order, as far as the instants being measured are ready, and what was taken is not kept
alive by the instant's future (the measuring thread's slot holds that future on)."""

from __future__ import annotations

import gc
import weakref
from concurrent.futures import Future

from usarsim.sim.measuring import OrderedOutbox
from usarsim.sim.outputs import Output


class Reading:
    """A reading that can be watched for being freed."""


def done(values: list[Output]) -> Future:
    f: Future = Future()
    f.set_result(values)
    return f


def test_outputs_come_in_order_as_far_as_ready():
    box = OrderedOutbox()
    box.append(Output(1, 0.0, "a", "STA"))
    ready = done([Output(1, 0.1, "b", "SEN")])
    box.push(ready)
    box.append(Output(1, 0.1, "c", "RES", periodic=False))
    later: Future = Future()
    box.push(later)
    box.append(Output(1, 0.2, "e", "STA"))
    assert [o.value for o in box.take(wait=False)] == ["a", "b", "c"]
    assert box.waiting
    later.set_result([Output(1, 0.2, "d", "SEN")])
    assert [o.value for o in box.take(wait=False)] == ["d", "e"]
    assert not box.waiting and box.take() == []


def test_taken_readings_are_not_kept_alive_by_their_future():
    box = OrderedOutbox()
    reading = Reading()
    watch = weakref.ref(reading)
    future = done([Output(1, 0.1, reading, "SEN:Sonar")])  # the slot keeps this one
    box.push(future)
    del reading
    taken = box.take()
    assert taken[0].value is watch()
    del taken  # the server drops what it wrote
    gc.collect()
    assert watch() is None
    assert future.result() == []
