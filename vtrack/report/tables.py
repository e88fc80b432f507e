"""The report's tables as plain data, rendered to HTML and Markdown by :mod:`vtrack.report.pages`.

A :class:`Table` is a header and rows of :class:`Cell`; a cell marked ``best`` holds the best
value of its column within its group of rows (the configurations of one input, or all
configurations in the averages table). Ties for best are all marked; a column whose values are
all equal (or a group of one row) marks nothing, and neither does a column that describes a
run rather than ranks it (frame counts, lost frames: a tracker that never says ``lost`` has 0;
miss flagged: honesty of the state, high also for a tracker that misses everything).
Each column may carry a ``note``, shown as the header's tooltip.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field

from vtrack.errors import plural
from vtrack.report.runs import OVERSIZED_AREA, RunResult
from vtrack.run import STATUS_COMPLETE, STATUS_INTERRUPTED, STATUS_PARTIAL

#: Multi-target metrics the page shows, in this order, when a run records them: key ->
#: (title as MOTChallenge abbreviates it, which way is better (None: not ranked), tooltip).
#: Other recorded metrics follow, unranked, under their own names.
MOT_COLUMNS: dict[str, tuple[str, bool | None, str]] = {
    "mota": ("MOTA", True, "CLEAR MOT accuracy: 1 - (FN + FP + IDs) / ground-truth boxes"),
    "motp": ("MOTP", True, "mean IoU of the matched (object, track) pairs"),
    "idf1": ("IDF1", True, "identity F1: the share of boxes matched with the track identity "
                           "paired with their object over the whole run"),
    "idp": ("IDP", True, "identity precision: IDF1's matches over the track boxes"),
    "idr": ("IDR", True, "identity recall: IDF1's matches over the ground-truth boxes"),
    "id_switches": ("IDs", False, "identity switches: a matched object's track changed"),
    "fragmentations": ("Frag", False, "a matched object's track interrupted"),
    "false_positives": ("FP", False, "track boxes matched to no object"),
    "misses": ("FN", False, "ground-truth boxes matched to no track (misses)"),
    "precision": ("Prcn", True, "matched track boxes over all track boxes"),
    "recall": ("Rcll", True, "matched ground-truth boxes over all ground-truth boxes"),
    "mostly_tracked": ("MT", True, "objects matched in at least 80% of their frames"),
    "partially_tracked": ("PT", None, "objects matched in 20% to 80% of their frames "
                                      "(not ranked)"),
    "mostly_lost": ("ML", False, "objects matched in less than 20% of their frames"),
    "gt_ids": ("GT ids", None, "objects in the ground truth (not ranked)"),
    "track_ids": ("Tracks", None, "track identities the tracker confirmed (not ranked)"),
}
#: Recorded but left off the page (summary.csv keeps them): the Frames column already shows
#: ``frames``; the box counts follow from the others (ground-truth boxes = matches + FN,
#: track boxes = matches + FP).
MOT_HIDDEN = frozenset({"frames", "gt_boxes", "track_boxes", "matches"})

@dataclass
class Cell:
    text: str
    best: bool = False


@dataclass
class Table:
    """``groups`` are the row indices where a new group (an input) starts; ``notes`` the
    explanation of a header (by title), if it has one."""

    header: list[str]
    rows: list[list[Cell]] = field(default_factory=list)
    groups: list[int] = field(default_factory=list)
    notes: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Column:
    """A numeric column: title, decimals shown, which way is better (None: neither, nothing
    is marked best), and what it means (the header's tooltip)."""

    title: str
    digits: int
    higher_is_better: bool | None = True
    note: str = ""


#: What the less common columns mean (the tooltips, and the report's footer).
NOTES = {
    "Evaluated": "frames with ground truth present (the others are not scored), frames the "
                 "input skipped among them included (misses: no box), so it may exceed Frames",
    "SR0.5": "success rate at IoU 0.5: share of evaluated frames whose overlap is > 0.5 "
             "(GOT-10k's SR0.50)",
    "SR0.75": "success rate at IoU 0.75: share of evaluated frames whose overlap is > 0.75",
    "Norm. precision": "normalised precision (TrackingNet): the centre error divided by the "
                       "ground truth's width and height, area under its precision curve for "
                       "thresholds 0 to 0.5",
    "Tracking miss": "of the frames the tracker calls 'tracking', the share whose box misses "
                     "the target (IoU 0): lower is better, a tracker should not claim a target "
                     "it has lost; not ranked for a run whose box in those frames is mostly "
                     f"(median) over {OVERSIZED_AREA:g} times the target's area, said beside its "
                     "value ('box 60x'; in the averages, on how many inputs): a box that covers "
                     "the frame rarely misses, however poorly it tracks",
    "Miss flagged": "of the frames whose box misses the target (or that have no box while it "
                    "is in view; not the frames the input skipped, which the tracker never "
                    "saw), the share the tracker itself calls 'occluded' or 'lost': how "
                    "honest its state is, not how well it tracks (not ranked)",
    "Lost frames": "frames the tracker called 'lost' (no box); 0 for trackers that never say "
                   "lost (not ranked)",
}


def _column(title: str, digits: int, higher_is_better: bool | None = True) -> Column:
    return Column(title, digits, higher_is_better, NOTES.get(title, ""))


def _table(labels: list[str], columns: Sequence[Column]) -> Table:
    return Table(labels + [c.title for c in columns],
                 notes={c.title: c.note for c in columns if c.note})


Values = list[float | None]


def _finite(value: float | None) -> bool:
    return value is not None and math.isfinite(value)


def _text(value: float | None, digits: int) -> str:
    if not _finite(value):
        return "—"
    return f"{value:.{digits}f}" if digits else str(round(value))


def _add_group(table: Table, labels: list[list[str]], values: list[Values],
               columns: Sequence[Column], ranked: Sequence[bool] | None = None,
               unranked: Sequence[Collection[int]] | None = None) -> None:
    """Append rows (label cells, then the formatted values) marking each column's best among
    the ``ranked`` rows (default all: a run that did not complete scores frames it chose),
    each row in none of the columns (their indices) ``unranked`` gives it."""
    table.groups.append(len(table.rows))
    rows = [[Cell(t) for t in label] + [Cell(_text(v, c.digits))
                                        for v, c in zip(row, columns, strict=True)]
            for label, row in zip(labels, values, strict=True)]
    offset = len(labels[0]) if labels else 0
    ranked = [True] * len(values) if ranked is None else ranked
    unranked = [()] * len(values) if unranked is None else unranked
    for c, column in enumerate(columns):
        here = [r and c not in u for r, u in zip(ranked, unranked, strict=True)]
        present = [row[c] for row, r in zip(values, here, strict=True) if r and _finite(row[c])]
        if column.higher_is_better is None or len(set(present)) < 2:
            continue
        best = max(present) if column.higher_is_better else min(present)
        for cells, row, r in zip(rows, values, here, strict=True):
            cells[offset + c].best = r and row[c] == best
    table.rows += rows


def _scores(run: RunResult) -> Values:
    s = run.scores
    return [None] * 9 if s is None else [s.frames_evaluated, s.auc, s.precision20,
                                          s.success50, s.success75, s.norm_precision,
                                          s.mean_overlap, s.tracking_miss, s.miss_flagged]


#: The scores, speed and lost frames every results table shows after its count columns.
SCORE_COLUMNS = (
    _column("AUC", 3),
    _column("Precision@20", 3),
    _column("SR0.5", 3),
    _column("SR0.75", 3),
    _column("Norm. precision", 3),
    _column("Mean IoU", 3),
    _column("Tracking miss", 3, False),
    _column("Miss flagged", 3, None),
    _column("FPS", 1),
    _column("Lost frames", 0, None),
)
#: How many of :data:`SCORE_COLUMNS` are a run's scores (:func:`_scores` after its frames
#: evaluated): all but FPS and lost frames.
SCORED = len(SCORE_COLUMNS) - 2

#: Per input x configuration: OTB scores, speed and lost frames.
RESULT_COLUMNS = (
    _column("Frames", 0, None),
    _column("Evaluated", 0, None),
    *SCORE_COLUMNS,
)
RUN_LABELS = ["Input", "Config", "Status"]


#: Statuses of runs that stopped before the end of their input (their results are partial).
INCOMPLETE = (STATUS_PARTIAL, STATUS_INTERRUPTED)


def status_text(run: RunResult) -> str:
    """The run's status; one that stopped early (partial, interrupted, failed) says how far
    it got (``partial: 40 of 60 frames``)."""
    if run.status != STATUS_COMPLETE and run.input_frames:
        return f"{run.status}: {run.frames} of {plural(run.input_frames, 'frame')}"
    return run.status


def _run_label(run: RunResult) -> list[str]:
    return [run.input, run.config, status_text(run)]


def _tracking_miss(columns: Sequence[Column]) -> int:
    """Where the tracking miss is among ``columns`` (a table's value columns)."""
    return next(n for n, c in enumerate(columns) if c.title == "Tracking miss")


def _say_beside(table: Table, column: int, notes: Sequence[str | None]) -> None:
    """Append each note (if any) to its row's value in ``column`` of the rows last added, as
    many as there are notes (none: nothing): why that value is not ranked (``0.000 (box
    60x)``, ``0.250 (on 1 of 2 inputs)``; the header's note says more)."""
    for cells, note in zip(table.rows[len(table.rows) - len(notes):], notes, strict=True):
        if note:
            cells[column].text += f" ({note})"


def _times(ratio: float) -> str:
    """``ratio`` as a cell says it: one decimal under 10 (``4.1``, not ``4``, past a limit of
    4), none from there (``60``)."""
    return f"{ratio:.1f}" if ratio < 10 else f"{ratio:.0f}"


def results_table(by_input: Sequence[Sequence[RunResult]]) -> Table:
    """One row per input x configuration, best per column within each input; a run whose
    box is :attr:`~vtrack.report.runs.RunResult.oversized` is not ranked by its tracking miss,
    which says how large its box is."""
    table = _table(RUN_LABELS, RESULT_COLUMNS)
    miss = _tracking_miss(RESULT_COLUMNS)
    for runs in by_input:
        _add_group(table, [_run_label(r) for r in runs],
                   [[r.frames, *_scores(r), r.fps, r.frames_lost] for r in runs],
                   RESULT_COLUMNS, [r.status == STATUS_COMPLETE for r in runs],
                   [{miss} if r.oversized else () for r in runs])
        _say_beside(table, len(RUN_LABELS) + miss, [
            f"box {_times(r.box_to_target)}x" if r.oversized and r.box_to_target else None
            for r in runs])
    return table


#: Per configuration, over inputs: mean scores, mean fps, total lost frames.
AVERAGE_COLUMNS = (
    _column("Inputs", 0, None),
    *SCORE_COLUMNS,
)


def _mean(values: Sequence[float | None]) -> float | None:
    present = [v for v in values if _finite(v)]
    return sum(present) / len(present) if present else None


def _fewer_inputs(scored_by: Sequence[Sequence[RunResult]]) -> list[dict[int, str]]:
    """Per configuration (its scored runs), the score columns (indices in
    :data:`AVERAGE_COLUMNS`) it has on fewer inputs than the configurations together: its
    mean there is over other inputs than theirs, not ranked, and said so, ``on 1 of 2
    inputs`` (of the inputs any configuration has that score on). None where every
    configuration has a score on the same inputs (an input none has one on, with no frame
    evaluated say, leaves every mean alike), nor where one has it on none (``—``)."""
    notes: list[dict[int, str]] = [{} for _ in scored_by]
    for c in range(1, 1 + SCORED):  # (AUC ... miss flagged: at c in _scores and the table)
        have = [{r.input for r in scored if _finite(_scores(r)[c])} for scored in scored_by]
        every = set().union(*have)
        for config, inputs in zip(notes, have, strict=True):
            if inputs and inputs != every:
                config[c] = on_inputs(len(inputs), len(every))
    return notes


def on_inputs(inputs: int, every: int) -> str:
    """What a mean over ``inputs`` of ``every`` inputs says beside it: ``on 1 of 2 inputs``."""
    return f"on {inputs} of {plural(every, 'input')}"


def average_table(by_config: dict[str, list[RunResult]]) -> Table:
    """One row per configuration over the inputs it counts: the runs with ground truth (the
    inputs of the "All inputs" plot), or, for a configuration without any, the runs that
    tracked frames. Each score is the mean over those runs that have it (``—`` where none
    has), fps their mean and lost frames their total; a configuration whose counted runs
    include partial (or interrupted) ones says how many. A score a configuration lacks on
    an input where another has it (``—`` in its row there: tracking miss where no frame is
    called tracking) is not ranked and says over how many inputs it is (``0.250 (on 1 of 2
    inputs)``, :func:`_fewer_inputs`), as a tracking miss of
    :attr:`~vtrack.report.runs.RunResult.oversized` runs says on how many inputs (both:
    ``0.250 (on 1 of 2 inputs; box >4x on 1 input)``)."""
    table = _table(["Config"], AVERAGE_COLUMNS)
    values, labels, scored_by = [], [], []
    for config, runs in by_config.items():
        scored = [r for r in runs if r.scores is not None]
        counted = scored or [r for r in runs if r.frames > 0]
        scores = list(zip(*(_scores(r)[1:] for r in scored), strict=True))
        means = [_mean(column) for column in scores] if scores else [None] * SCORED
        values.append([len(counted), *means, _mean([r.fps for r in counted]),
                       sum(r.frames_lost for r in counted)])
        partial = sum(r.status in INCOMPLETE for r in counted)
        labels.append([f"{config} ({partial} partial)" if partial else config])
        scored_by.append(scored)
    miss = _tracking_miss(AVERAGE_COLUMNS)
    notes = _fewer_inputs(scored_by)
    for config, scored in zip(notes, scored_by, strict=True):
        if oversized := sum(r.oversized for r in scored):
            box = f"box >{OVERSIZED_AREA:g}x on {plural(oversized, 'input')}"
            config[miss] = "; ".join(filter(None, (config.get(miss), box)))
    _add_group(table, labels, values, AVERAGE_COLUMNS, None, notes)
    for c in sorted({c for config in notes for c in config}):
        _say_beside(table, 1 + c, [config.get(c) for config in notes])
    return table


def _mot_column(key: str, runs: Sequence[RunResult]) -> Column:
    values = [r.mot[key] for r in runs if key in r.mot]
    digits = 0 if all(isinstance(v, int) for v in values) else 3
    title, higher_is_better, note = MOT_COLUMNS.get(key, (key.replace("_", " "), None, ""))
    return Column(title, digits, higher_is_better, note)


def mot_table(by_input: Sequence[Sequence[RunResult]]) -> Table:
    """Multi-target runs: the metrics their ``run.json`` records (MOTA, MOTP, IDF1, ID
    switches, ...; :data:`MOT_COLUMNS`) per input x configuration; ``—`` where a run has none
    (no ground truth)."""
    runs = [r for group in by_input for r in group]
    keys = {k for r in runs for k, v in r.mot.items()
            if isinstance(v, int | float) and not isinstance(v, bool)} - MOT_HIDDEN
    ordered = [k for k in MOT_COLUMNS if k in keys] + sorted(keys - set(MOT_COLUMNS))
    columns = [Column("Frames", 0, None), *(_mot_column(k, runs) for k in ordered),
               Column("FPS", 1)]
    table = _table(RUN_LABELS, columns)
    for group in by_input:
        _add_group(table, [_run_label(r) for r in group],
                   [[r.frames, *(r.mot.get(k) for k in ordered), r.fps] for r in group],
                   columns)
    return table

