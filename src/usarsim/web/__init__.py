"""The operator console in the browser (``usarsim serve``, http://127.0.0.1:8080 by default):
a spectator view of the world, robot operation with video and range sensors, and a
command console, all through the simulator's own protocol and image server."""

from usarsim.web.console import WebConsole

__all__ = ["WebConsole"]
