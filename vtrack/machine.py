"""What this machine offers the process: the cores it may run on (batch workers, decoder
threads) and the memory it may still take (batch workers)."""

from __future__ import annotations

import os
from dataclasses import dataclass


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
#: swapping, this process's cgroup (a container's, a Slurm job's, a ``systemd-run`` scope's)
#: and the cgroup file systems' mount point.
_MEMINFO = "/proc/meminfo"
_SELF_CGROUP = "/proc/self/cgroup"
_CGROUP_MOUNT = "/sys/fs/cgroup"

#: A cgroup v1 limit at or above this is its "unlimited" (9223372036854771712 on 4 KiB pages).
_UNLIMITED = 2**60


@dataclass(frozen=True)
class _CgroupFiles:
    """A cgroup version's memory files: its hierarchy's folder under :data:`_CGROUP_MOUNT`,
    the limit, the use, and ``memory.stat``'s key of the page cache the kernel takes back
    first (counted in the use, yet free to take)."""

    folder: str
    limit: str
    usage: str
    inactive: str


_V2 = _CgroupFiles("", "memory.max", "memory.current", "inactive_file")
_V1 = _CgroupFiles("memory", "memory.limit_in_bytes", "memory.usage_in_bytes",
                   "total_inactive_file")


def available_memory() -> int | None:
    """Bytes of memory new processes may still take: the system's ``MemAvailable``, or less
    where this process's cgroup, or one above it, leaves less under its limit (page cache it
    may drop not counted as used); None where neither can be read (not Linux)."""
    known: list[int] = []
    try:
        with open(_MEMINFO, encoding="ascii") as table:
            for line in table:
                if line.startswith("MemAvailable:"):
                    known.append(int(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    known += [free for files, path in _own_cgroups()
              if (free := _cgroup_free(files, path)) is not None]
    return min(known, default=None)


def _own_cgroups() -> list[tuple[_CgroupFiles, str]]:
    """This process's memory cgroup as ``/proc/self/cgroup`` names it: v1's ``memory`` line
    (the controller is there, on a hybrid system too), else v2's ``0::`` line; both
    hierarchies' roots where that file cannot be read."""
    try:
        with open(_SELF_CGROUP, encoding="utf-8", errors="surrogateescape") as table:
            lines = [line.rstrip("\n").split(":", 2) for line in table]
    except OSError:
        return [(_V2, "/"), (_V1, "/")]
    fields = [line for line in lines if len(line) == 3]
    for _, controllers, path in fields:
        if "memory" in controllers.split(","):
            return [(_V1, path)]
    return [(_V2, path) for number, controllers, path in fields
            if number == "0" and not controllers]


def _cgroup_free(files: _CgroupFiles, path: str) -> int | None:
    """The least memory any limit from the cgroup ``path`` up to its hierarchy's root leaves
    free; None where none is set or can be read. A path not under the mount point (a
    container that sees only its own cgroup, as the root) is read at the root."""
    root = os.path.normpath(os.path.join(_CGROUP_MOUNT, files.folder))
    here = os.path.normpath(os.path.join(root, path.lstrip("/")))
    if not os.path.isdir(here) or os.path.commonpath([root, here]) != root:
        here = root
    free: list[int] = []
    while True:
        level = _level_free(here, files)
        if level is not None:
            free.append(level)
        if here == root:
            return min(free, default=None)
        here = os.path.dirname(here)


def _level_free(folder: str, files: _CgroupFiles) -> int | None:
    """What one cgroup's limit leaves free: the limit less its use less the inactive page
    cache in its ``memory.stat``; None when it has no limit (``max``, v1's unlimited) or
    its files cannot be read."""
    try:
        with open(os.path.join(folder, files.limit), encoding="ascii") as limit, \
                open(os.path.join(folder, files.usage), encoding="ascii") as used:
            cap, use = limit.read().strip(), used.read().strip()
    except (OSError, ValueError):
        return None
    if not (cap.isdigit() and use.isdigit()) or int(cap) >= _UNLIMITED:  # "max": no limit
        return None
    cache = 0
    try:
        with open(os.path.join(folder, "memory.stat"), encoding="ascii") as stat:
            for line in stat:
                key, _, value = line.partition(" ")
                if key == files.inactive and value.strip().isdigit():
                    cache = int(value)
                    break
    except (OSError, ValueError):
        pass
    return max(0, int(cap) - max(0, int(use) - cache))


def workers_memory_holds(available: int | None) -> int | None:
    """How many batch workers of :data:`WORKER_MEMORY` the ``available`` bytes
    (:func:`available_memory`) hold: at least one; None when it is not known."""
    return None if available is None else max(1, available // WORKER_MEMORY)
