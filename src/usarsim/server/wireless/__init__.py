"""The wireless simulation (manual section 3.2.4; protocol.md 12): three servers that carry
the robots' team communication only while the radio link between them would hold.

* :mod:`.comserver`: the ComServer (WCS, TCP 5874, ``--wcs-port``; protocol.md 12.1),
  USARSim's in-simulator server, which relays ``SEND``/``CLOSE`` links it opened;
* :mod:`.wss`: the Wireless Simulation Server (TCP 50000, ``--wss-port``; protocol.md
  12.2), the RoboCup one, with a relay port per ordered robot pair;
* :mod:`.interface`: the ComServerInterface (TCP 7435, ``--cominterface-port``;
  protocol.md 12.3), what the WSS's propagation models asked the simulator;
* :mod:`.service`: what they share, the radio links (through the facade) and the
  connection bases.

This package is asyncio glue: every line and reply of the three protocols is parsed and
formatted in :mod:`usarsim.protocol.wireless`, and the simulation is reached only through
the facade's radio methods.  Bad input never takes a server down: a malformed command gets
the documented error reply, or is ignored where the protocol has none; each kind is
logged once per connection.
"""

from __future__ import annotations

import asyncio
import logging

from usarsim.protocol.wireless import INTERFACE_PORT, WCS_PORT, WSS_PORT, SendParser
from usarsim.server.listener import Service
from usarsim.sim.api import Facade
from usarsim.sim.types import describe_channel, resolve_channel, resolve_model

from .comserver import MAX_LINKS, MAX_LISTENING, MAX_REGISTERED, ComServer
from .interface import ComInterfaceServer
from .service import MAX_CONNECTIONS, WirelessOptions, WirelessService
from .wss import MAX_RELAY_PORTS, WssServer

__all__ = [
    "INTERFACE_PORT",
    "MAX_CONNECTIONS",
    "MAX_LINKS",
    "MAX_LISTENING",
    "MAX_REGISTERED",
    "MAX_RELAY_PORTS",
    "WCS_PORT",
    "WSS_PORT",
    "ComInterfaceServer",
    "ComServer",
    "SendParser",
    "WirelessOptions",
    "WirelessServers",
    "WirelessService",
    "WssServer",
]

log = logging.getLogger("usarsim.wireless")


class WirelessServers:
    """The three servers and what they share, as one ``usarsim serve`` runs them.  Made
    before the simulation starts: the radio model is handed to the facade here."""

    def __init__(self, facade: Facade, options: WirelessOptions, *, host: str = "127.0.0.1"):
        model = resolve_model(facade.world.wireless, options.config, model=options.model)
        channel = resolve_channel(facade.world.wireless, options.config)
        self.service = WirelessService(facade, model, channel=channel, debug=options.debug)
        limit = options.max_connections
        self.comserver = ComServer(self.service, host=host, port=options.wcs_port, max_connections=limit)
        self.wss = WssServer(self.service, host=host, port=options.wss_port, max_connections=limit)
        self.interface = ComInterfaceServer(self.service, host=host, port=options.interface_port, max_connections=limit)
        log.info("wireless: radio model %s", model.describe())
        if not channel.ideal:
            log.info("wireless: channel %s", describe_channel(channel))

    def servers(self) -> list[Service]:
        """The three listeners, as the server starts and names them."""
        return [
            Service("comserver", self.comserver, "the ComServer port", "--wcs-port"),
            Service("wss", self.wss, "the WSS port", "--wss-port"),
            Service("cominterface", self.interface, "the ComServerInterface port", "--cominterface-port"),
        ]

    def bind_loop(self) -> None:
        """The event loop the link changes are handed to (call from it, before the start)."""
        self.service.loop = asyncio.get_running_loop()
