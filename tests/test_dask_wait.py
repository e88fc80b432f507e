"""`vtrack batch --scheduler`: no worker connected (say so, wait, give up after
--worker-timeout) and an unreachable scheduler (one line, no finaliser traceback). Loopback only."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from conftest import ClipFactory

distributed = pytest.importorskip("distributed")


def vtrack(*args: str, **kwargs: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, timeout=120, check=False, **kwargs)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory, clip_factory: ClipFactory) -> Path:
    clip = clip_factory("smooth", width=160, height=120, frames=24)
    folder = tmp_path_factory.mktemp("dask-in")
    shutil.copy(clip.path, folder / "smooth.mp4")
    shutil.copy(clip.gt, folder / "smooth.gt.txt")
    return folder


def closed_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]  # closed when the block ends: nothing listens there


def start_scheduler() -> tuple[subprocess.Popen[str], str]:
    """A ``dask scheduler`` on loopback, and its address once it says it."""
    scheduler = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
         "--port", str(closed_port()), "--no-dashboard"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert scheduler.stderr is not None
    for line in scheduler.stderr:  # "Scheduler at:   tcp://127.0.0.1:PORT"
        if "Scheduler at" in line:
            return scheduler, line.split()[-1]
    scheduler.wait(timeout=30)
    raise AssertionError("the scheduler said no address")


def run_with_a_worker(batch: subprocess.Popen[str], address: str) -> tuple[str, str]:
    """``batch``'s stdout and stderr once it ends, with one ``dask worker`` process of one
    thread started to connect to ``address`` (stopped after)."""
    worker = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "1",
         "--nthreads", "1", "--no-dashboard"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        return batch.communicate(timeout=120)
    finally:
        worker.terminate()
        worker.wait(timeout=30)


def assert_one_error(result: subprocess.CompletedProcess[str], *words: str) -> list[str]:
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr and "Exception ignored" not in result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("vtrack: error: ")]
    assert len(errors) == 1, result.stderr
    for word in words:
        assert word in errors[0]
    return lines


def test_no_worker_says_it_waits_and_gives_up(folder: Path, tmp_path: Path) -> None:
    with distributed.LocalCluster(n_workers=0, host="127.0.0.1", dashboard_address=None,
                                  processes=True) as cluster:
        result = vtrack("batch", str(folder), "--scheduler", cluster.scheduler_address,
                        "--worker-timeout", "1", "--no-video", "--out", str(tmp_path / "out"))
    lines = assert_one_error(result, cluster.scheduler_address, "no Dask worker", "1 s")
    assert lines[0].startswith("vtrack: waiting for a Dask worker")
    assert len(lines) == 2
    assert not (tmp_path / "out" / "summary.csv").exists()  # nothing ran, nothing recorded


def test_a_worker_that_connects_while_waiting_runs_the_batch(folder: Path,
                                                             tmp_path: Path) -> None:
    scheduler, address = start_scheduler()
    try:
        assert address.startswith("tcp://127.0.0.1:")
        batch = subprocess.Popen(
            [sys.executable, "-m", "vtrack", "batch", str(folder), "--scheduler", address,
             "--worker-timeout", "90", "--no-video", "--out", str(tmp_path / "out")],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert batch.stderr is not None
        first = batch.stderr.readline()
        assert first.startswith("vtrack: waiting for a Dask worker") and "90 s" in first
        out, err = run_with_a_worker(batch, address)
        assert batch.returncode == 0, first + err
        assert "1 run (1 complete)" in out
    finally:
        scheduler.terminate()
        scheduler.wait(timeout=30)


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM])
def test_a_scheduler_gone_while_the_batch_waits_for_a_worker_is_one_line(
        folder: Path, tmp_path: Path, signum: int) -> None:
    """`vtrack batch in/ --scheduler ADDRESS` waiting for a worker when its scheduler stopped
    (killed, or SIGTERM) ended in Dask's traceback (CommClosedError, or OSError "Timed out
    trying to connect"), exit 1. It is now one line naming the scheduler, exit 2, as the
    wait's own timeout is, and nothing is written."""
    scheduler, address = start_scheduler()
    try:
        batch = subprocess.Popen(
            [sys.executable, "-m", "vtrack", "batch", str(folder), "--scheduler", address,
             "--scheduler-timeout", "2", "--worker-timeout", "90", "--no-video", "--out",
             str(tmp_path / "out")],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert batch.stderr is not None
        first = batch.stderr.readline()
        assert first.startswith("vtrack: waiting for a Dask worker"), first
        scheduler.send_signal(signum)
        out, err = batch.communicate(timeout=120)
    finally:
        scheduler.kill()
        scheduler.wait(timeout=30)
    result = subprocess.CompletedProcess(batch.args, batch.returncode, out, first + err)
    lines = assert_one_error(result, f"--scheduler {address}: lost the connection to the "
                                     "scheduler before a worker connected")
    if "Timed out" in err or "within" in err:  # (SIGTERM: its reconnection gave up)
        assert "(no reconnection within 2 s, --scheduler-timeout)" in err, err
    assert len(lines) == 2 and out == ""
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:{port}", "foo://127.0.0.1:{port}"])
def test_an_unreachable_scheduler_is_one_line_without_a_finaliser_traceback(
        folder: Path, tmp_path: Path, address: str) -> None:
    address = address.format(port=closed_port())
    result = vtrack("batch", str(folder), "--scheduler", address, "--scheduler-timeout", "1",
                    "--out", str(tmp_path / "out"))
    lines = assert_one_error(result, address)
    assert len(lines) == 1


def test_a_refused_connection_is_said_at_once(folder: Path, tmp_path: Path) -> None:
    """Nothing listening: it waited the whole --scheduler-timeout, then said "Timed out" (the
    refusal is now told from the connection's own answer, not from a wait)."""
    address = f"tcp://127.0.0.1:{closed_port()}"
    result = vtrack("batch", str(folder), "--scheduler", address, "--scheduler-timeout", "20",
                    "--out", str(tmp_path / "out"))
    assert_one_error(result, address, "connection refused")


def test_a_waiting_line_nobody_reads_is_no_lost_scheduler(folder: Path, tmp_path: Path) -> None:
    """`vtrack batch in/ --scheduler ADDRESS 2>&1 | true` with no worker yet: the waiting line
    met the closed pipe, and its BrokenPipeError was taken for the scheduler gone ("lost the
    connection to the scheduler"), exit 2. The line is dropped; the batch waits, and runs once
    a worker connects."""
    scheduler, address = start_scheduler()
    reader, writer = os.pipe()
    os.close(reader)  # stderr's reader is gone from the start
    try:
        batch = subprocess.Popen(
            [sys.executable, "-m", "vtrack", "batch", str(folder), "--scheduler", address,
             "--worker-timeout", "90", "--no-video", "--out", str(tmp_path / "out")],
            stdout=subprocess.PIPE, stderr=writer, text=True)
        os.close(writer)
        with distributed.Client(address, set_as_default=False) as client:
            def others() -> set[str]:  # the scheduler's clients but this one
                ids = client.run_on_scheduler(lambda dask_scheduler: list(dask_scheduler.clients))
                return set(ids) - {client.id, "fire-and-forget"}
            while not others() and batch.poll() is None:  # until the batch connects
                time.sleep(0.05)
        out, _ = run_with_a_worker(batch, address)
        assert batch.returncode == 0
        assert "1 run (1 complete)" in out
    finally:
        scheduler.terminate()
        scheduler.wait(timeout=30)


def test_a_reconnection_given_up_names_scheduler_timeout() -> None:
    """A scheduler stopped by SIGTERM while the batch waited could end (as Dask's client
    retried) in "lost the connection ... (Timed out trying to connect to tcp://... after 2 s)",
    naming no option: the wait was --scheduler-timeout's."""
    from vtrack.batch.executors import lost_reason

    timed_out = OSError("Timed out trying to connect to tcp://127.0.0.1:8786 after 2 s")
    assert lost_reason(timed_out, 2) == "no reconnection within 2 s, --scheduler-timeout"
    reset = OSError("in <TCP (closed)>: ConnectionResetError: [Errno 104] Connection reset by peer")
    assert lost_reason(reset, 2) == "[Errno 104] Connection reset by peer"


def test_a_worker_without_vtrack_is_named_before_any_job_is_sent(folder: Path,
                                                                 tmp_path: Path) -> None:
    """A `dask worker` that cannot import vtrack (README: every worker needs the batch's
    version) died unpickling the first job (its `dask worker` process ended), and the batch,
    left without a worker, failed every row after --worker-timeout: "Dask: no worker
    connected to ADDRESS for 5 s", exit 1, never naming the cause. It is now one line naming
    the worker, what it lacks and the version to install, exit 2, before anything runs."""
    fake = tmp_path / "path" / "vtrack"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text('raise ImportError("no vtrack here")\n')
    scheduler, address = start_scheduler()
    worker = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "1",
         "--nthreads", "1", "--no-dashboard"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        env={**os.environ, "PYTHONPATH": str(tmp_path / "path")}, cwd=tmp_path)
    try:
        result = vtrack("batch", str(folder), "--scheduler", address, "--worker-timeout", "5",
                        "--no-video", "--out", str(tmp_path / "out"))
        assert worker.poll() is None  # the worker lives on, no job sent to it
    finally:
        worker.terminate()
        worker.wait(timeout=30)
        scheduler.terminate()
        scheduler.wait(timeout=30)
    from vtrack import __version__

    lines = assert_one_error(result, f"--scheduler {address}: worker tcp://127.0.0.1:",
                             "has no vtrack it can import (no vtrack here)",
                             f"every worker needs vtrack {__version__}")
    assert len(lines) == 1 or lines[0].startswith("vtrack: waiting for a Dask worker")
    assert not (tmp_path / "out" / "summary.csv").exists()


def test_a_stopped_worker_asked_which_vtrack_it_imports_cannot_hold_the_batch(
        folder: Path, tmp_path: Path) -> None:
    """A worker stopped (`kill -STOP` of a `dask worker --no-nanny`) before the batch asked
    which vtrack it imports held the batch for ever: the question had no time limit, and
    neither --worker-timeout nor --scheduler-timeout applied. It has the worker timeout now
    (30 s at most): one line names the worker that did not answer, exit 2, nothing run."""
    scheduler, address = start_scheduler()
    worker = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_worker", address, "--no-nanny",
         "--nthreads", "1", "--no-dashboard"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        with distributed.Client(address, timeout=30) as client:
            client.wait_for_workers(1, timeout=60)
        os.kill(worker.pid, signal.SIGSTOP)
        result = vtrack("batch", str(folder), "--scheduler", address, "--worker-timeout", "2",
                        "--no-video", "--out", str(tmp_path / "out"))
    finally:
        os.kill(worker.pid, signal.SIGCONT)
        worker.terminate()
        worker.wait(timeout=30)
        scheduler.terminate()
        scheduler.wait(timeout=30)
    assert_one_error(result, f"--scheduler {address}: worker tcp://127.0.0.1:",
                     "did not answer which vtrack it imports (no answer within 2 s)",
                     "no job is sent before every connected worker has")
    assert not (tmp_path / "out" / "summary.csv").exists()
