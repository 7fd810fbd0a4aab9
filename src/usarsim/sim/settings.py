"""How the simulation runs on this machine: what ``usarsim serve``'s options choose besides the
world, handed down by the composition root (:class:`usarsim.server.config.ServeConfig`).  None
of them but the report phases changes what is simulated: the same seed and commands give the
same readings whatever they are (pictures aside: shadows and textures are what cameras see)."""

from __future__ import annotations

from dataclasses import dataclass

# A number of MuJoCo pool threads asked for is held to this (serve --physics-threads takes no more).
PHYSICS_THREADS_LIMIT = 256
REPORT_PHASES = ("grid", "spread")  # usarsim.sim.reports
ANTIALIAS = (0, 2, 4, 8)  # multisampling samples a pixel of a picture (4: MuJoCo's default)


@dataclass(frozen=True, kw_only=True)
class SimSettings:
    """``shadows``: the world's lights cast shadows in pictures (each such light draws the scene
    once more, into its shadow map: on a software renderer that halves the image server's
    frames a second); ``textures``: surfaces show their materials' textures (off: plain
    colours, the quickest pictures); ``physics_threads``: MuJoCo's thread pool (None: the
    automatic rule of :func:`usarsim.sim.simulation.physics_threads`; 0 or 1: no pool);
    ``sensor_thread``: sensor readings are taken on a thread of their own while the physics
    runs on (:mod:`usarsim.sim.measuring`); ``report_phases``: "grid" (every robot reports at
    the same instants, the physics runs in the longest stretches) or "spread" (each robot on a
    phase of its own, the readings of many robots in small groups: :mod:`usarsim.sim.reports`;
    a reading is then taken at other instants, so this one does change what robots report);
    ``antialias``: the multisampling of pictures, samples a pixel (MuJoCo's ``offsamples``; 0:
    none, about twice the pictures a second on a software renderer, with jagged edges)."""

    shadows: bool = False
    textures: bool = True
    antialias: int = 4
    physics_threads: int | None = None
    sensor_thread: bool = True
    report_phases: str = "grid"

    def __post_init__(self) -> None:
        n = self.physics_threads
        if n is not None and not 0 <= n <= PHYSICS_THREADS_LIMIT:
            raise ValueError(f"physics_threads must be within 0..{PHYSICS_THREADS_LIMIT} (or None: automatic), got {n}")
        if self.antialias not in ANTIALIAS:
            raise ValueError(f"antialias must be one of {', '.join(map(str, ANTIALIAS))}, got {self.antialias!r}")
        if self.report_phases not in REPORT_PHASES:
            raise ValueError(f"report_phases must be one of {', '.join(REPORT_PHASES)}, got {self.report_phases!r}")
