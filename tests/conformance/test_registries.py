"""Every entry of every plugin registry keeps the recipe (docs/architecture.md): mounted items
(sensors, effecters, cameras), drives, world systems and radio models, built in or added.  A new
plugin is checked here by being registered, with no test of its own needed for these rules."""

from __future__ import annotations

import dataclasses
import inspect
import math

import pytest

import usarsim.effecters  # noqa: F401  (registers the effecters)
import usarsim.robots  # noqa: F401  (registers the drives)
import usarsim.sim.systems  # noqa: F401  (registers the world systems)
from usarsim.robots import DRIVES
from usarsim.sensors import ITEMS, ItemConfig
from usarsim.sim.radio import RADIO_MODELS, RadioModel, new_model
from usarsim.sim.systems.base import SYSTEMS, System

REGISTRIES = [*ITEMS.registries, DRIVES, SYSTEMS, RADIO_MODELS]
ENTRIES = [(r.kind, name, r.get(name)) for r in REGISTRIES for name in r.names()]


def test_every_kind_of_plugin_has_entries():
    kinds = {kind for kind, _, _ in ENTRIES}
    assert {"sensor", "effecter", "camera", "drive", "world system", "radio model"} <= kinds
    assert len(ENTRIES) > 40


@pytest.mark.parametrize(("kind", "name", "cls"), ENTRIES, ids=lambda v: v if isinstance(v, str) else "")
def test_an_entry_is_named_documented_and_found_in_any_case(kind, name, cls):
    registry = next(r for r in REGISTRIES if r.kind == kind)
    assert cls.TYPE == name and registry.get(name.upper()) is cls and registry.canonical(name.lower()) == name
    assert (cls.__doc__ or "").strip(), f"the {kind} {name} says what it is in a docstring"


ITEM_ENTRIES = [(k, n, c) for k, n, c in ENTRIES if k in ("sensor", "effecter", "camera")]


@pytest.mark.parametrize(("kind", "name", "cls"), ITEM_ENTRIES, ids=lambda v: v if isinstance(v, str) else "")
def test_an_items_settings_have_defaults_and_its_aliases_name_real_fields(kind, name, cls):
    assert issubclass(cls.Config, ItemConfig)
    try:
        cls.Config()  # a robot file may give no setting at all,
    except ValueError as exc:  # or is told plainly what the item cannot do without
        assert len(str(exc)) > 20, exc
    fields = {f.name for f in dataclasses.fields(cls.Config)}
    assert set(cls.ALIASES.values()) <= fields, f"{name}: an alias names no field"
    for preset, values in cls.PRESETS.items():
        assert set(values) <= fields, f"{name}: preset {preset} sets no field"
        cls.Config(**values)  # and is valid


@pytest.mark.parametrize("name", DRIVES.names())
def test_a_drive_says_which_drive_parts_it_applies(name):
    from usarsim import controls

    accepts = DRIVES.get(name).ACCEPTS
    kinds = {obj for _, obj in inspect.getmembers(controls, inspect.isclass)}
    assert isinstance(accepts, frozenset) and accepts <= kinds


@pytest.mark.parametrize("name", SYSTEMS.names())
def test_a_world_system_is_a_system(name):
    assert issubclass(SYSTEMS.get(name), System)


@pytest.mark.parametrize("name", RADIO_MODELS.names())
def test_a_radio_model_weakens_with_distance_and_describes_itself(name):
    model = new_model(name)
    assert isinstance(model, RadioModel) and model.name == name and model.describe().startswith(name)
    near, far = model.signal_dbm(1.0), model.signal_dbm(100.0)
    assert math.isfinite(near) and far <= near  # far may be -inf: nothing heard
    if model.counts_walls:
        assert model.signal_dbm(10.0, walls=2) < model.signal_dbm(10.0, walls=0)
    else:
        assert model.signal_dbm(10.0, walls=2) == model.signal_dbm(10.0, walls=0)
    assert model.holds(model.signal_dbm(1.0))  # two antennas a metre apart hear each other
    assert dataclasses.replace(model, cutoff_dbm=-50.0).name == name  # the ini keys change its constants
