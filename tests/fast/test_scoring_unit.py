"""The scorer (usarsim.scoring.Scorer) on constructed frames: radio contact shares, robots
lost to an empty battery, collisions counted once per push, reports matched to victims."""

from __future__ import annotations

import pytest

from usarsim.config.catalog import resolve_robot, resolve_world
from usarsim.readings import CommandResult, VictimPart, VictimReading
from usarsim.scoring import Scorer
from usarsim.sim.types import LinkFrame, Output, RobotFrame, WorldFrame

WORLD = resolve_world("DM-USAR_yellow")
P2AT = resolve_robot("P2AT")


def robot(uid, name, x, *, battery=100.0, force=0.0, rotation=(0.0, 0.0, 0.0)):
    return RobotFrame(uid, name, P2AT, (x, 0.0, -0.15), rotation, battery, 0.0, force)


def frame(t, robots, links=None):
    return WorldFrame(t, tuple(robots), (), links)


def test_radio_contact_share_counts_the_seconds_a_link_holds():
    sc = Scorer(WORLD)
    for k in range(10):
        up = k < 7  # R1-R2 in contact for 7 of 10 samples; R3 never
        sc.frame(
            frame(
                float(k),
                [robot(1, "R1", 0.0), robot(2, "R2", 1.0), robot(3, "R3", 9.0)],
                links=(
                    LinkFrame("r1", "r2", -60.0, 1.0, 0, up),
                    LinkFrame("r1", "r3", -95.0, 9.0, 3, False),
                    LinkFrame("r2", "r3", -95.0, 8.0, 3, False),
                ),
            )
        )
    r = sc.result()
    assert r["robots"]["R1"]["radio_contact_share"] == pytest.approx(0.7)
    assert r["robots"]["R2"]["radio_contact_share"] == pytest.approx(0.7)
    assert r["robots"]["R3"]["radio_contact_share"] == 0.0
    assert r["team"]["radio_contact_share"] == pytest.approx(1.4 / 3, abs=1e-4)


def test_an_empty_battery_loses_the_robot_and_a_push_is_one_collision():
    sc = Scorer(WORLD)
    forces = [0.0, 80.0, 120.0, 90.0, 0.0, 0.0, 200.0, 5.0]  # two pushes
    for k, f in enumerate(forces):
        sc.frame(frame(0.1 * k, [robot(1, "R1", 0.01 * k, force=f, battery=10.0 - 2 * k)]))
    r = sc.result()
    assert r["robots"]["R1"]["collisions"] == 2
    assert r["robots"]["R1"]["lost"] == "battery" and r["team"]["robots_lost"] == 1
    assert r["robots"]["R1"]["distance_m"] == pytest.approx(0.07, abs=1e-6)


def test_sensed_victims_count_unless_the_team_reports_and_then_reports_count():
    sc = Scorer(WORLD)
    sc.frame(frame(0.0, [robot(1, "R1", 0.0)]))
    sc.output(
        Output(
            1,
            0.0,
            VictimReading(
                "VictSensor", (VictimPart("Head", (1.0, 0.0, 0.0), "Ben"), VictimPart("Head", (1.0, 0.0, 0.0), None))
            ),
            "SEN",
        )
    )
    assert sc.result()["team"]["victims_found"] == 1
    assert sc.result()["team"]["score"] == pytest.approx(50.0)
    sc.output(Output(1, 0.0, CommandResult("Victim", "V1", True, (("Location", (-5.0, -3.0, 0.0)),)), "RES"))
    r = sc.result()["team"]
    assert r["victims_reported"] == 1 and r["false_reports"] == 0  # Carl, 0.5 m away
    assert r["score"] == pytest.approx(50.0)  # reported victims count now (Carl), not Ben
