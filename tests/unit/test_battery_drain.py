"""The batteries' compiled drain (usarsim.sim.battery._drain_all) gives the numbers the
array operations gave, to the bit: the power of each robot's actuators summed in actuator
order, the load capped at 1 (NaN kept), the drain, and which batteries are out."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from usarsim.sim.battery import BATTERY_LOAD_FACTOR, _drain_all


def reference(owners, force, velocity, rated, capacity, used, seconds):
    """The drain as numpy computes it, array by array."""
    power = np.bincount(owners, weights=np.abs(force * velocity), minlength=rated.size + 1)
    if seconds > 0:
        load = np.minimum(power[1:] / rated, 1.0)
        used += seconds * (1.0 + load * BATTERY_LOAD_FACTOR)
    return int(np.count_nonzero(~(capacity - used > 0.0)))


@settings(max_examples=200, deadline=None)
@given(
    robots=st.integers(1, 40),
    per_robot=st.integers(0, 8),
    seed=st.integers(0, 2**32 - 1),
    seconds=st.sampled_from([0.0, 0.004, 0.02, 0.1, 1.0]),
    nan=st.booleans(),
)
def test_the_compiled_drain_is_numpys_to_the_bit(robots, per_robot, seed, seconds, nan):
    rng = np.random.default_rng(seed)
    nu = robots * per_robot + int(rng.integers(0, 4))  # actuators of no robot too
    owners = rng.permutation(
        np.concatenate(
            [np.repeat(np.arange(1, robots + 1), per_robot), np.zeros(nu - robots * per_robot, dtype=np.intp)]
        )
    ).astype(np.intp)
    force = rng.normal(0.0, 20.0, nu)
    velocity = rng.normal(0.0, 5.0, nu)
    if nan and nu:
        force[rng.integers(0, nu)] = np.nan  # a robot blown up
    rated = rng.uniform(1e-6, 400.0, robots)
    capacity = rng.uniform(0.0, 3600.0, robots)
    used = capacity * rng.uniform(0.0, 1.2, robots)
    expected_used = used.copy()
    out = reference(owners, force, velocity, rated, capacity, expected_used, seconds)
    got = _drain_all(owners, force, velocity, rated, capacity, used, seconds, BATTERY_LOAD_FACTOR)
    assert got == out
    assert used.tobytes() == expected_used.tobytes()
