"""What this machine offers the process: the cores it may run on (batch workers, decoder
threads)."""

from __future__ import annotations

import os


def cpu_count() -> int:
    """Cores this process may use (its CPU affinity where the system has one, as FFmpeg counts
    them)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1
