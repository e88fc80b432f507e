"""Finding and reading result folders for a report: ``run.json`` + ``track.csv``/``tracks.csv``.

Per-frame scores of a single-target run are its ``track.csv`` boxes scored by
:func:`vtrack.evaluate.metrics.frame_scores`, rounded as ``track.csv`` writes scores (as
``run.json``'s are), against:

- the ground truth the run recorded in ``run.json``, read with the recorded ``gt_origin`` and
  ``gt_first`` (the frame of its first box; 0 for a record without one); a
  record without one gets the origin (0 or 1) whose scores reproduce the run's own ``overlap``
  column. If that file can no longer be read, the run's ``overlap`` and ``center_error`` columns
  are used as they are (rounded to 6 and 3 decimals; an empty ``center_error`` next to an
  overlap is a frame where the tracker claimed no box: infinite error);
- otherwise the report's ``--gt`` file for the run's input (``--gt INPUT=FILE``), else its
  plain ``--gt FILE``; a file whose box count differs from the run's frames is not used (the run
  stays unscored and :attr:`RunResult.note` says why), so one input is never scored against
  another's ground truth.

Sequence scores (AUC, precision@20, mean IoU) come from :mod:`vtrack.evaluate.metrics` and
nowhere else.
"""

from __future__ import annotations

import csv
import errno
import json
import math
import os
import shlex
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache, cached_property
from pathlib import Path
from typing import Any

import numpy as np

from vtrack.batch.summary import NEVER_RAN
from vtrack.errors import COMMAND_NAMES, ConfigError, InputError, plural, printable
from vtrack.evaluate import metrics
from vtrack.evaluate.groundtruth import (
    MAX_GT_FIRST,
    FrameBoxes,
    MultiTargetTruthError,
    boxes_for_frames,
    gt_origin_of,
    later_first_hint,
    negative_note,
    read_boxes,
    read_truth,
    target_input,
)
from vtrack.geometry import Box
from vtrack.io.csvfile import scores_as_written
from vtrack.io.files import folder_name, os_reason, read_name
from vtrack.io.identity import file_identity, sizes
from vtrack.io.jsonfile import read_run_record
from vtrack.io.limits import special_kind
from vtrack.io.outdir import (
    BATCH_COLUMNS,
    EARLIER_BATCH_COLUMNS,
    LOCK_NAME,
    is_report_folder,
    live_holder,
)
from vtrack.io.sidecar import sequence_of
from vtrack.io.specs import is_live, is_url
from vtrack.report.walk import Walked
from vtrack.run import STATUS_COMPLETE, STATUS_FAILED, STATUS_INTERRUPTED, STATUS_PARTIAL


@dataclass(frozen=True)
class Scores:
    """One run's OTB scores (NaN when no frame is evaluated)."""

    frames_evaluated: int
    auc: float
    precision20: float
    mean_overlap: float
    mean_center_error: float
    success: np.ndarray
    precision: np.ndarray
    tracking_miss: float = math.nan
    miss_flagged: float = math.nan
    success50: float = math.nan
    success75: float = math.nan
    norm_precision: float = math.nan

    @classmethod
    def of(cls, overlaps: Sequence[float | None], errors: Sequence[float | None],
           states: Sequence[str] | None = None,
           norm_errors: Sequence[float | None] | None = None) -> Scores:
        """Scores of per-frame overlaps and errors; with one state per frame also the honest-state
        measures (:func:`~vtrack.evaluate.metrics.tracking_miss_rate`, ``flagged_miss_rate``);
        with the normalised centre errors the normalised precision."""
        honest = states is not None and len(states) == len(overlaps)
        return cls(
            frames_evaluated=sum(o is not None for o in overlaps),
            auc=metrics.auc(overlaps),
            precision20=metrics.precision_at(errors),
            mean_overlap=metrics.mean_overlap(overlaps),
            mean_center_error=metrics.mean_center_error(errors),
            tracking_miss=metrics.tracking_miss_rate(states, overlaps) if honest else math.nan,
            miss_flagged=metrics.flagged_miss_rate(states, overlaps) if honest else math.nan,
            success50=metrics.success_rate(overlaps, 0.5),
            success75=metrics.success_rate(overlaps, 0.75),
            norm_precision=(math.nan if norm_errors is None
                            else metrics.normalized_precision(norm_errors)),
            success=metrics.success_curve(overlaps),
            precision=metrics.precision_curve(errors),
        )


#: A run whose box, in the frames it calls tracking, is (by its median) over this many times
#: the ground truth's area is :attr:`RunResult.oversized`: twice the target's width and height.
OVERSIZED_AREA = 4.0


@dataclass
class RunResult:
    """One run folder as the report needs it.

    ``overlaps`` / ``errors`` are per frame (None: not evaluated) and None altogether when the
    run has no ground truth; ``states`` is per frame (single target). ``mot`` holds a
    multi-target run's metrics from ``run.json`` (empty without ground truth).
    """

    folder: Path
    input: str
    config: str
    status: str
    frames: int
    fps: float | None
    frames_occluded: int
    frames_lost: int
    multi_target: bool
    #: Frames of the input that could not be decoded (or were missing) and were skipped.
    frames_skipped: int = 0
    ground_truth: str | None = None
    error: str | None = None
    #: Frames of the input as ``run.json`` recorded when it opened (exact or estimated).
    input_frames: int | None = None
    states: list[str] = field(default_factory=list)
    #: The tracker's own score per frame (``track.csv``'s ``score``; None where it has none).
    confidence: list[float | None] = field(default_factory=list)
    overlaps: list[float | None] | None = None
    errors: list[float | None] | None = None
    #: Centre errors in units of the ground truth's size (None: the boxes were not rescored).
    norm_errors: list[float | None] | None = None
    mot: dict[str, Any] = field(default_factory=dict)
    #: Why the report's ``--gt`` was not used for this run (one line), if it was not.
    note: str | None = None
    #: The input as the run opened it (``run.json``'s request; None for raw frames or stdin,
    #: which cannot be read again), and the input's frame number of the run's first frame.
    source: str | None = None
    first_frame: int = 0
    #: Why ``source`` is None for an input that is there: it is not the file the run read.
    source_changed: str | None = None
    #: The run read its input once as it came (a stream, a URL, stdin, a device or a FIFO,
    #: :func:`read_once`): ``source`` is None, what is there now is not what was tracked.
    live_input: bool = False
    #: The tracker's box per frame (None: lost) and the ground truth's, when it was rescored.
    boxes: list[Box | None] = field(default_factory=list)
    truth: Sequence[Box | None] | None = None
    #: What tells inputs of one name apart (:func:`_input_key`).
    input_key: str = ""
    #: An image sequence's: the fingerprint of its images the run recorded
    #: (:func:`vtrack.io.identity.images_identity`; None: not a sequence, or a record from
    #: before vtrack recorded it), which tells two sequences of one key apart
    #: (:func:`vtrack.report.build._same_inputs`).
    image_identity: str | None = None
    #: An image sequence's total size, which a record without ``image_identity`` may hold
    #: instead (``input.image_bytes``: vtrack recorded it for a short while): two of one key
    #: and other sizes are other sequences.
    image_bytes: int | None = None
    #: The target of an OTB sequence of several the run tracked (None: the input's only one).
    target: int | None = None
    #: What tells configs of one name apart: the resolved chain the run recorded, else the name.
    config_key: str = ""
    #: The report's ``--gt`` for this run (:func:`pick_ground_truth`: its input's before a
    #: plain one; None: none is for it), and whether the run was scored with it (not: its own
    #: ground truth, several targets, another length).
    gt_given: GroundTruth | None = field(default=None, compare=False, repr=False)
    gt_scored: bool = False

    @cached_property
    def box_to_target(self) -> float | None:
        """The median, over the evaluated frames this run calls ``tracking``, of its box's area
        over the ground truth's (None: no such frame, or its ground-truth boxes are not here:
        scored with the overlaps it recorded)."""
        if not self.truth:
            return None
        ratios = [box.area / truth.area for box, truth, state
                  in zip(self.boxes, self.truth, self.states, strict=False)
                  if state == "tracking" and box is not None and truth is not None
                  and truth.area > 0]
        return float(np.median(ratios)) if ratios else None

    @property
    def oversized(self) -> bool:
        """Whether this run's box is mostly far larger than the target where it says it is
        tracking (:data:`OVERSIZED_AREA`): a box that covers the frame rarely misses the
        target (IoU 0), so its tracking miss says nothing of its honesty."""
        return (self.box_to_target or 0.0) > OVERSIZED_AREA

    @cached_property
    def scores(self) -> Scores | None:
        """OTB scores, or None without ground truth, for multi-target runs and for runs that
        stopped before their first frame."""
        if not self.overlaps or self.errors is None:
            return None
        return Scores.of(self.overlaps, self.errors, self.states, self.norm_errors)


def _int_or_none(value: object) -> int | None:
    return value if isinstance(value, int) and not isinstance(value, bool) else None


@dataclass(frozen=True)
class GroundTruth:
    """A ground-truth file given to the report (``--gt [INPUT=]FILE``), read once."""

    path: str
    boxes: Sequence[Box | None]
    #: The input it belongs to (``--gt INPUT=FILE``); None: any run that recorded none.
    input: str | None = None
    #: The warning of its boxes with a negative width or height, read as the target absent
    #: (:func:`~vtrack.evaluate.groundtruth.negative_note`); None when it has none.
    note: str | None = None

    @property
    def first(self) -> int:
        """The frame its first box belongs to (``--gt-first``): ``boxes`` holds None before it
        (:func:`~vtrack.evaluate.groundtruth.read_truth`'s boxes: a list when it is 0)."""
        return self.boxes.first if isinstance(self.boxes, FrameBoxes) else 0

    @classmethod
    def read(cls, path: Path, origin: int | None = 0, input: str | None = None,
             first: int = 0) -> GroundTruth:
        """Read ``path`` with :func:`~vtrack.evaluate.groundtruth.read_truth` (InputError),
        its first box frame ``first``'s; ``origin`` None:
        :func:`~vtrack.evaluate.groundtruth.gt_origin_of` the file."""
        try:
            truth = read_truth(path, origin=gt_origin_of(path, origin), first=first)
            return cls(str(path), truth.boxes, input, negative_note(path, truth))
        except MultiTargetTruthError:
            raise InputError(f"--gt {path}: MOTChallenge ground truth (many targets); the "
                             "report's --gt scores single-target runs: a multi-target run is "
                             "scored with the ground truth given to vtrack run --gt") from None

    @classmethod
    def parse(cls, text: str, origin: int | None = 0, first: int = 0,
              names_run: Callable[[str], bool] | None = None) -> GroundTruth:
        """``--gt FILE`` or ``--gt INPUT=FILE`` (INPUT: an input's name, as the report shows
        it, or its path as given to ``vtrack run``), its first box frame ``first``'s. A file
        whose name holds ``=`` is a FILE; an INPUT holding ``=`` (``a=b.mp4``, named ``a=b``:
        ``--gt a=b=FILE``, as the report's warnings suggest) is split at the ``=`` after which
        a file is there (at the first ``=`` when none is: the file is missing).
        ``names_run(INPUT)``: whether INPUT names a run the report found (None: any does); of
        several such splits, those naming one count (the first split when none does).
        InputError naming the readings when files are there after several that count
        (``--gt a=b=c.txt``, both ``b=c.txt`` and ``c.txt`` there, runs of inputs ``a`` and
        ``a=b``)."""
        splits = [(text[:at], text[at + 1:]) for at, mark in enumerate(text) if mark == "="]
        splits = [(name, path) for name, path in splits if name and path]
        if not splits or Path(text).exists():
            return cls.read(Path(text), origin, first=first)
        there = [(name, path) for name, path in splits if Path(path).exists()]
        if len(there) > 1 and names_run is not None:
            there = [(name, path) for name, path in there if names_run(name)] or there[:1]
        if len(there) > 1:
            readings = " or ".join(f"input {name} with file {path}" for name, path in there)
            held = ", ".join(path for _, path in there[:-1])  # (each holds the next one's =)
            raise InputError(f"--gt {text}: reads as {readings}, and each file is there; rename "
                             f"{held}")
        name, path = (there or splits)[0]
        return cls.read(Path(path), origin, name, first)

    def belongs_to(self, name: str, request: dict[str, Any], found: str | None = None) -> bool:
        """Whether this file is for the run of input ``name`` (True for a plain ``--gt``):
        :func:`names_input` of its INPUT."""
        return self.input is None or names_input(self.input, name, request, found)

    def misfit(self, frames: int, whole: bool, start: int = 0) -> str | None:
        """Why these boxes cannot be a run's ground truth: a run over the whole input (from
        ``start`` on) must span as many frames as the boxes reach (from their :attr:`first`
        frame on), a run that stopped early (``--frames``, an error) no more (None: they
        fit); for fewer boxes than a whole run's frames, also how a file whose first box is of
        a later frame is aligned (:func:`~vtrack.evaluate.groundtruth.later_first_hint`)."""
        covers = max(len(self.boxes) - start, 0)
        if frames <= covers and not (whole and frames != covers):
            return None
        boxes = len(self.boxes) - self.first
        hint = ("" if not whole or frames < covers
                else later_first_hint(boxes, frames, start, self.first, COMMAND_NAMES))
        return (f"{self.path} has {boxes_for_frames(boxes, self.first, frames, start, 'its ')}"
                f"{hint}")

    def second_to(self, earlier: GroundTruth) -> str:
        """The one line refusing this file as a second ground truth for the runs ``earlier``
        (given before it) is for: naming both files."""
        if self.input is None:
            return (f"--gt {self.path}: a second ground truth for every run (--gt "
                    f"{earlier.path} is the first); give one --gt FILE, or --gt INPUT=FILE "
                    "for each input")
        return (f"--gt {self.input}={self.path}: input {self.input} has its ground truth "
                f"already (--gt {earlier.input}={earlier.path}); give one file per input")


def names_input(given_input: str, name: str, request: dict[str, Any],
                found: str | None = None) -> bool:
    """Whether ``--gt INPUT=FILE``'s INPUT (``given_input``) names the run of input ``name``:
    its name, its path as the run recorded it (``request``'s input), or a path to the same
    file as ``found`` (where the run's input is found from here: a batch records absolute
    paths, and ``--gt footage/a.mp4=...`` names one of them)."""
    given = str(request.get("input") or "").rstrip("/")
    if given_input.rstrip("/") in (name, given, Path(given).name):
        return True
    try:
        return found is not None and os.path.samefile(given_input, found)
    except (OSError, ValueError):  # (not a file here: a name, a URL, -)
        return False


def names_a_run(folders: Sequence[Path]) -> Callable[[str], bool]:
    """Whether a ``--gt INPUT=FILE``'s INPUT names the input of a run in ``folders``
    (:func:`names_input`); their records are read on the first question (one that cannot
    be read names none: the report leaves it out, saying why)."""
    @cache
    def runs() -> list[tuple[str, dict[str, Any], str | None]]:
        found = []
        for folder in folders:
            try:
                record = read_run_record(folder / "run.json")
                found.append((_input_name(record, folder), dict(record.get("request") or {}),
                              _found_path(record, "input")))
            except (InputError, TypeError, ValueError, AttributeError):
                continue
        return found

    def named(given_input: str) -> bool:
        return any(names_input(given_input, *run) for run in runs())

    return named


def pick_ground_truth(truths: Sequence[GroundTruth], name: str, request: dict[str, Any],
                      found: str | None = None) -> GroundTruth | None:
    """The ``--gt`` for the run of input ``name`` (its input ``found`` here, see
    :meth:`GroundTruth.belongs_to`): its own (``INPUT=FILE``) before a plain one. ConfigError
    (not a run left out: the options are wrong) naming both files when two ``INPUT=FILE``
    match the run, however each named its input (``--gt clip=a --gt clip.mp4=b``)."""
    own = [t for t in truths if t.input is not None and t.belongs_to(name, request, found)]
    if len(own) > 1:
        raise ConfigError(own[1].second_to(own[0]))
    plain = [t for t in truths if t.input is None]
    return (own or plain or [None])[0]


@dataclass(frozen=True)
class FailedRun:
    """A batch row with no results: a run that failed before it wrote any, or one the batch
    never ran (``interrupted`` before it started)."""

    input: str
    config: str
    error: str
    status: str
    #: The batch folder whose ``summary.csv`` holds the row.
    batch: Path | None = None


def _number(text: str | None) -> float | None:
    return None if text is None or text == "" else float(text)


def _read_csv(path: Path) -> list[dict[str, str]]:
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            return list(csv.DictReader(handle))
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: not a readable CSV file ({exc})") from None


#: Per-frame ``(overlaps, centre errors)``, None where a frame is not evaluated.
FrameScores = tuple[list[float | None], list[float | None]]


def _recorded_scores(rows: list[dict[str, str]]) -> FrameScores:
    overlaps = [_number(row.get("overlap")) for row in rows]
    errors = [
        math.inf if overlap is not None and row.get("center_error") in (None, "")
        else _number(row.get("center_error"))
        for overlap, row in zip(overlaps, rows, strict=True)
    ]
    return overlaps, errors


def _rescored(rows: list[dict[str, str]], request: dict[str, Any], gt: str, start: int
              ) -> tuple[FrameScores, Sequence[Box | None] | None]:
    """The run's boxes against the ground truth it recorded (found at ``gt``, see the module
    docstring), and those ground-truth boxes (None: the file could not be read, the recorded
    scores are used)."""
    recorded = _recorded_scores(rows)
    boxes = _boxes(rows)
    origins = [request["gt_origin"]] if "gt_origin" in request else [0, 1]
    candidates = []
    for origin in origins:
        try:
            truth = read_boxes(gt, origin=origin, first=_gt_first(request))[start:]
            scores = _scored_as_written(boxes, truth)
        except InputError:
            return recorded, None
        distance = sum(abs(a - b) for a, b in zip(scores[0], recorded[0], strict=True)
                       if a is not None and b is not None)
        candidates.append((distance, scores, truth))
    _, scores, truth = min(candidates, key=lambda c: c[0])
    return scores, truth


def _scored_as_written(boxes: Sequence[Box | None], truth: Sequence[Box | None]
                       ) -> FrameScores:
    """:func:`vtrack.evaluate.metrics.frame_scores`, each score rounded as ``track.csv`` writes
    it: as ``vtrack run`` scores its ``run.json`` (a threshold such as OTB's 0.95 then falls on
    the same side of every score in both)."""
    written = [scores_as_written(*pair) for pair in zip(*metrics.frame_scores(boxes, truth),
                                                         strict=True)]
    return [overlap for overlap, _ in written], [error for _, error in written]


def _start(record: dict[str, Any]) -> int:
    """The first frame the run tracked (``--start``, a time already found as a frame; 0 for
    records made before it existed). ValueError when it is not a frame number."""
    start = record.get("start_frame")
    if start is None:
        start = (record.get("request") or {}).get("start") or 0
    return _whole_number(start, "start_frame")


def _gt_first(request: dict[str, Any]) -> int:
    """The frame the recorded ground truth's first box belongs to (``--gt-first``; 0 for
    records made before it existed). ValueError when it is not a frame number."""
    first = _whole_number(request.get("gt_first") or 0, "gt_first")
    if first > MAX_GT_FIRST:
        raise ValueError(f"gt_first {first!r}")
    return first


def _last_frame(record: dict[str, Any]) -> int | None:
    """The last frame whose results the run wrote (``last_frame``; None: none was, or a record
    made before it existed). ValueError when it is not a frame number."""
    last = record.get("last_frame")
    return None if last is None else _whole_number(last, "last_frame")


def _whole_number(value: object, key: str) -> int:
    """``value``, a record's ``key``, when it is a whole number >= 0; ValueError otherwise."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{key} {value!r}")
    return value


def _with_skipped_frames(rows: list[dict[str, str]], start: int = 0, last: int | None = None
                         ) -> list[dict[str, str]]:
    """One row per frame from ``start`` on: frames the input skipped (damaged, no row in
    ``track.csv``) get an empty row, a frame without a box or a score, so rows line up with the
    ground truth. ValueError for frame numbers that do not increase from ``start``, or go past
    ``last`` (the run's last frame, None: not known) (rows moved or edited: vtrack writes each
    frame of the run once, in order), which would shift every later row off its frame."""
    if all(row.get("frame") == str(start + i) for i, row in enumerate(rows)) and (
            last is None or start + len(rows) - 1 <= last):
        return rows
    filled: list[dict[str, str]] = []
    for row in rows:
        frame, due = int(row["frame"]), start + len(filled)
        if frame < start:
            raise ValueError(f"frame {frame}: before the run's first frame, {start}")
        if frame < due:
            raise ValueError(f"frame {frame} after frame {due - 1}: its frame numbers do not "
                             "increase")
        if last is not None and frame > last:
            raise ValueError(f"frame {frame} after the run's last, {last}")
        filled += [{"frame": str(i), "state": metrics.SKIPPED, "x": "", "overlap": "",
                    "center_error": ""} for i in range(due, frame)]
        filled.append(row)
    return filled


def _boxes(rows: list[dict[str, str]]) -> list[Box | None]:
    return [None if row.get("x") in (None, "") else
            Box(float(row["x"]), float(row["y"]), float(row["w"]), float(row["h"]))
            for row in rows]


def _input_name(record: dict[str, Any], folder: Path) -> str:
    """The name of the run's input, as the run named it; ``SEQ-N`` for target N of an OTB
    sequence of several (its request's ``target``: ``Jogging-1``, ``Jogging-2`` are two
    sequences). ValueError for a target that is no whole number (a record edited by hand)."""
    target = _target(record)
    info = record.get("input") or {}
    if info.get("name"):
        return target_input(str(info["name"]), target)
    given = str((record.get("request") or {}).get("input") or folder.name).rstrip("/")
    path = Path(given)
    return target_input(path.stem if path.suffix else path.name, target)


def _check_whole(folder: Path, record: dict[str, Any], name: str) -> None:
    """Raise InputError when the run's CSV is not the size its ``run.json`` recorded (records
    from before sizes were recorded are checked by their row count only)."""
    recorded = (record.get("output_bytes") or {}).get(name)
    if recorded is None:
        return
    if isinstance(recorded, bool) or not isinstance(recorded, int):
        raise InputError(f"{folder / 'run.json'}: not a vtrack run record")
    found = sizes(folder, [name]).get(name)
    if found != recorded:
        held = "is missing" if found is None else f"holds {found} bytes"
        raise InputError(f"{folder / name}: {held}, run.json records {recorded} (cut or edited "
                         "after the run); not scored")


def _target(record: dict[str, Any]) -> int | None:
    """The target of an OTB sequence of several the run tracked (its request's ``target``),
    None for none; ValueError for one that is no whole number (a record edited by hand)."""
    target = (record.get("request") or {}).get("target")
    return None if target is None else _whole_number(target, "target")


def _input_key(record: dict[str, Any]) -> str:
    """What tells a run's input from another of the same name: its file name and the file's
    size (and a folder's file count) as the run recorded them, not the modification time (a
    copy of the same clip is the same input) nor the folder (a relative path's depends on where
    the run was started). An image sequence is its sequence folder's name as the run recorded
    it (``SEQ`` for ``SEQ/img``, :func:`~vtrack.io.sidecar.sequence_of`: one sequence given
    either way, ``.`` from inside ``SEQ/img`` too), the target it tracked and its frames'
    count and size as the run opened them (its folder's files are not its images': ``SEQ``
    holds its ground truth too)."""
    identity = (record.get("identity") or {}).get("input")
    given = Path(str((record.get("request") or {}).get("input") or "").rstrip("/"))
    info = record.get("input") or {}
    if isinstance(info, dict) and info.get("kind") == "images":
        return json.dumps({"name": info.get("name") or (sequence_of(given) or given).name,
                           "target": _target(record),
                           **{k: info.get(k) for k in ("frame_count", "width", "height")}},
                          sort_keys=True)
    return json.dumps({"name": given.name,
                       **({k: identity.get(k) for k in ("size", "files")}
                          if isinstance(identity, dict) else {})}, sort_keys=True)


def source_name(run: RunResult) -> str | None:
    """The name of the input ``run`` read (None: it cannot be read again, ``source``) as its
    file or folder shows it (``a.mkv``), an image sequence's by its sequence folder
    (``Jogging/img``: ``Jogging``) and one target of an OTB sequence of several by the
    target too (``Jogging-1``: :func:`~vtrack.evaluate.groundtruth.target_input`)."""
    if not run.source:
        return None
    path = Path(run.source)
    folder = sequence_of(path) if path.is_dir() else None
    return target_input((folder or path).name, run.target)


def _found_path(record: dict[str, Any], role: str) -> str | None:
    """Where the file the run recorded as its ``role`` (``input``, ``gt``) is found from here:
    a relative path is read from the folder the run was started in (``working_dir``) when
    that holds it, else as given (a record without one, or a tree moved with its runs); None
    when the run recorded none."""
    given = (record.get("request") or {}).get(role)
    if given is None:
        return None
    path = str(given)
    started_in = record.get("working_dir")
    if not isinstance(started_in, str) or path == "-" or is_url(path) or os.path.isabs(path):
        return path
    there = os.path.join(started_in, path)
    # one file, one name: its real path (`..` after a link is not removed as text)
    return os.path.realpath(there) if os.path.exists(there) else path


def read_once(spec: str) -> bool:
    """Whether the input a run recorded (``run.json``'s request) gave its frames once, as they
    came: stdin (``-``), a URL (a live stream, or a server that may send another video now), a
    capture device, a FIFO or another special file. Reading it again would wait for a sender
    or show what is there now, not the frames the run tracked."""
    return spec == "-" or is_url(spec) or is_live(spec) or special_kind(spec) is not None


def _changed_since_run(record: dict[str, Any], role: str, path: str) -> bool:
    """Whether the file the run recorded as its ``role`` (``input``, ``gt``) now has another
    identity (size, modification time) than the one ``run.json`` recorded; False when the
    run recorded none (an older record, or not a regular file) or the file is not found here
    (a relative path from another folder: the recorded scores are used, see ``_rescored``)."""
    recorded, now = (record.get("identity") or {}).get(role), file_identity(path)
    return recorded is not None and now is not None and now != recorded


def _multi_target(folder: Path, record: dict[str, Any]) -> bool:
    """Whether the run tracked many targets: its ``run.json`` lists ``tracks.csv`` among its
    outputs (so a missing one is named as missing), or the folder holds one (older records)."""
    recorded = [*(record.get("outputs") or []), *(record.get("output_bytes") or {})]
    return "tracks.csv" in recorded or (folder / "tracks.csv").is_file()


def _run_result(folder: Path, record: dict[str, Any], summary: dict[str, Any]) -> RunResult:
    """What ``run.json`` says of a run (its scores are read after). ValueError or TypeError
    for values of the wrong kind (a record edited by hand)."""
    fps = (record.get("timing") or {}).get("fps", summary.get("fps"))
    if fps is not None and (isinstance(fps, bool) or not isinstance(fps, int | float)):
        raise ValueError(f"fps {fps!r}")
    if (record.get("request") or {}).get("gt_origin", 0) not in (0, 1):
        raise ValueError("gt_origin")
    _gt_first(record.get("request") or {})
    if record["status"] not in BATCH_STATUSES:  # (read_run_record: it has one)
        raise ValueError("status")
    _start(record)  # frame numbers (read again with the rows)
    _last_frame(record)
    return RunResult(
        folder=folder,
        input=_input_name(record, folder),
        config=str((record.get("config") or {}).get("name") or summary.get("config") or "?"),
        status=str(record["status"]),
        frames=record["frames"],
        fps=fps,
        frames_occluded=int(summary.get("frames_occluded") or 0),
        frames_lost=int(summary.get("frames_lost") or 0),
        frames_skipped=int(summary.get("frames_skipped") or 0),
        multi_target=_multi_target(folder, record),
        error=record.get("error"),
        input_frames=_int_or_none((record.get("input") or {}).get("frame_count")),
        input_key=_input_key(record),
        image_identity=_image_identity(record),
        image_bytes=_int_or_none((record.get("input") or {}).get("image_bytes")),
        target=_target(record),
        config_key=json.dumps((record.get("config") or {}).get("stages") or "",
                              sort_keys=True),
    )


def _mot_metrics(record: dict[str, Any]) -> dict[str, int | float | None]:
    """A multi-target run's ``metrics`` as ``run.json`` records them: a finite number (or
    null) per name. ValueError naming the first that is not (a string, a list, a true/false,
    a number past a float's range: a record edited by hand)."""
    metrics = dict(record.get("metrics") or {})
    for key, value in metrics.items():
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"metrics.{key} {value!r}")
        try:
            finite = math.isfinite(value)
        except OverflowError:  # an int past a float's range
            finite = False
        if not finite:
            raise ValueError(f"metrics.{key} is not a finite number")
    return metrics


def _image_identity(record: dict[str, Any]) -> str | None:
    """The ``input.image_identity`` of ``record`` when it is text, else None (none recorded:
    an older vtrack's, or not an image sequence)."""
    identity = (record.get("input") or {}).get("image_identity")
    return identity if isinstance(identity, str) else None


def _text_or_none(value: object) -> str | None:
    """``value`` when it is a string or None; ValueError for anything else."""
    if value is not None and not isinstance(value, str):
        raise ValueError(f"{value!r} is not text")
    return value


def _stopped_by_frames(record: dict[str, Any], frames: int) -> bool:
    """Whether ``--frames`` ended the run of ``record`` (spanning ``frames`` frames) before
    its input ended, as ``run.json`` records it (``stopped_by_frames``); a record from before
    that: ``--frames N`` reached, or any ``--frames Ts`` (a duration may have ended it)."""
    recorded = record.get("stopped_by_frames")
    if recorded is not None:
        return bool(recorded)
    request = record.get("request") or {}
    limit = request.get("max_frames")
    return bool(limit and frames >= limit) or request.get("max_s") is not None


def load_run(folder: Path, gt: GroundTruth | Sequence[GroundTruth] | None = None) -> RunResult:
    """Read one run folder. ``gt`` scores a single-target run that recorded no ground truth
    (the file for its input, see :func:`pick_ground_truth`, if its length fits the run).

    Raises InputError naming the file when ``run.json`` or the CSV cannot be read, or the CSV
    is not what the run wrote (another size than recorded, or another number of rows than
    the frames recorded: cut or edited).
    """
    record_path = folder / "run.json"
    record = read_run_record(record_path)
    summary = record.get("summary") or {}
    request = record.get("request") or {}
    truths = [] if gt is None else [gt] if isinstance(gt, GroundTruth) else list(gt)
    try:
        result = _run_result(folder, record, summary)
        # one file, however each run named it: found from the folder the run started in
        found_gt = result.ground_truth = _found_path(record, "gt")
        found_input = _found_path(record, "input")
        # the --gt for its input, matched for every run: one input named two ways is refused
        # whether or not the run takes it (its own ground truth, several targets)
        truth = result.gt_given = pick_ground_truth(truths, result.input, request, found_input)
        if result.multi_target:
            result.mot = _mot_metrics(record)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{record_path}: not a vtrack run record") from None
    if result.multi_target:
        _check_whole(folder, record, "tracks.csv")
        return result
    _check_whole(folder, record, "track.csv")
    try:
        written = _read_csv(folder / "track.csv")
        if len(written) != result.frames:
            raise InputError(f"{folder / 'track.csv'}: holds {plural(len(written), 'row')}, "
                             f"run.json records {plural(result.frames, 'frame')} (cut or "
                             "edited after the run); not scored")
        start = _start(record)
        rows = _with_skipped_frames(written, start, _last_frame(record))
        result.states = [row["state"] for row in rows]
        result.confidence = [_number(row.get("score")) for row in rows]
        result.boxes, result.first_frame = _boxes(rows), start
        if found_input is not None and read_once(found_input):
            result.live_input = True
        elif not request.get("raw") and found_input is not None:
            if _changed_since_run(record, "input", found_input):
                result.source_changed = (f"the input {found_input} changed since the run (its "
                                         "size or modification time); its frames may not be "
                                         "the ones tracked")
            else:
                result.source = found_input
        if found_gt and _changed_since_run(record, "gt", found_gt):
            result.overlaps, result.errors = _recorded_scores(rows)
            result.note = (f"{folder}: the ground truth {request['gt']} changed after the run; "
                           "scored with the overlaps the run recorded")
        elif found_gt:
            (result.overlaps, result.errors), result.truth = _rescored(rows, request, found_gt,
                                                                      start)
            if result.truth is not None:
                result.norm_errors = metrics.normalized_center_errors(result.boxes,
                                                                      result.truth)
        elif truth is not None:
            # Frames the run spans (skipped frames included); one stopped by --frames (N or
            # a duration) is scored on its frames like one that stopped on an error
            frames = len(rows)
            whole = result.status == "complete" and not _stopped_by_frames(record, frames)
            misfit = truth.misfit(frames, whole, start)
            if misfit:
                # (quoted as a shell word, without shell_word's ./ before a leading -: INPUT
                # is a name here, and --gt takes a value starting with - as it is)
                result.note = (f"{folder}: input {result.input} not scored: {misfit}; give "
                               f"--gt {shlex.quote(result.input)}=FILE with its own ground "
                               "truth")
            else:
                result.ground_truth, result.gt_scored = truth.path, True
                result.truth = truth.boxes[start:]
                result.overlaps, result.errors = _scored_as_written(result.boxes,
                                                                    result.truth)
                result.norm_errors = metrics.normalized_center_errors(result.boxes,
                                                                      result.truth)
    except (KeyError, ValueError, TypeError, OverflowError) as exc:
        raise InputError(f"{folder / 'track.csv'}: not a vtrack track.csv ({exc})") from None
    return result


def run_folders(paths: Sequence[Path], walked: Mapping[Path, Walked],
                problems: list[str]) -> list[Path]:
    """Every folder holding a ``run.json`` at or below ``paths`` (sorted, without repeats), as
    ``walked`` (:func:`~vtrack.report.walk.walk_results`) found them.

    A path may be a run folder, a batch folder, any folder above them, or a ``run.json``.
    A symbolic link to a folder below one is not followed (it may lead anywhere, or back up):
    one that leads out of the folders walked is one line naming it appended to ``problems``
    (one into them, as a batch tree's ``latest``, is nothing: its runs are found where it
    leads); so is each folder that could not be read, once.
    """
    found: dict[Path, None] = {}
    links: dict[Path, None] = {}
    unreadable: dict[str, None] = {}
    tops = [path.resolve() for path in paths if path.is_dir()]
    for path in paths:
        if path.is_dir():
            here = walked[path]
            for folder in sorted(here.holding["run.json"]):
                found.setdefault(folder.resolve())
            links.update(dict.fromkeys(here.links))
            unreadable.update(dict.fromkeys(here.unreadable))
        elif path.name == "run.json" and os.path.lexists(path):
            found.setdefault(path.parent.resolve())  # (a link in a loop: reading it says why)
        elif not path.exists():
            raise InputError(f"{path}: no such file or folder{_link_note(path)}")
        else:
            raise InputError(f"{path}: not a results folder or run.json")
    problems += list(unreadable)
    problems += [f"not followed: {link} (a symbolic link to a folder; give it as RESULTS "
                 "to report the runs in it)" for link in sorted(links)
                 if not any(link.resolve().is_relative_to(top) for top in tops)]
    return list(found)


def _link_note(path: Path) -> str:
    """What ``path``, which cannot be found, is when it is a symbolic link: `` (a symbolic
    link to nothing)`` or `` (a symbolic link in a loop)``; else nothing."""
    if not path.is_symlink():
        return ""
    try:
        os.stat(path)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return " (a symbolic link in a loop)"
    return " (a symbolic link to nothing)"


def still_written(walked: Mapping[Path, Walked]) -> list[str]:
    """A warning per folder at, above or below the paths ``walked``
    (:func:`~vtrack.report.walk.walk_results`) that a running ``vtrack batch`` (or ``vtrack
    run``) still writes (its lock is held by a live process,
    :func:`~vtrack.io.outdir.live_holder`; a stale lock is no warning): a report of it shows
    only what was finished. A folder inside one already named is not named again."""
    folders: set[Path] = set()
    for path, found in walked.items():  # (a path not there: named as missing by run_folders)
        path = path.resolve()
        start = path if path.is_dir() else path.parent
        folders.update([start, *start.parents])
        folders.update(folder.resolve() for folder in found.holding[LOCK_NAME])
    named: list[Path] = []
    warnings = []
    for folder in sorted(folders, key=lambda f: len(f.parts)):
        holder = live_holder(folder)
        if holder is None or any(folder.is_relative_to(n) for n in named):
            continue
        named.append(folder)
        what = "a batch" if holder.split(": ", 1)[-1].startswith("vtrack batch") else "vtrack"
        warnings.append(f"{folder}: {what} is still writing it ({holder}); this report shows "
                        "only what it had finished")
    return warnings


#: The statuses a batch's ``summary.csv`` row may have.
BATCH_STATUSES = frozenset({STATUS_COMPLETE, STATUS_PARTIAL, STATUS_INTERRUPTED, STATUS_FAILED})


def _batch_rows(summary: Path, problems: list[str]) -> list[dict[str, str]]:
    """The rows of a batch's ``summary.csv``, one per (input, config) (a repeated pair: its
    last row, the newest), empty rows skipped. A file that cannot be read, a header other than
    the batch's, rows that are not a batch's (another number of columns, a broken quote, an
    unknown status, no input or config) are each one line appended to ``problems`` naming the
    file."""
    rows: dict[tuple[str, str], dict[str, str]] = {}
    unread: list[str] = []
    try:
        with summary.open(newline="", encoding="utf-8") as handle:
            reader = csv.reader(handle, strict=True)
            header = next(reader, [])
            if not header:
                return []
            if tuple(header) not in (BATCH_COLUMNS, EARLIER_BATCH_COLUMNS):
                problems.append(f"{summary}: not a vtrack batch summary (its header is "
                                f"{printable(','.join(header))[:80]!r}); the runs without "
                                "results it may list are not shown")
                return []
            while True:
                first = reader.line_num + 1
                try:
                    fields = next(reader)
                except StopIteration:
                    break
                except csv.Error:  # a broken quote: the rows it swallowed
                    unread.append(_lines(first, reader.line_num))
                    continue
                row = dict(zip(header, fields, strict=False))
                if not any(field.strip() for field in fields):
                    continue
                if (len(fields) != len(header) or row["status"] not in BATCH_STATUSES
                        or not row["input"] or not row["config"]):
                    unread.append(_lines(first, reader.line_num))
                    continue
                row["input"] = read_name(row["input"])  # (c\xff: the input c\udcff)
                rows[(row["input"], row["config"])] = row
    except OSError as exc:
        problems.append(f"{summary}: cannot read ({os_reason(exc)}); the runs without results "
                        "it lists are not shown")
    except UnicodeDecodeError:
        problems.append(f"{summary}: not a text file; the runs without results it lists are "
                        "not shown")
    if unread:
        problems.append(f"{summary}: line{'s' if len(unread) > 1 or '-' in unread[0] else ''} "
                        f"{', '.join(unread[:5])}{' ...' if len(unread) > 5 else ''} not read "
                        f"(not a batch row: {len(header)} columns with a known "
                        "status, or a broken quote); a run without results there is not shown")
    return list(rows.values())


def _lines(first: int, last: int) -> str:
    return str(first) if first >= last else f"{first}-{last}"


def failed_runs(paths: Iterable[Path], walked: Mapping[Path, Walked],
                reported: Iterable[RunResult], problems: list[str]) -> list[FailedRun]:
    """Rows of batch ``summary.csv`` files at or below ``paths`` (as ``walked`` found them,
    :func:`~vtrack.report.walk.walk_results`) that are not complete and
    left no results (no run of ``reported`` is in their results folder, the batch's
    ``<input>/<config>/``: names alone may have been told apart since), each (input, config)
    once (a report's own ``summary.csv``, :func:`~vtrack.io.outdir.is_report_folder`, is no
    batch's). What could not be read of those files is appended to ``problems`` (see
    :func:`_batch_rows`), and one line per file naming its complete rows whose results folder
    holds no ``run.json``."""
    ran = {run.folder.resolve() for run in reported}
    failed = []
    for path in paths:
        summaries = [path] if path.is_file() else sorted(
            folder / "summary.csv" for folder in walked.get(path, Walked()).holding["summary.csv"])
        for summary in summaries:
            if summary.name != "summary.csv" or is_report_folder(summary.parent):
                continue
            gone = []
            for r in _batch_rows(summary, problems):
                folder = summary.parent / folder_name(r["input"], "input") / folder_name(
                    r["config"])
                if folder.resolve() in ran:
                    continue
                if r["status"] != STATUS_COMPLETE:
                    failed.append(FailedRun(r["input"], r["config"], r["error"] or NEVER_RAN,
                                            r["status"],
                                            summary.parent.resolve()))
                elif not os.path.lexists(folder / "run.json"):  # (one that is: left out)
                    gone.append(f"{r['input']} [{r['config']}]")
            if gone:
                named = ", ".join(sorted(gone)[:5]) + (" ..." if len(gone) > 5 else "")
                problems.append(
                    f"{summary}: {plural(len(gone), 'complete run')} listed without results "
                    f"here (no run.json in <input>/<config>/: moved or removed): {named}; not "
                    "in this report")
    return failed
