"""Issue 21 item 14: `vtrack batch --scheduler` honours --scheduler-timeout whatever the peer
does (accepts and stays silent, is the dashboard's HTTP port, is no address at all), and gives
up, with its summary, when every worker is gone for --worker-timeout. Loopback only."""

from __future__ import annotations

import contextlib
import csv
import json
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import START_BOUND_S

from vtrack.scenes import make_scene, write_groundtruth, write_video

distributed = pytest.importorskip("distributed")


def vtrack(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, timeout=120, check=False)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("dask-lost")
    scene = make_scene("smooth", seed=1, width=320, height=240, frames=600, fps=30.0)
    write_video(scene, folder / "a.mp4", preset="veryfast")
    write_groundtruth(scene, folder / "a.gt.txt")
    return folder


def one_error(result: subprocess.CompletedProcess[str], *words: str) -> str:
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr and "Exception ignored" not in result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("vtrack: error")]
    assert len(errors) == 1, result.stderr
    for word in words:
        assert word in errors[0], errors[0]
    return errors[0]


def test_a_silent_peer_times_out(folder: Path, tmp_path: Path) -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(8)
        accepted: list[socket.socket] = []
        thread = threading.Thread(target=lambda: accepted.append(server.accept()[0]),
                                  daemon=True)
        thread.start()
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        result = vtrack("batch", str(folder), "--scheduler", address, "--scheduler-timeout", "2",
                        "-o", str(tmp_path / "out"))
        for peer in accepted:
            peer.close()
    one_error(result, address, "no answer within 2 s")


def test_a_peer_that_speaks_another_protocol_first_is_one_line(folder: Path,
                                                               tmp_path: Path) -> None:
    """An SSH banner read as Dask's frame sizes asked NumPy for 2.8 EiB: a traceback."""
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(8)

        def greet() -> None:
            while True:
                try:
                    peer = server.accept()[0]
                except OSError:
                    return
                peer.sendall(b"SSH-2.0-OpenSSH_9.2p1\r\n")

        threading.Thread(target=greet, daemon=True).start()
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        result = vtrack("batch", str(folder), "--scheduler", address, "--scheduler-timeout", "3",
                        "-o", str(tmp_path / "out"))
    one_error(result, address, "not a Dask scheduler")


def test_a_malformed_address_is_one_line(folder: Path, tmp_path: Path) -> None:
    one_error(vtrack("batch", str(folder), "--scheduler", "tcp://[::zz]:x",
                     "--scheduler-timeout", "2", "-o", str(tmp_path / "out")), "[::zz]")


@pytest.mark.parametrize(("address", "said"), [
    ("tcp://127.0.0.1:8786/", "not '/': drop it"), ("127.0.0.1:8786/x?y", "not '/x?y'"),
    ("tcp://127.0.0.1:8786#a", "not '#a'"), ("tcp://me@127.0.0.1:8786", "no user@")])
def test_an_address_with_more_than_host_and_port_says_what_to_drop(address: str,
                                                                   said: str) -> None:
    """`--scheduler tcp://localhost:8786/` (a slash pasted from a browser) reached a running
    scheduler and was refused as "cannot reach the Dask scheduler (not a Dask scheduler)";
    `tcp://me@HOST:8786` waited the whole --scheduler-timeout, then "Timed out trying to
    connect". Both are refused before connecting, saying what to drop."""
    from vtrack.batch.executors import scheduler_address_problem

    problem = scheduler_address_problem(address)
    assert problem is not None and said in problem
    assert scheduler_address_problem(address.partition("/x")[0].rstrip("/#a")
                                     .replace("me@", "")) is None


@pytest.mark.parametrize("address", ["tcp:///h:8786", "tcp://:8786/x"])
def test_an_address_without_a_host_says_so_before_what_follows_the_port(address: str) -> None:
    """`--scheduler tcp:///h:8786` (a third slash) was told "nothing follows the port in
    tcp://HOST:PORT, not '/h:8786': drop it", and dropping it leaves no host: a missing host
    is said first."""
    from vtrack.batch.executors import scheduler_address_problem

    assert scheduler_address_problem(address) == "no host: give tcp://HOST:PORT"


@pytest.mark.parametrize("address", ["tcp://h/x", "tcp://h?y"])
def test_an_address_without_a_port_says_so_before_what_follows_it(address: str) -> None:
    """`--scheduler tcp://h/x` was told "nothing follows the port in tcp://HOST:PORT, not
    '/x': drop it", and dropping it leaves no port: a missing port is said first."""
    from vtrack.batch.executors import scheduler_address_problem

    assert scheduler_address_problem(address).startswith("no port: give tcp://HOST:PORT")


def start(command: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", *command], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)


def start_scheduler() -> tuple[subprocess.Popen[str], str]:
    """A local scheduler on a free port, and its address once it listens."""
    scheduler = start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                       "--no-dashboard"])
    assert scheduler.stderr is not None
    for line in scheduler.stderr:
        if "Scheduler at" in line:
            return scheduler, line.split("Scheduler at:")[1].strip()
    raise AssertionError("the scheduler did not start")


@contextlib.contextmanager
def batch_on_a_cluster(folder: Path, out: Path) -> Iterator[
        tuple[str, subprocess.Popen[str], subprocess.Popen[str], subprocess.Popen[str]]]:
    """A local scheduler, one worker and a ``slow`` batch of ``folder`` on them, yielded once
    its job has tracked a few frames (their rows are on disk as they are written: header + 3
    rows): ``(address, scheduler, worker, batch)``. Whatever is still running is killed at
    the end."""
    scheduler, address = start_scheduler()
    worker = batch = None
    try:
        worker = start(["distributed.cli.dask_worker", address, "--nthreads", "1",
                        "--no-nanny", "--no-dashboard"])
        batch = subprocess.Popen(
            [sys.executable, "-m", "vtrack", "batch", str(folder), "--scheduler", address,
             "--preset", "slow", "-o", str(out)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + START_BOUND_S
        while not any(p.read_bytes().count(b"\n") > 3
                      for p in (out / "a").glob("*/.track.tmp-*.csv")):
            assert time.monotonic() < deadline and batch.poll() is None, "the job should start"
            time.sleep(0.05)
        yield address, scheduler, worker, batch
    finally:
        for process in (batch, worker, scheduler):
            if process is not None and process.poll() is None:
                process.kill()
                process.wait()


def test_the_dashboard_port_and_a_batch_whose_workers_all_die(folder: Path,
                                                              tmp_path: Path) -> None:
    with socket.socket() as a, socket.socket() as b:
        a.bind(("127.0.0.1", 0))
        b.bind(("127.0.0.1", 0))
        port, dashboard = a.getsockname()[1], b.getsockname()[1]
    scheduler = start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port",
                       str(port), "--dashboard-address", f"127.0.0.1:{dashboard}"])
    worker = batch = None
    try:
        assert scheduler.stderr is not None
        for line in scheduler.stderr:
            if "Scheduler at" in line:
                break
        time.sleep(1)  # the dashboard starts right after
        one_error(vtrack("batch", str(folder), "--scheduler", f"tcp://127.0.0.1:{dashboard}",
                         "--scheduler-timeout", "2", "-o", str(tmp_path / "x")),
                  str(dashboard))
        worker = start(["distributed.cli.dask_worker", f"tcp://127.0.0.1:{port}", "--nthreads",
                        "1", "--no-nanny", "--no-dashboard"])
        out = tmp_path / "out"
        batch = subprocess.Popen(
            [sys.executable, "-m", "vtrack", "batch", str(folder), "--scheduler",
             f"tcp://127.0.0.1:{port}", "--worker-timeout", "2", "--preset", "slow",
             "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + START_BOUND_S
        while not list((out / "a").glob("*/.track.tmp-*.csv")):
            assert time.monotonic() < deadline and batch.poll() is None, "the job should start"
            time.sleep(0.05)
        worker.send_signal(signal.SIGKILL)
        worker.wait()
        stdout, stderr = batch.communicate(timeout=60)
    finally:
        for process in (batch, worker, scheduler):
            if process is not None and process.poll() is None:
                process.kill()
                process.wait()
    assert batch.returncode == 1, stderr
    assert "Traceback" not in stderr
    assert "no worker connected" in stderr and "--worker-timeout" in stderr
    with (out / "summary.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [row["status"] for row in rows] == ["failed"]
    assert "no worker connected" in rows[0]["error"]


@pytest.mark.parametrize(("signum", "error"), [(signal.SIGINT, "interrupted by the user"),
                                                (signal.SIGTERM, "interrupted by SIGTERM")],
                         ids=["SIGINT", "SIGTERM"])
def test_a_stopped_batch_stops_its_running_job(folder: Path, tmp_path: Path, signum: int,
                                               error: str) -> None:
    """Ctrl-C cancelled the job's future, but a Dask task already running is not stopped by
    that: the batch reported it ``interrupted`` while the worker went on and finished it (its
    run.json then said ``complete``, the summary ``interrupted``). The job's records name the
    signal the batch got: a SIGTERM was recorded as "interrupted by the user"."""
    out = tmp_path / "out"
    with batch_on_a_cluster(folder, out) as (_, _, _, batch):
        batch.send_signal(signum)
        _, stderr = batch.communicate(timeout=60)
        records = list(out.glob("a/*/run.json"))
        assert len(records) == 1, stderr  # the job recorded itself before the batch ended
        first = json.loads(records[0].read_text())
        time.sleep(3)  # the worker does not carry on with the job
        last = json.loads(records[0].read_text())
    assert batch.returncode == 128 + signum, stderr
    assert "Traceback" not in stderr
    assert first["status"] == last["status"] == "interrupted", (first, last)
    assert first["error"] == error, first
    assert 0 < first["frames"] < 600 and last == first
    with (out / "summary.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [(row["status"], row["error"]) for row in rows] == [("interrupted", error)]


def test_a_scheduler_lost_mid_batch_is_one_line_per_job_and_the_job_carries_on(
        folder: Path, tmp_path: Path) -> None:
    """The scheduler stopped (SIGTERM) while a job ran: the batch printed Dask's reconnect
    traceback and a two-line error per job ('... cancelled for reason:
    scheduler-connection-lost.' then 'Client lost the connection ...'), also two lines in
    summary.csv; on the worker, which its scheduler closed, the job's check of the stop event
    raised AttributeError: the run ended ``failed`` (internal error, error.log) part way.
    The job's error said only "its outcome is unknown", while the job went on to write a
    complete run.json: it now says so, and the same batch run again takes that run up."""
    out = tmp_path / "out"
    with batch_on_a_cluster(folder, out) as (address, scheduler, worker, batch):
        scheduler.send_signal(signal.SIGTERM)
        _, stderr = batch.communicate(timeout=60)
        worker.wait(timeout=120)  # closed by its scheduler, once its running job has ended
    assert batch.returncode == 1, stderr
    assert "Traceback" not in stderr, stderr
    # (the batch's progress lines come too on a slow machine: stderr is no terminal here; so
    # does the notice that it waits for the worker, when the batch is quicker to reach the
    # scheduler than the worker, started first, is)
    errors = [line for line in stderr.splitlines() if line.startswith("vtrack:")
              and not line.startswith("vtrack: waiting for a Dask worker")]
    assert len(errors) == 1 and errors[0].startswith("vtrack: error: a [robust]: failed: "), stderr
    assert f"lost the connection to the scheduler {address}" in errors[0]
    with (out / "summary.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [row["status"] for row in rows] == ["failed"]
    assert "\n" not in rows[0]["error"] and address in rows[0]["error"]
    run = out / "a" / "robust"
    assert not (run / "error.log").exists(), (run / "error.log").read_text()
    record = json.loads((run / "run.json").read_text())
    assert (record["status"], record["frames"]) == ("complete", 600), record
    assert errors[0].endswith("its outcome is unknown here: a running job may still end on its "
                              "worker and write its run.json (the same vtrack batch again takes "
                              "up a complete one, vtrack report shows it)")
    again = vtrack("batch", str(folder), "--preset", "slow", "-o", str(out))
    assert again.returncode == 0, again.stderr
    assert "1 of them complete before, not run again" in again.stdout
    with (out / "summary.csv").open() as handle:
        assert [row["status"] for row in csv.DictReader(handle)] == ["complete"]


def test_a_job_done_before_its_worker_died_is_not_run_again(tmp_path: Path) -> None:
    """A worker that had finished job ``a`` died while it ran ``b``: the batch still held
    ``a``'s future, so Dask ran ``a`` again on the next worker ("lose already computed
    task(s), which will be recomputed elsewhere"), rewriting a/robust after the batch had
    reported it: summary.csv's row (its fps) and .summary-sources.json then no longer agreed
    with a/robust/run.json. A job reported is now released: its folder is not touched again."""
    folder = tmp_path / "in"
    folder.mkdir()
    for name, frames in (("a", 20), ("b", 600)):
        scene = make_scene("smooth", seed=1, width=320, height=240, frames=frames, fps=30.0)
        write_video(scene, folder / f"{name}.mp4", preset="veryfast")
        write_groundtruth(scene, folder / f"{name}.gt.txt")
    out = tmp_path / "out"
    scheduler, address = start_scheduler()
    workers: list[subprocess.Popen[str]] = []
    batch = None
    try:
        worker_args = ["distributed.cli.dask_worker", address, "--nthreads", "1",
                       "--no-nanny", "--no-dashboard"]
        workers.append(start(worker_args))
        batch = subprocess.Popen(
            [sys.executable, "-m", "vtrack", "batch", str(folder), "--scheduler", address,
             "--preset", "slow", "-o", str(out)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert batch.stdout is not None
        first = batch.stdout.readline()  # the batch has taken a's outcome
        assert first.startswith("a [robust]: 20 frames"), first
        deadline = time.monotonic() + START_BOUND_S
        while not list((out / "b").glob("*/.track.tmp-*.csv")):  # b runs
            assert time.monotonic() < deadline and batch.poll() is None, "b should start"
            time.sleep(0.05)
        record = out / "a" / "robust" / "run.json"
        before = (record.read_bytes(), record.stat().st_mtime_ns)
        workers.append(start(worker_args))
        workers[0].send_signal(signal.SIGKILL)
        workers[0].wait()
        _, stderr = batch.communicate(timeout=120)
        time.sleep(2)  # (a job run again after the batch ended would be writing now)
    finally:
        for process in (batch, *workers, scheduler):
            if process is not None and process.poll() is None:
                process.kill()
                process.wait()
    assert batch.returncode == 0, stderr
    assert (record.read_bytes(), record.stat().st_mtime_ns) == before
    with (out / "summary.csv").open() as handle:
        rows = {row["input"]: row for row in csv.DictReader(handle)}
    assert rows["a"]["status"] == rows["b"]["status"] == "complete", rows
    fps = json.loads(record.read_text())["timing"]["fps"]
    assert float(rows["a"]["fps"]) == pytest.approx(fps, abs=1e-5), (rows["a"], fps)
