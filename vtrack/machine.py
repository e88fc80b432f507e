"""What this machine offers the process: the cores it may run on, its CPU quota counted (batch
workers, decoder threads), and the memory it may still take (batch workers)."""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass


def cpu_count() -> int:
    """Cores this process may use: its CPU affinity where the system has one (as FFmpeg
    counts them: a Slurm job's or ``taskset``'s cores), or fewer where this process's cgroup,
    or one above it, has a CPU quota (a container's, a Kubernetes pod's: :func:`cpu_quota`);
    at least 1."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
        os.cpu_count() or 1)
    quota = cpu_quota()
    return max(1, cores if quota is None else min(cores, quota))


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
    """A cgroup version's memory files: the limit, the use, and ``memory.stat``'s key of the
    page cache the kernel takes back first (counted in the use, yet free to take)."""

    limit: str
    usage: str
    inactive: str


_V2 = _CgroupFiles("memory.max", "memory.current", "inactive_file")
_V1 = _CgroupFiles("memory.limit_in_bytes", "memory.usage_in_bytes", "total_inactive_file")


@dataclass(frozen=True)
class _Cgroup:
    """This process's cgroup of one controller: cgroup v1's or v2's (``v1``), its
    hierarchy's folder under :data:`_CGROUP_MOUNT` (v1's, named by its controllers: ``memory``,
    ``cpu,cpuacct``; v2's is the mount point itself, ``""``) and its path in that hierarchy,
    as ``/proc/self/cgroup`` names it."""

    v1: bool
    hierarchy: str
    path: str


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
    known += [free for group in _own_cgroups("memory")
              if (free := _least(_level_free(folder, _V1 if group.v1 else _V2)
                                 for folder in _cgroup_levels(group))) is not None]
    return min(known, default=None)


def cpu_quota() -> int | None:
    """The cores the CPU quota of this process's cgroup, or of one above it, allows: the
    least of ``ceil(quota / period)`` up the tree (cgroup v2's ``cpu.max``, v1's
    ``cpu.cfs_quota_us`` over ``cpu.cfs_period_us``), at least 1; None where no quota is set
    or can be read (not Linux)."""
    return _least(_level_cpus(folder, group.v1)
                  for group in _own_cgroups("cpu") for folder in _cgroup_levels(group))


def _least(values: Iterable[int | None]) -> int | None:
    """The least of the ``values`` that are not None; None when none is."""
    return min((value for value in values if value is not None), default=None)


def _own_cgroups(controller: str) -> list[_Cgroup]:
    """This process's cgroup of ``controller`` (``memory``, ``cpu``) as ``/proc/self/cgroup``
    names it: v1's line that lists the controller (it is there, on a hybrid system too), else
    v2's ``0::`` line; both hierarchies' roots where that file cannot be read."""
    try:
        with open(_SELF_CGROUP, encoding="utf-8", errors="surrogateescape") as table:
            lines = [line.rstrip("\n").split(":", 2) for line in table]
    except OSError:
        return [_Cgroup(False, "", "/"), _Cgroup(True, controller, "/")]
    fields = [line for line in lines if len(line) == 3]
    for _, controllers, path in fields:
        if controller in controllers.split(","):  # (mounted as listed, or as the controller)
            mounted = os.path.isdir(os.path.join(_CGROUP_MOUNT, controllers))
            return [_Cgroup(True, controllers if mounted else controller, path)]
    return [_Cgroup(False, "", path) for number, controllers, path in fields
            if number == "0" and not controllers]


def _cgroup_levels(group: _Cgroup) -> list[str]:
    """The folders of ``group`` and of each cgroup above it, up to its hierarchy's root. A
    path not under the mount point (a container that sees only its own cgroup, as the root)
    is read at the root."""
    root = os.path.normpath(os.path.join(_CGROUP_MOUNT, group.hierarchy))
    here = os.path.normpath(os.path.join(root, group.path.lstrip("/")))
    if not os.path.isdir(here) or os.path.commonpath([root, here]) != root:
        here = root
    levels = [here]
    while here != root:
        here = os.path.dirname(here)
        levels.append(here)
    return levels


def _level_cpus(folder: str, v1: bool) -> int | None:
    """The cores one cgroup's CPU quota allows (``ceil(quota / period)``, at least 1); None
    when it has none (v2's ``max``, v1's -1) or its files cannot be read."""
    try:
        if v1:
            with open(os.path.join(folder, "cpu.cfs_quota_us"), encoding="ascii") as quota, \
                    open(os.path.join(folder, "cpu.cfs_period_us"), encoding="ascii") as period:
                allowed, every = quota.read().strip(), period.read().strip()
        else:
            with open(os.path.join(folder, "cpu.max"), encoding="ascii") as limit:
                allowed, _, every = limit.read().strip().partition(" ")
    except (OSError, ValueError):
        return None
    if not (allowed.isdigit() and every.isdigit()) or int(every) == 0:  # "max", -1: none
        return None
    return max(1, -(-int(allowed) // int(every)))


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
