"""The ComServerInterface (TCP 7435, ``--cominterface-port``; protocol.md 12.3): what the
WSS's propagation models ask the simulator, ``GETPOS`` (where every robot is) and
``GETOBS`` (how many walls lie between two robots or two points).

asyncio glue only: lines -> requests (:func:`~usarsim.protocol.wireless.parse_interface_request`)
-> the facade's robot positions and wall counts -> a typed reply, formatted by
:func:`~usarsim.protocol.wireless.format_interface_reply`.  A malformed line or an unknown
request is ignored (logged once per connection kind); a GETOBS that cannot be answered
gets ``{ObstCount -1}``.
"""

from __future__ import annotations

from usarsim.errors import ProtocolError
from usarsim.protocol.wireless import (
    INTERFACE_PORT,
    GetObsIncomplete,
    GetObsPoints,
    GetObsRobots,
    GetPos,
    InterfaceReply,
    InterfaceRequest,
    NumObs,
    Positions,
    RobotPosition,
    format_interface_reply,
    parse_interface_request,
)

from .service import MAX_CONNECTIONS, LineConnection, WirelessServer, WirelessService


class InterfaceConnection(LineConnection):
    """A connection of a WSS propagation model: ``GETPOS`` and ``GETOBS`` (protocol.md 12.3)."""

    what = "cominterface"

    async def handle(self, line: str) -> None:
        req = self.parse(line, parse_interface_request)
        reply = await self._answer(req) if req is not None else None
        if reply is not None:
            self.write_text(format_interface_reply(reply))

    async def _answer(self, req: InterfaceRequest) -> InterfaceReply | None:
        """The reply to ``req``; None: the request is ignored."""
        svc: WirelessService = self.owner.service
        if isinstance(req, GetPos):
            rows = await svc.positions()
            return Positions(tuple(RobotPosition(name, loc, empty) for name, loc, empty in rows))
        if isinstance(req, GetObsRobots):
            return NumObs(await svc.walls_between_robots(req.from_robot, req.to_robot), req)
        if isinstance(req, GetObsPoints):
            try:
                start, end = req.points()
            except ProtocolError as exc:
                self.log_once("getobs-vector", "GETOBS with a bad Start or End: %s", exc)
                return NumObs(-1, req)
            return NumObs(await svc.walls_between(start, end), req)
        if isinstance(req, GetObsIncomplete):
            self.log_once("getobs", "GETOBS needs {From r} {To r} or {Start x,y,z} {End x,y,z}")
            return NumObs(-1)
        self.log_once(f"unknown-{req.type}", "unknown command %s; ignored", req.type)
        return None


class ComInterfaceServer(WirelessServer):
    """The ComServerInterface (protocol.md 12.3): robot positions and walls between two points."""

    connection = InterfaceConnection

    def __init__(
        self,
        service: WirelessService,
        *,
        host: str = "127.0.0.1",
        port: int = INTERFACE_PORT,
        max_connections: int = MAX_CONNECTIONS,
    ):
        super().__init__(service, host, port, max_connections)
