"""Wires the simulation and every listener of one ``usarsim serve`` process."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable

from usarsim.server.config import ServeConfig
from usarsim.server.control import ControlServer
from usarsim.server.image import CameraBindings, ImageServer
from usarsim.server.truth import TruthServer
from usarsim.server.wireless import WirelessServers
from usarsim.sim.facade import SimFacade

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
        self.facade = SimFacade(world, seed=c.seed, speed=c.speed, lockstep=c.lockstep, settings=c.sim)
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
        self.image = None
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
        self.web = None
        if c.web_port is not None:
            from usarsim.web import WebConsole

            self.web = WebConsole(self, host=c.host, port=c.web_port, max_connections=c.max_web_connections)
        # the recording (--record) and the live Foxglove view (--foxglove); None: neither
        self.recorder = None
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
            for srv, name, _ in self._extras():
                listener = getattr(srv, "listener", srv)
                if name != "web" and hasattr(listener, "tap_name"):
                    listener.tap, listener.tap_name, listener.tap_binary = self.recorder, name, name == "image"

        # the score (--score prints it live, --score-file writes it at the end); None: not kept
        self.score = None
        if c.score or c.score_file is not None:
            from usarsim.scoring import ScoreKeeper
            from usarsim.sim.types import resolve_model

            self.score = ScoreKeeper(
                world,
                seed=c.seed,
                path=c.score_file,
                print_every_s=c.score_every_s if c.score else 0.0,
                on_line=on_score_line,
            )
            self.score.attach(
                self.facade, self.wireless.service.model if self.wireless is not None else resolve_model(world.wireless)
            )

    def _extras(self) -> list[tuple[object, str, str]]:
        """(server, listener name, what names its port in an error) of every listener
        beside the control port."""
        out = []
        if self.truth is not None:
            out.append((self.truth, "truth", "the ground-truth port %s (--truth-port)"))
        if self.image is not None:
            out.append((self.image, "image", "the image port %s (--image-port)"))
        if self.wireless is not None:
            out += self.wireless.servers()
        if self.web is not None:  # last: it connects to the others
            out.append((self.web, "web", "the web port %s (--web-port)"))
        return out

    async def start(self) -> None:
        """Open every listener, then start the simulation.  An OSError (a port taken) names
        the listener in its ``usarsim_listener`` attribute."""
        try:
            await self.control.start()
        except OSError as exc:
            exc.usarsim_listener = f"the control port {self.control.port} (--port)"
            raise
        started = [self.control]
        if self.wireless is not None:
            self.wireless.bind_loop()
        for extra, _, what in self._extras():
            try:
                await extra.start()
            except OSError as exc:
                exc.usarsim_listener = what % extra.port
                for srv in started:
                    await srv.stop()
                raise
            started.append(extra)
        if self.recorder is not None:
            try:
                self.recorder.start()
            except OSError:  # the file not writable, the Foxglove port taken: named in the error
                for srv in started:
                    await srv.stop()
                raise
        if self.score is not None:
            self.score.start()
        self.facade.start()

    def listeners(self) -> list[tuple[str, str, int]]:
        out = [("control", self.host, self.control.port)] + [
            (name, self.host, srv.port) for srv, name, _ in self._extras()
        ]
        if self.recorder is not None and self.recorder.server is not None:
            out.append(("foxglove", self.host, self.recorder.foxglove_port))
        return out

    async def stop(self) -> None:
        for srv, _, _ in reversed(self._extras()):
            await srv.stop()
        await self.control.stop()
        for _ in range(3):  # the closed connections' connection_lost (scheduled by close()) run
            await asyncio.sleep(0)
        self.facade.stop()
        if self.recorder is not None:
            self.recorder.stop()  # after the simulation: its last outputs are written
        if self.score is not None:
            self.score.stop()
