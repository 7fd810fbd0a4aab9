"""NFO messages: the game on connect (protocol.md §6.1), the start poses (§5.2) and the UDK
path nodes (§5.8), with their formats and parsers.  Poses are printed with 2 decimals."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..grammar import Segment
from ..numbers import vec2
from .common import Vec3, _Reader
from .declare import key, message
from .kinds import INT, TEXT, VEC2


@dataclass(frozen=True, slots=True, kw_only=True)
class GameInfo:
    """``NFO {Gametype g} {Level map} {TimeLimit minutes}``, sent on connect (§6.1)."""

    gametype: str = key("Gametype", TEXT, default="BotDeathMatch")
    level: str = key("Level", TEXT)
    time_limit: int = key("TimeLimit", INT, default=0)


@dataclass(frozen=True, slots=True)
class StartPose:
    """A named pose: start poses and path nodes (metres, radians, Z down)."""

    name: str
    location: Vec3
    rotation: Vec3


@dataclass(frozen=True, slots=True)
class StartPoses:
    """Reply to GETSTARTPOSES: all poses in one segment, 2 decimals (§5.2)."""

    poses: tuple[StartPose, ...] = ()


@dataclass(frozen=True, slots=True)
class PathNodes:
    """Reply to GETPATHNODES (UDK): same layout as start poses under ``PathNodes``."""

    nodes: tuple[StartPose, ...] = ()


@dataclass(frozen=True, slots=True)
class ClosestPathNode:
    """Reply to GETCLOSESTPATHNODE (UDK): ``NFO {Pathnode name} {Location x,y,z}``."""

    name: str = key("Pathnode", TEXT)
    location: Vec3 = key("Location", VEC2)


InfoMessage = GameInfo | StartPoses | PathNodes | ClosestPathNode

# ---- formatting: the game and the closest path node from their declarations above; a pose
# list (every pose in one segment, its count before it) by hand

_GAME = message(GameInfo, "NFO")
_CLOSEST = message(ClosestPathNode, "NFO")


def _poses(poses: tuple[StartPose, ...]) -> str:
    return " ".join("%s %s %s" % (p.name, vec2(p.location), vec2(p.rotation)) for p in poses)


def _fmt_start_poses(m: StartPoses) -> str:
    if not m.poses:
        return "NFO {StartPoses 0}\r\n"
    return "NFO {StartPoses %d} {%s}\r\n" % (len(m.poses), _poses(m.poses))


def _fmt_path_nodes(m: PathNodes) -> str:
    if not m.nodes:
        return "NFO {PathNodes 0}\r\n"
    return "NFO {PathNodes %d} {%s}\r\n" % (len(m.nodes), _poses(m.nodes))


# ---- parsing


def _split_poses(r: _Reader, seg: Segment) -> tuple[StartPose, ...]:
    tokens = ([seg.key] + seg.value.split()) if seg.value else [seg.key]
    if len(tokens) % 3:
        raise r.error(seg.key, seg.value, "'name x,y,z roll,pitch,yaw' triples")
    poses = []
    for i in range(0, len(tokens), 3):
        poses.append(
            StartPose(
                name=tokens[i],
                location=r.vector("location", tokens[i + 1]),  # type: ignore[arg-type]
                rotation=r.vector("rotation", tokens[i + 2]),  # type: ignore[arg-type]
            )
        )
    return tuple(poses)


def _parse_nfo(r: _Reader) -> InfoMessage:
    raw = r.raw
    segs = raw.segments
    # a pose list: its kind is the first StartPoses or PathNodes segment (a pose further on
    # may itself be named so)
    idx = next((i for i, s in enumerate(segs) if s.key.lower() in ("startposes", "pathnodes")), None)
    if idx is not None:
        key = "StartPoses" if segs[idx].key.lower() == "startposes" else "PathNodes"
        count = r.req_int(key)
        poses = _split_poses(r, segs[idx + 1]) if count and idx + 1 < len(segs) else ()
        if len(poses) != count:
            raise r.error(key, str(count), f"the number of poses listed ({len(poses)})")
        return StartPoses(poses=poses) if key == "StartPoses" else PathNodes(nodes=poses)
    layout = _CLOSEST if raw.has("Pathnode") else _GAME
    info: GameInfo | ClosestPathNode = layout.parse(r)
    return info


FORMATTERS: dict[type, Callable[[Any], str]] = {
    GameInfo: _GAME.format,
    StartPoses: _fmt_start_poses,
    PathNodes: _fmt_path_nodes,
    ClosestPathNode: _CLOSEST.format,
}

PARSERS: dict[str, Callable[[_Reader], InfoMessage]] = {"NFO": _parse_nfo}
