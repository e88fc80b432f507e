"""One input end to end: reader -> pipeline -> writers, with ground truth, errors and a summary.

``run(RunRequest(...))`` is what ``vtrack run`` and every ``vtrack batch`` job call. It writes into
``request.out_dir``:

- ``track.csv`` (single target) or ``tracks.csv`` (multi-target, MOTChallenge order), rows
  flushed as frames complete;
- ``annotated.mp4`` unless ``video=False``;
- ``run.json``, written last and atomically: its ``status`` says whether the run is
  ``complete``, ``partial`` (the input broke part way; everything before was tracked),
  ``interrupted`` (Ctrl-C or SIGTERM) or ``failed`` (an output could not be written, e.g. a full
  disk, or the tracker stopped on an error). A complete-looking file is complete: the CSV and
  video are written under temporary names (unique to the process) and renamed when closed, then
  checked (CSV rows, the video's frame count); ``outputs`` lists only files that passed. The
  CSV is renamed last, once the video is closed, just before ``run.json``: a run killed
  outright before then leaves no ``track.csv`` without a record.

The folder is taken with :class:`~vtrack.io.outdir.OutputFolder` (a lock: a second run on it is
refused), only once the input has opened and the request is valid, and the files an earlier run
left in it are replaced (only vtrack's own: ``RUN_OUTPUTS``). User errors raise
:class:`~vtrack.errors.VtrackError` before anything is written (and leave no empty folder); an
input that breaks part way returns a summary with ``status = "partial"`` and the error message.
"""

from __future__ import annotations

import math
import os
import platform
import signal
import sys
import time
from collections import Counter, deque
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import av
import cv2
import numpy as np

from vtrack import __version__
from vtrack.annotate import Annotator
from vtrack.config import config_file
from vtrack.errors import (
    LIBRARY_NAMES,
    ConfigError,
    FirstFrameError,
    InputError,
    Interrupted,
    OptionNames,
    OutputBrokenError,
    OutputError,
    PartialInputError,
    StreamReaderGone,
    VtrackError,
    cut,
    handling_stop_signals,
    number_text,
    plural,
    printable,
    shell_word,
)
from vtrack.evaluate.groundtruth import (
    boxes_for_frames,
    dropped_notes,
    groundtruth_beside,
    later_first_hint,
    negative_note,
    numbered_groundtruth,
    past_end_note,
    read_mot_counting,
    read_truth,
)
from vtrack.evaluate.metrics import SKIPPED, score_frame, summarize_scores
from vtrack.frame import Frame
from vtrack.geometry import Box, check_init_box
from vtrack.io import (
    CsvWriter,
    InputInfo,
    Source,
    VideoWriter,
    check_input,
    open_source,
    write_json,
)
from vtrack.io.csvfile import box_as_written, scores_as_written
from vtrack.io.files import (
    is_temp_of,
    places_of,
    real_path,
    refuse_replacing_file,
    same_file,
)
from vtrack.io.identity import sizes
from vtrack.io.images import is_image_of, sequence_info
from vtrack.io.outdir import LOCK_NAME, RUN_OUTPUTS, OutputFolder, refuse_replacing
from vtrack.io.sidecar import has_sidecar, read_sidecar, sidecar_path
from vtrack.io.source import (
    TIME_SLACK_S,
    no_frame_after_text,
    past_end,
    past_end_text,
    seek_time,
    start_toward,
)
from vtrack.io.stream import STDOUT, StreamWriter
from vtrack.io.videowriter import VideoRefusedError, verify_video
from vtrack.latency import Latencies
from vtrack.params import MAX_TRACK_ID
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.request import RunRequest
from vtrack.stages.base import TrackState, TrackStatus

if TYPE_CHECKING:
    from vtrack.evaluate.mot import MotScore

#: Columns every single-target ``track.csv`` starts with (the columns every tracker writes).
TRACK_COLUMNS = (
    "frame", "time_s", "x", "y", "w", "h", "cx", "cy", "state", "score", "overlap", "center_error",
)
#: MOTChallenge order for multi-target ``tracks.csv`` (frames 1-based), then our ``state``.
MOT_COLUMNS = ("frame", "id", "x", "y", "w", "h", "conf", "wx", "wy", "wz", "state")

STATUS_COMPLETE, STATUS_PARTIAL, STATUS_INTERRUPTED = "complete", "partial", "interrupted"
#: The tracker stopped on an error that is not the input's (e.g. a target with no colour for a
#: hue model): outputs up to there are valid, ``run.json`` says so, and the error is re-raised.
STATUS_FAILED = "failed"


@dataclass
class RunSummary:
    """The outcome of one run: what ``vtrack run`` prints and ``vtrack batch`` tabulates."""

    input: str
    out_dir: str
    config: str
    status: str
    frames: int
    seconds: float
    fps: float
    mean_overlap: float | None = None
    auc: float | None = None
    precision20: float | None = None
    frames_occluded: int = 0
    frames_lost: int = 0
    #: A multi-target run: the track ids ``tracks.csv`` holds (None: single target), and the
    #: highest of them (None: no track): :attr:`resume` numbers the next run's tracks on from
    #: it (``--first-id``, one more).
    tracks: int | None = None
    last_track_id: int | None = None
    #: Frames of the input that could not be decoded and were skipped (damaged file), and
    #: those with no picture at all (``frames_missing``).
    frames_skipped: int = 0
    #: Of ``frames_skipped``, images missing from a folder's numbering.
    frames_missing: int = 0
    #: A live source's frames passed over because a newer one arrived while the tracker was
    #: busy (``--live``); track.csv keeps the source's frame numbers, with these left out.
    frames_passed: int = 0
    error: str | None = None
    warnings: list[str] = field(default_factory=list)
    mot: dict[str, Any] | None = None
    #: A multi-target chain (tracks.csv): the single target's occluded/lost counts do not apply.
    multi_target: bool = False
    #: The signal that interrupted the run (``SIGINT``, ``SIGTERM``), if one did.
    interrupted_by: str | None = None
    #: An interrupted run: the options that go on from where it stopped (``--start 157 --init
    #: 9.74,9.83,10.4,10.4``: the last frame tracked and its box as written; a multi-target
    #: run's ``--start 534 --frames 866 --first-id 13``: the frame after the last one written,
    #: and ids on from this run's), given again with the run's other options; None when there
    #: is nothing to go on from (a live source).
    resume: str | None = None

    def line(self, label: str | None = None) -> str:
        """The one-line summary printed at the end of ``vtrack run`` (headed by ``label``,
        default the input)."""
        parts = [plural(self.frames, "frame"), f"{self.fps:.1f} fps"]
        if self.tracks is not None:
            parts.append(plural(self.tracks, "track"))
        if self.mean_overlap is not None:
            parts.append(f"mean overlap {self.mean_overlap:.3f}")
            parts.append(f"AUC {self.auc:.3f}")
            parts.append(f"precision@20 {self.precision20:.3f}")
        if self.mot:  # a metric with no value (motp without a match) is left out
            parts += [f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                      for k, v in self.mot.items()
                      if k in ("mota", "motp", "idf1", "id_switches", "mostly_tracked",
                               "mostly_lost") and v is not None]
        if not self.multi_target:  # one target's states; tracks have their own in tracks.csv
            parts.append(f"occluded {self.frames_occluded}")
            parts.append(f"lost {self.frames_lost}")
        if self.frames_skipped > self.frames_missing:
            parts.append(f"skipped {self.frames_skipped - self.frames_missing} undecodable")
        if self.frames_missing:
            parts.append(f"skipped {self.frames_missing} missing from the numbering")
        if self.frames_passed:
            parts.append(f"skipped {self.frames_passed} while busy (live)")
        status = "" if self.status == STATUS_COMPLETE else f" ({self.status})"
        head = f"{label or self.input}{status}: "
        return printable(head + ", ".join(parts) + f" -> {self.out_dir}")  # one line


def versions() -> dict[str, str]:
    """Versions of everything that shapes a result, for ``run.json``."""
    return {
        "vtrack": __version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "pyav": av.__version__,
        # FFmpeg's release (what a paper cites), then the decoder library's own version
        "ffmpeg": str(getattr(av, "ffmpeg_version_info", "")),  # PyAV >= 13.1
        "libavcodec": ".".join(str(v) for v in av.library_versions.get("libavcodec", ())),
        # not platform.platform(): it runs `uname -p` in a subprocess (~4 ms of every run)
        "platform": f"{platform.system()}-{platform.release()}-{platform.machine()}",
    }


class _Signals:
    """SIGINT and SIGTERM as Ctrl-C, never in the middle of one frame's outputs.

    Outside ``writing()`` a signal raises :class:`~vtrack.errors.Interrupted` at once (e.g.
    while waiting for the next frame); inside, it is held and raised when the frame's row and
    picture are both out. After :meth:`hold` (the outputs are being closed and recorded) signals
    are only noted: the run finishes its records. Only installed in the main thread (signal
    handlers can only be set there).

    While ``drain`` is set (the frame loop of a ``--follow`` run: ``Source.stop_at_end``), a
    first signal that comes once the followed file has been read to its end is only noted
    (``draining``): the input ends there, the frames the decoder still holds (already in the
    file; milliseconds of work) are tracked, then the run ends interrupted. A second signal
    stops it as usual.
    """

    def __init__(self) -> None:
        self.pending: int | None = None
        #: The first signal received, even one whose exception FFmpeg's C code swallowed (a
        #: read or an open it interrupted then fails with EINTR or "invalid data").
        self.received: int | None = None
        self.inside = False
        #: Ends a followed input where it is now, True if it did (see the class docstring).
        self.drain: Callable[[], bool] | None = None
        #: The signal that ended the input (``drain``): the run ends interrupted by it once
        #: the frames already read are tracked.
        self.draining: int | None = None
        self._handlers = ExitStack()

    def __enter__(self) -> _Signals:
        self._handlers.enter_context(handling_stop_signals(self._handle))
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._handlers.close()

    def _handle(self, signum: int, frame: object) -> None:
        self.received = self.received or signum
        if self.draining is None and self.pending is None and self.drain is not None \
                and self.drain():
            self.draining = signum
        elif self.inside:
            self.pending = self.pending or signum
        else:
            raise Interrupted(signum)

    def stopping(self) -> bool:
        """Whether a signal held (``pending``) will end the run once the frame is out."""
        return self.pending is not None

    def hold(self) -> None:
        """From now on signals are only noted (``pending``), never raised."""
        self.inside = True

    def release(self) -> None:
        """Signals raise again: one noted while held at once (Interrupted)."""
        self.inside = False
        if self.pending:
            raise Interrupted(self.pending)

    @contextmanager
    def live(self) -> Iterator[None]:
        """Inside the block signals raise at once (one noted before: on entry), whatever
        held them: for a wait a signal must cut short. The hold is back after it."""
        held = self.inside
        try:
            self.release()
            yield
        finally:
            self.inside = held

    @contextmanager
    def writing(self) -> Iterator[None]:
        self.inside = True
        try:
            yield
        except BaseException:
            self.inside = False
            raise
        self.release()


def _numbering(info: InputInfo) -> str:
    """How an input's frames are numbered, for a message about one it does not have: ``frames
    0..149`` when its frame count is known (exact: read to its end, or listed by its
    container), else ``frames are numbered from 0``."""
    count = info.frame_count
    if count and not info.frame_count_estimated:
        return f"frames 0..{count - 1}"
    return "frames are numbered from 0"


def _from(source: Source, start: int, what: str, option: str, boxed: bool) -> Iterator[Frame]:
    """``source``'s frames numbered ``start`` and on (the earlier ones are decoded and
    dropped). With a first box (``boxed``), InputError when frame ``start`` itself is missing
    (damaged, or no image numbered for it: ``what`` is the input's name) and a later one comes
    first: the initial box is frame ``start``'s, not that one's (the message names the start
    ``option``). A chain without one (it finds its targets itself) starts at the next frame
    there is, as it would go past that frame in a whole run (the way an interrupted run's
    ``--start`` goes on)."""
    if start == 0:
        yield from source
        return
    first = True
    for frame in source:
        if frame.index < start:
            continue
        if first and boxed and frame.index > start:
            raise InputError(f"{option} {start}: frame {start} of {what} {source.absent(start)}"
                             f"; the next is frame {frame.index}: start at a frame it has")
        first = False
        yield frame


@dataclass
class _Span:
    """``--frames``: how much a run tracks from its first frame on: at most ``count`` frames,
    or (``seconds``, as ``ffmpeg -t``) the frames whose timestamp is less than ``seconds``
    past the first one's, so a variable frame rate is followed (the first frame is always
    taken; :data:`TIME_SLACK_S` of rounding: a constant rate gives ``ceil(seconds x fps)``
    frames); neither: every frame."""

    count: int | None = None
    seconds: float | None = None
    #: A frame at or past ``seconds`` came: the duration, not the input, ended the run.
    ended_by_time: bool = False
    #: Frames handed on so far.
    taken: int = 0
    #: The count's last frame was the input's last (:meth:`Source.ends_after`): the input
    #: ended there as well, so ``--frames`` did not end the run before it.
    input_ended: bool = False

    @property
    def given(self) -> bool:
        """Whether ``--frames`` was given."""
        return self.count is not None or self.seconds is not None

    @property
    def stopped(self) -> bool:
        """Whether ``--frames`` ended the run (its count of frames taken, unless the last of
        them was the input's last, known without reading on; or a frame at or past its
        duration came) rather than the input's end."""
        return self.ended_by_time or (self.count is not None and self.taken >= self.count
                                      and not self.input_ended)

    def take(self, source: Source, frames: Iterator[Frame]) -> Iterator[Frame]:
        """``frames`` (``source``'s) up to the end of the span. A count ends it as its last
        frame is handed on, without asking ``frames`` for one more (a pipe or stream may hold
        it back for ever); a duration needs the next frame's timestamp to end, and gives that
        frame back (:meth:`Source.not_taken`): the places between the last frame taken and it
        are not the run's."""
        end: float | None = None
        if self.count is not None and self.count <= 0:
            return
        for frame in frames:
            if self.seconds is not None:
                if end is None:
                    end = frame.time_s + self.seconds - TIME_SLACK_S
                elif frame.time_s >= end:
                    self.ended_by_time = True
                    source.not_taken(frame)
                    return
            self.taken += 1
            yield frame
            if self.count is not None and self.taken >= self.count:
                self.input_ended = source.ends_after(frame.index)
                return


@dataclass
class _Timeline:
    """The input's own timestamps (``time_s``) as the frames come: how often they went back
    (a live sender restarted, a stream spliced) while frame numbers carried on, and how many
    frames repeated the timestamp of the frame before (a muxer that stamped them alike)."""

    #: Times a frame's timestamp was earlier than the one before it.
    jumps: int = 0
    #: The first such jump: (frame, the timestamp before, the frame's).
    first: tuple[int, float, float] | None = None
    #: Frames whose timestamp was the one of the frame before, and the first of them:
    #: (frame, the timestamp).
    repeats: int = 0
    first_repeat: tuple[int, float] | None = None
    _last: float | None = None

    def add(self, index: int, time_s: float) -> None:
        """Note frame ``index``'s timestamp."""
        if self._last is not None and time_s < self._last:
            self.jumps += 1
            self.first = self.first or (index, self._last, time_s)
        elif self._last is not None and time_s == self._last:
            self.repeats += 1
            self.first_repeat = self.first_repeat or (index, time_s)
        self._last = time_s

    def warnings(self, what: str, gt_path: Path | None) -> list[str]:
        """A line each for ``run.json`` and stderr when the timestamps went back, and when
        frames repeated a timestamp; none when neither happened."""
        notes = []
        if self.first is not None:
            index, before, after = self.first
            note = (f"{what}: its timestamps jumped back {plural(self.jumps, 'time')} (first "
                    f"at frame {index}: {before:.4f} s -> {after:.4f} s; the source "
                    "restarted?): track.csv's time_s starts again there while frame numbers "
                    "carry on")
            if gt_path is not None:
                note += (f"; {gt_path} is matched by frame number counted from the first "
                         "frame received, so its boxes after a restart may belong to other "
                         "frames")
            notes.append(note)
        if self.first_repeat is not None:
            index, at = self.first_repeat
            notes.append(
                f"{what}: {plural(self.repeats, 'frame')} repeated the timestamp of the frame "
                f"before (first at frame {index}: {at:.4f} s again; a damaged or re-stamped "
                "file?): track.csv's time_s is the same for those frames while frame numbers "
                "carry on")
        return notes


def _fmt(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else value


class _SingleTargetRows:
    """Formats single-target results as ``track.csv`` rows and, with ground truth, keeps each
    frame's overlap, centre error and state for the metrics (without it nothing grows with the
    run's length). The scores are those of the box as written, rounded as written: run.json's
    metrics are what anyone recomputes from ``track.csv``."""

    def __init__(self, extras: tuple[str, ...], gt: Sequence[Box | None] | None,
                 start: int = 0) -> None:
        self.columns = TRACK_COLUMNS + extras
        self.extras = extras
        self.gt = gt
        #: ``overlaps``, ``errors`` and ``states`` hold the frames from ``start`` on
        #: (``--start``), those the input skipped included (no box).
        self.start = start
        self.overlaps: list[float | None] = []
        self.errors: list[float | None] = []
        self.states: list[str] = []

    def _score(self, index: int, box: Box | None) -> tuple[float | None, float | None]:
        """Frame ``index``'s (overlap, centre error) of ``box`` (as ``track.csv`` writes it)
        as ``track.csv`` holds them (an error of ``inf``, no box claimed, is an empty cell)."""
        if self.gt is None or index >= len(self.gt):
            return None, None
        return scores_as_written(*score_frame(box, self.gt[index]))

    def rows(self, result: FrameResult) -> list[list[Any]]:
        # scored as written, so a reader's rescoring of track.csv gives the same
        written = None if result.box is None else box_as_written(result.box)
        overlap, error = self._score(result.index, written)
        if self.gt is not None:  # kept for the metrics only: without ground truth, nothing
            at = result.index - self.start
            for skipped in range(self.start + len(self.overlaps), result.index):
                gone = self._score(skipped, None)  # frames the input skipped: no box
                self.overlaps.append(gone[0])
                self.errors.append(gone[1])
            self.overlaps.append(overlap)
            self.errors.append(error)
            self.states += [SKIPPED] * (at - len(self.states))  # no state of the tracker's
            self.states.append(result.state)
        box = result.box
        geometry = [None] * 6 if box is None else [*written, box.cx, box.cy]
        row = [result.index, result.time_s, *geometry, result.state, _fmt(result.score),
               overlap, _fmt(error)]
        return [row + [result.extras.get(column) for column in self.extras]]

    def undo(self, result: FrameResult) -> None:
        """Forget ``result`` (its rows could not be written)."""
        for kept in (self.overlaps, self.errors, self.states):
            del kept[result.index - self.start:]


class _MultiTargetRows:
    """Formats multi-target results as MOTChallenge rows (1-based frames) plus ``state``; with
    ground truth (``gt``, MOTChallenge boxes by 0-based frame; ``distractors``, the rows that
    take track boxes on distractors out) it scores the confirmed boxes as the run goes
    (:class:`~vtrack.evaluate.mot.MotScore`): no boxes of past frames are kept.
    A frame is scored once the next frame's rows are written (until then :meth:`undo` may
    withdraw it); :meth:`mot` scores the rest."""

    columns = MOT_COLUMNS

    def __init__(self, gt: Mapping[int, Sequence[tuple[int, Box]]] | None, start: int,
                 distractors: Mapping[int, Sequence[tuple[Box, bool]]] | None = None) -> None:
        self.gt = gt
        self.distractors = distractors or {}
        self.score: MotScore | None = None
        if gt is not None:
            from vtrack.evaluate.mot import MotScore  # SciPy: only for MOT ground truth

            self.score = MotScore()
        self._start = self._next = start  # the first frame, the next frame to score
        #: One past the last frame whose rows were written: the input's frames up to the
        #: run's end (frames the input skipped, ``--start``'s frames before it, included).
        self.end = start
        self._pending: tuple[int, list[tuple[int, Box]]] | None = None
        #: The last frame holding a ground-truth row (-1: none), and how many track boxes
        #: scored after it (each a false positive: the warning of :meth:`after_truth_note`).
        self.truth_end = max((*(gt or {}), *self.distractors), default=-1)
        self.boxes_after_truth = 0
        #: The rows written per track id.
        self.written: Counter[int] = Counter()
        self._last_ids: list[int] = []

    def rows(self, result: FrameResult) -> list[list[Any]]:
        rows, boxes = [], []
        for track in result.tracks:
            if track.state != TrackStatus.CONFIRMED:
                continue
            b = box_as_written(track.box)  # scored as written, as track.csv's box
            boxes.append((track.id, b))
            rows.append([result.index + 1, track.id, b.x, b.y, b.w, b.h, track.confidence,
                         -1, -1, -1, track.state])
        #: the ids whose rows this frame gave (what :meth:`undo` takes back)
        self._last_ids = [track_id for track_id, _ in boxes]
        self.written.update(self._last_ids)
        if self.score is not None:
            self._score_pending()
            self._pending = (result.index, boxes)
        self.end = result.index + 1
        return rows

    def undo(self, result: FrameResult) -> None:
        """Forget ``result``, the frame :meth:`rows` was last given (its rows could not be
        written)."""
        if self._pending is not None and self._pending[0] == result.index:
            self._pending = None
        self.written.subtract(self._last_ids)
        self.written = +self.written  # ids left with no row are gone
        if self.end == result.index + 1:
            self.end = result.index

    def counts(self, frames: int) -> dict[str, int]:
        """What a run without ground truth records of its tracks: the ids and rows of
        ``tracks.csv`` (``track_ids``, ``track_boxes``) over its ``frames``."""
        return {"track_ids": len(self.written), "track_boxes": self.written.total(),
                "frames": frames}

    def mot(self, frames: int) -> dict[str, Any]:
        """The MOT measures of the ``frames`` frames from the start (ground truth only where no
        frame was tracked)."""
        assert self.score is not None
        self._score_pending()
        self._score_until(self._start + frames)
        return self.score.result(frames)

    def _score_pending(self) -> None:
        if self._pending is not None:
            index, boxes = self._pending
            self._score_until(index)
            assert self.score is not None and self.gt is not None
            self.score.add(self.gt.get(index, ()), boxes, self.distractors.get(index, ()))
            if index > self.truth_end:
                self.boxes_after_truth += len(boxes)
            self._next = index + 1
            self._pending = None

    def after_truth_note(self, gt_path: object) -> str | None:
        """The warning for ground truth that ends before the run's last frame (:attr:`end`)
        while track boxes were scored after it, as false positives; None otherwise, or when no
        row was kept (that has its own warning)."""
        if not self.boxes_after_truth or not self.gt:
            return None
        boxes = plural(self.boxes_after_truth, "track box", "track boxes")
        return (f"{gt_path}: ground truth ends at frame {self.truth_end + 1} (MOTChallenge's "
                f"1-based numbering, as tracks.csv's), before the run's last frame "
                f"{self.end}; the {boxes} after it count as false positives")

    def past_truth_note(self, gt_path: object) -> str | None:
        """The warning for ground-truth rows in frames after the run's last one
        (:attr:`end`: the input's frames up to there, not only those tracked), which are not
        evaluated; None when there are none."""
        return past_end_note(gt_path, "ground truth has boxes", self.gt or {}, self.end,
                             "they are not evaluated")

    def _score_until(self, end: int) -> None:
        """Score the frames from the next one to ``end`` (excluded) as frames without tracks."""
        assert self.score is not None and self.gt is not None
        for frame in range(self._next, end):
            self.score.add(self.gt.get(frame, ()), ())
        self._next = max(self._next, end)


@dataclass
class _Resolved:
    """What a request resolves to before any frame is tracked."""

    pipeline: Pipeline
    gt: Sequence[Box | None] | None  # single-target ground truth (a FrameBoxes past --gt-first)
    mot_gt: dict[int, list[tuple[int, Box]]] | None  # multi-target ground truth (MOTChallenge)
    init_box: Box | None
    #: Where ``init_box`` came from, for messages and ``run.json``: ``--init``, a sidecar file or
    #: a ground-truth file (None: no box).
    init_from: str | None = None
    #: An ``--init`` box the chain does not use (s4 finds its target itself): checked like one
    #: it uses, recorded in run.json as ``init_ignored``, never handed to the tracker.
    init_ignored: Box | None = None
    #: The input's and ground truth's identity when the run started (run.json ``identity``).
    identity: dict[str, Any] = field(default_factory=dict)
    #: The run's first frame (``--start N``, tracked unless the input skipped it: the frames
    #: skipped from it on are the run's; for a time the first frame decoded at or after it).
    start: int = 0
    #: The frame the input is read from: 0, or for a later ``start`` where the input can jump
    #: (:meth:`Source.start_near`: a constant-rate MP4 or MOV file's key frame at or before it,
    #: an image folder's image) the frame it jumped to (the frames before it are not decoded;
    #: run.json ``read_from_frame``).
    read_from: int = 0
    #: How much to track from ``start`` on (``--frames``: a count, or a duration measured in
    #: the frames' timestamps).
    span: _Span = field(default_factory=_Span)
    #: What the run warns of before it tracks (ground truth whose every row is ignored).
    warnings: list[str] = field(default_factory=list)
    #: The MOTChallenge rows that take track boxes on distractors out of the score
    #: (:attr:`~vtrack.evaluate.groundtruth.MotTruth.distractors`).
    mot_distractors: dict[int, list[tuple[Box, bool]]] = field(default_factory=dict)
    #: How messages call what the caller gave (``--start``, ``start``).
    names: OptionNames = LIBRARY_NAMES


@dataclass
class _Resumable:
    """A frame written by the frame loop that a run can go on from."""

    index: int
    time_s: float
    #: Frames written before it.
    before: int
    box: Box | None = None


@dataclass
class _Tracked:
    """How the frame loop ended."""

    status: str = STATUS_COMPLETE
    error: str | None = None
    failure: Exception | None = None
    signum: int | None = None
    frames: int = 0
    #: Wall time from the loop's start to the last frame handled (its outputs written): what
    #: came after it (a live stream's ``--timeout`` wait that only found the end, the closing)
    #: is not tracking, nor is the loop's wait while ``--follow`` waited for the end; the
    #: whole loop when no frame was handled.
    seconds: float = 0.0
    #: CPU time of the frame loop's own thread (tracking, CSV rows, hand-over to the writers;
    #: not the decoder's and encoder's threads, nor the time others had the core), over the
    #: same span as ``seconds``.
    cpu_seconds: float = 0.0
    states: dict[TrackState, int] = field(
        default_factory=lambda: {TrackState.OCCLUDED: 0, TrackState.LOST: 0})
    #: Live sources: each frame's time from decoded to its result written.
    latency: Latencies = field(default_factory=Latencies)
    #: Where an interrupted run can be taken up again (:func:`_resume_options`): the last
    #: frame written, and the last one the single target was ``tracking`` in, with its box.
    last_frame: _Resumable | None = None
    last_tracked: _Resumable | None = None
    #: The first frame's timestamp (None: no frame was written).
    first_time_s: float | None = None
    timeline: _Timeline = field(default_factory=_Timeline)
    #: The last frame the annotated video holds, as (index, timestamp) (None: none yet).
    last_shown: tuple[int, float] | None = None
    #: The video ended before the run (its clock cannot hold a frame after those before it):
    #: that frame (index, timestamp) and why (:attr:`VideoWriter.ended`); None: it did not.
    video_end: tuple[int, float, str] | None = None

    def interrupted(self, by: Interrupted) -> None:
        """Record that the loop ended by the signal ``by`` (Ctrl-C, SIGTERM)."""
        self.status, self.signum, self.error = STATUS_INTERRUPTED, by.signum, by.reason

    @property
    def untouched(self) -> bool:
        """The run stopped on a user error before its first frame was out (the tracker refused
        the target, exit 2): the folder is left as it was, no record is written."""
        return (self.frames == 0 and isinstance(self.failure, VtrackError)
                and not isinstance(self.failure, OutputError))


def run(request: RunRequest, on_frame: Callable[[int, float], None] | None = None,
        on_open: Callable[[InputInfo], None] | None = None, overwrite: bool = True,
        *, names: OptionNames = LIBRARY_NAMES) -> RunSummary:
    """Track one input and write its outputs; see the module docstring for what is written.

    Messages about what the caller gave (the request's ``init_box``, ``start``, ``gt_path``,
    ``out_dir``, ...; ``overwrite``) call it by ``names``: the library's field and keyword
    names (:data:`~vtrack.errors.LIBRARY_NAMES`), or the command's ``--init``, ``--start``,
    ``--gt``, ``--out`` (:data:`~vtrack.errors.COMMAND_NAMES`).

    ``overwrite=False`` refuses (OutputError, before anything is tracked) a folder that holds
    an earlier run's results (``vtrack run`` without ``--overwrite``).

    ``on_open(info)`` is called once the input has opened and checked (its frame count sizes a
    progress bar); ``on_frame(n, seconds)`` after each frame with the number of frames done and
    the seconds the frame loop has taken so far, counted as ``run.json``'s ``timing.seconds``
    is (:func:`_loop_seconds`: after the last frame they are that record's). Called in
    the main thread, it handles SIGINT and SIGTERM itself while it works: the run ends
    ``interrupted`` (``summary.interrupted_by`` names the signal) and the caller decides how to
    exit (``vtrack run``: 128 + the signal's number).
    Resolve (chain, ground truth, initial box) -> track (the frame loop, writing as it goes)
    -> record (metrics, summary, ``run.json``).
    """
    with _Signals() as signals:
        check_input(request.input)  # a mistyped name first, before what else it lacks
        # a start time (--start 2.5s) is found in the frames' timestamps, and a start frame
        # (or --gt-first) past the frames the input states is refused at once: it opens first
        source: Source | None = (_open(request, signals, names) if _opens_first(request)
                                 else None)
        try:
            resolved = _resolve(request, source, names)
            if source is None:
                source = _open(request, signals, names)
        except BaseException:
            if source is not None:
                source.close()
            raise
        try:
            info = source.info
            for box in (resolved.init_box, resolved.init_ignored):
                if box is not None:
                    check_init_box(box, info.width, info.height,
                                   resolved.init_from or names.init, info.turned_note())
            _refuse_writing_over_inputs(request, _output_names(request, resolved), names)
            if not overwrite:
                refuse_replacing(request.out_dir, names)
                if (stream := _stream_file(request)) is not None:  # a file holding something
                    refuse_replacing_file(stream, f"{names.stream} {stream}", names.overwrite)
            # from taking the folder until the frame loop, a signal is only noted (the loop
            # then ends at once, interrupted): none cuts the opening of the outputs short and
            # leaves their temporary files (or the folder's lock) behind without a record
            signals.hold()
            with OutputFolder(request.out_dir, names=names) as folder:
                folder.refuse_folders(_output_names(request, resolved))
                folder.clear(temporaries_only=True)
                writers = _open_writers(request, resolved, info, signals, names)
                if on_open is not None:
                    on_open(info)
                tracked = _track(request, resolved, source, writers, signals, on_frame, folder)
                if not tracked.untouched:
                    try:
                        summary = _record(request, resolved, source, writers, tracked)
                    except BaseException:  # its temporary is this process's: clear() keeps it
                        writers.csv.abort()
                        raise
        finally:
            source.close()
    if tracked.failure is not None:
        raise tracked.failure
    return summary


def _open(request: RunRequest, signals: _Signals, names: OptionNames) -> Source:
    """The request's input opened (its messages calling what the caller gave by ``names``);
    Interrupted when a signal came while it opened, whatever error the interrupted open then
    gave (FFmpeg turns it into EINTR or "invalid data")."""
    try:
        return open_source(request.input, request.raw, fps=request.fps, ffmpeg=request.ffmpeg,
                           live=request.live, names=names)
    except Exception:
        if signals.received is not None:
            raise Interrupted(signals.received) from None
        raise


@dataclass
class _Writers:
    """A run's writers: the CSV (and its row formatter) and the annotated video."""

    formatter: _SingleTargetRows | _MultiTargetRows
    csv: CsvWriter
    video: VideoWriter | None = None
    annotator: Annotator | None = None
    stream: StreamWriter | None = None  # --stream: a JSON line per frame


def _refuse_writing_over_inputs(request: RunRequest, files: list[str], names: OptionNames
                                ) -> None:
    """ConfigError when a file this run would write (``files`` in its folder, the ``--stream``
    file) is the input, its sidecar box, its seqinfo.ini, the ground truth it reads, its config
    file or a file a stage of it reads (:func:`_config_files`) (the stream: or an image of an
    input folder, :func:`~vtrack.io.images.is_image_of`), or the stream is one of its own
    outputs (any file of ``RUN_OUTPUTS``: the folder's clearing would remove it):
    ``--overwrite`` replaces an earlier run's results, never what this run reads. Messages call
    the folder and the stream by ``names``."""
    outputs = [(request.out_dir / name, names.out) for name in files]
    stream = _stream_file(request)
    # what a run reads, compared by path: a sidecar or seqinfo.ini not there yet would be read
    # by the next run (the input itself when it is a file: not stdin, a URL or a camera)
    reads = [(Path(request.input), "the input")] if os.path.exists(request.input) else []
    reads.append((request.gt_path, "the ground truth"))
    if has_sidecar(request.input):  # read when no --init is given, and by later runs
        reads.append((sidecar_path(request.input), "the sidecar box"))
    if Path(request.input).is_dir():  # its frame rate, when no --fps is given
        reads.append((sequence_info(Path(request.input)), "the sequence's seqinfo.ini"))
    reads += _config_files(request)
    for output, option in outputs + ([(stream, names.stream)] if stream else []):
        for source, what in reads:
            if source is not None and same_file(output, source):
                raise ConfigError(f"{option} {output}: is {what} of this run ({source}); "
                                  "write the results elsewhere")
    if stream is not None and is_image_of(request.input, stream):
        raise ConfigError(f"{names.stream} {stream}: is an image of the input of this run "
                          f"({request.input}); write the results elsewhere")
    own = [request.out_dir / name for name in (*RUN_OUTPUTS, LOCK_NAME)]  # all it clears
    if stream is not None and any(real_path(stream) == real_path(output) for output in own):
        raise ConfigError(f"{names.stream} {stream}: is one of this run's own outputs; name "
                          "another file")
    folder = real_path(request.out_dir)  # ... with their temporaries, however the stream is named
    for place in (places_of(stream) if stream else ()):
        if place.parent == folder and any(is_temp_of(place.name, n) for n in RUN_OUTPUTS):
            raise ConfigError(f"{names.stream} {stream}: is named as a temporary file of this "
                              "run's outputs, which the folder's clean-up removes; name "
                              "another file")


def _config_files(request: RunRequest) -> list[tuple[Path, str]]:
    """The files the request's config came from and its stages read, each with what it is:
    the config file (when its source names one: a path given, or a shipped config's file; not
    a Config made in code) and each file a stage parameter names (``mot_detections.path``:
    ``the mot_detections.path file``)."""
    config = config_file(request.config.source)
    files = [(config, "the config file")] if os.path.isfile(config) else []  # (never raises)
    return files + [(Path(value), f"the {stage}.{name} file")
                    for _, stage, name, value in request.config.file_values() if value]


def _stream_file(request: RunRequest) -> Path | None:
    """The file ``--stream`` names (None: no stream, or stdout)."""
    return None if request.stream in (None, STDOUT) else Path(request.stream)


def _output_names(request: RunRequest, resolved: _Resolved) -> list[str]:
    """The files this run writes into its folder."""
    csv_name = "tracks.csv" if resolved.pipeline.multi_target else "track.csv"
    return [csv_name, "run.json"] + (["annotated.mp4"] if request.video and
                                     request.video_out is None else [])


def _open_writers(request: RunRequest, resolved: _Resolved, info: InputInfo,
                  signals: _Signals, names: OptionNames) -> _Writers:
    """The run's writers, opened while ``signals`` are held; on an error none is left open
    (the stream's messages call it by ``names``, and a picture too small for the video names
    the way out: ``names.no_video``).
    The wait for a ``--stream`` FIFO's reader is cut short by a signal: the run then goes on
    without the stream, its signal noted (the frame loop ends at once, interrupted)."""
    pipeline = resolved.pipeline
    formatter = _MultiTargetRows(resolved.mot_gt, resolved.start, resolved.mot_distractors) \
        if pipeline.multi_target \
        else _SingleTargetRows(pipeline.columns, resolved.gt, resolved.start)
    csv_name = "tracks.csv" if pipeline.multi_target else "track.csv"
    writers = _Writers(formatter, CsvWriter(request.out_dir / csv_name, formatter.columns))
    if request.video:
        try:
            writers.video = VideoWriter(request.out_dir / "annotated.mp4", info.width,
                                        info.height, info.fps or 30.0, preset=request.preset,
                                        crf=request.crf, url=request.video_out,
                                        stall_s=request.ffmpeg.timeout_s,
                                        span_s=info.duration_s)
        except VideoRefusedError as exc:
            writers.csv.abort()
            raise _way_out(exc, request, names) from None
        except BaseException:
            writers.csv.abort()
            raise
        writers.annotator = Annotator(info.width, info.height, gt=resolved.gt,
                                      multi_target=pipeline.multi_target,
                                      gt_tracks=resolved.mot_gt)
    if request.stream is not None:
        try:
            with signals.live():
                writers.stream = StreamWriter(request.stream, pipeline.multi_target,
                                              stall_s=request.ffmpeg.timeout_s, names=names)
        except Interrupted as exc:
            signals.pending = signals.pending or exc.signum
        except BaseException:
            writers.csv.abort()
            if writers.video is not None:
                writers.video.abort()
            raise
    return writers


def _way_out(exc: VideoRefusedError, request: RunRequest, names: OptionNames
             ) -> VideoRefusedError:
    """``exc`` naming the way out, as the caller names it: tracking without the video."""
    way = (f"leave {names.video_out} out and give {names.no_video}" if request.video_out
           else f"give {names.no_video}")  # without --video-out: annotated.mp4, as small
    return type(exc)(f"{exc}; {way} to track it without the video")


def _resolve(request: RunRequest, source: Source | None, names: OptionNames) -> _Resolved:
    """Build the chain, read the ground truth, settle the first frame and the initial box
    (user errors raise before the output folder is touched; messages call what the caller
    gave by ``names``). A start time (``--start 2.5s``) needs the
    opened ``source``: it is found in its frames' own timestamps (:meth:`Source.skip_to`,
    which decodes up to it)."""
    init_name, give_box = names.init, names.give_box
    pipeline = Pipeline(request.config.build(), seed=request.seed,
                        first_track_id=request.first_track_id)
    gt = mot_gt = None
    distractors: dict[int, list[tuple[Box, bool]]] = {}
    warnings: list[str] = []
    if request.gt_first and pipeline.multi_target:
        raise ConfigError(f"{names.gt_first} {request.gt_first}: {request.config.name} reads "
                          "MOTChallenge ground truth, whose rows number their frames "
                          f"themselves; leave {names.gt_first} out")
    if request.gt_path is not None and pipeline.multi_target:
        try:
            truth = read_mot_counting(request.gt_path)
        except InputError as exc:
            raise InputError(
                f"{exc}; {request.config.name} tracks several targets and scores them against "
                "MOTChallenge ground truth (gt.txt lines frame,id,x,y,w,h,...)") from None
        mot_gt, distractors = truth.boxes, truth.distractors
        warnings += dropped_notes(request.gt_path, truth)
    elif request.gt_path is not None:
        if request.gt_first and source is not None and past_end(source.info, request.gt_first):
            raise InputError(f"{_gt_first_given(request, names)}: "
                             + past_end_text(request.input, request.gt_first, source.info)
                             + "; the file's first box is of one of its frames")
        single = read_truth(request.gt_path, origin=request.gt_origin, first=request.gt_first)
        gt = single.boxes
        warnings += filter(None, [negative_note(request.gt_path, single)])
    # the first box: --init, else the input's sidecar (0-based pixels whatever --gt-origin
    # says, vtrack.io.sidecar), else the first ground-truth box
    # (the sidecar holds frame 0's box: not for a run that starts later)
    init_box, init_from = request.init_box, request.init_from or init_name
    ignored = None
    if init_box is not None and request.init_from is None:
        pipeline.refuse_a_first_box(f"{init_name}: {request.config.name}",
                                    f"leave {init_name} out")
        if not pipeline.needs_init_box:  # s4: taken, but it would only be drawn, untracked
            warnings.append(f"{init_name}: {request.config.name} finds its target itself (from its "
                            "first detection, after learning the background) and does not use "
                            "a first box: no box is reported until it detects the target")
            ignored, init_box = init_box, None
    start, read_from = _first_frame(request, source, names)
    if init_box is None and pipeline.needs_init_box and request.raw is None and not start:
        init_box, init_from = read_sidecar(request.input), str(sidecar_path(request.input))
    if init_box is None and gt is not None and pipeline.needs_init_box:
        if start >= len(gt) or gt[start] is None:
            where = "first ground-truth box" if not start else f"ground-truth box of frame {start}"
            if start < request.gt_first:  # (the file has a box: gt_first < len(gt))
                raise InputError(
                    f"{request.gt_path}: the {where} is missing: the file's boxes begin at frame "
                    f"{request.gt_first} ({_gt_first_given(request, names)}); "
                    f"give {names.give(names.start, str(request.gt_first))} to track from "
                    f"there, or {give_box}")
            why = ("marked absent (NaN, or w or h <= 0: the target out of view)"
                   if start < len(gt) else
                   f"missing: the file has boxes for frames {request.gt_first}..{len(gt) - 1} only "
                   "(a file "
                   f"shorter than the input, or frame {start} past the input's end)")
            raise InputError(f"{request.gt_path}: the {where} is {why}; give {give_box}")
        init_box, init_from = gt[start], str(request.gt_path)
    if init_box is None and pipeline.needs_init_box:
        if source is None:
            _refuse_unreadable(request, names)
        give_gt = names.give(names.gt, "FILE")
        config = cut(request.config.source)  # (its record keeps it whole)
        sequence = sidecar_path(request.input).parent
        targets = (numbered_groundtruth(sequence)
                   if has_sidecar(request.input) and Path(request.input).is_dir() else [])
        if targets:  # OTB's sequences of several targets: which one is the user's to say
            needs = f"the target's box in frame {start}" if start else "an initial box"
            raise ConfigError(f"{config}: this tracker needs {needs}, and "
                              f"{_targets_truth(sequence, targets, names)}")
        if start:
            raise ConfigError(f"{names.start_given(request.start, request.start_s)}: this "
                              f"tracker needs the target's box in frame {start}: give "
                              f"{give_box} or {give_gt}")
        if request.raw is not None or not has_sidecar(request.input):  # a run reads none
            why = ("raw frames have no sidecar file" if request.raw is not None
                   else f"{request.input} has no sidecar file to hold one")
            raise ConfigError(f"{config}: this tracker needs an initial box: give "
                              f"{give_box} (or {give_gt}); {why}")
        beside = groundtruth_beside(request.input)
        if beside is None and Path(request.input).is_dir():  # SEQ/img: SEQ's ground truth
            beside = groundtruth_beside(sequence)
        gt_hint = (give_gt if beside is None else f"{_give_file(names, names.gt, beside)} "
                   "(its ground truth, which vtrack batch takes by itself)")
        raise ConfigError(
            f"{config}: this tracker needs an initial box: give {gt_hint}, "
            f"{give_box} or write x,y,w,h into {sidecar_path(request.input)} "
            f"(vtrack select {shell_word(request.input)} picks it)"
        )
    return _Resolved(pipeline, gt, mot_gt, init_box, init_from if init_box else None, ignored,
                     request.file_identities(), start, read_from,
                     _Span(request.max_frames, request.max_s), warnings, distractors, names)


def _truth_length_note(request: RunRequest, resolved: _Resolved, gt: Sequence[Box | None],
                       span: int, stopped: bool) -> str:
    """The warning of single-target ground truth ``gt`` (indexed by frame, its boxes from
    frame ``request.gt_first`` on) that has fewer or more boxes than the ``span`` frames the run
    tracked from ``resolved.start`` (``stopped`` by ``--frames``): how many, and from which
    frame on the overlap is empty or which boxes are ignored; with fewer in a run that read
    its input to the end, also how a file whose first box is of a later frame is aligned
    (:func:`~vtrack.evaluate.groundtruth.later_first_hint`)."""
    start, first = resolved.start, request.gt_first
    covers = max(len(gt) - start, 0)  # the run's frames the file reaches
    boxes = len(gt) - first  # the file's own
    fewer = covers < span
    note = (f"{request.gt_path}: ground truth has {boxes_for_frames(boxes, first, span, start)} "
            f"({'fewer' if fewer else 'more'}); "
            + (f"overlap is empty from frame {start + covers} on" if fewer
               else "extra boxes ignored"))
    if fewer and not stopped:
        note += later_first_hint(boxes, span, start, first, resolved.names)
    return note


def _targets_truth(sequence: Path, targets: list[Path], names: OptionNames) -> str:
    """What OTB ``sequence`` of several targets (their ``groundtruth_rect.N.txt``,
    ``targets``) holds for a first box, and how a run takes one: ``Jogging has 2 targets'
    ground truth (groundtruth_rect.1.txt, groundtruth_rect.2.txt), none of which a run takes
    by itself: give one per run (--gt Jogging/groundtruth_rect.1.txt, --gt ...), or --init
    x,y,w,h``, its ``groundtruth_rect.txt`` named first when it has one too."""
    beside = groundtruth_beside(sequence)
    files = [beside, *targets] if beside is not None else targets
    truth = plural(len(targets), "target's ground truth", "targets' ground truth")
    held = f"{truth} ({', '.join(p.name for p in targets)})"
    held = f"{beside.name} and {held}" if beside is not None else held
    if len(files) == 1:
        return (f"{sequence} has {held}, which a run does not take by itself: give "
                f"{_give_file(names, names.gt, files[0])} or {names.give_box}")
    return (f"{sequence} has {held}, none of which a run takes by itself: give one per run "
            f"({', '.join(_give_file(names, names.gt, p) for p in files)}), or {names.give_box}")


def _give_file(names: OptionNames, name: str, path: Path) -> str:
    """How ``name`` is given file ``path`` (:meth:`OptionNames.give`), quoted for a shell
    when ``names`` are a command's options: ``--gt 'my seq/groundtruth_rect.txt'``."""
    return names.give(name, shell_word(path) if names.options else str(path))


def _gt_first_given(request: RunRequest, names: OptionNames) -> str:
    """How ``request`` gave the frame of its ground truth's first box, as ``names`` call it:
    ``--gt-first 3`` (``gt_first=3`` for the library)."""
    return names.give(names.gt_first, str(request.gt_first))


def _refuse_unreadable(request: RunRequest, names: OptionNames) -> None:
    """InputError naming a local file or folder input that vtrack cannot read (a folder without
    images, a file that is not a video), found by opening it once: a run told that it lacks a
    first box hears of its input first. Stdin, FIFOs, devices and URLs are read once only, by
    the run itself."""
    if _local(request.input):
        open_source(request.input, request.raw, fps=request.fps, ffmpeg=request.ffmpeg,
                    live=request.live, names=names).close()


def _opens_first(request: RunRequest) -> bool:
    """Whether ``request`` is settled in its opened input: a start after the first frame
    (:attr:`RunRequest.starts_later`, found in its frames), or single-target ground truth whose
    first box is of a later frame (``--gt-first``), refused where the input's frame count says
    it has no such frame before a first box is looked for in the file. Only a local file or
    folder can state a frame count (stdin, a FIFO, a device or a URL would be waited on before
    the ground truth's own mistakes are told), and a multi-target chain refuses ``--gt-first``
    itself: those are resolved before the input opens."""
    return request.starts_later or bool(
        request.gt_first and request.gt_path is not None and not request.config.multi_target
        and _local(request.input))


def _local(source: str) -> bool:
    """Whether the input ``source`` is a local file or folder: one that can be opened to look
    and then read again (stdin, FIFOs, devices and URLs are read once only, by the run)."""
    return os.path.isfile(source) or os.path.isdir(source)


def _first_frame(request: RunRequest, source: Source | None, names: OptionNames
                 ) -> tuple[int, int]:
    """The first frame to track, ``--start N``, or for ``--start Ts`` the first frame of
    ``source`` whose timestamp is at or after T (decoded up to it: a variable frame rate is
    followed, where T x fps would miss); and the frame ``source`` is read from: where it can
    jump, a frame at or before it (:meth:`Source.start_near`: a seekable video's key frame, an
    image folder's image; for a time, before the frame T x fps names), else its first.
    A request that does not start later (:attr:`RunRequest.starts_later`: no ``--start``,
    ``--start 0`` or ``--start 0s``, the first frame's time) begins at frame 0 without
    ``source``; one that does needs it opened.
    InputError when the input ends before T, or its frame count says it has no frame N,
    before any is decoded (naming the start as ``names`` call it)."""
    if not request.starts_later:
        return 0, 0
    assert source is not None, "a start after the first frame needs the opened input"
    given = names.start_given(request.start, request.start_s)
    if request.start_s is None:
        read_from = start_toward(source, request.start)
        if read_from is None:
            raise InputError(f"{given}: "
                             + past_end_text(request.input, request.start, source.info))
        return request.start, read_from
    found, read_from = seek_time(source, request.start_s)
    if found is None:
        raise InputError(f"{given}: "
                         + no_frame_after_text(request.input, request.start_s, source))
    return found, read_from


def requested_frames(request: RunRequest
                     ) -> Callable[[Source], tuple[Box | None, Iterator[Frame]]]:
    """What ``request`` tracks of its opened input, as ``vtrack run`` takes it: the initial box
    (``--init``, else the input's sidecar, else the ground truth's box of the first frame
    tracked) and the frames from ``--start`` on, at most ``--frames`` of them, given by the
    function returned once it is called with the opened input. ConfigError or InputError as
    :func:`run` gives them: at once, before the input is opened, as run settles them, unless
    the request is settled in the opened input (:func:`_opens_first`: ``start``, ``start_s``,
    ``gt_first``), then from that function."""
    resolved = None if _opens_first(request) else _resolve(request, None, LIBRARY_NAMES)

    def frames(source: Source) -> tuple[Box | None, Iterator[Frame]]:
        settled = resolved or _resolve(request, source, LIBRARY_NAMES)
        return settled.init_box, _frames_to_track(request, settled, source)

    return frames


def _frames_to_track(request: RunRequest, resolved: _Resolved, source: Source
                     ) -> Iterator[Frame]:
    """``source``'s frames from the resolved first one on, within the resolved span (a frame
    count or a duration, ``--frames``)."""
    return resolved.span.take(source, _from(source, resolved.start, request.input,
                                            resolved.names.start, resolved.init_box is not None))


class _Waits:
    """The frames of ``frames``, noting when the loop waited for each of the last
    :data:`WAITS_KEPT` (``perf_counter`` start and end; a bounded record)."""

    def __init__(self, frames: Iterable[Frame]) -> None:
        self._frames = iter(frames)
        self.last: deque[tuple[float, float]] = deque(maxlen=WAITS_KEPT)

    def __iter__(self) -> Iterator[Frame]:
        return self

    def __next__(self) -> Frame:
        asked = time.perf_counter()
        try:
            return next(self._frames)
        finally:
            self.last.append((asked, time.perf_counter()))

    def during(self, span: tuple[float, float]) -> float:
        """How long the loop waited for frames during ``span`` (of the last waits noted)."""
        return sum(max(0.0, min(end, span[1]) - max(start, span[0]))
                   for start, end in self.last)


#: The waits for frames :class:`_Waits` keeps: more than the frames a decoder holds back
#: until the end of its input is found (one per frame thread).
WAITS_KEPT = 64


def _track(request: RunRequest, resolved: _Resolved, source: Source, writers: _Writers,
           signals: _Signals, on_frame: Callable[[int, float], None] | None,
           folder: OutputFolder) -> _Tracked:
    """The signal-safe frame loop: each frame's CSV rows and picture are written together;
    a broken input, Ctrl-C, SIGTERM, a full disk or a tracker error ends it with every output
    closed, and whole. The outputs are written under temporary names: only then do they
    replace what an earlier run left in ``folder`` (:meth:`OutputFolder.clear`), unless the
    run is :attr:`_Tracked.untouched` (then they are dropped and the folder is as it was)."""
    out = _Tracked()
    formatter, csv, video, annotator = (writers.formatter, writers.csv, writers.video,
                                        writers.annotator)
    # with --start the video's clock starts at its first frame (as ffmpeg -ss makes it)
    first_time: float | None = None if resolved.start else 0.0
    started, cpu_started = time.perf_counter(), time.thread_time()
    frames_in: _Waits | None = None
    handled: tuple[float, float] | None = None  # (wall, cpu) when the last frame was done
    try:
        signals.release()  # held while the outputs opened: one that came then ends it here
        signals.drain = source.stop_at_end
        frames_in = _Waits(_frames_to_track(request, resolved, source))
        for result in resolved.pipeline.track(frames_in, resolved.init_box):
            with signals.writing():
                rows = formatter.rows(result)
                try:
                    csv.write_rows(rows)
                except OutputError:
                    formatter.undo(result)
                    raise
                if result.state in out.states:
                    out.states[result.state] += 1
                if out.first_time_s is None:
                    out.first_time_s = result.time_s
                out.last_frame = _Resumable(result.index, result.time_s, out.frames)
                if result.state is TrackState.TRACKING and result.box is not None:
                    out.last_tracked = _Resumable(result.index, result.time_s, out.frames,
                                                  result.box)
                out.frames += 1  # its row is on disk; a video error below loses only the video
                out.timeline.add(result.index, result.time_s)
                if video is not None and annotator is not None:
                    assert result.frame is not None
                    if first_time is None:
                        first_time = result.time_s
                    if video.write(result.frame, lambda planes, r=result: annotator.draw(
                            planes, r), time_s=result.time_s - first_time,
                            stop=signals.stopping):
                        out.last_shown = result.index, result.time_s
                    elif video.ended is not None and out.video_end is None:  # tracked on
                        out.video_end = result.index, result.time_s, video.ended
                if writers.stream is not None:  # last: a signal may cut short its wait
                    writers.stream.write(result, stop=signals.stopping)
            received = source.received
            if received is not None:
                out.latency.add(time.perf_counter() - received)
            handled = time.perf_counter(), time.thread_time()
            if on_frame is not None:
                on_frame(out.frames, _loop_seconds(started, handled[0], frames_in, source))
        if signals.draining is not None:  # the frames the followed file held are tracked
            raise Interrupted(signals.draining)
        if out.frames == 0 and resolved.start:  # a user error: the folder stays as it was
            given = resolved.names.start_given(request.start, request.start_s)
            raise InputError(f"{given}: {request.input} has no frame "
                             f"{resolved.start} ({_numbering(source.info)})")
    except FirstFrameError as exc:  # a stage refused the first frame: name the input
        refused = "" if exc.frame_index is None else f"frame {exc.frame_index}: "
        named = FirstFrameError(f"{request.input}: {refused}{exc}", exc.frame_index)
        out.status, out.error, out.failure = STATUS_FAILED, str(named), named
    except PartialInputError as exc:
        if signals.draining is None:
            out.status, out.error = STATUS_PARTIAL, str(exc)
        else:  # a followed file ended by a signal where a recorder was writing: no damage
            out.interrupted(Interrupted(signals.draining))
    except Interrupted as exc:
        out.interrupted(exc)
    except KeyboardInterrupt:
        out.status, out.error = STATUS_INTERRUPTED, "interrupted by the user"
    except StreamReaderGone as exc:  # `--stream - | head -2`: stopped as by SIGPIPE
        out.status, out.signum, out.error = STATUS_INTERRUPTED, signal.SIGPIPE, str(exc)
    except OutputError as exc:  # a full disk part way: what is on disk is whole
        out.status, out.error = STATUS_FAILED, str(exc)
        out.failure = OutputBrokenError(str(exc))
    except Exception as exc:  # recorded in run.json, then raised again by run()
        out.status, out.error, out.failure = STATUS_FAILED, str(exc) or type(exc).__name__, exc
    finally:
        signals.drain = None  # first: a signal from here on is held, not taken for a drain
        signals.hold()  # a signal now must not cut the closing and the records short
        wall, cpu = handled or (time.perf_counter(), time.thread_time())
        out.seconds = _loop_seconds(started, wall, frames_in, source)
        out.cpu_seconds = cpu - cpu_started
        source.close()
        if out.untouched:  # (an earlier run's --stream file too is left as it was)
            for dropped in (csv, video, writers.stream):
                if dropped is not None:
                    dropped.abort()
        else:
            folder.clear()
            if video is not None and video.url is None and video.frames_written == 0:
                video.abort()  # no picture, no video (a file of none does not open)
        try:  # the CSV keeps its temporary name until its record is ready (_publish_csv)
            csv.finish()
        except OutputError as exc:
            _fail(out, str(exc))
        for writer in (video, writers.stream):
            if writer is None:
                continue
            try:
                writer.close()
            except OutputError as exc:
                _fail(out, str(exc))
    return out


def _loop_seconds(started: float, wall: float, frames_in: _Waits | None, source: Source
                  ) -> float:
    """The frame loop's seconds from ``started`` to ``wall`` (``perf_counter``) as
    ``timing.seconds`` counts them: the loop's wait for frames while the input waited at its
    end (--follow, a live stream's --timeout) is left out, it is not tracking (the decoder's
    frame threads hand over its last frames only after it)."""
    end_wait = source.end_wait
    waited = 0.0 if frames_in is None or end_wait is None else frames_in.during(
        (max(end_wait[0], started), min(end_wait[1], wall)))
    return wall - started - waited


def _fail(out: _Tracked, message: str) -> None:
    """Record an output that could not be written whole (the first such message is kept)."""
    if out.failure is None:
        out.failure = OutputBrokenError(message)
        if out.status == STATUS_COMPLETE:
            out.status, out.error = STATUS_FAILED, message
        else:
            out.error = f"{out.error}; {message}"


def _count_rows(path: Path) -> int:
    """Lines of a CSV file after its header."""
    lines = 0
    with path.open("rb") as handle:
        while chunk := handle.read(1 << 20):
            lines += chunk.count(b"\n")
    return lines - 1


def _verified_outputs(request: RunRequest, writers: _Writers, tracked: _Tracked) -> list[str]:
    """The outputs on disk that are whole: the CSV holds every row written, the video opens
    and holds every picture written. Anything else is reported (``_fail``); a broken video is
    removed."""
    outputs = []
    csv_path = writers.csv.path
    try:
        rows = _count_rows(writers.csv.on_disk)
    except OSError:
        rows = None
    if rows == writers.csv.rows:
        outputs.append(csv_path.name)
    elif rows is not None or tracked.failure is None:
        _fail(tracked, f"{csv_path}: holds {rows} rows, {writers.csv.rows} were written")
    video = writers.video
    if video is not None and video.url is None and video.path.exists():
        problem = verify_video(video.path, video.frames_written)
        if problem is None:
            outputs.append(video.path.name)
        else:
            video.path.unlink(missing_ok=True)
            _fail(tracked, f"{video.path}: {problem}; removed")
    return outputs


def _publish_csv(csv: CsvWriter) -> str | None:
    """Give the CSV its final name: only once the video is closed and verified, just before
    ``run.json`` is written, so a run killed before (``kill -9`` while a slow encoder
    flushes) leaves no ``track.csv`` that no record vouches for, only its temporary (the next
    run in the folder removes it). The error message when it cannot be renamed, else None."""
    try:
        csv.close()
    except OutputError as exc:
        return str(exc)
    return None


def _resume_options(resolved: _Resolved, tracked: _Tracked, fps: float | None,
                    next_id: int) -> str | None:
    """The options that take an interrupted run up again: ``--start`` the frame after the
    last one written (a multi-target chain, or one that finds its target itself: no frame is
    written twice), else the last frame the target was tracked in with ``--init`` its box as
    ``track.csv`` wrote it; and what is left of ``--frames`` from there (a count, or a time:
    the frame after the last one taken to come one interval of the input's ``fps`` later);
    for a multi-target chain ``--first-id next_id`` (the id after the highest this run wrote,
    so that the next run's tracks use none of this run's; left out when it is 1 or past
    :data:`~vtrack.params.MAX_TRACK_ID`, which the option refuses: :func:`_past_track_ids`).
    None when there is no such frame, or nothing is left of ``--frames``."""
    pipeline = resolved.pipeline
    needs_box = pipeline.needs_init_box and not pipeline.multi_target
    at = tracked.last_tracked if needs_box else tracked.last_frame
    if at is None:
        return None
    after = 0 if needs_box else 1  # frames the resumed run begins after ``at``
    options = f"--start {at.index + after}"
    if at.box is not None:
        options += " --init " + ",".join(number_text(v) for v in box_as_written(at.box))
    span = resolved.span
    if span.count is not None:
        left_frames = span.count - at.before - after
        if left_frames <= 0:
            return None
        options += f" --frames {left_frames}"
    elif span.seconds is not None and tracked.first_time_s is not None:
        begins_s = at.time_s + (after / fps if after and fps else 0.0)
        left = round(span.seconds - (begins_s - tracked.first_time_s), 6)
        if left <= 0:
            return None
        options += f" --frames {number_text(left)}s"
    if pipeline.multi_target and 1 < next_id <= MAX_TRACK_ID:
        options += f" --first-id {next_id}"
    return options


def _past_track_ids(request: RunRequest, summary: RunSummary, next_id: int) -> str | None:
    """The warning of an interrupted multi-target run whose hint (``summary.resume``) cannot
    give ``--first-id next_id``: the id after the highest it wrote is past
    :data:`~vtrack.params.MAX_TRACK_ID`; None for any other run (no hint, a single target,
    an id the option takes)."""
    if summary.resume is None or not summary.multi_target or next_id <= MAX_TRACK_ID:
        return None
    return (f"{request.out_dir / 'tracks.csv'}: its highest track id, {next_id - 1}, leaves "
            f"no --first-id (at most {MAX_TRACK_ID}) for the run the hint below makes: that run "
            "numbers its tracks as this one did; renumber one of the two tracks.csv to join them")


def _video_end_note(resolved: _Resolved, writers: _Writers, tracked: _Tracked) -> str | None:
    """The warning of an annotated video that ended before the run (its clock could not hold
    a frame after those before it): where it ends, why, and that the CSV goes on; frames
    numbered as the CSV and the video number them. None when it did not end early."""
    video, end, shown = writers.video, tracked.video_end, tracked.last_shown
    if video is None or end is None or shown is None or tracked.last_frame is None:
        return None
    number = 1 if resolved.pipeline.multi_target else 0  # tracks.csv's frames are 1-based
    index, time_s, why = end
    return (f"{video.path}: ends at frame {shown[0] + number} ({shown[1]:.9g} s; "
            f"{plural(video.frames_written, 'frame')} of the run's {tracked.frames}): frame "
            f"{index + number} ({time_s:.9g} s) is left out, {why}; {writers.csv.path.name} "
            f"goes on to frame {tracked.last_frame.index + number}")


def _next_track_id(request: RunRequest, last_track_id: int | None) -> int:
    """The id a run that goes on from this one numbers its tracks from: one after
    ``last_track_id``, the highest this run wrote to ``tracks.csv`` (its first track id when
    it wrote none: None)."""
    return request.first_track_id if last_track_id is None else last_track_id + 1


def _record(request: RunRequest, resolved: _Resolved, source: Source, writers: _Writers,
            tracked: _Tracked) -> RunSummary:
    """Metrics, the summary and ``run.json`` (written last, atomically; listing only the
    outputs verified whole)."""
    outputs = _verified_outputs(request, writers, tracked)
    formatter = writers.formatter
    status, error, frames, seconds = tracked.status, tracked.error, tracked.frames, tracked.seconds
    gt = resolved.gt
    last_id = (max(formatter.written, default=None)
               if isinstance(formatter, _MultiTargetRows) else None)
    next_id = _next_track_id(request, last_id)
    summary = RunSummary(
        input=request.input,
        out_dir=str(request.out_dir),
        config=request.config.name,
        status=status,
        frames=frames,
        seconds=seconds,
        fps=frames / seconds if seconds > 0 else 0.0,
        frames_occluded=tracked.states[TrackState.OCCLUDED],
        frames_lost=tracked.states[TrackState.LOST],
        frames_skipped=source.frames_skipped,
        frames_missing=source.frames_missing,
        frames_passed=source.frames_passed,
        multi_target=resolved.pipeline.multi_target,
        error=error,
        warnings=[*resolved.warnings, *source.warnings,
                  *(note for stage in resolved.pipeline.stages for note in stage.notes())],
        interrupted_by=None if tracked.signum is None else signal.Signals(tracked.signum).name,
        resume=(_resume_options(resolved, tracked, source.info.fps, next_id)
                if status == STATUS_INTERRUPTED and not source.live else None),
    )
    past_ids = _past_track_ids(request, summary, next_id)
    if past_ids:
        summary.warnings.append(past_ids)
    video_end = _video_end_note(resolved, writers, tracked)
    if video_end:
        summary.warnings.append(video_end)
    summary.warnings += tracked.timeline.warnings(request.input, request.gt_path)
    if frames == 0 and status == STATUS_COMPLETE:
        status = summary.status = STATUS_PARTIAL
        summary.error = error = f"{request.input}: no frame could be decoded"
    metrics: Mapping[str, Any] = {}
    start = resolved.start
    stopped = resolved.span.stopped  # by --frames
    read_to_end = status == STATUS_COMPLETE and not resolved.span.given  # the whole input
    if isinstance(formatter, _SingleTargetRows) and gt is not None:
        gt = gt[start:]  # the frames tracked (--start)
        metrics = summarize_scores(formatter.overlaps, formatter.errors, formatter.states)
        summary.mean_overlap = metrics.get("mean_overlap")
        summary.auc = metrics.get("auc")
        summary.precision20 = metrics.get("precision20")
        span = len(formatter.overlaps)  # frames tracked, and those the input skipped among them
        end = start + span  # the frame after the run's last
        if request.gt_first >= end and status == STATUS_COMPLETE:
            summary.warnings.append(
                f"{request.gt_path}: the file's boxes begin at frame {request.gt_first} "
                f"({_gt_first_given(request, resolved.names)}), "
                f"after the run's last frame ({end - 1}): no frame is scored")
        elif len(gt) != span and status == STATUS_COMPLETE and not (stopped and len(gt) > span):
            summary.warnings.append(_truth_length_note(request, resolved, resolved.gt, span,
                                                      stopped))
        # the run's frames the file has a box for (none before its first, --gt-first)
        absent = max(min(len(gt), span) - max(request.gt_first - start, 0), 0)
        if absent and not metrics["frames_evaluated"] and status == STATUS_COMPLETE:
            summary.warnings.append(
                f"{request.gt_path}: the ground truth marks the target absent (NaN, or w or "
                f"h <= 0) in all {plural(absent, 'frame')} of the run it has boxes for: no "
                "frame is scored (frames_evaluated 0; mean_overlap, auc, precision20 null)")
    elif isinstance(formatter, _MultiTargetRows):
        summary.tracks = len(formatter.written)
        summary.last_track_id = last_id
        if resolved.mot_gt is None:
            metrics = formatter.counts(frames)
        else:
            metrics = formatter.mot(frames)
            note = formatter.after_truth_note(request.gt_path)
            if note is not None and status == STATUS_COMPLETE:
                summary.warnings.append(note)
            past = formatter.past_truth_note(request.gt_path)
            if past is not None and read_to_end:
                summary.warnings.append(past)
        summary.mot = dict(metrics)
    if read_to_end:
        summary.warnings += [note for stage in resolved.pipeline.stages
                             for note in stage.past_end_notes()]

    unnamed = _publish_csv(writers.csv)
    if unnamed is not None:  # the CSV is not there: the run failed
        _fail(tracked, unnamed)
        outputs = [name for name in outputs if name != writers.csv.path.name]
        status = summary.status = STATUS_FAILED if status == STATUS_COMPLETE else status
        error = summary.error = unnamed if error is None else f"{error}; {unnamed}"
    record = {
        "status": status,
        "error": error,
        "warnings": summary.warnings,
        "frames": frames,
        "input": {**source.info.to_dict(), "image_identity": source.image_identity()},
        "request": request.to_dict(),
        "start_frame": resolved.start,
        # the last frame whose results were written (None: none was)
        "last_frame": None if tracked.last_frame is None else tracked.last_frame.index,
        # where the input was read from: a frame at or before start_frame it jumped to (a
        # seekable video's key frame, an image folder's image: those before were not decoded)
        "read_from_frame": resolved.read_from,
        # --frames ended the run, not the input: ground truth past it belongs to frames not read
        "stopped_by_frames": stopped,
        "init": list(resolved.init_box) if resolved.init_box is not None else None,
        "init_from": resolved.init_from,
        # an --init box the config does not use (s4): given, not tracked from (a warning)
        "init_ignored": None if resolved.init_ignored is None else list(resolved.init_ignored),
        "config": request.config.resolved(),
        "metrics": metrics,
        "summary": {k: v for k, v in summary.__dict__.items() if k not in ("warnings", "mot")},
        "timing": {
            "seconds": seconds,
            "fps": summary.fps,
            "stage_us_per_frame": resolved.pipeline.stage_microseconds_per_frame(),
            "loop_cpu_us_per_frame": 1e6 * tracked.cpu_seconds / frames if frames else None,
            # the threads OpenCV's parallel loops had (a batch's worker sets them: a local one
            # from this machine's cores over the workers started, a Dask one from its machine's)
            "opencv_threads": cv2.getNumThreads(),
            # live sources: frame decoded -> its row, stream line and picture handed over
            "latency": tracked.latency.to_dict() if source.live else None,
        },
        "live": source.live,
        "outputs": outputs,
        "output_bytes": sizes(request.out_dir, outputs),
        # the frames the annotated video holds (null: no video): fewer than frames when its
        # clock ended it before the run (a warning names where)
        "video_frames": None if writers.video is None else writers.video.frames_written,
        "identity": resolved.identity,
        "versions": versions(),
        "command": sys.argv,
        # what the request's relative paths (input, ground truth) are relative to: a report
        # made from another folder reads them from here
        "working_dir": os.getcwd(),
    }
    try:
        write_json(request.out_dir / "run.json", record)
    except OutputError as exc:
        first = f"{tracked.error}; " if tracked.failure is not None else ""
        tracked.failure = OutputBrokenError(f"{first}{exc}")
    return summary
