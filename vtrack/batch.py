"""Folders of inputs: every input x configuration, in parallel, resumable, failure-isolated.

``vtrack batch`` is :func:`find_inputs` -> :func:`plan` -> :func:`run_batch` (through a
:class:`LocalExecutor` or :class:`DaskExecutor`). Each job is one :func:`vtrack.run.run`
writing the files of ``vtrack run`` into ``OUT/<input>/<config>/``; ``OUT/summary.csv`` has one
row per input x config and is rewritten (atomically) as each job finishes.

Inputs (:func:`find_inputs`), looked for directly inside the folder:

- video files (by suffix, :data:`VIDEO_SUFFIXES`), with ground truth beside them:
  ``name.gt.txt`` or ``name.txt`` (single target, ``x,y,w,h`` lines) and ``name.mot.txt``
  (MOTChallenge, for multi-target configs);
- sequence folders (OTB layout: an ``img/`` folder), with ground truth inside them:
  ``groundtruth_rect.txt`` or ``groundtruth.txt`` (single target) and ``groundtruth_mot.txt``,
  ``gt.txt`` or ``gt/gt.txt`` (MOTChallenge).

An input without single-target ground truth still runs: detecting (multi-target) configs need
nothing, single-target ones take their first box from ``name.init.txt`` beside the video or
``init.txt`` in the sequence folder (one ``x,y,w,h`` line); its ``track.csv`` then has no overlap.

Ground-truth origin (``gt_origin=None``, the CLI's ``--gt-origin auto``): a sequence folder's
file is read as OTB's 1-based MATLAB boxes (OTB, VOT, UAV123 and LaSOT ship them that way), a file
beside a video as 0-based (what ``vtrack scene`` writes). ``0`` or ``1`` forces one origin on all.

Resume: a job whose ``run.json`` says ``complete`` and records the same configuration, input,
ground truth, seed and output settings is skipped (status ``skipped``); anything else is run
again from an emptied folder. Failure isolation: a job's user error (unreadable input, bad
ground truth) or crash is recorded in its row (status ``failed``); an input that breaks part way
is ``partial``. A worker process that dies is retried once, then reported ``failed``.
"""

from __future__ import annotations

import csv
import io
import json
import multiprocessing
import os
import shutil
import signal
import traceback
import uuid
from collections import deque
from collections.abc import Iterable, Iterator, Sequence
from contextlib import closing, suppress
from dataclasses import dataclass, fields, replace
from multiprocessing.connection import Connection, wait
from pathlib import Path
from typing import Any, Protocol

import cv2

from vtrack.config import Config
from vtrack.errors import InputError, VtrackError
from vtrack.evaluate.groundtruth import read_boxes
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.run import (
    STATUS_COMPLETE,
    STATUS_FAILED,
    STATUS_INTERRUPTED,
    RunRequest,
    RunSummary,
    run,
)

#: File suffixes taken as video inputs (anything else beside them is ignored).
VIDEO_SUFFIXES = frozenset({
    ".mp4", ".m4v", ".mov", ".mkv", ".webm", ".avi", ".ts", ".mts", ".m2ts", ".mpg", ".mpeg",
    ".flv", ".wmv", ".ogv", ".3gp", ".y4m", ".h264", ".264", ".h265", ".hevc", ".mjpeg",
})
#: Single-target ground truth inside a sequence folder, first found wins.
SEQUENCE_GT = ("groundtruth_rect.txt", "groundtruth.txt")
#: MOTChallenge ground truth inside a sequence folder, first found wins.
SEQUENCE_MOT_GT = ("groundtruth_mot.txt", "gt.txt", "gt/gt.txt")
#: Single-target ground truth beside ``name.mp4`` (``{}`` is the name), first found wins.
VIDEO_GT = ("{}.gt.txt", "{}.txt")
#: MOTChallenge ground truth beside ``name.mp4``.
VIDEO_MOT_GT = ("{}.mot.txt",)
#: Initial box of an input without single-target ground truth (video, sequence folder).
VIDEO_INIT, SEQUENCE_INIT = "{}.init.txt", "init.txt"

STATUS_SKIPPED = "skipped"
#: ``summary.csv`` columns, in order.
SUMMARY_COLUMNS = ("input", "config", "frames", "fps", "mean_overlap", "auc", "precision20",
                   "frames_lost", "status", "error")
#: How often a job whose worker process died is started again before it is reported failed.
RETRIES = 1


@dataclass(frozen=True)
class BatchInput:
    """One input of a batch folder: its unique name (the results folder), path and ground truth.

    ``groundtruth`` is for single-target configs, ``mot_groundtruth`` for multi-target ones;
    ``init`` holds the first box when there is no ``groundtruth``; ``gt_origin`` is the origin
    of the boxes of ``groundtruth`` and ``init`` (see the module docstring).
    """

    name: str
    path: Path
    groundtruth: Path | None = None
    mot_groundtruth: Path | None = None
    init: Path | None = None
    gt_origin: int = 0


@dataclass(frozen=True)
class Job:
    """One input x config: what a worker needs (paths and settings, never frames)."""

    input: str
    config: str
    request: RunRequest
    threads: int = 1
    attempt: int = 1


@dataclass
class Outcome:
    """What became of a job: a status of ``vtrack.run`` or ``failed`` / ``skipped``."""

    input: str
    config: str
    status: str
    summary: RunSummary | None = None
    error: str | None = None
    #: Which attempt this is: 2 after a worker process died running the job.
    attempt: int = 1

    @property
    def ok(self) -> bool:
        return self.status in (STATUS_COMPLETE, STATUS_SKIPPED)

    def line(self) -> str:
        """One line for the terminal: the run's summary line, or what went wrong."""
        if self.status == STATUS_FAILED or self.summary is None:
            line = f"{self.input} [{self.config}]: {self.status}: {self.error}"
        else:
            line = self.summary.line()
        if self.status == STATUS_SKIPPED:
            line += " (skipped: already complete)"
        if self.attempt > 1:
            line += f" (attempt {self.attempt}: a worker process died on this job before)"
        return line

    def row(self) -> dict[str, Any]:
        """This job's ``summary.csv`` row (:data:`SUMMARY_COLUMNS`)."""
        s = self.summary
        return {
            "input": self.input,
            "config": self.config,
            "frames": s.frames if s else None,
            "fps": _round(s.fps, 1) if s else None,
            "mean_overlap": _round(s.mean_overlap, 4) if s else None,
            "auc": _round(s.auc, 4) if s else None,
            "precision20": _round(s.precision20, 4) if s else None,
            "frames_lost": s.frames_lost if s else None,
            "status": self.status,
            "error": self.error,
        }


def _round(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


# --- finding inputs --------------------------------------------------------------------------

def _first(folder: Path, names: Iterable[str]) -> Path | None:
    return next((folder / n for n in names if (folder / n).is_file()), None)


def _sequence(folder: Path, gt_origin: int | None) -> BatchInput:
    return BatchInput(
        name=folder.name,
        path=folder,
        groundtruth=_first(folder, SEQUENCE_GT),
        mot_groundtruth=_first(folder, SEQUENCE_MOT_GT),
        init=_first(folder, [SEQUENCE_INIT]),
        gt_origin=1 if gt_origin is None else gt_origin,
    )


def _video(path: Path, name: str, gt_origin: int | None) -> BatchInput:
    stem = path.stem
    return BatchInput(
        name=name,
        path=path,
        groundtruth=_first(path.parent, (p.format(stem) for p in VIDEO_GT)),
        mot_groundtruth=_first(path.parent, (p.format(stem) for p in VIDEO_MOT_GT)),
        init=_first(path.parent, [VIDEO_INIT.format(stem)]),
        gt_origin=0 if gt_origin is None else gt_origin,
    )


def is_sequence_folder(path: Path) -> bool:
    """An OTB-style image-sequence folder: it holds an ``img/`` folder."""
    return (path / "img").is_dir()


def find_inputs(folder: Path, gt_origin: int | None = None) -> list[BatchInput]:
    """Every input directly inside ``folder`` (or ``folder`` itself if it is a sequence folder),
    sorted by name, with the ground truth found beside or inside each (module docstring).

    Inputs are named after their file stem (folder name for sequences); videos whose stem is
    taken twice (``a.mp4`` and ``a.avi`` or a folder ``a/``) keep their full file names.
    Raises InputError when ``folder`` is not a folder or holds no input.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder")
    if is_sequence_folder(folder):
        return [_sequence(folder.resolve(), gt_origin)]
    entries = sorted(folder.resolve().iterdir())
    videos = [p for p in entries if p.is_file() and p.suffix.lower() in VIDEO_SUFFIXES]
    found = [_sequence(p, gt_origin) for p in entries if p.is_dir() and is_sequence_folder(p)]
    taken = [item.name for item in found] + [p.stem for p in videos]
    found += [_video(p, p.stem if taken.count(p.stem) == 1 else p.name, gt_origin)
              for p in videos]
    if not found:
        raise InputError(
            f"{folder}: no inputs (video files or sequence folders with an img/ folder)"
        )
    return sorted(found, key=lambda i: i.name)


# --- planning --------------------------------------------------------------------------------

def completed_summary(request: RunRequest) -> RunSummary | None:
    """The summary of a finished run of exactly ``request`` in ``request.out_dir``, else None.

    Finished means ``run.json`` (written last, atomically) says ``complete``; exactly means its
    ``request`` is this one, every field (:meth:`RunRequest.same_run`).
    """
    try:
        record = json.loads((request.out_dir / "run.json").read_text(encoding="utf-8"))
        if record.get("status") != STATUS_COMPLETE or not request.same_run(record["request"]):
            return None
        names = {f.name for f in fields(RunSummary)}
        return RunSummary(**{k: v for k, v in record["summary"].items() if k in names})
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


@dataclass
class Plan:
    """Every input x config of a batch (``order``: input-major): ``jobs`` to run, and
    ``known`` outcomes that need no run."""

    jobs: list[Job]
    known: list[Outcome]
    order: list[tuple[str, str]]


def plan(inputs: Sequence[BatchInput], configs: dict[str, Config], out_dir: Path,
         settings: RunRequest, threads: int = 1, force: bool = False) -> Plan:
    """What to do for every input x config, results in ``out_dir/<input>/<config>/``.

    Each job's request is ``settings`` (what ``vtrack batch`` was given: video, preset, crf,
    seed, max_frames) with the input, output folder, config and ground truth of the job.

    Known outcomes: ``skipped`` for results complete from an earlier batch (unless ``force``),
    ``failed`` for a single-target config on an input with neither ground truth nor a readable
    initial box. ``threads`` is the number of OpenCV threads of each job.
    """
    result = Plan([], [], [])
    out_dir = out_dir.resolve()
    pipelines = {label: Pipeline(config.build()) for label, config in configs.items()}
    for item in inputs:
        for label, config in configs.items():
            if pipelines[label].multi_target:
                gt_path, gt_origin = item.mot_groundtruth, 0
            else:
                gt_path, gt_origin = item.groundtruth, item.gt_origin
            result.order.append((item.name, label))
            try:
                init = (_init_box(item, label) if gt_path is None
                        and pipelines[label].needs_init_box else None)
            except InputError as exc:
                result.known.append(Outcome(item.name, label, STATUS_FAILED, error=str(exc)))
                continue
            request = replace(settings, input=str(item.path), out_dir=out_dir / item.name / label,
                              config=config, init_box=init, gt_path=gt_path, gt_origin=gt_origin)
            done = None if force else completed_summary(request)
            if done is not None:
                result.known.append(Outcome(item.name, label, STATUS_SKIPPED, done))
            else:
                result.jobs.append(Job(item.name, label, request, threads=threads))
    return result


def _init_box(item: BatchInput, config: str) -> Box:
    """The first box of an input without single-target ground truth, from its init file."""
    if item.init is None:
        if item.path.is_dir():
            names = (*SEQUENCE_GT, SEQUENCE_INIT)
        else:
            names = tuple(p.format(item.path.stem) for p in (*VIDEO_GT, VIDEO_INIT))
        raise InputError(f"{item.path}: config '{config}' tracks a given target, but there is "
                         f"no ground truth or initial box ({', '.join(names)})")
    box = read_boxes(item.init, origin=item.gt_origin)[0]
    if box is None:
        raise InputError(f"{item.init}: the initial box is empty")
    return box


# --- one job, in a worker --------------------------------------------------------------------

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


# --- executors -------------------------------------------------------------------------------

class Executor(Protocol):
    """Runs jobs somewhere and yields one outcome per job, in completion order."""

    def run(self, jobs: Sequence[Job]) -> Iterator[Outcome]: ...


def _died(job: Job, how: str) -> Outcome:
    times = "once" if job.attempt == 1 else f"{job.attempt} times"
    return Outcome(job.input, job.config, STATUS_FAILED,
                   error=f"the worker process died ({how}), {times}", attempt=job.attempt)


def _exit_reason(code: int | None) -> str:
    if code is not None and code < 0:
        try:
            return signal.Signals(-code).name
        except ValueError:
            return f"signal {-code}"
    return f"exit code {code}"


def _context() -> multiprocessing.context.BaseContext:
    """Fork-server processes where the platform has them (a fork of an interpreter that has
    already imported vtrack and the main script: fast to start, and safe, it runs no threads);
    spawn elsewhere. Preloading ``__main__`` keeps each child from running the main script
    again (multiprocessing's main-module fix-up)."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["__main__", __name__])
        return context
    return multiprocessing.get_context("spawn")


class _Worker:
    """A long-lived local worker process, its end of the pipe, and the job it is running."""

    def __init__(self, context: multiprocessing.context.BaseContext) -> None:
        self.connection, theirs = context.Pipe()
        self.process = context.Process(target=_serve, args=(theirs,), daemon=True,
                                       name="vtrack batch worker")
        self.process.start()
        theirs.close()  # the worker holds the only other end: EOF here when it dies
        self.job: Job | None = None

    def start(self, job: Job) -> bool:
        """Hand ``job`` to the worker; False if it is gone."""
        self.job = job
        try:
            self.connection.send(job)
        except OSError:
            return False
        return True

    def result(self) -> Outcome | None:
        """The outcome of the running job, or None if the worker died first."""
        try:
            return self.connection.recv()
        except (EOFError, OSError):
            return None

    def stop(self, grace_s: float = 5) -> None:
        """Ask the worker to finish; a job still running (interrupted, it is writing its
        ``run.json``) gets ``grace_s``, then the process is terminated."""
        with suppress(OSError):
            self.connection.send(None)
        self.process.join(grace_s)
        if self.process.is_alive():
            self.process.terminate()
            self.process.join()
        self.connection.close()


class LocalExecutor:
    """At most ``workers`` long-lived worker processes, each running one job at a time.

    Unlike a ``ProcessPoolExecutor`` (which breaks entirely, ``BrokenProcessPool``, when one of
    its workers dies), every worker has its own pipe and the executor knows which job each one
    runs: a worker that dies (killed, segfault) costs only that job, which is started again on
    a fresh worker :data:`RETRIES` times and then reported ``failed``; the other workers carry
    on. Workers stay alive between jobs, so a job starts warm (imports, codec and OpenCV set-up
    are done once per worker, not once per job).
    """

    def __init__(self, workers: int) -> None:
        self.workers = max(1, workers)

    def run(self, jobs: Sequence[Job]) -> Iterator[Outcome]:
        context = _context()
        pending = deque(jobs)
        workers: list[_Worker] = []
        try:
            while pending or workers:
                while pending and len(workers) < self.workers:
                    workers.append(_Worker(context))
                lost = []  # workers found dead, with the job they had
                for worker in workers:
                    if worker.job is None and pending and not worker.start(pending.popleft()):
                        lost.append(worker)
                busy = {w.connection: w for w in workers if w.job is not None and w not in lost}
                for connection in wait(list(busy)) if busy else ():
                    worker = busy[connection]
                    outcome = worker.result()
                    if outcome is None:
                        lost.append(worker)
                    else:
                        worker.job = None
                        yield outcome
                for worker in lost:
                    workers.remove(worker)
                    worker.stop()
                    job = worker.job
                    if job.attempt <= RETRIES:
                        pending.appendleft(replace(job, attempt=job.attempt + 1))
                    else:
                        yield _died(job, _exit_reason(worker.process.exitcode))
                if not pending and all(w.job is None for w in workers):
                    return
        finally:
            for worker in workers:
                worker.stop()


class DaskExecutor:
    """Jobs as tasks on an existing Dask distributed scheduler (``pip install vtrack[dask]``).

    Connects when created (so a wrong address fails before anything runs) and disconnects at
    the end of :meth:`run`: one run per executor. Only the small :class:`Job` objects travel;
    workers read inputs by path and write results to the output path, which they must share
    with this machine. Dask reschedules a task whose worker died; once the scheduler's
    ``allowed-failures`` is exceeded it gives up and the job is reported ``failed``. Each job
    uses one OpenCV thread: the cluster already runs one job per worker thread.
    """

    def __init__(self, address: str, timeout_s: float = 10) -> None:
        try:
            from distributed import Client
        except ImportError:
            raise VtrackError(
                "--scheduler needs Dask distributed: pip install 'vtrack[dask]'") from None
        try:
            self.client = Client(address, timeout=timeout_s, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise VtrackError(
                f"--scheduler {address}: cannot reach the Dask scheduler ({reason})"
            ) from None

    def run(self, jobs: Sequence[Job]) -> Iterator[Outcome]:
        from distributed import as_completed

        batch = uuid.uuid4().hex[:8]
        futures = {self.client.submit(execute, replace(job, threads=1), pure=False,
                                      key=f"vtrack-{batch}-{n}-{job.input}-{job.config}"): job
                   for n, job in enumerate(jobs)}
        try:
            for future in as_completed(futures, loop=self.client.loop):
                job = futures[future]
                try:
                    yield future.result()
                except Exception as exc:  # KilledWorker, lost connection: report, carry on
                    yield Outcome(job.input, job.config, STATUS_FAILED,
                                  error=f"Dask: {type(exc).__name__}: {exc}")
        finally:
            self.client.cancel(list(futures))
            self.client.close()


def run_batch(batch: Plan, executor: Executor, summary_path: Path) -> Iterator[Outcome]:
    """Yield every outcome, known ones first, keeping ``summary_path`` current.

    The summary has one row per input x config of the plan; if the batch stops early
    (Ctrl-C), jobs without an outcome are written with the status ``interrupted``.
    """
    summary = SummaryWriter(summary_path, batch.order)
    finished = False
    try:
        for outcome in batch.known:
            summary.add(outcome)
            yield outcome
        with closing(executor.run(batch.jobs)) as outcomes:
            for outcome in outcomes:
                summary.add(outcome)
                yield outcome
        finished = True
    finally:
        if not finished:
            summary.write(unfinished=STATUS_INTERRUPTED)


# --- summary ---------------------------------------------------------------------------------

class SummaryWriter:
    """``OUT/summary.csv``: one row per input x config in plan order, rewritten atomically
    (temporary file + rename) each time an outcome arrives, so it is never half written."""

    def __init__(self, path: Path, order: Iterable[tuple[str, str]]) -> None:
        self.path = path
        self.rows: dict[tuple[str, str], dict[str, Any] | None] = dict.fromkeys(order)

    def add(self, outcome: Outcome) -> None:
        self.rows[(outcome.input, outcome.config)] = outcome.row()
        self.write()

    def write(self, unfinished: str | None = None) -> None:
        """Write the file; jobs without an outcome get the status ``unfinished`` (or no row)."""
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, SUMMARY_COLUMNS, lineterminator="\n")
        writer.writeheader()
        for (name, config), row in self.rows.items():
            if row is not None:
                writer.writerow(row)
            elif unfinished is not None:
                writer.writerow({"input": name, "config": config, "status": unfinished})
        self.path.parent.mkdir(parents=True, exist_ok=True)
        temporary = self.path.with_name(self.path.name + ".tmp")
        temporary.write_text(buffer.getvalue(), encoding="utf-8")
        os.replace(temporary, self.path)


def cpu_count() -> int:
    """Cores this process may use."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1
