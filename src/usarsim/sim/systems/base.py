"""World systems: forces and motions the simulation applies by hand before each stretch of
physics steps (self-righting, levelling, water, roller tables, gaits, waving victims);
gz-sim's ``ISystemPreUpdate``, dm_control's ``before_step``.

A system is collected once per model build (when its ``wanted`` says the world needs it)
and runs in ``ORDER`` before every stretch of physics steps; while it is ``active`` a
stretch is at most ``EVERY_STEPS`` physics steps long, so that the forces it sets are
renewed often enough.  Adding one is a module with a :class:`System` subclass registered
with ``@SYSTEMS.register("name")``, imported by this package's ``__init__``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar, TypeVar

from usarsim.registry import Registry

if TYPE_CHECKING:
    from usarsim.sim.context import WorldContext

SYSTEMS = Registry("world system")
T = TypeVar("T")

# Forces the simulation sets by hand (self-righting, levelling, water, rollers) are renewed
# at least every 10 physics steps (40 ms).
EXTERNAL_FORCE_STEPS = 10


class System:
    """One system of one model build.  ``sim`` is the simulation: its model, data, robots,
    world and clock."""

    TYPE: ClassVar[str] = ""
    ORDER: ClassVar[int] = 100  # systems run in increasing order
    EVERY_STEPS: ClassVar[int | None] = EXTERNAL_FORCE_STEPS

    def __init__(self, sim: WorldContext) -> None:
        self.sim = sim

    @classmethod
    def wanted(cls, sim: WorldContext) -> bool:
        """Whether the world as built now needs this system."""
        return True

    def active(self) -> bool:
        """Whether its forces must be renewed every ``EVERY_STEPS`` now."""
        return True

    def max_steps(self) -> int | None:
        """How many physics steps may run before :meth:`pre_step` runs again (None: any)."""
        return self.EVERY_STEPS if self.EVERY_STEPS is not None and self.active() else None

    def pre_step(self) -> None:
        """Set this system's forces (or motions) for the next stretch of physics steps."""


def mounted(sim: WorldContext, kind: type[T]) -> list[T]:
    """Every item of class ``kind`` (a Gripper, a RollerTable) mounted on the world's robots."""
    return [s for r in sim.robots.values() for s in r.sensors if isinstance(s, kind)]


def collect(sim: WorldContext, previous: Sequence[System] = ()) -> list[System]:
    """The systems the world needs now, in order; one still wanted keeps its instance (and
    its state) from ``previous``."""
    kept = {type(s): s for s in previous}
    classes: list[type[System]] = sorted((SYSTEMS.get(n) for n in SYSTEMS.names()), key=lambda c: (c.ORDER, c.TYPE))
    return [kept.get(cls) or cls(sim) for cls in classes if cls.wanted(sim)]
