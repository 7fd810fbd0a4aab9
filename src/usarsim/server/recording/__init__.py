"""Recording a run (MCAP) and showing it live (Foxglove): :class:`Recorder`; the protocol
transcript a replay reads back: :mod:`.transcript`."""

from .recorder import FRAME_PERIOD_S, Recorder
from .transcript import Chunk, RunInfo, parse_run_info, run_info

__all__ = ["FRAME_PERIOD_S", "Chunk", "Recorder", "RunInfo", "parse_run_info", "run_info"]
