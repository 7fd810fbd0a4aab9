"""The real facade (usarsim.sim.facade.SimFacade) offers every member of the interface the
servers are written against (usarsim.sim.api.Facade), with the same parameters."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "fast"))
from test_facade_interface import interface, members_of  # noqa: E402

from usarsim.sim.api import Facade  # noqa: E402
from usarsim.sim.facade import SimFacade  # noqa: E402


def test_the_real_facade_has_every_member_of_the_interface_with_its_parameters():
    wanted = members_of(Facade)
    real = interface(SimFacade)
    real.update({"world": None, "lockstep": None, "speed": None})  # set in __init__
    missing = sorted(set(wanted) - set(real))
    assert not missing, f"SimFacade lacks {missing}"
    differ = {n: (p, real[n]) for n, p in wanted.items() if p is not None and real[n] != p}
    assert not differ, f"parameters differ from usarsim.sim.api.Facade: {differ}"
