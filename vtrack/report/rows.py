"""``summary.csv``, a batch's and a report's: one writer, one column set.

Every ``summary.csv`` has the columns :data:`~vtrack.io.outdir.BATCH_COLUMNS`: per run its
status and frames, the single-target scores (:class:`~vtrack.report.runs.Scores`, empty for a
multi-target run or one without ground truth), the multi-target metrics its ``run.json``
records (empty for a single-target run), its ground truth, its folder and its error. Numbers
are written with at most :data:`DIGITS` decimals. ``vtrack batch`` writes a row per run from
the run's folder as :func:`~vtrack.report.runs.load_run` reads it, the report does too: a run
has the same row in both.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Mapping
from typing import Any

from vtrack.io.outdir import BATCH_COLUMNS, MOT_METRICS
from vtrack.report.runs import RunResult

#: Decimals of the numbers in ``summary.csv`` (scores, fps, metrics).
DIGITS = 6

Row = dict[str, Any]


def cell(value: object) -> str:
    """``value`` as ``summary.csv`` writes it: a float with at most :data:`DIGITS` decimals,
    nothing for None or a value that is not finite."""
    if isinstance(value, float):
        return "" if not math.isfinite(value) else str(round(value, DIGITS))
    return "" if value is None else str(value)


def run_row(run: RunResult) -> Row:
    """``run``'s row: the scores that apply to it, the others left out (empty)."""
    row: Row = {"input": run.input, "config": run.config, "status": run.status,
                "frames": run.frames, "fps": run.fps, "frames_skipped": run.frames_skipped,
                "ground_truth": run.ground_truth, "run": str(run.folder), "error": run.error}
    if not run.multi_target:  # (one target's states; tracks have their own in tracks.csv)
        row.update(frames_occluded=run.frames_occluded, frames_lost=run.frames_lost)
    s = run.scores
    if s is not None:
        row.update(frames_evaluated=s.frames_evaluated, auc=s.auc, precision20=s.precision20,
                   success50=s.success50, success75=s.success75,
                   norm_precision=s.norm_precision, mean_overlap=s.mean_overlap,
                   mean_center_error=s.mean_center_error, tracking_miss=s.tracking_miss,
                   miss_flagged=s.miss_flagged)
    row.update({key: run.mot.get(key) for key in MOT_METRICS if key in run.mot})
    return row


def render(rows: Iterable[Mapping[str, Any]]) -> str:
    """The file: the header, then each row (its columns of :data:`BATCH_COLUMNS`; the others
    empty), each value written by :func:`cell`."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(BATCH_COLUMNS)
    for row in rows:
        writer.writerow([cell(row.get(column)) for column in BATCH_COLUMNS])
    return buffer.getvalue()
