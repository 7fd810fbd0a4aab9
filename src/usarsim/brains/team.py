"""A team of frontier explorers that share their maps over the simulated radio.

Each robot runs its own :class:`~usarsim.brains.frontier.FrontierExplorer` and, every
``share_s`` seconds, sends its team-mates through the ComServer (:mod:`usarsim.client.radio`)
its own map (log-odds quantised to bytes and compressed: a few kB), its position and its
goal; every ``position_s`` seconds in between, its position and goal alone (a robot leaves
the beams that end on a team-mate out of its map and its scan matching).  A robot plans on
its own map where it has seen for itself and on the sum of the latest maps its team-mates
sent elsewhere, and keeps its goals away from theirs, so that the team spreads out.  Only what gets through
the radio is shared: a link the ComServer closes (too far, too many walls) is opened again
every ``relink_s`` seconds, and a robot out of touch explores on what it has.  The maps are
in world coordinates: each robot knows the start pose it was set down at.

    python -m usarsim.brains.team --robots 4                    # starts its own lock-step simulator
    python -m usarsim.brains.team --robots 4 --compare          # ... and one robot alone, for comparison
    python -m usarsim.brains.team --port 3000 --wcs-port 5874 --robots 3   # a running simulator

Started without ``--port`` it launches a lock-step simulator of ``--world`` with its
wireless services, and scores the run: the share of the arena's reachable floor the team's
lasers swept (:class:`usarsim.brains.coverage.Referee`, from the robots' ground truth).
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import struct
import sys
import tempfile
import time
import zlib
from typing import Any

from usarsim.brains.coverage import NEAR_M
from usarsim.brains.frontier import FrontierExplorer
from usarsim.brains.grid import Bounds
from usarsim.brains.runner import numbers_first, run
from usarsim.client import ClientError, connect, launch
from usarsim.client.radio import Radio, RadioError, link

log = logging.getLogger("usarsim.brains.team")

MAGIC = b"UMAP1"
_HEAD = struct.Struct("<5sB d 4f")  # magic, name length, time, position x y, goal x y
YELLOW_ARENA = Bounds(-6.0, -7.2, 6.0, 7.2)  # DM-USAR_yellow inside its outer walls


def encode(
    name: str, t: float, position: tuple[float, float] | None, goal: tuple[float, float] | None, map_bytes: bytes
) -> bytes:
    """One message: who, when, where it is, where it goes (NaN: nowhere), its map (empty:
    a message with the position and goal only)."""
    nm = name.encode("utf-8")[:255]
    px, py = position if position is not None else (math.nan, math.nan)
    gx, gy = goal if goal is not None else (math.nan, math.nan)
    return _HEAD.pack(MAGIC, len(nm), t, px, py, gx, gy) + nm + map_bytes


def decode(payload: bytes) -> tuple[str, float, tuple[float, float] | None, tuple[float, float] | None, bytes]:
    """The parts of a message made by :func:`encode`; ValueError for anything else."""
    if len(payload) < _HEAD.size or not payload.startswith(MAGIC):
        raise ValueError("not a map message")
    magic, n, t, px, py, gx, gy = _HEAD.unpack_from(payload)
    name = payload[_HEAD.size : _HEAD.size + n].decode("utf-8", "replace")
    pos = None if math.isnan(px) else (px, py)
    goal = None if math.isnan(gx) else (gx, gy)
    return name, t, pos, goal, payload[_HEAD.size + n :]


class Team:
    """Steps ``explorers`` together, sharing their maps through ``radios`` (one per
    explorer, in the same order; None: no sharing).  Has ``step``, ``stop`` and ``done``
    like a brain, so :func:`usarsim.brains.runner.run` runs it."""

    def __init__(
        self,
        explorers: list[FrontierExplorer],
        radios: list[Radio] | None = None,
        *,
        share_s: float = 2.0,
        relink_s: float = 5.0,
        position_s: float = 0.4,
    ):
        if radios is not None and len(radios) != len(explorers):
            raise ValueError(f"{len(explorers)} explorers need {len(explorers)} radios, got {len(radios)}")
        self.explorers, self.radios = explorers, radios
        self.share_s, self.relink_s, self.position_s = share_s, relink_s, position_s
        self.time = 0.0
        self.messages = 0  # map messages received
        self._shared = -math.inf
        self._told = -math.inf
        self._linked = -math.inf

    @property
    def done(self) -> bool:
        return all(e.done for e in self.explorers)

    def relink(self) -> None:
        """Open the links that are not open (each pair once)."""
        self._linked = self.time
        radios = self.radios or []
        for i, a in enumerate(radios):
            for b in radios[i + 1 :]:
                if b.name not in a.links or a.name not in b.links:
                    a.forget(b.name)  # one end closed: close the other too
                    b.forget(a.name)
                    try:
                        link(a, b)
                    except RadioError as exc:
                        log.info("link %s - %s: %s", a.name, b.name, exc)

    def share(self, maps: bool) -> None:
        """Send each team-mate this robot's position and goal, and its map if ``maps``."""
        self._told = self.time
        if maps:
            self._shared = self.time
        for e, r in zip(self.explorers, self.radios or []):
            pose = e.pose()
            r.broadcast(encode(r.name, e.time, pose[:2] if pose else None, e.goal, e.own.to_bytes() if maps else b""))

    def deliver(self) -> None:
        for e, r in zip(self.explorers, self.radios or []):
            for _, payload in r.poll():
                try:
                    name, _, pos, goal, data = decode(payload)
                    e.receive(name, e.own.from_bytes(data) if data else None, pos, goal)
                except (ValueError, zlib.error) as exc:
                    log.info("%s: a message it cannot read (%s)", r.name, exc)
                    continue
                self.messages += 1

    def step(self, dt: float) -> None:
        self.time += dt
        if self.radios:
            if self.time - self._linked >= self.relink_s:
                self.relink()
            self.deliver()
            if self.time - self._shared >= self.share_s:
                self.share(maps=True)
            elif self.time - self._told >= self.position_s:
                self.share(maps=False)
        for e in self.explorers:
            e.step(dt)

    def stop(self) -> None:
        for e in self.explorers:
            e.stop()


# ------------------------------------------------------------------------------ the demo


def explore(
    world: Any,
    n: int,
    seconds: float,
    *,
    bounds: Bounds,
    comserver: tuple[str, int] | None,
    referee: Any = None,
    period: float = 0.2,
    starts: list[str] | None = None,
    robot_class: str = "P2AT",
) -> dict[str, Any]:
    """Spawn ``n`` explorers at the world's first start poses (or ``starts``), link them
    through the ComServer at ``comserver`` (None: no sharing) and explore for ``seconds``.
    Returns the figures of the run."""
    poses = world.start_poses
    chosen = [next(p for p in poses if p.name == s) for s in starts] if starts else poses[:n]
    if len(chosen) < n:
        raise ClientError(f"the world has {len(poses)} start poses, fewer than {n} robots")
    robots, explorers, radios = [], [], []
    try:
        for k, pose in enumerate(chosen[:n]):
            robot = world.spawn(robot_class, f"R{k + 1}", start=pose.name)
            robots.append(robot)
            explorers.append(
                FrontierExplorer(robot, bounds=bounds, origin=(pose.location[0], pose.location[1], pose.rotation[2]))
            )
            if comserver is not None:
                radios.append(Radio(comserver[0], comserver[1], robot.name))
        team = Team(explorers, radios if comserver is not None else None)
        if world.lockstep:
            world.step(period)
        shares: dict[int, tuple[float, float]] = {}

        def score(t: float) -> None:
            if referee is not None:
                referee.observe(robots)
                mark = int(round(t - t0))
                if mark % 30 == 0 and mark not in shares:
                    shares[mark] = (referee.arena_share(), referee.arena_share(near=True))

        t0 = world.time
        wall = time.monotonic()
        ran = run(world, [team], seconds, period=period, on_step=score)
        out: dict[str, Any] = {
            "robots": n,
            "simulated_s": ran,
            "wall_s": time.monotonic() - wall,
            "messages": team.messages,
            "done": team.done,
        }
        if referee is not None:
            out["arena_share"] = referee.arena_share()
            out["arena_near_share"] = referee.arena_share(near=True)
            out["reachable_share"] = referee.reachable_share()
            out["arena_share_every_30s"] = shares
        return out
    finally:
        for r in radios:
            r.close()
        for robot in robots:
            robot.close()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description="Frontier explorers sharing their maps over the simulated radio.")
    p.add_argument("--robots", type=int, default=4, help="how many robots (default 4)")
    p.add_argument("--seconds", type=float, default=300.0, help="simulated seconds (default 300)")
    p.add_argument("--world", default="DM-USAR_yellow", help="world to launch (default DM-USAR_yellow)")
    p.add_argument("--seed", type=int, default=1, help="the launched simulator's seed (default 1)")
    p.add_argument(
        "--bounds",
        default=None,
        help="the area to explore, xmin,ymin,xmax,ymax (default: DM-USAR_yellow's arena, "
        "-6,-7.2,6,7.2; with another world: the bounding box of its solids)",
    )
    p.add_argument("--host", default="127.0.0.1", help="a running simulator's address")
    p.add_argument("--port", type=int, default=None, help="a running simulator's control port (default: launch one)")
    p.add_argument("--wcs-port", type=int, default=5874, help="its ComServer port (default 5874)")
    p.add_argument("--lockstep", action="store_true", help="the running simulator is in lock-step: step it")
    p.add_argument("--no-radio", action="store_true", help="explore without sharing maps")
    p.add_argument(
        "--wireless-config",
        metavar="FILE",
        help="the launched simulator's radio (usarsim serve --wireless-config): a YAML file with a "
        "world's wireless keys, for example examples/subt_radio.yaml (capacity, fading and loss "
        "like DARPA SubT's); the figures then give the team's messages delivered and lost",
    )
    p.add_argument(
        "--compare",
        action="store_true",
        help="also run one robot alone on a fresh simulator, same seed and time (launched only)",
    )
    p.add_argument("-v", "--verbose", action="store_true")
    args = p.parse_args(numbers_first(argv))
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="%(asctime)s %(name)s: %(message)s"
    )
    if args.robots < 1:
        p.error("--robots must be at least 1")
    try:
        if args.port is not None:
            bounds = Bounds.parse(args.bounds) if args.bounds else YELLOW_ARENA
            with connect(args.host, args.port, lockstep=args.lockstep) as world:
                fig = explore(
                    world,
                    args.robots,
                    args.seconds,
                    bounds=bounds,
                    comserver=None if args.no_radio else (args.host, args.wcs_port),
                )
            print_figures(fig)
            return 0
        from usarsim.brains.coverage import Referee
        from usarsim.config.catalog import resolve_world

        config = resolve_world(args.world)
        if args.bounds:
            bounds = Bounds.parse(args.bounds)
        elif config.name == "DM-USAR_yellow":
            bounds = YELLOW_ARENA
        else:
            from usarsim.brains.coverage import FloorMap

            bounds = Bounds(*FloorMap.from_world(config).solids_box)
        runs = [(args.robots, not args.no_radio)] + ([(1, False)] if args.compare else [])
        for n, radio in runs:
            with tempfile.TemporaryDirectory() as tmp:
                score_file = os.path.join(tmp, "score.json")
                extra: tuple[str, ...] = ("--score-file", score_file)
                if radio and args.wireless_config:
                    extra += ("--wireless-config", args.wireless_config)
                with launch(
                    world=args.world, seed=args.seed, lockstep=True, wireless=radio, extra_args=extra
                ) as server:
                    world = server.connect()
                    poses = world.start_poses
                    referee = Referee(config, (poses[0].location[0], poses[0].location[1]))
                    comserver = (server.host, server.ports["comserver"]) if radio else None
                    fig = explore(world, n, args.seconds, bounds=bounds, comserver=comserver, referee=referee)
                    world.close()
                fig.update(radio_figures(score_file))
            print_figures(fig)
    except (ClientError, RadioError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    return 0


def radio_figures(score_file: str) -> dict[str, Any]:
    """What the simulator's radio channel carried, from the score file it wrote when it stopped:
    the team's messages delivered and lost, and the losses by cause (empty: no channel beyond
    USARSim's, or no file)."""
    try:
        with open(score_file, encoding="utf-8") as f:
            score = json.load(f)
    except (OSError, ValueError):
        return {}
    links = score.get("radio") or {}
    if not links:
        return {}
    causes = {c: sum(ln["dropped"][c] for ln in links.values()) for c in ("range", "loss", "capacity")}
    return {
        "messages_delivered": score["team"]["messages_delivered"],
        "messages_lost": score["team"]["messages_lost"],
        "lost_by_cause": causes,
    }


def print_figures(fig: dict[str, Any]) -> None:
    line = (
        f"{fig['robots']} robot{'s' if fig['robots'] > 1 else ''}: {fig['simulated_s']:.0f} simulated s in "
        f"{fig['wall_s']:.1f} s wall, {fig['messages']} map messages received"
    )
    if "arena_share" in fig:
        every = ", ".join(
            f"{t} s {100 * s:.0f}/{100 * n:.0f} %" for t, (s, n) in sorted(fig["arena_share_every_30s"].items())
        )
        line += (
            f"; arena floor swept {100 * fig['arena_share']:.1f} %, within {NEAR_M:g} m "
            f"{100 * fig['arena_near_share']:.1f} % (all reachable floor {100 * fig['reachable_share']:.1f} %)"
            f" [{every}]"
        )
    if "messages_lost" in fig:
        c = fig["lost_by_cause"]
        line += (
            f"; radio: {fig['messages_delivered']} messages delivered, {fig['messages_lost']} lost "
            f"({c['range']} out of range, {c['loss']} on the way, {c['capacity']} to full queues)"
        )
    print(line, flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
