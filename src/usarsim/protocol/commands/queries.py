"""Queries, with their parsers and formats: ``GETSTARTPOSES`` (protocol.md §5.2), ``GETGEO``
and ``GETCONF`` (§5.5), and the UDK path nodes, ``GETPATHNODES`` and
``GETCLOSESTPATHNODE`` (§5.8)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from ..grammar import RawMessage
from .common import Vec3
from .declare import TEXT, VEC3, command, key


@dataclass(frozen=True, slots=True, kw_only=True)
class GetStartPoses:
    """``GETSTARTPOSES`` (§5.2)."""

    keyword: ClassVar[str] = "GETSTARTPOSES"


@dataclass(frozen=True, slots=True, kw_only=True)
class GetGeo:
    """``GETGEO {Type T} [{Name N}]`` (§5.5); ``Type Robot`` asks for the robot itself."""

    keyword: ClassVar[str] = "GETGEO"
    type: str | None = key("Type", TEXT)
    name: str | None = key("Name", TEXT)


@dataclass(frozen=True, slots=True, kw_only=True)
class GetConf:
    """``GETCONF {Type T} [{Name N}]`` (§5.5)."""

    keyword: ClassVar[str] = "GETCONF"
    type: str | None = key("Type", TEXT)
    name: str | None = key("Name", TEXT)


@dataclass(frozen=True, slots=True, kw_only=True)
class GetPathNodes:
    """``GETPATHNODES`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GETPATHNODES"


@dataclass(frozen=True, slots=True, kw_only=True)
class GetClosestPathNode:
    """``GETCLOSESTPATHNODE {Location x,y,z}`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GETCLOSESTPATHNODE"
    location: Vec3 | None = key("Location", VEC3)


Query = GetStartPoses | GetGeo | GetConf | GetPathNodes | GetClosestPathNode


# ---- parsing and formatting, from the declarations above

_LAYOUTS = [command(c) for c in (GetStartPoses, GetGeo, GetConf, GetPathNodes, GetClosestPathNode)]

PARSERS: dict[str, Callable[[RawMessage], Query]] = {layout.keyword: layout.parse for layout in _LAYOUTS}

FORMATTERS: dict[type, Callable[[Any], str]] = {layout.cls: layout.format for layout in _LAYOUTS}
