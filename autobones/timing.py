"""Seconds per pipeline stage, logged as each stage ends."""
from __future__ import annotations

import logging
import time

log = logging.getLogger("autobones")


class Stopwatch:
    """``lap(stage)`` records the seconds since the previous lap in ``timings``."""

    def __init__(self):
        self.timings = {}
        self._t = time.perf_counter()

    def lap(self, stage):
        now = time.perf_counter()
        self.timings[stage] = now - self._t
        log.info("%-10s %.2f s", stage, now - self._t)
        self._t = now
