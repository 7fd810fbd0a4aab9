"""A bench run in this process leaves nothing of its server behind: the stopped server is
garbage in reference cycles, and a run that left it to a later collection had the next run
built beside it (three runs of 128 robots peaked at 1.0 GB instead of 0.69)."""

from __future__ import annotations

import gc

from usarsim.bench import measure_rtf
from usarsim.server.app import Application
from usarsim.sim.simulation import Simulation


def alive(cls) -> int:
    return sum(1 for o in gc.get_objects() if isinstance(o, cls))


def test_a_run_leaves_no_simulation_or_server_alive(yellow_world):
    gc.collect()
    sims, apps = alive(Simulation), alive(Application)
    gc.disable()  # only the run's own collection may free them
    try:
        run = measure_rtf(yellow_world, 2, 0.3)
        assert run["sim_seconds"] >= 0.3 and run["model"] is not None
        assert (alive(Simulation), alive(Application)) == (sims, apps)
    finally:
        gc.enable()


def test_the_radio_load_flows_through_the_channel_and_is_counted(yellow_world):
    from usarsim.bench.radio import SUBT_CHANNEL, radio_rtf

    ideal = radio_rtf(yellow_world, 3, 1.0, None, 10.0)
    subt = radio_rtf(yellow_world, 3, 1.0, SUBT_CHANNEL, 10.0)
    assert ideal["rtf"] > 0 and subt["rtf"] > 0
    assert ideal["delivered"] == 0  # USARSim's channel relays at once: nothing goes through the channel
    assert subt["links"] >= 1 and subt["delivered"] > 0  # every robot's messages to each teammate in reach
