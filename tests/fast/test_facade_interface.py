"""The fast tier's fake facade offers what the servers may ask of the real one
(usarsim.sim.api.Facade), with the same parameters: a test that passes against the fake
exercises the calls the real facade answers (tests/unit/test_facade_conformance.py checks the
real one against the same interface)."""

from __future__ import annotations

import inspect

from fakes import FakeFacade

from usarsim.sim.api import Facade


def interface(cls: type) -> dict[str, list[str] | None]:
    """Member name -> parameter names (None: an attribute or a property)."""
    out: dict[str, list[str] | None] = {}
    for name in dir(cls):
        if name.startswith("_"):
            continue
        member = inspect.getattr_static(cls, name)
        if isinstance(member, staticmethod):  # called on an instance: as if it took self
            out[name] = ["self", *inspect.signature(member.__func__).parameters]
        else:
            out[name] = list(inspect.signature(member).parameters) if inspect.isfunction(member) else None
    return out


def members_of(protocol: type) -> dict[str, list[str] | None]:
    out = interface(protocol)
    for name in protocol.__annotations__:
        out.setdefault(name, None)
    return out


def test_the_fake_facade_has_every_member_of_the_interface_with_its_parameters():
    wanted = members_of(Facade)
    assert len(wanted) > 30 and "spawn" in wanted and "world" in wanted
    fake = interface(FakeFacade)
    fake.update({k: None for k in FakeFacade.__dataclass_fields__})
    missing = sorted(set(wanted) - set(fake))
    assert not missing, f"FakeFacade lacks {missing}"
    differ = {n: (p, fake[n]) for n, p in wanted.items() if p is not None and fake[n] != p}
    assert not differ, f"parameters differ from usarsim.sim.api.Facade: {differ}"


def test_the_fast_tier_cannot_load_mujoco():
    """scripts/test.sh runs this tier with USARSIM_FAST_TIER=1: MuJoCo then fails to import, so a
    test here that reached the physics (even through an import deep down) would fail."""
    import os

    import pytest

    if os.environ.get("USARSIM_FAST_TIER") != "1":
        pytest.skip("the guard is on in the fast tier's own run (USARSIM_FAST_TIER=1)")
    with pytest.raises(ImportError, match="the fast test tier"):
        import mujoco  # noqa: F401


def test_an_answer_is_a_typed_future_and_when_done_hands_it_on_once_settled():
    """The facade answers with futures; ``when_done`` calls back with (result, None) or
    (None, error): at once for a future already settled, else when it is settled."""
    from concurrent.futures import Future

    from usarsim.sim.api import when_done

    seen: list = []
    pending: Future[float] = Future()
    when_done(pending, lambda r, e: seen.append((r, e)))
    assert seen == []  # not settled yet: nothing called
    pending.set_result(1.5)
    assert seen == [(1.5, None)]
    refused: Future[float] = Future()
    error = RuntimeError("stopped")
    refused.set_exception(error)
    when_done(refused, lambda r, e: seen.append((r, e)))  # settled already: called at once
    assert seen[-1] == (None, error)
    hints = inspect.get_annotations(Facade.step, eval_str=False)
    assert hints["return"] == "Future[float]"  # typed, as the server reads it
