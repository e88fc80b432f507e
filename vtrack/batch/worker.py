"""One job in a worker process (local or Dask): run it, never raise for a broken input."""

from __future__ import annotations

import shutil
import traceback
from multiprocessing.connection import Connection

import cv2

from vtrack.batch.jobs import Job, Outcome
from vtrack.errors import VtrackError
from vtrack.run import STATUS_FAILED, STATUS_INTERRUPTED, run


def execute(job: Job) -> Outcome:
    """Run one job from an emptied results folder; never raises for a broken input or a bug.

    This is what a worker process (local or Dask) calls. A user error becomes a ``failed``
    outcome with its one-line message; an unexpected exception also leaves its traceback in
    ``error.log`` in the job's folder.
    """
    cv2.setNumThreads(job.threads)
    out_dir = job.request.out_dir
    shutil.rmtree(out_dir, ignore_errors=True)
    try:
        summary = run(job.request)
    except VtrackError as exc:
        return Outcome(job.input, job.config, STATUS_FAILED, error=str(exc), attempt=job.attempt)
    except Exception as exc:  # a bug in one run must not take the batch down: record it
        log = out_dir / "error.log"
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
            log.write_text(traceback.format_exc(), encoding="utf-8")
        except OSError:
            log = None
        where = f" (traceback in {log})" if log else ""
        return Outcome(job.input, job.config, STATUS_FAILED,
                       error=f"internal error: {type(exc).__name__}: {exc}{where}",
                       attempt=job.attempt)
    return Outcome(job.input, job.config, summary.status, summary, summary.error, job.attempt)


def _serve(connection: Connection) -> None:
    """A local worker process: run each job received, send back its outcome; stop at None."""
    try:
        while (job := connection.recv()) is not None:
            try:
                outcome = execute(job)
            except KeyboardInterrupt:
                outcome = Outcome(job.input, job.config, STATUS_INTERRUPTED, error="interrupted",
                                  attempt=job.attempt)
            connection.send(outcome)
    except (EOFError, OSError, KeyboardInterrupt):
        pass  # the batch went away or was interrupted: nothing left to do
