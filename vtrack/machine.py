"""What this machine offers the process: the cores it may run on (batch workers, decoder
threads) and the memory it may still take (batch workers)."""

from __future__ import annotations

import os


def cpu_count() -> int:
    """Cores this process may use (its CPU affinity where the system has one, as FFmpeg counts
    them)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


#: The memory one local ``vtrack batch`` worker is taken to need: a Python process with NumPy,
#: OpenCV and PyAV, its decoder, encoder and chain of stages (about 75 MB resident for a 960x720
#: input), with room to spare: what bounds the workers a batch starts
#: (:func:`workers_memory_holds`).
WORKER_MEMORY = 100 * 2**20

#: Where the memory limits are read: the kernel's estimate of what can be taken without
#: swapping, and a cgroup's (v2, then v1) limit and use (a container's).
_MEMINFO = "/proc/meminfo"
_CGROUP_LIMITS = (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                  ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                   "/sys/fs/cgroup/memory/memory.usage_in_bytes"))


def available_memory() -> int | None:
    """Bytes of memory new processes may still take: the system's ``MemAvailable``, or less
    where this process's cgroup (a container) leaves less under its limit; None where neither
    can be read (not Linux)."""
    known: list[int] = []
    try:
        with open(_MEMINFO, encoding="ascii") as table:
            for line in table:
                if line.startswith("MemAvailable:"):
                    known.append(int(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    for limit_path, used_path in _CGROUP_LIMITS:
        try:
            with open(limit_path, encoding="ascii") as limit, \
                    open(used_path, encoding="ascii") as used:
                cap, use = limit.read().strip(), used.read().strip()
        except OSError:
            continue
        if cap.isdigit() and use.isdigit() and int(cap) < 2**60:  # "max": no limit
            known.append(max(0, int(cap) - int(use)))
        break
    return min(known, default=None)


def workers_memory_holds(available: int | None) -> int | None:
    """How many batch workers of :data:`WORKER_MEMORY` the ``available`` bytes
    (:func:`available_memory`) hold: at least one; None when it is not known."""
    return None if available is None else max(1, available // WORKER_MEMORY)
