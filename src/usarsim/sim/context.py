"""What a drive model, a world system or a joint order sees of the simulation: its context.

Plugins that act on the world between physics steps (drive models, :mod:`usarsim.robots`;
world systems, :mod:`usarsim.sim.systems`; the systems effecters bring,
:mod:`usarsim.effecters`) are given a :class:`WorldContext`, never the simulation itself:
the MuJoCo model and data, the simulated clock, the world file, the robots in the world,
the world's moving entities and systems, and writing a robot's controls.  The simulation
(:class:`usarsim.sim.simulation.Simulation`) is one; a test may hand a plugin another.
Sensors see less still: a :class:`usarsim.sim.view.WorldView` at one instant.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Protocol, runtime_checkable

if TYPE_CHECKING:
    import mujoco
    import numpy as np

    from usarsim.config.world import WorldConfig
    from usarsim.sim.robot import SimRobot
    from usarsim.sim.systems.base import System


class MovingEntities(Protocol):
    """The world's entities that move on their own (victims waving their arms)."""

    @property
    def has_motion(self) -> bool: ...

    def update(self, d: mujoco.MjData, time: float) -> None: ...


class Hull(Protocol):
    """What the water needs of a vessel's hull: the volume it displaces (m^3), its drag along
    its length (N per m/s) and against turning (N m per rad/s)."""

    @property
    def volume_m3(self) -> float: ...
    @property
    def drag_n_per_m_s(self) -> float: ...
    @property
    def angular_drag(self) -> float: ...


@runtime_checkable
class Vessel(Protocol):
    """A drive built for water (:mod:`usarsim.robots.nautical`), as the world's water
    (:mod:`usarsim.sim.systems.water`) carries it: its hull, and its own propulsion."""

    @property
    def vessel(self) -> Hull: ...

    def propulsion(
        self, rot: np.ndarray, lin: np.ndarray, frac: float
    ) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """Its own force and torques in water (propeller, rudder and planes), in the world frame."""
        ...


class WorldContext(Protocol):
    """The simulation as its plugins see it (see the module's text)."""

    @property
    def model(self) -> mujoco.MjModel: ...

    @property
    def data(self) -> mujoco.MjData: ...

    @property
    def time(self) -> float: ...

    @property
    def world(self) -> WorldConfig: ...

    @property
    def robots(self) -> Mapping[int, SimRobot]: ...

    @property
    def entities(self) -> MovingEntities: ...

    @property
    def systems(self) -> Sequence[System]: ...

    def apply_controls(self, r: SimRobot) -> None:
        """Write the robot's headlight and its drive's controls into the model."""


if TYPE_CHECKING:
    from usarsim.sim.simulation import Simulation

    def _the_simulation_is_a_context(sim: Simulation) -> WorldContext:
        return sim  # mypy checks here that the simulation gives its plugins all of the above
