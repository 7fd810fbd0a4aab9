"""Plugins registered under a name: sensors, effecters and cameras (by their USARSim type
name), drive models (by a robot file's ``drive`` key), world systems.

Names are looked up in any letter case and reported in their canonical spelling; an
unknown name fails with the closest match and the list of valid ones; registering a name
twice is an error (two plugins must never silently replace one another).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from usarsim.config.reader import did_you_mean
from usarsim.errors import PluginNotFoundError

T = TypeVar("T", bound=type)


class Registry:
    """Plugin classes of one kind (``sensor``, ``drive``...) by name, any case.  Each
    registered class gets its canonical name as ``TYPE``."""

    def __init__(self, kind: str):
        self.kind = kind
        self._by_lower: dict[str, type] = {}
        self._canonical: dict[str, str] = {}

    def register(self, name: str, *aliases: str) -> Callable[[T], T]:
        """A class decorator: the class under ``name`` (its canonical spelling) and ``aliases``."""

        def deco(cls: T) -> T:
            for n in (name, *aliases):
                known = self._by_lower.get(n.lower())
                if known is not None:
                    raise ValueError(
                        f"{self.kind} name '{n}' is registered already (by {known.__module__}."
                        f"{known.__qualname__}); choose another name for {cls.__qualname__}"
                    )
            setattr(cls, "TYPE", name)  # noqa: B010  (every plugin class has TYPE; T is any class)
            for n in (name, *aliases):
                self._by_lower[n.lower()] = cls
                self._canonical[n.lower()] = name
            return cls

        return deco

    def names(self) -> list[str]:
        return sorted(set(self._canonical.values()))

    def canonical(self, name: str) -> str | None:
        return self._canonical.get(name.lower())

    def get(self, name: str) -> type:
        cls = self._by_lower.get(name.lower())
        if cls is None:
            raise PluginNotFoundError(f"unknown {self.kind} type '{name}'{did_you_mean(name, self.names())}")
        return cls

    def __contains__(self, name: str) -> bool:
        return name.lower() in self._by_lower
