"""The score of a run (docs/scoring.md): :class:`Scorer` (from the simulator's ground truth,
no I/O), and :class:`ScoreKeeper`, which keeps it for a served run (``usarsim serve --score``,
``--score-file``)."""

from .keeper import ScoreKeeper
from .score import COLLISION_FORCE_N, REPORT_RADIUS_M, Scorer, Weights

__all__ = ["COLLISION_FORCE_N", "REPORT_RADIUS_M", "ScoreKeeper", "Scorer", "Weights"]
