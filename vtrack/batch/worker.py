"""One job in a worker process (local or Dask): run it, never raise for a broken input."""

from __future__ import annotations

import contextlib
import logging
import os
import select
import signal
import threading
import time
import traceback
from collections.abc import Callable, Mapping
from dataclasses import replace
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import cv2

from vtrack.batch.jobs import Job, Outcome, Progress, read_row
from vtrack.batch.plan import recorded_summary
from vtrack.errors import (
    BATCH_NAMES,
    FolderInUseError,
    Interrupted,
    OutputBrokenError,
    OutputError,
    VtrackError,
)
from vtrack.io import InputInfo
from vtrack.io.outdir import OutputFolder
from vtrack.machine import cpu_count
from vtrack.run import STATUS_FAILED, STATUS_INTERRUPTED, RunSummary, run

#: How long a job waits for its folder while another vtrack holds it (seconds).
LOCK_WAIT_S = 15.0


#: Seconds between two progress messages of a running job.
PROGRESS_PERIOD = 0.25
#: Seconds between two questions a Dask job asks the scheduler: is the batch stopped?
STOP_CHECK_S = 1.0
Report = Callable[[Progress], None]


def execute(job: Job, report: Report | None = None) -> Outcome:
    """Run one job; never raises for a broken input or a bug.

    This is what a worker process (local or Dask) calls. The run replaces what an earlier run
    left in the job's folder (:func:`vtrack.run.run`); a job that fails before it starts
    tracking removes those old results too, so no earlier ``run.json`` outlives it, while one
    that fails part way keeps the outputs and records its run wrote (as ``vtrack run`` does,
    its ``track.csv`` too when there was no room for its ``run.json``). A user
    error becomes a ``failed`` outcome with its one-line message; an unexpected exception also
    leaves its traceback in ``error.log`` in the job's folder. ``report`` receives the job's
    :class:`Progress` at most every :data:`PROGRESS_PERIOD` seconds while it tracks.
    """
    cv2.setNumThreads(job.threads)
    out_dir = job.request.out_dir
    started = time.time()
    try:
        summary = _run_when_free(job, report)
    except VtrackError as exc:
        # failed part way (a full disk): what the run wrote stays, as vtrack run leaves it,
        # even when there was no room for its run.json
        recorded = (recorded_summary(job.request, since=started)
                    if isinstance(exc, OutputBrokenError) else _discard(job, started))
        if recorded is not None:  # failed part way (a full disk): its row is its run.json's
            return _outcome(job, replace(recorded, status=STATUS_FAILED, error=str(exc)))
        return Outcome(job.input, job.config, STATUS_FAILED, error=str(exc), attempt=job.attempt)
    except Exception as exc:  # a bug in one run must not take the batch down: record it
        _discard(job, started)
        log: Path | None = out_dir / "error.log"
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
            log.write_text(traceback.format_exc(), encoding="utf-8")
        except OSError:
            log = None
        where = f" (traceback in {log})" if log else ""
        return Outcome(job.input, job.config, STATUS_FAILED,
                       error=f"internal error: {type(exc).__name__}: {exc}{where}",
                       attempt=job.attempt)
    return _outcome(job, summary)


def _outcome(job: Job, summary: RunSummary) -> Outcome:
    """The outcome of ``job``, whose run ended as ``summary`` says, with the ``summary.csv``
    row of the run its folder holds (read here, in the worker)."""
    row, source = None, None
    with contextlib.suppress(Exception):  # (the batch reads it then: never fails the job)
        row, source = read_row(Path(summary.out_dir)) if summary.out_dir else ({}, None)
    return Outcome(job.input, job.config, summary.status, summary, summary.error, job.attempt,
                   row=row, row_source=source)


def stop_signal_name(stop_event: str) -> str:
    """The name of the Dask ``Variable`` that holds the signal (its number) a Dask batch was
    stopped by, beside its stop ``Event`` named ``stop_event``."""
    return f"{stop_event}-signal"


def dask_threads() -> int:
    """The OpenCV threads of a job on this Dask worker: this machine's cores
    (:func:`~vtrack.machine.cpu_count`, the worker's own) over the jobs the workers at this
    worker's host address run at once (:func:`tasks_at_host`), at least 1: as a local batch
    shares the cores among its workers.
    ``dask worker --nworkers 2 --nthreads 1`` on 8 cores: 4 a job."""
    from distributed import get_client, get_worker

    worker = get_worker()
    tasks = tasks_at_host(worker.address, worker.state.nthreads,
                          lambda: get_client().scheduler_info(n_workers=-1)["workers"])
    return max(1, cpu_count() // max(1, tasks))


def tasks_at_host(address: str, own: int,
                  listed: Callable[[], Mapping[str, Mapping[str, Any]]]) -> int:
    """The tasks the Dask workers at the host of the worker at ``address`` run at once: the
    sum of their threads, as ``listed()`` (the scheduler's workers by address) gives them.
    Any error there (the scheduler gone, no entry for ``address``, an answer not as expected)
    only costs that guess: it returns ``own`` (the worker's own threads) and leaves a
    warning, with its traceback, in the worker's log (``distributed.worker``)."""
    try:
        workers = listed()
        host = workers[address]["host"]
        return sum(int(entry["nthreads"]) for entry in workers.values()
                   if entry.get("host") == host)
    except Exception:  # a thread-count guess must never fail the job
        logging.getLogger("distributed.worker").warning(
            "vtrack: the workers at this worker's host are not known: a job's OpenCV threads "
            "are its cores over this worker's %d tasks", own, exc_info=True)
        return own


def execute_on_dask(job: Job, stop_event: str) -> Outcome:
    """:func:`execute` as a Dask task: the batch sets the Dask ``Event`` named ``stop_event``
    when it is stopped (Ctrl-C, SIGTERM), after putting the signal it got in the ``Variable``
    :func:`stop_signal_name` names. A job that has not started by then returns
    ``interrupted`` without touching its folder; a running one asks the scheduler about the
    event at most every :data:`STOP_CHECK_S` seconds of tracking (with its progress reports)
    and ends ``interrupted``, its records whole, as a local worker's job does: its error
    names that signal (``interrupted by the user`` for SIGINT, ``interrupted by SIGTERM``;
    SIGINT if the scheduler cannot say). An event the scheduler cannot answer for (a lost
    connection, a worker whose scheduler closed it) counts as not set: the job carries on."""
    from distributed import Event, Variable

    stop = Event(stop_event)
    stop_signal = Variable(stop_signal_name(stop_event))

    def stopped() -> Interrupted | None:
        try:
            if not stop.is_set():
                return None
        except Exception:  # lost (OSError), or the worker closing: its client is gone
            return None
        try:
            return Interrupted(signal.Signals(int(stop_signal.get(timeout=STOP_CHECK_S))))
        except Exception:  # not set, not a signal, the scheduler gone: as on Ctrl-C
            return Interrupted(signal.SIGINT)

    interrupted = stopped()
    if interrupted is not None:
        return Outcome(job.input, job.config, STATUS_INTERRUPTED, error=interrupted.reason,
                       attempt=job.attempt)
    checked = time.monotonic()

    def check(progress: Progress) -> None:
        nonlocal checked
        now = time.monotonic()
        if progress.frames and now - checked >= STOP_CHECK_S:
            checked = now
            interrupted = stopped()
            if interrupted is not None:
                raise interrupted

    return execute(replace(job, threads=dask_threads()), check)


class _Reporter:
    """``on_open`` / ``on_frame`` of one run, as :class:`Progress` messages to ``report``.

    A message that cannot be sent (the batch process is gone: its end of the connection is
    closed) ends the reporting, never the run: the run is stopped by the SIGTERM of
    :func:`_die_with_parent`, which ends it ``interrupted`` with its records whole. Raising
    here instead would fail the run, and the SIGTERM arriving while it closes its outputs
    could cut its ``run.json`` short."""

    def __init__(self, job: Job, report: Report) -> None:
        self.job, self.report = job, report
        self.info: InputInfo | None = None
        self.last = time.monotonic()
        self.connected = True

    def on_open(self, info: InputInfo) -> None:
        self.info = info
        self._send(0)

    @property
    def total(self) -> int | None:
        """The frames the run will track, as far as the input's count tells (read again each
        time: the reader replaces an estimated count as it reads)."""
        if self.info is None:
            return None
        return self.job.request.frames_expected(self.info.frame_count, self.info.fps)

    def on_frame(self, done: int, seconds: float) -> None:
        now = time.monotonic()
        if now - self.last >= PROGRESS_PERIOD:
            self.last = now
            self._send(done)

    def _send(self, done: int) -> None:
        if not self.connected:
            return
        try:
            self.report(Progress(self.job.input, self.job.config, done, self.total))
        except OSError:  # BrokenPipeError, ConnectionResetError: the batch went away
            self.connected = False


def _run_when_free(job: Job, report: Report | None = None) -> RunSummary:
    """:func:`vtrack.run.run`, waiting up to :data:`LOCK_WAIT_S` for the job's folder while
    another vtrack holds it (a worker of a batch that was just killed, finishing its frame and
    its record): then the run replaces what that one recorded."""
    deadline = time.monotonic() + LOCK_WAIT_S
    progress = _Reporter(job, report) if report is not None else None
    on_frame = progress.on_frame if progress is not None else None
    on_open = progress.on_open if progress is not None else None
    while True:
        try:
            # a batch's messages name the options its runs share with vtrack run, as before
            # the library's names (init_box, start, out_dir) are for run()'s own callers
            return run(job.request, on_frame=on_frame, on_open=on_open,
                       names=BATCH_NAMES)
        except FolderInUseError:
            if time.monotonic() >= deadline:
                raise
            time.sleep(0.2)


def _die_with_parent(connection: Connection) -> None:
    """Stop this worker process when the batch process goes away, however it ends (``kill
    -9`` included): a thread waits for the batch's end of ``connection`` to close, then
    sends this process SIGTERM, so a running job ends ``interrupted`` as on Ctrl-C (its
    outputs whole, its ``run.json`` written) and the process exits. Linux only
    (``POLLRDHUP``); elsewhere the worker stops at its next job."""
    hang_up = getattr(select, "POLLRDHUP", None)
    if hang_up is None:
        return
    poller = select.poll()
    poller.register(connection.fileno(), hang_up)

    def watch() -> None:
        while not poller.poll():
            pass
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, name="vtrack parent watch", daemon=True).start()


def _discard(job: Job, started: float) -> RunSummary | None:
    """Remove an earlier run's outputs from the job's folder (unless another run holds it),
    unless this job's run recorded itself there since ``started`` (it failed part way): then
    return the summary its ``run.json`` records (else None)."""
    out_dir = job.request.out_dir
    if not out_dir.is_dir():
        return None
    recorded = recorded_summary(job.request, since=started)
    if recorded is None:
        with contextlib.suppress(OutputError), OutputFolder(out_dir) as folder:
            folder.clear()
    return recorded


def _serve(connection: Connection) -> None:
    """A local worker process: run each job received, send back its outcome; stop at None
    (or when the batch process is gone, :func:`_die_with_parent`)."""
    _die_with_parent(connection)
    try:
        while (job := connection.recv()) is not None:
            try:
                outcome = execute(job, connection.send)
            except KeyboardInterrupt:
                outcome = Outcome(job.input, job.config, STATUS_INTERRUPTED, error="interrupted",
                                  attempt=job.attempt)
            connection.send(outcome)
    except (EOFError, OSError, KeyboardInterrupt):
        pass  # the batch went away or was interrupted: nothing left to do
