"""Wires the simulation and every listener of one ``usarsim serve`` process."""

from __future__ import annotations

import logging

from usarsim.config.world import WorldConfig
from usarsim.server.control import ControlServer
from usarsim.server.truth import TruthServer
from usarsim.sim.facade import SimFacade

log = logging.getLogger("usarsim")


class Application:
    def __init__(self, world: WorldConfig, *, host: str = "127.0.0.1", port: int = 3000, seed: int = 0,
                 speed: float | None = 1.0, lockstep: bool = False, max_connections: int = 64,
                 robot_dirs: tuple[str, ...] = (), truth_port: int | None = 3989):
        self.world = world
        self.host = host
        self.facade = SimFacade(world, seed=seed, speed=speed, lockstep=lockstep)
        self.control = ControlServer(self.facade, host=host, port=port, max_connections=max_connections,
                                     robot_dirs=tuple(robot_dirs))
        # the ground-truth service (protocol.md 12.4); None: not served
        self.truth = TruthServer(self.facade, host=host, port=truth_port) if truth_port is not None else None

    async def start(self) -> None:
        await self.control.start()
        if self.truth is not None:
            try:
                await self.truth.start()
            except OSError:
                await self.control.stop()
                raise
        self.facade.start()

    def listeners(self) -> list[tuple[str, str, int]]:
        out = [("control", self.host, self.control.port)]
        if self.truth is not None:
            out.append(("truth", self.host, self.truth.port))
        return out

    async def stop(self) -> None:
        if self.truth is not None:
            await self.truth.stop()
        await self.control.stop()
        self.facade.stop()
