"""Mounted items (design.md 4): sensors, effecters and cameras have bases and registries
of their own, one name space between them; a robot file's item is looked up among all
three (no MuJoCo model is built here)."""

from __future__ import annotations

import pytest

from usarsim.config.catalog import resolve_robot
from usarsim.config.robot import MountedItem
from usarsim.effecters import EFFECTERS, Effecter, Gripper, RFIDReleaser, RollerTable
from usarsim.errors import PluginNotFoundError
from usarsim.sensors import CAMERAS, ITEMS, SENSORS, CameraItem, Sensor, make_item
from usarsim.sensors.base import Item, ItemKinds


def test_each_kind_has_its_registry():
    assert {"Sonar", "RangeScanner", "RFID", "Odometry"} <= set(SENSORS.names())
    assert {"Gripper", "RFIDReleaser", "RollerTable"} <= set(EFFECTERS.names())
    assert {"Camera", "OmniCam"} <= set(CAMERAS.names())
    assert not set(SENSORS.names()) & (set(EFFECTERS.names()) | set(CAMERAS.names()))
    assert set(ITEMS.names()) == set(SENSORS.names()) | set(EFFECTERS.names()) | set(CAMERAS.names())
    assert all(issubclass(SENSORS.get(n), Sensor) for n in SENSORS.names())
    assert all(issubclass(EFFECTERS.get(n), Effecter) for n in EFFECTERS.names())
    assert all(issubclass(CAMERAS.get(n), CameraItem) for n in CAMERAS.names())
    assert RollerTable is EFFECTERS.get("rollertable")


def test_a_name_registered_twice_is_an_error():
    kinds = ItemKinds()
    sensors, effecters = kinds.new("sensor"), kinds.new("effecter")

    @sensors.register("Probe", "ProbeSensor")
    class Probe(Item):
        pass

    with pytest.raises(ValueError, match="'probe' is registered already"):

        @sensors.register("probe")
        class Again(Item):
            pass

    with pytest.raises(ValueError, match="'ProbeSensor' is registered already as a sensor"):

        @effecters.register("Pusher", "ProbeSensor")
        class Pusher(Item):
            pass

    assert kinds.get("PROBE") is Probe and kinds.canonical("probesensor") == "Probe"
    assert "Pusher" not in kinds  # refused as a whole


def test_the_item_look_up_covers_every_kind_in_any_case():
    assert ITEMS.get("gripper") is Gripper
    assert ITEMS.canonical("omnicamera") == "OmniCam"
    assert ITEMS.canonical("SONAR") == "Sonar"
    assert ITEMS.canonical("Nothing") is None


def test_an_unknown_item_type_names_the_closest_and_every_valid_one():
    with pytest.raises(PluginNotFoundError) as info:
        ITEMS.get("Griper")
    msg = str(info.value)
    assert "unknown sensor type 'Griper'" in msg and "did you mean 'Gripper'" in msg
    allowed = msg.split("allowed:", 1)[1]
    assert "Sonar" in allowed and "Camera" in allowed and "RollerTable" in allowed


def test_make_item_makes_effecters_cameras_and_sensors_from_a_robot_file():
    robot = resolve_robot("P2AT")
    made = {item.name: make_item(item, robot, 0, "test") for item in robot.items}
    assert isinstance(made["Gun"], RFIDReleaser) and isinstance(made["Gun"], Effecter)
    assert isinstance(made["Camera"], CameraItem) and not made["Camera"].PERIODIC
    assert isinstance(made["F1"], Sensor) and made["F1"].PERIODIC
    gripper = make_item(
        MountedItem(item_type="gripper", name="Claw", params={"Fingers": ["CameraPanTilt_Link2"]}), robot, 0, "test"
    )
    assert isinstance(gripper, Gripper) and gripper.TYPE == "Gripper"
    assert gripper.config.fingers == ["CameraPanTilt_Link2"]
    assert gripper.conf_fields() == ()
