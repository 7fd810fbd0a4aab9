"""Sensor readings taken on the measuring thread (usarsim.sim.measuring) are the very
readings the simulation thread takes itself, in the same order; in the clocked modes they
come out in time order, and requests that change what sensors read wait for them."""

from __future__ import annotations

import math
import os

import pytest

from helpers import segments, sen_type
from usarsim.sim.settings import SimSettings

ROBOTS = (
    "INIT {ClassName USARBot.P2AT} {Name R1} {Start PlayerStart1}",
    "INIT {ClassName USARBot.Kurt3D} {Name R2} {Start PlayerStart2}",
)
# STEPs of one physics step, of less than a report period, of several report periods and
# of odd lengths, so that report instants fall inside and at the ends of STEPs
STEPS = (0.004, 0.004, 0.1, 0.37, 0.2, 1.0, 0.052, 0.5, 0.004, 2.0)


def lockstep_session(server_factory, thread: bool) -> tuple[list[str], bool]:
    srv = server_factory(lockstep=True, sim=SimSettings(sensor_thread=thread))
    clients = []
    for init in ROBOTS:
        c = srv.connect()
        c.nfo()
        c.send(init)
        c.sync()  # spawned before the next client's robot, and before the first STEP
        clients.append(c)
    lines: list[str] = []
    for who, (c, drive) in enumerate(zip(clients, ("DRIVE {Left 1.5} {Right 0.5}", "DRIVE {Left -1.0} {Right 1.0}"))):
        c.send(drive)
        lines += [f"{who} {ln.text}" for ln in c.sync()]
    for seconds in STEPS:
        lines += [f"0 {ln.text}" for ln in clients[0].step(seconds)]
        # the other client's lines of that STEP: all of them were sent before its STEPPED
        lines += [f"1 {ln.text}" for ln in clients[1].sync()]
    threaded = srv.on_sim(lambda sim: sim.measurer is not None)
    return lines, threaded


def test_the_measuring_thread_gives_the_same_lines_as_the_simulation_thread(server_factory):
    inline, inline_threaded = lockstep_session(server_factory, False)
    threaded, threaded_threaded = lockstep_session(server_factory, True)
    assert not inline_threaded and threaded_threaded
    kinds = {sen_type(ln.split(" ", 1)[1]) for ln in inline if " SEN " in f" {ln.split(' ', 1)[1]}"}
    assert {"Sonar", "RangeScanner", "GPS", "INS", "GroundTruth", "Encoder"} <= kinds, kinds
    assert len(inline) > 300
    assert threaded == inline


def test_clocked_readings_come_in_time_order_and_settings_wait_for_them(server_factory):
    srv = server_factory(lockstep=False, speed=None, sim=SimSettings(sensor_thread=True))
    c = srv.connect()
    c.nfo()
    c.send(ROBOTS[0])
    c.send("DRIVE {Left 1.0} {Right 1.0}")
    assert srv.on_sim(lambda sim: sim.measurer is not None)
    stamps: dict[str, float] = {}
    last = 0.0
    for _ in range(400):
        ln = c.next_line()
        t = segments(ln.text).get("Time")
        if t is None:
            continue
        key = ln.text.split(" ", 1)[0] + str(sen_type(ln))
        # every stream's stamps grow, and no line is older than one already seen by more than
        # what one instant's readings may trail a status of the same instant (nothing)
        assert float(t) >= stamps.get(key, 0.0)
        assert float(t) >= last - 1e-9, ln.text
        stamps[key] = float(t)
        last = max(last, float(t))
    # a query that waits for the readings under way comes after them, still in time order
    c.send("GETGEO {Type Sonar}")
    before = c.lines_until("GEO")
    times = [float(segments(ln.text)["Time"]) for ln in before if "Time" in segments(ln.text)]
    assert all(b >= a - 1e-9 for a, b in zip(times, times[1:]))


@pytest.mark.parametrize("thread", [False, True])
def test_sensors_read_the_world_with_or_without_the_measuring_thread(server_factory, thread):
    """A robot facing a wall reads it on its laser either way."""
    srv = server_factory(lockstep=True, sim=SimSettings(sensor_thread=thread))
    c = srv.connect()
    c.nfo()
    c.send(ROBOTS[0])
    lines = c.step(1.0)
    scans = [ln for ln in lines if sen_type(ln) == "RangeScanner"]
    assert scans
    ranges = [float(v) for v in segments(scans[-1].text)["Range"].split(",")]
    assert min(ranges) < 20.0  # something of the arena is in sight


def test_a_status_made_on_the_measuring_thread_is_the_robots_status_at_its_instant(test_world):
    """The measuring thread makes an instant's STA after the simulation has moved on: what it
    shows (battery, headlight) is still what the robot had at the instant."""
    import threading

    from usarsim.config.catalog import resolve_robot
    from usarsim.sim.simulation import Simulation

    sim = Simulation(test_world, seed=1)
    for uid, pose in ((1, "Open"), (2, "Far")):
        p = test_world.start_pose(pose)
        sim.spawn(uid, resolve_robot("P2AT"), f"R{uid}", p.location, p.rotation)
    sim.advance(0.5)
    sim.measure_on_thread(True)
    try:
        sim.take_outputs()
        gate = threading.Event()
        sim.measurer.call(gate.wait)  # the measuring thread waits until the instant is past
        due = sim.reports.next_due()
        sim.advance(due - sim.time + sim.dt / 2)
        assert sim.time > due - 1e-9 and sim.outbox.waiting  # the instant was handed over, not measured yet
        r = sim.robots[1]
        used_then = r.battery_used_s
        r.light = True
        r.battery_used_s = r.config.battery_s - 0.5
    finally:
        gate.set()
        outs = sim.take_outputs()
        sim.measure_on_thread(False)
    sta = [o for o in outs if o.key == "STA" and o.uid == 1 and abs(o.time - due) < 1e-9]
    assert len(sta) == 1
    value = sta[0].value
    assert value.light_toggle is False and value.light_intensity == 0
    assert value.battery_s == int(math.ceil(r.config.battery_s - used_then - 1e-6)) > 1
    assert value.view == 0


@pytest.mark.skipif(not hasattr(os, "setpriority"), reason="no thread priorities on this system")
def test_the_measuring_thread_yields_processors_to_the_simulation_thread():
    """The measuring thread runs MEASURING_NICE nicer than the thread that made it, so that
    the kernel gives the simulation thread, the critical path, the larger share of a busy
    machine; the thread that made it keeps its own priority."""
    import threading

    from usarsim.sim.measuring import MEASURING_NICE, Measurer

    def nice() -> int:
        return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())

    own = nice()
    measurer = Measurer()
    try:
        theirs = measurer.call(nice).result(10)
    finally:
        measurer.close()
    assert MEASURING_NICE > 0
    assert theirs == min(19, own + MEASURING_NICE)
    assert nice() == own
