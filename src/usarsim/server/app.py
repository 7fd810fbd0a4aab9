"""Wires the simulation and every listener of one ``usarsim serve`` process."""

from __future__ import annotations

import logging

from usarsim.config.world import WorldConfig
from usarsim.server.control import ControlServer
from usarsim.sim.facade import SimFacade

log = logging.getLogger("usarsim")


class Application:
    def __init__(self, world: WorldConfig, *, host: str = "127.0.0.1", port: int = 3000, seed: int = 0,
                 speed: float | None = 1.0, lockstep: bool = False, max_connections: int = 64,
                 robot_dirs: tuple[str, ...] = ()):
        self.world = world
        self.host = host
        self.facade = SimFacade(world, seed=seed, speed=speed, lockstep=lockstep)
        self.control = ControlServer(self.facade, host=host, port=port, max_connections=max_connections,
                                     robot_dirs=tuple(robot_dirs))

    async def start(self) -> None:
        await self.control.start()
        self.facade.start()

    def listeners(self) -> list[tuple[str, str, int]]:
        return [("control", self.host, self.control.port)]

    async def stop(self) -> None:
        await self.control.stop()
        self.facade.stop()
