"""Queries, with their parsers and formats: ``GETSTARTPOSES`` (protocol.md §5.2), ``GETGEO``
and ``GETCONF`` (§5.5), and the UDK path nodes, ``GETPATHNODES`` and
``GETCLOSESTPATHNODE`` (§5.8)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from ..grammar import RawMessage
from .common import _TYPE_NAME_KEYS, Vec3, _Line, _read_fields, _Table, _vec3


@dataclass(frozen=True, slots=True, kw_only=True)
class GetStartPoses:
    """``GETSTARTPOSES`` (§5.2)."""

    keyword: ClassVar[str] = "GETSTARTPOSES"


@dataclass(frozen=True, slots=True, kw_only=True)
class GetGeo:
    """``GETGEO {Type T} [{Name N}]`` (§5.5); ``Type Robot`` asks for the robot itself."""

    keyword: ClassVar[str] = "GETGEO"
    type: str | None = None
    name: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class GetConf:
    """``GETCONF {Type T} [{Name N}]`` (§5.5)."""

    keyword: ClassVar[str] = "GETCONF"
    type: str | None = None
    name: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class GetPathNodes:
    """``GETPATHNODES`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GETPATHNODES"


@dataclass(frozen=True, slots=True, kw_only=True)
class GetClosestPathNode:
    """``GETCLOSESTPATHNODE {Location x,y,z}`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GETCLOSESTPATHNODE"
    location: Vec3 | None = None


Query = GetStartPoses | GetGeo | GetConf | GetPathNodes | GetClosestPathNode


# ---- parsing


def _parse_get_start_poses(raw: RawMessage) -> GetStartPoses:
    return GetStartPoses()


def _parse_getgeo(raw: RawMessage) -> GetGeo:
    return GetGeo(**_read_fields(raw.type, raw.segments, _TYPE_NAME_KEYS))


def _parse_getconf(raw: RawMessage) -> GetConf:
    return GetConf(**_read_fields(raw.type, raw.segments, _TYPE_NAME_KEYS))


def _parse_get_path_nodes(raw: RawMessage) -> GetPathNodes:
    return GetPathNodes()


_LOCATION_KEYS: _Table = {"location": ("location", _vec3)}


def _parse_get_closest_path_node(raw: RawMessage) -> GetClosestPathNode:
    return GetClosestPathNode(**_read_fields(raw.type, raw.segments, _LOCATION_KEYS))


PARSERS: dict[str, Callable[[RawMessage], Query]] = {
    "GETSTARTPOSES": _parse_get_start_poses,
    "GETGEO": _parse_getgeo,
    "GETCONF": _parse_getconf,
    "GETPATHNODES": _parse_get_path_nodes,
    "GETCLOSESTPATHNODE": _parse_get_closest_path_node,
}

# ---- formatting

FORMATTERS: dict[type, Callable[[Any], str]] = {
    GetStartPoses: lambda c: "GETSTARTPOSES\r\n",
    GetGeo: lambda c: _Line("GETGEO").text("Type", c.type).text("Name", c.name).end(),
    GetConf: lambda c: _Line("GETCONF").text("Type", c.type).text("Name", c.name).end(),
    GetPathNodes: lambda c: "GETPATHNODES\r\n",
    GetClosestPathNode: lambda c: _Line("GETCLOSESTPATHNODE").vector("Location", c.location).end(),
}
