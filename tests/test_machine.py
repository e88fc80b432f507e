"""What ``vtrack batch`` takes to be the memory it may still use, and vtrack the cores it may
use (:mod:`vtrack.machine`), read from files laid out as Linux lays them out (``/proc``,
``/sys/fs/cgroup``), in a temporary folder the module's paths point at."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from vtrack import machine

MiB, GiB = 2**20, 2**30
V1_UNLIMITED = 9223372036854771712  # cgroup v1's memory.limit_in_bytes when none is set


@pytest.fixture
def system(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A machine with 8 GiB available whose cgroup files are yet to be written."""
    (tmp_path / "meminfo").write_text(f"MemTotal: {16 * GiB // 1024} kB\n"
                                      f"MemAvailable: {8 * GiB // 1024} kB\n")
    (tmp_path / "cgroup").mkdir()
    monkeypatch.setattr(machine, "_MEMINFO", str(tmp_path / "meminfo"))
    monkeypatch.setattr(machine, "_SELF_CGROUP", str(tmp_path / "self-cgroup"))
    monkeypatch.setattr(machine, "_CGROUP_MOUNT", str(tmp_path / "cgroup"))
    return tmp_path


def cgroup(folder: Path, **files: str | int) -> None:
    """Write a cgroup's files (``memory_max="max"`` -> ``memory.max``)."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name.replace("_", ".", 1)).write_text(f"{text}\n")


def test_a_cgroup_v2_job_is_bounded_by_its_own_limits_less_the_page_cache(system: Path
                                                                          ) -> None:
    """A Slurm job or a `systemd-run` scope (`0::/path` in /proc/self/cgroup): only
    /sys/fs/cgroup/memory.max was read (the root's, which has none), so the job's limit was
    not seen (8 GiB, the machine's); and page cache counted as used. Now the smallest of the
    limits up the tree counts, its inactive page cache free."""
    (system / "self-cgroup").write_text("0::/user.slice/job_7/step\n")
    root = system / "cgroup"
    cgroup(root / "user.slice", memory_max="max", memory_current=3 * GiB)
    cgroup(root / "user.slice/job_7", memory_max=GiB, memory_current=600 * MiB,
           memory_stat=f"anon {400 * MiB}\nfile {200 * MiB}\ninactive_file {200 * MiB}")
    cgroup(root / "user.slice/job_7/step", memory_max=2 * GiB, memory_current=500 * MiB)
    assert machine.available_memory() == GiB - (600 - 200) * MiB
    cgroup(root / "user.slice/job_7/step", memory_max=700 * MiB)  # the step's own is less
    assert machine.available_memory() == 200 * MiB
    cgroup(root / "user.slice/job_7", memory_max="max")
    cgroup(root / "user.slice/job_7/step", memory_max="max")  # no limit: the machine's
    assert machine.available_memory() == 8 * GiB


def test_a_cgroup_v1_memory_line_names_the_cgroup_read(system: Path) -> None:
    """cgroup v1 (`4:memory:/slurm/job_3`): the hierarchy's root limit was read, not the
    job's; its unlimited sentinel is no limit; total_inactive_file is not counted as used."""
    (system / "self-cgroup").write_text("5:cpu,cpuacct:/slurm/job_3\n4:memory:/slurm/job_3\n"
                                        "0::/\n")
    job = system / "cgroup/memory/slurm/job_3"
    cgroup(system / "cgroup/memory", memory_limit_in_bytes=V1_UNLIMITED,
           memory_usage_in_bytes=12 * GiB)
    cgroup(job, memory_limit_in_bytes=V1_UNLIMITED, memory_usage_in_bytes=300 * MiB)
    assert machine.available_memory() == 8 * GiB
    cgroup(job, memory_limit_in_bytes=GiB,
           memory_stat=f"inactive_file {50 * MiB}\ntotal_inactive_file {100 * MiB}")
    assert machine.available_memory() == GiB - (300 - 100) * MiB


def test_memory_files_that_cannot_be_read_are_left_out(system: Path) -> None:
    """A limit or a use that cannot be read (or holds no number) bounds nothing; a
    memory.stat that cannot be read counts no cache; with /proc/self/cgroup unreadable, the
    hierarchies' roots are read; with nothing readable the memory is not known."""
    (system / "self-cgroup").write_text("0::/job\n")
    job = system / "cgroup/job"
    cgroup(job, memory_max=GiB)
    (job / "memory.current").mkdir()  # cannot be read as a file
    assert machine.available_memory() == 8 * GiB
    (job / "memory.current").rmdir()
    cgroup(job, memory_current="many")
    assert machine.available_memory() == 8 * GiB
    cgroup(job, memory_current=100 * MiB)
    (job / "memory.stat").mkdir()
    assert machine.available_memory() == GiB - 100 * MiB
    (system / "self-cgroup").unlink()  # then the roots are read
    cgroup(system / "cgroup", memory_max=2 * GiB, memory_current=GiB)
    assert machine.available_memory() == GiB
    (system / "meminfo").unlink()
    (system / "cgroup/memory.max").unlink()
    assert machine.available_memory() is None


def affinity() -> int:
    """The cores this process may run on, a CPU quota aside."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
        os.cpu_count() or 1)


def test_a_cgroup_v2_cpu_quota_bounds_the_cores(system: Path) -> None:
    """A Kubernetes pod of 1 CPU on a 64-core node (`0::/kubepods/pod1/c1`, the pod's
    cpu.max "50000 100000"): cpu_count() read the affinity only (64), so the pod ran 64
    OpenCV and decoder threads. Now the least quota up the tree counts, rounded up, at least 1,
    at most the affinity; "max" is none."""
    (system / "self-cgroup").write_text("0::/kubepods/pod1/c1\n")
    root = system / "cgroup"
    cgroup(root / "kubepods", cpu_max="max 100000")
    cgroup(root / "kubepods/pod1", cpu_max="50000 100000")
    cgroup(root / "kubepods/pod1/c1", cpu_max="max 100000")
    assert machine.cpu_quota() == 1
    assert machine.cpu_count() == 1
    cgroup(root / "kubepods/pod1", cpu_max="150000 100000")  # 1.5 CPUs: 2 threads
    assert machine.cpu_quota() == 2
    assert machine.cpu_count() == min(2, affinity())
    cgroup(root / "kubepods/pod1/c1", cpu_max="1000 100000")  # the container's own is less
    assert machine.cpu_quota() == 1
    cgroup(root / "kubepods/pod1", cpu_max="6400000 100000")
    cgroup(root / "kubepods/pod1/c1", cpu_max="max 100000")
    assert machine.cpu_quota() == 64
    assert machine.cpu_count() == min(64, affinity())
    cgroup(root / "kubepods/pod1", cpu_max="max 100000")
    assert machine.cpu_quota() is None
    assert machine.cpu_count() == affinity()


def test_a_cgroup_v1_cpu_line_names_the_cgroup_read(system: Path) -> None:
    """cgroup v1 (`5:cpu,cpuacct:/docker/abc`): cpu.cfs_quota_us over cpu.cfs_period_us in
    the hierarchy the line names (-1: none); a container that sees only its own cgroup (the
    path is not there) is read at the hierarchy's root; a hierarchy mounted as the controller
    alone (`cpu`) is read there."""
    (system / "self-cgroup").write_text("5:cpu,cpuacct:/docker/abc\n4:memory:/docker/abc\n"
                                        "0::/\n")
    hierarchy = system / "cgroup/cpu,cpuacct"
    cgroup(hierarchy, cpu_cfs_quota_us=-1, cpu_cfs_period_us=100000)
    cgroup(hierarchy / "docker/abc", cpu_cfs_quota_us=250000, cpu_cfs_period_us=100000)
    assert machine.cpu_quota() == 3
    cgroup(hierarchy / "docker/abc", cpu_cfs_quota_us=-1)
    assert machine.cpu_quota() is None
    (hierarchy / "docker/abc/cpu.cfs_quota_us").unlink()
    (hierarchy / "docker/abc/cpu.cfs_period_us").unlink()
    (hierarchy / "docker/abc").rmdir()
    cgroup(hierarchy, cpu_cfs_quota_us=100000)  # the container's own, seen as the root
    assert machine.cpu_quota() == 1
    hierarchy.rename(system / "cgroup/cpu")
    assert machine.cpu_quota() == 1
    assert machine.cpu_count() == 1


def test_cpu_files_that_cannot_be_read_are_left_out(system: Path) -> None:
    """A quota or period that cannot be read, holds no number or a period of 0 bounds
    nothing; with /proc/self/cgroup unreadable, the hierarchies' roots are read."""
    (system / "self-cgroup").write_text("0::/job\n")
    job = system / "cgroup/job"
    cgroup(job, cpu_max="200000 0")
    assert machine.cpu_quota() is None
    cgroup(job, cpu_max="some 100000")
    assert machine.cpu_quota() is None
    (job / "cpu.max").unlink()
    (job / "cpu.max").mkdir()
    assert machine.cpu_quota() is None
    assert machine.cpu_count() == affinity()
    (system / "self-cgroup").unlink()  # then the roots are read: v2's, then v1's cpu
    cgroup(system / "cgroup/cpu", cpu_cfs_quota_us=200000, cpu_cfs_period_us=100000)
    assert machine.cpu_quota() == 2
    cgroup(system / "cgroup", cpu_max="100000 100000")
    assert machine.cpu_quota() == 1
