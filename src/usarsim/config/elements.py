"""Kinds of world element a world file may list beyond the built-in sections: one class per
kind, registered with :data:`ELEMENT_KINDS` under the world file's key it reads.

A kind says what each entry of its section is (:meth:`ElementKind.parse`, with the same strict
reader as the rest of the file), what solid shapes it puts into the world
(:meth:`ElementKind.solids`: static boxes, cylinders or meshes, which the physics, every ray
cast, the cameras, the operator console's map and the recording then handle like any other
object of the world) and what the ground-truth service lists of it
(:meth:`ElementKind.landmarks`).  Adding a kind is one module with one registered class
(``tests/plugins/beacon_element.py``); it is imported before the world is loaded, as a drive
plugin is before a robot that names it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from usarsim.registry import Registry

if TYPE_CHECKING:
    from usarsim.config.reader import Section
    from usarsim.config.world import StaticObject

Vec3 = tuple[float, float, float]

ELEMENT_KINDS = Registry("world element kind")


@dataclass(frozen=True)
class Landmark:
    """A thing the ground-truth service lists (protocol.md 12.4): its name, its class (what
    ``{Class c}`` asks for), where it is and how it is turned (USARSim frame)."""

    name: str
    class_name: str
    location: Vec3
    rotation: Vec3 = (0.0, 0.0, 0.0)


class ElementKind:
    """Base of every world element kind (see the module's docstring).  ``TYPE`` (the world
    file's key) is given by registration."""

    TYPE: ClassVar[str] = ""

    @classmethod
    def parse(cls, s: Section) -> Any:
        """One entry of the section as a frozen value with a ``name`` (unique among the kind's
        entries); call ``s.finish()`` so that an unknown key is an error."""
        raise NotImplementedError

    @classmethod
    def solids(cls, element: Any) -> tuple[StaticObject, ...]:
        """The static shapes the entry puts into the world (their names are made unique by
        the loader: ``<kind>/<entry>/<name>``); none by default."""
        return ()

    @classmethod
    def landmarks(cls, element: Any) -> tuple[Landmark, ...]:
        """What the ground-truth service lists of the entry; nothing by default."""
        return ()


__all__ = ["ELEMENT_KINDS", "ElementKind", "Landmark"]
