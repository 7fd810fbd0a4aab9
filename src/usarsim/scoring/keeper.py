"""Keeps the score of a served run (``usarsim serve --score``, ``--score-file``): a
:class:`~usarsim.scoring.score.Scorer` fed on a thread of its own with the frames and outputs
the simulation hands its observers (the simulation thread only queues them)."""

from __future__ import annotations

import json
import logging
import os
import queue
import threading
from collections.abc import Callable

from usarsim.config.world import WorldConfig
from usarsim.sim.types import Output, RadioModel, WorldFrame

from .score import Scorer, Weights, laser_mounts

log = logging.getLogger("usarsim.score")

FRAME_PERIOD_S = 0.1  # poses and pushes against walls (10 Hz, the rate of most USARSim sensors)
LINKS_PERIOD_S = 1.0  # radio links (a ray cast per pair of robots that moved)


class ScoreKeeper:
    """``print_every_s``: simulated seconds between two live score lines handed to ``on_line``
    (0: none); ``path``: where the final score is written as JSON when the server stops."""

    def __init__(
        self,
        world: WorldConfig,
        *,
        seed: int = 0,
        path: str | None = None,
        print_every_s: float = 0.0,
        on_line: Callable[[str], None] | None = None,
        weights: Weights | None = None,
        team_map: str | None = None,
    ):
        self.world = world
        self.path = path
        self.team_map = team_map
        self.print_every_s = print_every_s
        self.on_line = on_line or (lambda line: None)
        self.scorer = Scorer(world, seed=seed, weights=weights)
        self._q: queue.SimpleQueue = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._run, name="usarsim-score", daemon=True)
        self._describe = None
        self._last_line = 0.0
        self.error: BaseException | None = None

    def attach(self, facade, radio_model: RadioModel) -> None:
        """Watch ``facade``'s outputs and frames (before its simulation starts)."""
        self._describe = facade.describe
        facade.add_output_watcher(self._on_outputs)
        facade.watch_frames(FRAME_PERIOD_S, self._on_frame, radio_model=radio_model, links_period_s=LINKS_PERIOD_S)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> dict:
        """Score what is queued; write the file; the final score."""
        if self._thread.is_alive():
            self._q.put(None)
            self._thread.join()
        result = self.scorer.result()
        if self.team_map is not None:
            result["map"] = score_team_map(self.team_map, self.world)
        if self.print_every_s > 0:
            self.on_line(self.scorer.line())
        if self.path is not None:
            tmp = f"{self.path}.tmp"
            with open(tmp, "w", encoding="utf-8") as f:
                json.dump(result, f, indent=1)
                f.write("\n")
            os.replace(tmp, self.path)
            log.info("score written to %s", self.path)
        return result

    # simulation thread: queue only
    def _on_outputs(self, outs: list[Output]) -> None:
        self._q.put(outs)

    def _on_frame(self, frame: WorldFrame) -> None:
        self._q.put(frame)

    # the keeper's thread
    def _run(self) -> None:
        sc = self.scorer
        while True:
            item = self._q.get()
            if item is None:
                return
            try:
                if isinstance(item, list):
                    sc.outputs(item)
                    continue
                for r in item.robots:  # a class seen for the first time: where its lasers sit
                    cls = r.config.class_name
                    if cls not in sc.mounts and self._describe is not None:
                        sc.mounts[cls] = laser_mounts(self._describe(r.config))
                sc.frame(item)
                if self.print_every_s > 0 and item.time - self._last_line >= self.print_every_s - 1e-9:
                    self._last_line = item.time
                    self.on_line(sc.line())
            except Exception as exc:  # a scoring problem must not stop the server
                if self.error is None:
                    self.error = exc
                    log.exception("score: cannot score %s", type(item).__name__)


def score_team_map(path: str, world: WorldConfig) -> dict:
    """The score of the map the team handed in at ``path`` (docs/scoring.md, "Map quality"), or
    ``{"error": ...}`` saying why there is none."""
    from usarsim.errors import UsarsimError
    from usarsim.maps.mapfile import read_map
    from usarsim.maps.quality import score_map
    from usarsim.maps.truth import ground_truth_map

    if not os.path.exists(path):
        log.warning("score: no map was handed in at %s", path)
        return {"error": f"no map was handed in at {path}"}
    try:
        team = read_map(path)
        result: dict = score_map(team, ground_truth_map(world, variant=world.variant)).as_dict()
    except (UsarsimError, ValueError) as exc:
        log.warning("score: the map handed in at %s cannot be scored: %s", path, exc)
        return {"error": f"the map handed in at {path} cannot be scored: {exc}"}
    log.info("score: map %s scored (coverage %.3f, accuracy %.3f)", path, result["coverage"], result["accuracy"])
    return result
