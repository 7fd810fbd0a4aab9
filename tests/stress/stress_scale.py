"""Sizes of the stress suite: reduced by default (CI), full with ``USARSIM_STRESS=full``."""

from __future__ import annotations

import os

FULL = os.environ.get("USARSIM_STRESS", "").lower() == "full"


def scaled(reduced: int, full_size: int) -> int:
    return full_size if FULL else reduced
