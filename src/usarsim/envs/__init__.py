"""Reinforcement-learning environments on the simulator (docs/envs.md).

* ``usarsim/Explore-v0`` and ``usarsim/ExploreDiscrete-v0`` (Gymnasium, registered when
  this package is imported: ``import usarsim.envs`` then ``gymnasium.make(...)``, or
  ``gymnasium.make("usarsim.envs:usarsim/Explore-v0")`` without the import): one robot
  explores a world (:class:`ExploreEnv`).
* :func:`parallel_env` (PettingZoo): a team of robots explores together and may send each
  other messages that get through only while the simulator's radio link holds
  (:class:`TeamExplore`).
* :func:`make_vector` (Gymnasium vector): several worlds of ``Explore-v0`` stepped together
  in worker processes, each world's simulator in-process (:class:`ExploreVectorEnv`).
* :func:`bench_env`: environment steps per second.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from .bench import bench_env
from .explore import ExploreEnv
from .explorer import Rewards
from .team import TeamExplore, parallel_env
from .vector import ExploreVectorEnv, make_vector

__all__ = [
    "ENV_IDS",
    "ExploreEnv",
    "ExploreVectorEnv",
    "Rewards",
    "TeamExplore",
    "bench_env",
    "make_vector",
    "parallel_env",
    "register_envs",
]

ENV_IDS = {
    "usarsim/Explore-v0": {},
    "usarsim/ExploreDiscrete-v0": {"discrete": True},
}
"""The Gymnasium ids and the ExploreEnv keyword arguments each stands for."""


def register_envs() -> None:
    """Register :data:`ENV_IDS` with Gymnasium (once; done on import)."""
    for env_id, kwargs in ENV_IDS.items():
        if env_id not in registry:
            register(id=env_id, entry_point="usarsim.envs.explore:ExploreEnv", kwargs=dict(kwargs))


register_envs()
