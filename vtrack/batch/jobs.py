"""What travels between the planner, the workers and the summary: jobs and their outcomes."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from vtrack.errors import InputError, printable
from vtrack.io.identity import file_identity
from vtrack.io.outdir import BATCH_COLUMNS
from vtrack.request import RunRequest
from vtrack.run import STATUS_COMPLETE, STATUS_FAILED, RunSummary

#: ``summary.csv`` columns, in order (a report's ``summary.csv`` has the same).
SUMMARY_COLUMNS = BATCH_COLUMNS


@dataclass(frozen=True)
class Job:
    """One input x config: what a worker needs (paths and settings, never frames)."""

    input: str
    config: str
    request: RunRequest
    #: OpenCV threads of the run on a local worker (a Dask worker chooses its own:
    #: :func:`~vtrack.batch.worker.dask_threads`).
    threads: int = 1
    attempt: int = 1


@dataclass(frozen=True)
class Progress:
    """A running job's frames done (and the input's frame count, when known), sent by a local
    worker while it tracks so the batch's bar counts frames, not runs."""

    input: str
    config: str
    frames: int
    total: int | None = None


@dataclass
class Outcome:
    """What became of a job: a status of ``vtrack.run`` or ``failed``; ``resumed`` when the
    result was already complete from an earlier batch (no run)."""

    input: str
    config: str
    status: str
    summary: RunSummary | None = None
    error: str | None = None
    #: Which attempt this is: 2 after a worker process died running the job.
    attempt: int = 1
    resumed: bool = False
    #: A job refused because its folder holds a run made with other settings: that run's
    #: summary (from its ``run.json``), which the ``summary.csv`` row keeps describing (the
    #: folder still holds it).
    kept: RunSummary | None = None
    #: The ``summary.csv`` row of the run the job's folder holds (:func:`read_row`), read
    #: where the job ran (a worker: in parallel, not in the batch's process), and the identity
    #: of the ``run.json`` it was read from (:func:`read_row`); None: not read there.
    row: dict[str, Any] | None = None
    row_source: dict[str, int] | None = None

    @property
    def ok(self) -> bool:
        return self.status == STATUS_COMPLETE

    @property
    def held(self) -> str:
        """The status of what the pair's folder holds, as its ``summary.csv`` row says: the
        ``kept`` run's when this job was refused, else the job's own."""
        return self.kept.status if self.kept else self.status

    @property
    def verdict(self) -> str:
        """The run's status (``complete``, ``failed`` ...), or ``not run`` when it was refused
        (its folder keeps the earlier run, which its row describes)."""
        return "not run" if self.kept else self.status

    def line(self, results: Path | None = None) -> str:
        """One line for the terminal: the run's summary line, or what went wrong. With
        ``results``, the batch's results folder as the user gave it (``-o``), the run's folder
        is named inside it as given (``results/a/s0``), not by the absolute path it ran in."""
        label = f"{printable(self.input)} [{printable(self.config)}]"
        if self.status == STATUS_FAILED or self.summary is None:
            line = printable(f"{label}: {self.verdict}: {self.error}")  # one line
        else:
            summary = self.summary
            if results is not None:
                summary = replace(summary, out_dir=str(_as_given(Path(summary.out_dir),
                                                                 results)))
            line = summary.line(label)
        if self.resumed:
            line += " (already complete: not run again)"
        if self.attempt > 1:
            line += f" (attempt {self.attempt}: a worker process died on this job before)"
        return line


    def warnings(self) -> list[str]:
        """The warnings of the run this job made, each headed by its input and config (``NAME
        [CONFIG]: ...``; ``vtrack batch`` prints them as ``vtrack: warning:`` lines, as ``vtrack
        run`` does after its run; they are in its ``run.json`` too): none for a run not made
        now (complete before, or refused)."""
        if self.summary is None or self.resumed or self.kept is not None:
            return []
        label = f"{printable(self.input)} [{printable(self.config)}]"
        return [f"{label}: {warning}" for warning in self.summary.warnings]


def _as_given(folder: Path, results: Path) -> Path:
    """``folder`` named inside ``results`` (as the user gave it) when it lies there, else as
    it is."""
    try:
        return results / folder.relative_to(results.resolve())
    except ValueError:  # a run recorded elsewhere
        return folder


def read_row(folder: Path) -> tuple[dict[str, Any], dict[str, int] | None]:
    """The ``summary.csv`` row of the run ``folder`` holds, as a report's has it
    (:func:`vtrack.report.rows.run_row`), and the identity (size, modification time) of the
    ``run.json`` it was read from: None when that file changed while it was read. ``({},
    None)`` when the folder holds no run that can be read."""
    from vtrack.report.rows import run_row  # (reading runs: not loaded for --help)
    from vtrack.report.runs import load_run

    record = folder / "run.json"
    source = file_identity(record)
    try:
        row = run_row(load_run(folder))
    except InputError:
        return {}, None
    return row, source if source is not None and file_identity(record) == source else None
