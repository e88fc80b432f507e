"""``OUT/summary.csv`` kept current while a batch runs."""

from __future__ import annotations

import contextlib
import csv
import json
import math
import os
import time
from collections.abc import Callable, Collection, Generator, Iterable, Mapping
from contextlib import closing
from pathlib import Path
from typing import Any

from vtrack.batch.executors import Executor
from vtrack.batch.jobs import SUMMARY_COLUMNS, Outcome, read_row
from vtrack.batch.plan import Plan, recorded_summary
from vtrack.errors import OutputError, passing_stop_to
from vtrack.io.files import folder_name, name_cell, read_name, write_text_atomic
from vtrack.io.identity import file_identity
from vtrack.io.outdir import EARLIER_BATCH_COLUMNS
from vtrack.run import STATUS_COMPLETE, STATUS_FAILED, STATUS_INTERRUPTED

#: A run's end writes ``summary.csv`` again once this many times the last write's own time has
#: passed since it: writing takes at most about 1/20 of a batch's time however many pairs it
#: has (each write is of every row: writing at every end made a batch's bookkeeping grow as the
#: square of its pairs).
WRITE_SPACING = 19.0

#: The error of a pair the batch had not finished when it last wrote ``summary.csv``.
UNFINISHED = "not finished when the batch last wrote this file (it was still running, or killed)"
#: What a pair a stopped batch never started is (``vtrack report`` says so of such a row).
NEVER_RAN = "never ran (the batch stopped first)"
#: The error of such a pair in ``summary.csv``: also what to do.
NEVER_STARTED = (f"{NEVER_RAN}: the same vtrack batch command runs it (without --force, "
                 "the runs complete are not run again)")
#: The error of a pair the stopped batch started whose worker was killed before the run
#: recorded itself (it could not end within the grace periods: a slow encoder's flush).
KILLED_UNRECORDED = ("started, then killed when the batch stopped, before it recorded itself "
                     "(no run.json; its folder may hold part of its outputs): the same vtrack "
                     "batch command with --overwrite (-y) runs it again")


def run_batch(batch: Plan, executor: Executor, summary_path: Path,
              late: list[Outcome] | None = None) -> Generator[Outcome, None, None]:
    """Yield every outcome, known ones first, keeping ``summary_path`` current.

    The summary has one row per input x config of the plan. If the batch stops early (Ctrl-C,
    SIGTERM), the executor first lets running jobs finish or record themselves (those it must
    stop are stopped by the signal the batch got, which their records name); a job whose
    outcome did not arrive then gets the row of its own ``run.json`` when this batch wrote one
    (a run that finished in the grace period is ``complete``), else the status
    ``interrupted``: the summary agrees with the runs' records. A job that wrote in its folder
    during this batch but recorded nothing (its worker killed) is ``interrupted`` with
    :data:`KILLED_UNRECORDED`, not a pair never started. The outcomes of those jobs (which the
    stopped generator can no longer yield) are appended to ``late``, for the caller to report,
    after the known outcomes not yet handed over (the last one handed may be among them: the
    caller reports each pair once).
    """
    started = time.time()
    finished = False
    handed = 0  # known outcomes the consumer has taken and come back from
    summary: SummaryWriter | None = None
    try:
        summary = SummaryWriter(summary_path, batch.order,  # (reads the earlier rows)
                                split=batch.split, ground_truth=batch.ground_truth)
        for outcome in batch.known:  # resumed pairs: one write for all of them
            summary.add(outcome, write=False)
        summary.write()
        for outcome in batch.known:
            yield outcome
            handed += 1
        with closing(executor.run(batch.jobs)) as outcomes, passing_stop_to(outcomes):
            for outcome in outcomes:
                summary.add(outcome)
                yield outcome
        summary.flush()
        finished = True
    finally:
        if not finished:
            if late is not None:  # (the one being handed when the stop came may come twice)
                late.extend(batch.known[handed:])
            if summary is not None:
                _write_stopped(summary, batch, started, late)


def _write_stopped(summary: SummaryWriter, batch: Plan, started: float,
                   late: list[Outcome] | None) -> None:
    """Write ``summary`` for a batch stopped early: each job without an outcome gets its own
    ``run.json``'s row when it recorded itself since ``started``, else ``interrupted`` with
    :data:`KILLED_UNRECORDED` when it wrote in its folder (those outcomes are appended to
    ``late``), else the row of a pair never started."""
    for job in batch.jobs:
        if summary.rows.get((job.input, job.config)) is not None:
            continue
        recorded = recorded_summary(job.request, since=started)
        if recorded is not None:
            outcome = Outcome(job.input, job.config, recorded.status, recorded,
                              recorded.error, job.attempt)
        elif _written_since(job.request.out_dir, started):
            outcome = Outcome(job.input, job.config, STATUS_INTERRUPTED,
                              error=KILLED_UNRECORDED, attempt=job.attempt)
        else:
            continue
        summary.add(outcome, write=False)
        if late is not None:
            late.append(outcome)
    summary.write(stopped=True)


def _written_since(folder: Path, since: float) -> bool:
    """Whether anything in ``folder`` (its lock, a temporary output) was written at or after
    ``since`` (``time.time()``): a job that took its folder; one not started leaves it as it
    was."""
    try:
        return any(entry.stat(follow_symlinks=False).st_mtime >= since
                   for entry in os.scandir(folder))
    except OSError:
        return False


def outcome_row(outcome: Outcome, summary_path: Path
                ) -> tuple[dict[str, Any], dict[str, int] | None]:
    """``outcome``'s ``summary.csv`` row: the row a report's ``summary.csv`` has for the run its
    folder holds (:func:`vtrack.batch.jobs.read_row`: as the worker read it, else read now;
    the ``kept`` run when the job was refused), under the batch's input and config names, the
    status and error of what its folder holds (:attr:`Outcome.held`) and its folder named
    inside the batch's (``clip/s0``); and the identity of the ``run.json`` it was read from
    (None: none). A job without a run folder that can be read (it failed before writing one)
    has its input, config, status and error only."""
    recorded = outcome.kept or outcome.summary
    read: dict[str, Any] = {}
    source = folder = None
    if recorded is not None and recorded.out_dir:
        folder = Path(recorded.out_dir)
        if outcome.row is not None and outcome.kept is None:
            read, source = outcome.row, outcome.row_source
        else:
            read, source = read_row(folder)
    return summary_row(read, folder, summary_path.parent, outcome.input, outcome.config,
                       outcome.held, outcome.kept.error if outcome.kept else outcome.error
                       ), source


def summary_row(read: Mapping[str, Any], folder: Path | None, batch: Path, name: str,
                config: str, status: str, error: str | None) -> dict[str, Any]:
    """A ``summary.csv`` row: ``read``, the columns of the run in ``folder`` (as
    :func:`~vtrack.batch.jobs.read_row` reads them, or an earlier row of it), with ``run``
    naming ``folder`` inside the batch's folder ``batch`` (as it is when outside) when there
    are any, under the pair's input ``name`` and ``config``, with its ``status`` and
    ``error``. Without ``read`` the row has those four only."""
    row = dict(read)
    if row and folder is not None:
        row["run"] = _inside(folder, batch)
    row.update(input=name, config=config, status=status, error=error)
    return row


def _inside(folder: Path, batch: Path) -> str:
    """``folder`` relative to the batch's folder ``batch`` when it is inside it, else as it is."""
    try:
        return folder.resolve().relative_to(batch.resolve()).as_posix()
    except ValueError:
        return str(folder)


#: Beside ``summary.csv``: the identity (size, modification time) of the ``run.json`` each
#: of its rows was read from, so a batch resuming the folder keeps the row of a run it does
#: not run again while that file is unchanged instead of reading the run again (written after
#: ``summary.csv``: a batch stopped between the two leaves identities that match no newer row).
SUMMARY_SOURCES = ".summary-sources.json"


def _read_sources(path: Path) -> dict[tuple[str, str], dict[str, int]]:
    """:data:`SUMMARY_SOURCES` beside the ``summary.csv`` at ``path`` by (input, config); none
    when it is missing or not as written."""
    try:
        entries = json.loads((path.parent / SUMMARY_SOURCES).read_text(encoding="utf-8"))
        return {(name, config): {"size": size, "mtime_ns": mtime}
                for name, config, size, mtime in entries}
    except (OSError, ValueError, TypeError):
        return {}


def earlier_rows(path: Path, planned: Collection[tuple[str, str]] = ()
                 ) -> tuple[dict[tuple[str, str], dict[str, Any]],
                            dict[tuple[str, str], dict[str, int]]]:
    """The rows of an existing ``summary.csv`` by (input, config) (none if it is missing or
    cannot be read), and the identity of the ``run.json`` each was read from where that is
    known (:data:`SUMMARY_SOURCES`, for a file with this vtrack's header). A file written by an
    earlier vtrack (:data:`EARLIER_BATCH_COLUMNS`) has each row not ``planned`` now (which this
    batch writes anew) rebuilt from its run's folder, ``<input>/<config>/``
    (:func:`~vtrack.batch.jobs.read_row`), as this batch writes it: its input, config, status
    and error as they were (the row as it was where the folder holds no run)."""
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            reader = csv.DictReader(handle)
            # (an input named as text_bytes writes it: c\xff, a byte not UTF-8, is c\udcff)
            rows = {(read_name(row["input"]), row["config"]): {c: row.get(c)
                                                             for c in SUMMARY_COLUMNS}
                    for row in reader}
    except (OSError, KeyError, UnicodeDecodeError, csv.Error):
        return {}, {}
    header = tuple(reader.fieldnames or ())
    if header == SUMMARY_COLUMNS:
        return rows, _read_sources(path)
    sources = {}
    if header == EARLIER_BATCH_COLUMNS:
        for key, row in rows.items():
            if key not in planned:
                folder = path.parent / folder_name(key[0], "input") / folder_name(key[1])
                read, source = read_row(folder)
                rows[key] = {**row, **summary_row(read, folder, path.parent, *key,
                                                  row["status"], row["error"])}
                if source is not None:
                    sources[key] = source
    return rows, sources


#: What a vtrack before each target of an OTB sequence of several was an input said of the
#: sequence, failing a single-target config on it ("config 's0' tracks one given target, and
#: the sequence has 2 targets' ground truth ...").
REFUSED_SEVERAL_TARGETS = "tracks one given target, and the sequence has"


def _refused_as_several_targets(row: dict[str, Any], folder: Path) -> bool:
    """Whether ``row`` is that old refusal of an OTB sequence of several targets (a
    single-target config's row, ``failed`` with :data:`REFUSED_SEVERAL_TARGETS` in its error,
    no run in its ``folder``): no result once the sequence's targets are inputs."""
    return (row.get("status") == STATUS_FAILED
            and REFUSED_SEVERAL_TARGETS in (row.get("error") or "")
            and not (folder / "run.json").is_file())


class SummaryWriter:
    """``OUT/summary.csv``: one row per input x config, rewritten atomically (temporary file +
    rename), so it is never half written: as an outcome arrives, unless the last write was
    less than :data:`WRITE_SPACING` times its own time ago (then at the next outcome after
    that, or :meth:`flush`).

    The rows of an earlier batch into the same folder (other configs, other inputs) are kept:
    the summary covers every run in the folder, input by input, each input's configs in the
    order they first ran; but an earlier row of an input in ``split`` (an OTB sequence of
    several targets whose targets ``SEQ-N`` this batch runs, :attr:`Plan.split`) that is the
    refusal of a vtrack before targets were inputs (:func:`_refused_as_several_targets`) is
    dropped: any other row of it (a multi-target config's, one a stopped batch never ran) is
    kept.
    ``clock``: seconds, for the spacing of writes. ``ground_truth``: the ground-truth file of
    each pair that has one, the ``ground_truth`` of a row whose folder holds no run to read it
    from (an input that failed to open, a pair never started or unfinished)."""

    def __init__(self, path: Path, order: Iterable[tuple[str, str]],
                 clock: Callable[[], float] = time.monotonic,
                 split: Collection[str] = (),
                 ground_truth: Mapping[tuple[str, str], Path] | None = None) -> None:
        self.path = path
        self.clock = clock
        self.ground_truth = ground_truth or {}
        self._next_write = -math.inf  # the clock's time from which an outcome writes again
        self._pending = False  # outcomes added since the last write
        order = list(order)
        planned = set(order)
        earlier, sources = earlier_rows(path, planned)
        earlier = {key: row for key, row in earlier.items()
                   if key in planned or key[0] not in split
                   or not _refused_as_several_targets(row, path.parent / folder_name(
                       key[0], "input") / folder_name(key[1]))}
        # input-major; sorted() is stable: each input's configs in the order they first ran
        keys = sorted(dict.fromkeys([*earlier, *order]), key=lambda key: key[0])
        self.rows: dict[tuple[str, str], dict[str, Any] | None] = {
            key: None if key in planned else earlier[key] for key in keys}
        #: The identity of the ``run.json`` each row was read from (:data:`SUMMARY_SOURCES`).
        self.sources = {key: sources[key] for key in keys if key in sources}
        #: The earlier rows of the pairs planned now, with the identity of the ``run.json``
        #: each was read from: a resumed pair's row while that file is unchanged.
        #: (only a complete row: a pair a stopped batch was running again is no result)
        self._resumable = {key: (earlier[key], sources[key])
                           for key in planned if key in earlier and key in sources
                           and earlier[key].get("status") == STATUS_COMPLETE}

    def add(self, outcome: Outcome, write: bool = True) -> None:
        """Record ``outcome``'s row (a resumed pair's as the file had it when its ``run.json``
        is the one that row was read from, else :func:`outcome_row`); with ``write``, write
        the file unless the last write was too recent (:data:`WRITE_SPACING`)."""
        key = (outcome.input, outcome.config)
        row, source = self._resumed_row(outcome) or outcome_row(outcome, self.path)
        if "run" not in row:  # no run of it was read
            row.update(self._planned_ground_truth(key))
        self.rows[key] = row
        if source is None:
            self.sources.pop(key, None)
        else:
            self.sources[key] = source
        self._pending = True
        if write and self.clock() >= self._next_write:
            self.write()

    def _planned_ground_truth(self, key: tuple[str, str]) -> dict[str, str]:
        """The ``ground_truth`` cell of the pair ``key``'s row when no run of it was read (it
        failed to open, it never started, it is unfinished): its file as a run's row names
        it; nothing when it has none."""
        return {"ground_truth": str(self.ground_truth[key])} if key in self.ground_truth else {}

    def _resumed_row(self, outcome: Outcome
                     ) -> tuple[dict[str, Any], dict[str, int]] | None:
        """The earlier row of ``outcome``, a pair resumed (complete before, not run again), when
        its ``run.json`` is the very file that row was read from; None otherwise."""
        earlier = self._resumable.get((outcome.input, outcome.config))
        if not outcome.resumed or earlier is None or outcome.summary is None:
            return None
        row, source = earlier
        folder = Path(outcome.summary.out_dir)
        if file_identity(folder / "run.json") != source:
            return None
        return summary_row(row, folder, self.path.parent, outcome.input, outcome.config,
                           outcome.held, outcome.error), source

    def flush(self) -> None:
        """Write the file if an outcome was added since the last write."""
        if self._pending:
            self.write()

    def write(self, stopped: bool = False) -> None:
        """Write the file. Pairs without an outcome yet are ``interrupted``: while the batch
        runs, with the error :data:`UNFINISHED` (so a batch killed outright, ``kill -9``,
        leaves a row for each pair it did not finish, not a summary of fewer pairs that looks
        whole); once it has ``stopped`` early (Ctrl-C, SIGTERM), with :data:`NEVER_STARTED`."""
        from vtrack.report.rows import render

        began = self.clock()
        rows = [{"input": name, "config": config, "status": STATUS_INTERRUPTED,
                 "error": NEVER_STARTED if stopped else UNFINISHED,
                 **self._planned_ground_truth((name, config))} if row is None else row
                for (name, config), row in self.rows.items()]
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # (an input's name as read_name reads it back: one holding the text \xff stays itself)
        write_text_atomic(self.path, render([{**row, "input": name_cell(row["input"])}
                                             for row in rows]))
        with contextlib.suppress(OutputError):  # (without it, a resumed pair is read again)
            write_text_atomic(self.path.parent / SUMMARY_SOURCES, json.dumps(
                [[*key, source["size"], source["mtime_ns"]]
                 for key, source in self.sources.items() if self.rows.get(key) is not None]))
        ended = self.clock()
        self._pending = False
        self._next_write = ended + WRITE_SPACING * (ended - began)
