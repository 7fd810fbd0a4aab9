"""The narrow, thread-safe door from the servers into the simulation.

Servers (asyncio) call these methods from their own thread; every change of the
world runs on the simulation thread, in the order the calls were made.  Results
come back through callbacks, called on the simulation thread.
"""

from __future__ import annotations

import logging
from typing import Any, Callable

from usarsim.config.robot import RobotConfig
from usarsim.config.world import StartPose, WorldConfig
from usarsim.sim.runner import Request, SimulationRunner, StepRequest
from usarsim.sim.simulation import ItemDescription, Output, Simulation, describe_items

log = logging.getLogger("usarsim.sim")


class SimFacade:
    def __init__(self, world: WorldConfig, *, seed: int = 0, speed: float | None = 1.0, lockstep: bool = False,
                 deliver: Callable[[list[Output]], None] | None = None):
        self.world = world
        self.sim = Simulation(world, seed=seed)
        self.lockstep = lockstep
        self.speed = speed
        self._deliver = deliver or (lambda outs: None)
        self.runner = SimulationRunner(self.sim, self._on_outputs, speed=speed, lockstep=lockstep)
        self._descriptions: dict[str, list[ItemDescription]] = {}

    def set_deliver(self, deliver: Callable[[list[Output]], None]) -> None:
        self._deliver = deliver

    def _on_outputs(self, outs: list[Output]) -> None:
        self._deliver(outs)

    # Lifecycle ---------------------------------------------------------------------
    def start(self) -> None:
        self.runner.start()

    def stop(self) -> None:
        self.runner.stop()

    # Static facts ------------------------------------------------------------------
    @property
    def world_name(self) -> str:
        return self.world.name

    @property
    def start_poses(self) -> tuple[StartPose, ...]:
        return self.world.start_poses

    @property
    def time(self) -> float:
        """Current simulated time (a plain read; exact in lock-step mode)."""
        return self.sim.time

    def describe(self, robot: RobotConfig) -> list[ItemDescription]:
        d = self._descriptions.get(robot.path)
        if d is None:
            d = describe_items(robot)
            self._descriptions[robot.path] = d
        return d

    def live_conf(self, uid: int, item_type: str, name: str):
        """CONF fields of a robot's item that changed at run time, or None."""
        return self.sim.live_conf.get((uid, item_type, name))

    # Requests ----------------------------------------------------------------------
    def spawn(self, uid: int, robot: RobotConfig, name: str, location, rotation,
              on_done: Callable[[Any, BaseException | None], None], set_down: bool = False) -> None:
        self.runner.submit(Request(lambda sim: sim.spawn(uid, robot, name, location, rotation, set_down),
                                   immediate=True, on_done=on_done))

    def remove(self, uid: int) -> None:
        self.runner.submit(Request(lambda sim: sim.remove(uid), immediate=True))

    def drive_skid(self, uid: int, left, right, normalized: bool, light) -> None:
        self.runner.submit(Request(lambda sim: sim.drive_skid(uid, left, right, normalized, light)))

    def flip(self, uid: int) -> None:
        self.runner.submit(Request(lambda sim: sim.flip(uid)))

    def drive_ackermann(self, uid: int, speed, front, rear, normalized: bool, light) -> None:
        self.runner.submit(Request(lambda sim: sim.drive_ackermann(uid, speed, front, rear, normalized, light)))

    def drive_aerial(self, uid: int, altitude, linear, lateral, rotational, normalized: bool, light) -> None:
        self.runner.submit(Request(
            lambda sim: sim.drive_aerial(uid, altitude, linear, lateral, rotational, normalized, light)))

    def drive_nautical(self, uid: int, propeller, rudder, stern_plane, normalized: bool, light) -> None:
        self.runner.submit(Request(
            lambda sim: sim.drive_nautical(uid, propeller, rudder, stern_plane, normalized, light)))

    def drive_wheels(self, uid: int, wheels, normalized: bool, light) -> None:
        self.runner.submit(Request(lambda sim: sim.drive_wheels(uid, wheels, normalized, light)))

    def drive_joints(self, uid: int, commands: list[tuple[str, float, int]]) -> None:
        """Joint commands (name, value, order), applied together."""
        def action(sim: Simulation):
            for name, value, order in commands:
                if not sim.drive_joint(uid, name, value, order):
                    log.info("robot id %d: no joint '%s' for order %d (or no power); ignored", uid, name, order)

        self.runner.submit(Request(action))

    def operate(self, uid: int, item_type, name, opcode, params) -> None:
        def action(sim: Simulation):
            before = len(sim.outbox)
            res = sim.operate(uid, item_type, name, opcode, params)
            if res is not None:  # the RES first, then whatever the operation reported (EFF)
                sim.outbox.insert(before, Output(uid, sim.time, res, "RES", periodic=False))

        self.runner.submit(Request(action))

    def step(self, seconds: float, on_done: Callable[[float], None]) -> None:
        self.runner.submit(StepRequest(seconds, on_done))

    def call(self, fn: Callable[[Simulation], Any], on_done=None, immediate: bool = True) -> None:
        """Run ``fn(sim)`` on the simulation thread (tools, tests, benchmarks)."""
        self.runner.submit(Request(fn, immediate=immediate, on_done=on_done))
