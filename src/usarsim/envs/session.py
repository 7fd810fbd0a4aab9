"""The simulator an environment runs in: a lock-step ``usarsim serve`` launched for each
episode (the same seed and the same lines give the same episode), or one already running
at a given address, on which each episode spawns its robots again."""

from __future__ import annotations

import copy
import logging
import threading
import time
from collections.abc import Sequence

import numpy as np

from usarsim.client import ClientError, ClientTimeout, Robot, Server, World, connect, launch
from usarsim.config.robot import RobotConfig

from .spec import RobotSpec, describe_robot

log = logging.getLogger("usarsim.envs")

MAX_SPARES = 1
"""Simulators launched ahead of the resets that may need them."""
PRELAUNCH_AFTER_STEPS = 20
"""Steps into an episode after which its environment launches the next one's simulator
(resets in quick succession launch none ahead: they would only compete for the processors)."""
REMOVAL_TIMEOUT_S = 10.0  # a shared simulator: how long the robots of the last episode may take to leave
SEED_RANGE = 2**31 - 1  # simulator seeds are drawn from [0, SEED_RANGE)


def next_seed(rng: np.random.Generator) -> int:
    """The simulator seed the next reset without a seed will draw from ``rng`` (not drawn)."""
    return int(copy.deepcopy(rng).integers(0, SEED_RANGE))


Pose = str | tuple[tuple[float, float, float], tuple[float, float, float]]
"""Where a robot starts: a start pose's name, or (location, rotation) in the USARSim frame."""

PROBE_NAME = "EnvProbe"  # the robot spawned to read a robot class's GETGEO and GETCONF
_DESCRIBED: dict[tuple, RobotSpec] = {}  # robot file, robot folders, shared simulator -> spec


def spawn_at(world: World, class_name: str, name: str, start: Pose) -> Robot:
    """Spawn a robot at a start pose (by name) or at (location, rotation)."""
    if isinstance(start, str):
        return world.spawn(class_name, name, start=start)
    location, rotation = start
    return world.spawn(class_name, name, location=tuple(location), rotation=tuple(rotation))


def flush(robots: Sequence[Robot]) -> None:
    """Wait until every command sent on the robots' connections has reached the simulation
    (a PING on each, answered after the lines before it): a DRIVE sent before a STEP on the
    world's connection then takes effect at that STEP, every run alike."""
    pending = []
    for robot in robots:
        conn = robot._conn
        if conn.synchronous:  # carried out already (an in-process simulator)
            continue
        pid = conn.state.next_ping()
        conn.send(f"PING {{Id {pid}}}\r\n")
        pending.append((conn, pid))
    for conn, pid in pending:

        def is_pong(m: object, pid: str = pid) -> bool:
            return getattr(m, "id", None) == pid

        conn.wait_for(is_pong, "PONG (the reply to PING)", None)


TRANSPORTS = ("tcp", "inproc")


def check_variants(variants: Sequence[int] | None) -> tuple[int, ...]:
    """The environments' ``variants`` (a range or list of whole numbers >= 0) as a tuple."""
    if variants is None:
        return ()
    out = tuple(variants)
    if not out:
        raise ValueError("variants: give at least one variant (a range such as range(0, 800), or a list)")
    bad = [v for v in out if isinstance(v, bool) or not isinstance(v, int) or v < 0]
    if bad:
        raise ValueError(f"variants are whole numbers >= 0, got {bad[0]!r}")
    return out


class Simulator:
    """Where an environment's episodes run.  With ``port`` None each :meth:`start` launches
    a fresh lock-step simulator of ``world`` with the episode's seed (and its wireless
    servers when ``wireless``), and stops the previous one; otherwise every episode runs in
    the lock-step simulator at ``host``:``port``, whose seed is its own.  ``transport="inproc"``
    runs each episode's simulator in this process instead (:mod:`usarsim.client.direct`): the
    same episodes, bit for bit, without sockets or text."""

    def __init__(
        self,
        *,
        world: str,
        host: str = "127.0.0.1",
        port: int | None = None,
        truth_port: int | None = None,
        comserver_port: int | None = None,
        wireless: bool = False,
        wireless_model: str | None = None,
        wireless_config: str | None = None,
        robot_dirs: tuple[str, ...] = (),
        timeout: float = 10.0,
        transport: str = "tcp",
        variants: Sequence[int] | None = None,
    ):
        if transport not in TRANSPORTS:
            raise ValueError(f"transport must be one of {', '.join(TRANSPORTS)}, got {transport!r}")
        if transport == "inproc" and port is not None:
            raise ValueError("transport='inproc' runs its own simulator in this process: give no port")
        if transport == "inproc" and wireless:
            raise ValueError(
                "the radio (message_size > 0) needs transport='tcp': an in-process simulator has no ComServer"
            )
        self.transport = transport
        self.world_name = world
        self.variants = check_variants(variants)
        self.variant: int | None = None  # the current episode's
        if self.variants and port is not None:
            raise ValueError("variants need a simulator launched for each episode: give no port")
        self.host, self.port, self.truth_port = host, port, truth_port
        self._comserver_port = comserver_port
        self.wireless = wireless
        self.extra_args: list[str] = []
        if wireless_model:
            self.extra_args += ["--wireless-model", wireless_model]
        if wireless_config:
            self.extra_args += ["--wireless-config", str(wireless_config)]
        self.robot_dirs = tuple(str(d) for d in robot_dirs)
        self.timeout = timeout
        self.server: Server | None = None
        self.world: World | None = None
        self._spares: dict[int, _Launch] = {}
        self._closing: list[threading.Thread] = []

    @property
    def launches(self) -> bool:
        return self.port is None

    @property
    def address(self) -> str:
        """The simulator's host."""
        return self.server.host if self.server is not None else self.host

    @property
    def comserver_port(self) -> int:
        if self.server is not None:
            return self.server.ports["comserver"]
        return self._comserver_port if self._comserver_port is not None else 5874

    def describe(self, cfg: RobotConfig, start: Pose) -> RobotSpec:
        """The spec of a robot class: a robot of it spawned at ``start`` in a simulator
        launched for the purpose (or the shared one) answers GETGEO and GETCONF, then leaves.
        Kept for the rest of the process."""
        key = (cfg.path, self.robot_dirs, None if self.launches else (self.host, self.port))
        if key in _DESCRIBED:
            return _DESCRIBED[key]
        if self.launches:
            server = launch(
                self.world_name,
                seed=0,
                lockstep=True,
                robot_dirs=self.robot_dirs,
                timeout=self.timeout,
                transport=self.transport,
            )
            try:
                with server.connect() as world:
                    spec = describe_robot(cfg, spawn_at(world, cfg.class_name, PROBE_NAME, start))
            finally:
                self._background(server.close)
        else:
            assert self.port is not None  # a shared simulator: self.launches is False
            if self.world is None:
                self.world = connect(
                    self.host, self.port, lockstep=True, truth_port=self.truth_port, timeout=self.timeout
                )
            spec = describe_robot(cfg, spawn_at(self.world, cfg.class_name, PROBE_NAME, start))
            self._remove_robots()
        _DESCRIBED[key] = spec
        return spec

    def start(self, seed: int) -> World:
        """The world of a new episode, without robots: a simulator launched with ``seed``
        (one launched ahead by :meth:`prelaunch` if it has that seed), or the shared one."""
        if self.launches:
            self.variant = self.variant_for(seed)
            spare = self._spares.pop(seed, None)
            self._discard_spares()  # launched for a reset that did not come
            server = spare.result() if spare is not None else self._launch(seed)
            self._retire()  # after the launch: the last episode's simulator stands still until then
            self.server = server
            self.world = self.server.connect()
            return self.world
        assert self.port is not None  # a shared simulator: self.launches is False
        if self.world is None:
            self.world = connect(self.host, self.port, lockstep=True, truth_port=self.truth_port, timeout=self.timeout)
            return self.world
        self._remove_robots()  # the next episode's may spawn where they were
        return self.world

    def _remove_robots(self) -> None:
        """Close the robots' connections and wait until they have left the world."""
        assert self.world is not None
        names = list(self.world.robots)
        for robot in self.world.robots.values():
            robot.close()
        deadline = time.monotonic() + REMOVAL_TIMEOUT_S
        while names:
            left = {o.name for o in self.world.truth()}
            names = [n for n in names if n in left]
            if names and time.monotonic() > deadline:
                raise ClientTimeout(
                    f"robots {', '.join(names)} did not leave the simulator within {REMOVAL_TIMEOUT_S:g} s"
                )

    def prelaunch(self, seeds) -> None:
        """Launch simulators for the seeds the next episodes may ask for, in the background,
        so that a reset need not wait for one to start (at most :data:`MAX_SPARES`; those
        launched before for other seeds are stopped)."""
        if not self.launches or self.transport == "inproc":  # built at the reset, on this thread
            return
        wanted = list(dict.fromkeys(int(s) for s in seeds))[:MAX_SPARES]
        for seed in [s for s in self._spares if s not in wanted]:
            self._background(self._spares.pop(seed).discard)
        for seed in wanted:
            if seed not in self._spares:
                self._spares[seed] = _Launch(seed, self._launch)

    def _discard_spares(self) -> None:
        for spare in self._spares.values():
            self._background(spare.discard)
        self._spares.clear()

    def variant_for(self, seed: int) -> int | None:
        """The world's variant an episode of ``seed`` plays: ``variants[seed % len(variants)]``
        (None without variants: the world as written)."""
        return self.variants[seed % len(self.variants)] if self.variants else None

    def _launch(self, seed: int) -> Server:
        variant = self.variant_for(seed)
        if self.transport == "inproc":
            return launch(  # type: ignore[no-any-return]  # an InprocServer, with Server's connect and close
                self.world_name,
                seed=seed,
                variant=variant,
                robot_dirs=self.robot_dirs,
                timeout=self.timeout,
                transport="inproc",
            )
        return launch(
            self.world_name,
            seed=seed,
            variant=variant,
            lockstep=True,
            wireless=self.wireless,
            robot_dirs=self.robot_dirs,
            extra_args=tuple(self.extra_args),
            timeout=self.timeout,
        )

    def _retire(self) -> None:
        """The current episode's connections closed (in a shared simulator, once its robots
        have left) and its simulator stopped in the background."""
        if self.server is not None and self.transport == "inproc":
            # stopped first, on this thread (it is quick): its robots then leave with the world
            # instead of being removed one by one, each a rebuild of a model nobody will step
            self.server.close()
        if self.world is not None:
            if not self.launches:
                try:
                    self._remove_robots()
                except ClientError as exc:  # the simulator is gone or does not answer: nothing to wait for
                    log.warning("the robots may not have left the simulator at %s:%s: %s", self.host, self.port, exc)
            self.world.close()
            self.world = None
        if self.server is not None:
            if self.transport != "inproc":
                self._background(self.server.close)
            self.server = None

    def _background(self, fn) -> None:
        self._closing = [t for t in self._closing if t.is_alive()]
        t = threading.Thread(target=fn, name="usarsim-env-stop", daemon=True)
        t.start()
        self._closing.append(t)

    def step(self, seconds: float, sent: Sequence[Robot] = ()) -> float:
        """Advance the simulated time once the commands of the robots that ``sent`` some
        have arrived; returns the new simulated time (every robot has read its messages up
        to it)."""
        assert self.world is not None
        flush(sent)
        return self.world.step(seconds)

    def stop(self) -> None:
        """Close the world's connections (its robots leave) and stop every simulator launched
        (waiting until they have exited)."""
        self._retire()
        self._discard_spares()
        for t in self._closing:
            t.join()
        self._closing = []


class _Launch:
    """A simulator being launched in the background."""

    def __init__(self, seed: int, start):
        self.seed = seed
        self.server: Server | None = None
        self.error: BaseException | None = None
        self._start = start
        self.thread = threading.Thread(target=self._run, name=f"usarsim-env-launch-{seed}", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            self.server = self._start(self.seed)
        except BaseException as exc:  # handed to the reset that takes this simulator
            self.error = exc

    def result(self) -> Server:
        self.thread.join()
        if self.error is not None:
            raise self.error
        assert self.server is not None
        return self.server

    def discard(self) -> None:
        self.thread.join()
        if self.server is not None:
            self.server.close()
