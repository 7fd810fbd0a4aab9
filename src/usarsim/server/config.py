"""Everything one ``usarsim serve`` process is set up with, in one frozen, validated value.

The CLI builds it from its options (``usarsim serve``, ``usarsim replay``), the benchmarks and the
tests build it directly, and :class:`usarsim.server.app.Application` (the composition root) builds
the simulation and every listener from it and from nothing else: no setting travels through the
environment or through attributes patched after the fact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from usarsim.config.world import WorldConfig
from usarsim.server.image import ImageSettings
from usarsim.server.ordering import STEP_GRACE_S
from usarsim.server.wireless import WirelessOptions
from usarsim.sim.settings import SimSettings

# The smallest limits a server runs with (usarsim serve raises a smaller option to these).
MIN_LINE_BYTES = 64
MIN_PENDING_BYTES = 4 * 1024
MIN_WEB_CONNECTIONS = 2  # the page's own control connection and its picture


def _port(name: str, value: int | None) -> None:
    if value is not None and not (isinstance(value, int) and 0 <= value <= 65535):
        raise ValueError(
            f"{name} must be a port number 0..65535 (0: any free port) or None (not served), got {value!r}"
        )


@dataclass(frozen=True, kw_only=True)
class ServeConfig:
    """One server's settings.  A listener whose port is None is not served; port 0 takes any
    free port (the listener reports which)."""

    world: WorldConfig
    host: str = "127.0.0.1"
    port: int = 3000  # the control port (protocol.md 3)
    seed: int = 0
    speed: float | None = 1.0  # times real time; None: as fast as it goes
    lockstep: bool = False
    sim: SimSettings = field(default_factory=SimSettings)
    # the control port's limits
    max_connections: int = 64
    max_robots: int | None = None  # None: as many as connections
    robot_dirs: tuple[str, ...] = ()
    max_line_bytes: int = 8192
    max_pending_bytes: int = 256 * 1024
    step_grace_s: float = STEP_GRACE_S
    # the other listeners
    truth_port: int | None = 3989
    image_port: int | None = 5003
    image: ImageSettings = field(default_factory=ImageSettings)
    wireless: WirelessOptions | None = None  # None: no ComServer, WSS or ComServerInterface
    web_port: int | None = 8080
    max_viewers: int = 16
    max_web_connections: int = 64
    # observers of the run
    record: str | None = None  # an MCAP file
    foxglove_port: int | None = None
    run_options: dict[str, Any] = field(default_factory=dict)  # what a replay needs (the recording's metadata)
    record_cameras_fps: float = 0.0
    record_camera_size: tuple[int, int] = (320, 240)
    score: bool = False
    score_file: str | None = None
    team_map: str | None = None  # the team's map_server map, scored into the score file at the end
    score_every_s: float = 10.0

    def __post_init__(self) -> None:
        for name in ("port", "truth_port", "image_port", "web_port", "foxglove_port"):
            _port(name, getattr(self, name))
        if self.port is None:
            raise ValueError("a server has a control port")
        if self.speed is not None and not (math.isfinite(self.speed) and self.speed > 0):
            raise ValueError(f"speed must be a positive number of times real time (None: max), got {self.speed!r}")
        if self.max_connections < 1:
            raise ValueError(f"max_connections must be at least 1, got {self.max_connections}")
        if self.max_robots is not None and self.max_robots < 0:
            raise ValueError(f"max_robots must be 0 or more (None: as many as connections), got {self.max_robots}")
        if self.max_line_bytes < MIN_LINE_BYTES:
            raise ValueError(f"max_line_bytes must be at least {MIN_LINE_BYTES}, got {self.max_line_bytes}")
        if self.max_pending_bytes < MIN_PENDING_BYTES:
            raise ValueError(f"max_pending_bytes must be at least {MIN_PENDING_BYTES}, got {self.max_pending_bytes}")
        if self.max_viewers < 1:
            raise ValueError(f"max_viewers must be at least 1, got {self.max_viewers}")
        if self.max_web_connections < MIN_WEB_CONNECTIONS:
            raise ValueError(
                f"max_web_connections must be at least {MIN_WEB_CONNECTIONS}, got {self.max_web_connections}"
            )
        if not (self.step_grace_s >= 0 and math.isfinite(self.step_grace_s)):
            raise ValueError(f"step_grace_s must be 0 or more seconds, got {self.step_grace_s}")
        if not (self.record_cameras_fps >= 0 and math.isfinite(self.record_cameras_fps)):
            raise ValueError(f"record_cameras_fps must be 0 (none) or more, got {self.record_cameras_fps}")
        if min(self.record_camera_size) < 1:
            raise ValueError(f"record_camera_size must be positive, got {self.record_camera_size}")
        if not self.score_every_s > 0:
            raise ValueError(f"score_every_s must be positive, got {self.score_every_s}")
        object.__setattr__(self, "robot_dirs", tuple(self.robot_dirs))

    @property
    def robot_limit(self) -> int:
        """The most robots at once (``max_robots``, else one per connection)."""
        return self.max_connections if self.max_robots is None else self.max_robots
