"""Wires the simulation and every listener of one ``usarsim serve`` process."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from usarsim.plugins import BUILTIN
from usarsim.server.config import ServeConfig
from usarsim.server.control import ControlServer
from usarsim.server.image import CameraBindings, ImageServer
from usarsim.server.listener import Service
from usarsim.server.truth import TruthServer
from usarsim.server.wireless import WirelessServers
from usarsim.sim.facade import SimFacade

if TYPE_CHECKING:
    from usarsim.scoring import ScoreKeeper
    from usarsim.server.recording import Recorder
    from usarsim.web import WebConsole

log = logging.getLogger("usarsim")


class Application:
    """The composition root of one ``usarsim serve``: the simulation and every listener, built
    from one :class:`~usarsim.server.config.ServeConfig` (``on_score_line``: where the live
    score's lines go, with ``score``)."""

    def __init__(self, config: ServeConfig, *, on_score_line: Callable[[str], None] | None = None):
        self.config = c = config
        world = c.world
        self.world = world
        self.host = c.host
        self.facade = SimFacade(world, seed=c.seed, speed=c.speed, lockstep=c.lockstep, settings=c.sim, plugins=BUILTIN)
        self.camera_bindings = CameraBindings()
        self.control = ControlServer(
            self.facade,
            host=c.host,
            port=c.port,
            max_connections=c.max_connections,
            robot_dirs=c.robot_dirs,
            max_line_bytes=c.max_line_bytes,
            max_pending_bytes=c.max_pending_bytes,
            max_robots=c.robot_limit,
            step_grace_s=c.step_grace_s,
            camera_bindings=self.camera_bindings,
        )
        # the ground-truth service (protocol.md 12.4); None: not served
        self.truth = (
            TruthServer(self.facade, host=c.host, port=c.truth_port, max_connections=c.max_viewers)
            if c.truth_port is not None
            else None
        )
        # the image server (protocol.md 10) and its render thread; None: not served
        self.image_settings = c.image
        self.image: ImageServer | None = None
        if c.image_port is not None:
            renderer = self.facade.render_service(self.image_settings.max_fps)
            self.image = ImageServer(
                renderer,
                self.camera_bindings,
                self.image_settings,
                host=c.host,
                port=c.image_port,
                max_connections=c.max_viewers,
            )
        self.facade.set_multiview_cameras(self.image_settings.camera_num)  # before its thread starts
        # the wireless simulation (protocol.md 12): ComServer, WSS, ComServerInterface; None: not served
        self.wireless = WirelessServers(self.facade, c.wireless, host=c.host) if c.wireless is not None else None
        # the operator console in the browser (usarsim.web), a client of the listeners above;
        # None: not served
        self.web: WebConsole | None = None
        if c.web_port is not None:
            from usarsim.web import WebConsole

            self.web = WebConsole(self, host=c.host, port=c.web_port, max_connections=c.max_web_connections)
        self.services = self._services()  # every listener, started and stopped alike
        # the recording (--record) and the live Foxglove view (--foxglove); None: neither
        self.recorder: Recorder | None = None
        if c.record is not None or c.foxglove_port is not None:
            from usarsim import __version__
            from usarsim.server.recording import Recorder, run_info

            info = run_info(
                version=__version__,
                world=world.name,
                world_path=world.path,
                seed=c.seed,
                lockstep=c.lockstep,
                speed=c.speed,
                options=dict(c.run_options),
            )
            self.recorder = Recorder(
                world,
                info,
                path=c.record,
                foxglove_port=c.foxglove_port,
                host=c.host,
                camera_fps=c.record_cameras_fps,
                camera_size=c.record_camera_size,
            )
            self.recorder.attach(self.facade, self.wireless.service.model if self.wireless is not None else None)
            self.control.tap = self.recorder
            self.control.tap_name = "control"
            for service in self.services[1:]:
                listener: Any = getattr(service.server, "listener", service.server)
                if service.name != "web" and hasattr(listener, "tap_name"):
                    listener.tap, listener.tap_name = self.recorder, service.name
                    listener.tap_binary = service.name == "image"

        # the score (--score prints it live, --score-file writes it at the end); None: not kept
        self.score: ScoreKeeper | None = None
        if c.score or c.score_file is not None:
            from usarsim.scoring import ScoreKeeper
            from usarsim.sim.types import resolve_model

            self.score = ScoreKeeper(
                world,
                seed=c.seed,
                path=c.score_file,
                team_map=c.team_map,
                print_every_s=c.score_every_s if c.score else 0.0,
                on_line=on_score_line,
            )
            self.score.attach(
                self.facade, self.wireless.service.model if self.wireless is not None else resolve_model(world.wireless)
            )

    def _services(self) -> list[Service]:
        """Every listener, in the order they start: the control port first, the console last
        (it connects to the others)."""
        out = [Service("control", self.control, "the control port", "--port")]
        if self.truth is not None:
            out.append(Service("truth", self.truth, "the ground-truth port", "--truth-port"))
        if self.image is not None:
            out.append(Service("image", self.image, "the image port", "--image-port"))
        if self.wireless is not None:
            out += self.wireless.servers()
        if self.web is not None:
            out.append(Service("web", self.web, "the web port", "--web-port"))
        return out

    async def start(self) -> None:
        """Open every listener, then start the simulation.  An OSError (a port taken) names
        the listener in its ``usarsim_listener`` attribute; the listeners opened before it are
        closed again."""
        if self.wireless is not None:
            self.wireless.bind_loop()
        started: list[Service] = []
        try:
            for service in self.services:
                try:
                    await service.server.start()
                except OSError as exc:
                    exc.usarsim_listener = service.describe()  # type: ignore[attr-defined]  # read by the CLI
                    raise
                started.append(service)
            if self.recorder is not None:
                self.recorder.start()  # the file not writable, the Foxglove port taken: named in the error
        except OSError:
            for service in reversed(started):
                await service.server.stop()
            raise
        if self.score is not None:
            self.score.start()
        self.facade.start()

    def listeners(self) -> list[tuple[str, str, int]]:
        """(name, host, port) of every listener, once started."""
        out = [(s.name, self.host, s.server.port) for s in self.services]
        if self.recorder is not None and self.recorder.server is not None:
            port = self.recorder.foxglove_port
            assert port is not None  # the live server's, once started
            out.append(("foxglove", self.host, port))
        return out

    async def stop(self) -> None:
        for service in reversed(self.services):
            await service.server.stop()
        for _ in range(3):  # the closed connections' connection_lost (scheduled by close()) run
            await asyncio.sleep(0)
        self.facade.stop()
        if self.recorder is not None:
            self.recorder.stop()  # after the simulation: its last outputs are written
        if self.score is not None:
            self.score.stop()
