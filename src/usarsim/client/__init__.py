"""A Python client for the simulator, on the same protocol layer as the server.

    from usarsim.client import launch

    with launch(world="DM-USAR_yellow", seed=1) as server:    # a lock-step simulator
        world = server.connect()
        robot = world.spawn("P2AT", start="PlayerStart1")
        for _ in range(50):
            robot.drive(left=2.0, right=2.0)
            world.step(0.1)                                  # 0.1 s of simulated time
        print(robot.odometry(), robot.scan().ranges.min())

:func:`connect` talks to a server that is already running; :mod:`usarsim.client.aio` has the
same names for asyncio.  Every wait has a timeout (:class:`ClientTimeout`); the server's
refusals raise :class:`ServerError` with its reason.  See docs/client.md.
"""

from __future__ import annotations

from .blocking import Robot, World, connect
from .core import ClientError, ClientTimeout, Scan, ServerError
from .launch import Server, launch

__all__ = ["ClientError", "ClientTimeout", "Robot", "Scan", "Server", "ServerError", "World", "connect", "launch"]
