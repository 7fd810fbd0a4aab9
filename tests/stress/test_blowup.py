"""A physics blow-up under load (issue: reliability): one robot among many driving robots
gets an absurd torque on its chassis; it is reset where it last was stable and the reset
is logged, while every other robot runs on exactly as in the same run without the blow-up.
Reduced: 8 P2ATs with their full sensor kits; full (USARSIM_STRESS=full): 32."""

from __future__ import annotations

import logging
import math

from stress_scale import scaled

from helpers import ground_truth

SECONDS = 4.0
STEP_S = 0.2
BLOW_AT_S = 1.0
# Far beyond anything a motor gives: a P2AT's chassis (about 0.3 kg m^2 about its long axis)
# reaches thousands of rad/s in one 4 ms physics step.
ABSURD_TORQUE_NM = 1.0e6


def _robot(sim, name: str):
    return next(r for r in sim.robots.values() if r.name == name)


def _run(server_factory, n: int, blow: int | None):
    """Drive ``n`` P2ATs over their own connections in lock-step; at BLOW_AT_S robot
    ``blow`` (None: none) gets ABSURD_TORQUE_NM for 0.02 s.  Returns the server, every
    client's lines and the simulated times of the unstable-robot log lines."""
    from usarsim.bench import free_spots

    srv = server_factory(seed=11, max_connections=n + 1)
    spots = free_spots(srv.app.world, n)
    clients = []
    for i, (x, y, z, yaw) in enumerate(spots):
        c = srv.connect()
        c.nfo()
        c.send(
            f"INIT {{ClassName USARBot.P2AT}} {{Name R{i}}} {{Location {x:.2f},{y:.2f},{z:.2f}}} "
            f"{{Rotation 0,0,{yaw:.4f}}}"
        )
        c.sync()
        clients.append(c)
    stepper = clients[0]
    stepper.step(0.5)  # everyone lands
    for i, c in enumerate(clients):  # each drives a gentle curve of its own
        c.send(f"DRIVE {{Left {0.8 + 0.05 * (i % 5):.2f}}} {{Right {0.6 + 0.05 * (i % 3):.2f}}}")
        c.sync()
    marks = [len(c.history) for c in clients]
    t = 0.0
    while t < SECONDS - 1e-9:
        if abs(t - BLOW_AT_S) < 1e-9:

            def torque(sim, on: bool):
                if blow is not None:
                    body = _robot(sim, f"R{blow}").handle.body_id
                    sim.data.xfrc_applied[body, 3:] = (ABSURD_TORQUE_NM, 0.0, 0.0) if on else 0.0

            srv.on_sim(lambda sim: torque(sim, True))
            stepper.step(0.02)
            srv.on_sim(lambda sim: torque(sim, False))
            t += 0.02
        stepper.step(STEP_S)
        t += STEP_S
        for c in clients[1:]:
            c.sync()
    return srv, clients, [c.history[m:] for c, m in zip(clients, marks)]


def test_a_blow_up_under_load_resets_that_robot_alone(server_factory, caplog):
    n = scaled(8, 32)
    hurt = n // 2
    _, _, calm_lines = _run(server_factory, n, None)
    with caplog.at_level(logging.ERROR, logger="usarsim"):
        srv, clients, lines = _run(server_factory, n, hurt)
    resets = srv.on_sim(lambda sim: {r.name: r.resets for r in sim.robots.values()})
    assert resets.pop(f"R{hurt}") >= 1
    assert set(resets.values()) == {0}, resets
    logged = [r.getMessage() for r in caplog.records if "unstable" in r.getMessage()]
    assert logged and all(f"'R{hurt}'" in m for m in logged), logged

    # every other robot ran on exactly as without the blow-up: its status at 5 Hz, its path
    for k in range(n):
        if k == hurt:
            continue
        sta = [ln for ln in lines[k] if ln.text.startswith("STA")]
        assert len(sta) == len([ln for ln in calm_lines[k] if ln.text.startswith("STA")])
        assert abs(len(sta) - 5 * (SECONDS + 0.02)) <= 1.0
        (_, a, _), (_, b, _) = ground_truth(lines[k])[-1], ground_truth(calm_lines[k])[-1]
        assert math.dist(a, b) < 1e-3, (k, a, b)

    # the hurt robot is back on its wheels, its connection open, and it drives on
    track = [(t, loc, ori) for t, loc, ori in ground_truth(lines[hurt])]
    assert all(math.isfinite(v) for _, loc, ori in track for v in (*loc, *ori))
    (_, end, (roll, pitch, _)) = track[-1]
    assert abs(math.remainder(roll, 2 * math.pi)) < 0.3 and abs(math.remainder(pitch, 2 * math.pi)) < 0.3

    def late_path(lns) -> float:  # how far the robot went from a second after the blow-up on
        gt = ground_truth(lns)
        after = [loc for t, loc, _ in gt if t >= gt[0][0] + BLOW_AT_S + 1.0]
        return math.dist(after[0], after[-1])

    assert late_path(lines[hurt]) > 0.8 * late_path(calm_lines[hurt])  # it drives on at its pace
    assert clients[hurt].ask("GETSTARTPOSES", "NFO {StartPoses")
    print(
        f"\n{n} robots; R{hurt} reset {srv.on_sim(lambda sim: _robot(sim, f'R{hurt}').resets)} "
        f"time(s), logged {len(logged)} time(s); the {n - 1} others ran on exactly as without it"
    )
