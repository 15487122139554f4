"""Worker processes shared by the studies that spread work over the cores (the Monte
Carlo batch, the flight-control design's candidate judgements)."""

from __future__ import annotations

import multiprocessing as mp
import os
import sys


def process_context() -> mp.context.BaseContext:
    """``fork`` on Linux: a worker inherits the built model, the frozen plants and the
    loaded compiled engine without pickling them; ``spawn`` elsewhere."""
    return mp.get_context("fork" if sys.platform.startswith("linux") else "spawn")


def default_workers() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
