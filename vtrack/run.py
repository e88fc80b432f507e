"""One input end to end: reader -> pipeline -> writers, with ground truth, errors and a summary.

``run(RunRequest(...))`` is what ``vtrack run`` and every ``vtrack batch`` job call. It writes into
``request.out_dir``:

- ``track.csv`` (single target) or ``tracks.csv`` (multi-target, MOTChallenge order), rows
  flushed as frames complete;
- ``annotated.mp4`` unless ``video=False``;
- ``run.json``, written last and atomically: its ``status`` says whether the run is
  ``complete``, ``partial`` (the input broke part way; everything before was tracked) or
  ``interrupted`` (Ctrl-C). A complete-looking file is complete: the CSV and video are written
  under temporary names and renamed when closed.

User errors raise :class:`~vtrack.errors.VtrackError` before anything is written; an input that
breaks part way returns a summary with ``status = "partial"`` and the error message.
"""

from __future__ import annotations

import math
import platform
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import av
import cv2
import numpy as np

from vtrack import __version__
from vtrack.annotate import Annotator
from vtrack.errors import ConfigError, InputError, PartialInputError
from vtrack.evaluate.groundtruth import read_boxes, read_mot
from vtrack.evaluate.metrics import score_frame, summarize
from vtrack.evaluate.mot import evaluate_mot
from vtrack.geometry import Box
from vtrack.io import (
    CsvWriter,
    Source,
    VideoWriter,
    open_source,
    prepare_output_dir,
    write_json,
)
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.request import RunRequest
from vtrack.stages.base import TrackState, TrackStatus

#: Columns every single-target ``track.csv`` starts with (DESIGN.md contract).
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
    error: str | None = None
    warnings: list[str] = field(default_factory=list)
    mot: dict[str, Any] | None = None

    def line(self) -> str:
        """The one-line summary printed at the end of ``vtrack run``."""
        parts = [f"{self.frames} frames", f"{self.fps:.1f} fps"]
        if self.mean_overlap is not None:
            parts.append(f"mean overlap {self.mean_overlap:.3f}")
            parts.append(f"AUC {self.auc:.3f}")
            parts.append(f"precision@20 {self.precision20:.3f}")
        if self.mot:
            parts += [f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                      for k, v in self.mot.items() if k in ("mota", "motp", "idf1", "id_switches")]
        else:
            parts.append(f"occluded {self.frames_occluded}")
            parts.append(f"lost {self.frames_lost}")
        status = "" if self.status == STATUS_COMPLETE else f" ({self.status})"
        head = f"{self.input}{status}: "
        return head + ", ".join(parts) + f" -> {self.out_dir}"


def versions() -> dict[str, str]:
    """Versions of everything that shapes a result, for ``run.json``."""
    return {
        "vtrack": __version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "pyav": av.__version__,
        "ffmpeg": ".".join(str(v) for v in av.library_versions.get("libavcodec", ())),
        "platform": platform.platform(),
    }


def _check_init_box(box: Box, width: int, height: int, where: str) -> None:
    if not box.is_valid():
        raise ConfigError(f"{where}: the box {tuple(box)} is empty (width and height must be > 0)")
    if box.window(width, height) is None:
        raise ConfigError(
            f"{where}: the box {tuple(round(v, 2) for v in box)} lies outside the "
            f"{width}x{height} frame"
        )


class _AtomicFrames:
    """Delays Ctrl-C while one frame's outputs are written, so they never disagree.

    Outside ``writing()`` a SIGINT raises KeyboardInterrupt at once (e.g. while waiting for the
    next frame); inside, it is held and raised when the frame's row and picture are both out.
    Only installed in the main thread (signal handlers can only be set there).
    """

    def __init__(self) -> None:
        self.pending = False
        self.inside = False
        self.previous: Any = None

    def __enter__(self) -> _AtomicFrames:
        if threading.current_thread() is threading.main_thread():
            self.previous = signal.signal(signal.SIGINT, self._handle)
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)

    def _handle(self, signum: int, frame: object) -> None:
        if self.inside:
            self.pending = True
        else:
            raise KeyboardInterrupt

    @contextmanager
    def writing(self) -> Iterator[None]:
        self.inside = True
        try:
            yield
        finally:
            self.inside = False
        if self.pending:
            raise KeyboardInterrupt


def _limited(frames: Iterator, limit: int | None) -> Iterator:
    for n, frame in enumerate(frames):
        if limit is not None and n >= limit:
            return
        yield frame


def _fmt(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(value) else value


class _SingleTargetRows:
    """Formats single-target results as ``track.csv`` rows and keeps the boxes for metrics."""

    def __init__(self, extras: tuple[str, ...], gt: list[Box | None] | None) -> None:
        self.columns = TRACK_COLUMNS + extras
        self.extras = extras
        self.gt = gt
        self.boxes: list[Box | None] = []

    def rows(self, result: FrameResult) -> list[list[Any]]:
        box = result.box
        self.boxes.append(box)
        overlap = error = None
        if self.gt is not None and result.index < len(self.gt):
            overlap, error = score_frame(box, self.gt[result.index])
            error = _fmt(error)
        geometry = [None] * 6 if box is None else [box.x, box.y, box.w, box.h, box.cx, box.cy]
        row = [result.index, result.time_s, *geometry, result.state, _fmt(result.score),
               overlap, error]
        return [row + [result.extras.get(column) for column in self.extras]]


class _MultiTargetRows:
    """Formats multi-target results as MOTChallenge rows (1-based frames) plus ``state``."""

    columns = MOT_COLUMNS

    def __init__(self) -> None:
        self.tracks: dict[int, list[tuple[int, Box]]] = {}

    def rows(self, result: FrameResult) -> list[list[Any]]:
        rows = []
        for track in result.tracks:
            if track.state != TrackStatus.CONFIRMED:
                continue
            self.tracks.setdefault(result.index, []).append((track.id, track.box))
            b = track.box
            rows.append([result.index + 1, track.id, b.x, b.y, b.w, b.h, track.confidence,
                         -1, -1, -1, track.state])
        return rows


@dataclass
class _Resolved:
    """What a request resolves to before any frame is tracked."""

    pipeline: Pipeline
    gt: list[Box | None] | None  # single-target ground truth
    mot_gt: Any  # multi-target ground truth (MOTChallenge), read by the MOT metrics at the end
    init_box: Box | None


@dataclass
class _Tracked:
    """How the frame loop ended."""

    status: str = STATUS_COMPLETE
    error: str | None = None
    failure: Exception | None = None
    frames: int = 0
    seconds: float = 0.0
    states: dict[TrackState, int] = field(
        default_factory=lambda: {TrackState.OCCLUDED: 0, TrackState.LOST: 0})


def run(request: RunRequest, on_frame: Callable[[int], None] | None = None) -> RunSummary:
    """Track one input and write its outputs; see the module docstring for what is written.

    ``on_frame(n)`` is called after each frame with the number of frames done (progress bars).
    Resolve (chain, ground truth, initial box) -> track (the frame loop, writing as it goes)
    -> record (metrics, summary, ``run.json``).
    """
    resolved = _resolve(request)
    source: Source = open_source(request.input, request.raw)
    info = source.info
    if resolved.init_box is not None:
        _check_init_box(resolved.init_box, info.width, info.height,
                        "--init" if request.init_box else str(request.gt_path))
    pipeline = resolved.pipeline
    formatter = _MultiTargetRows() if pipeline.multi_target else _SingleTargetRows(
        pipeline.columns, resolved.gt)
    csv_name = "tracks.csv" if pipeline.multi_target else "track.csv"
    csv = CsvWriter(request.out_dir / csv_name, formatter.columns)
    video = annotator = None
    if request.video:
        video = VideoWriter(request.out_dir / "annotated.mp4", info.width, info.height,
                            info.fps or 30.0, preset=request.preset, crf=request.crf)
        annotator = Annotator(info.width, info.height, gt=resolved.gt)
    tracked = _track(request, resolved, source, formatter, csv, video, annotator, on_frame)
    summary = _record(request, resolved, info, formatter, csv_name, tracked)
    if tracked.failure is not None:
        raise tracked.failure
    return summary


def _resolve(request: RunRequest) -> _Resolved:
    """Build the chain, read the ground truth and settle the initial box (user errors raise
    before anything is written but the emptied output folder)."""
    pipeline = Pipeline(request.config.build(), seed=request.seed)
    prepare_output_dir(request.out_dir)
    gt = mot_gt = None
    if request.gt_path is not None and pipeline.multi_target:
        mot_gt = read_mot(request.gt_path)
    elif request.gt_path is not None:
        gt = read_boxes(request.gt_path, origin=request.gt_origin)
    init_box = request.init_box
    if init_box is None and gt is not None and pipeline.needs_init_box:
        if gt[0] is None:
            raise InputError(
                f"{request.gt_path}: the first ground-truth box is empty; give --init x,y,w,h"
            )
        init_box = gt[0]
    if init_box is None and pipeline.needs_init_box:
        raise ConfigError(
            f"{request.config.source}: this tracker needs an initial box: give --init x,y,w,h "
            "or --gt FILE"
        )
    return _Resolved(pipeline, gt, mot_gt, init_box)


def _track(request: RunRequest, resolved: _Resolved, source: Source,
           formatter: _SingleTargetRows | _MultiTargetRows, csv: CsvWriter,
           video: VideoWriter | None, annotator: Annotator | None,
           on_frame: Callable[[int], None] | None) -> _Tracked:
    """The signal-safe frame loop: each frame's CSV rows and picture are written together;
    a broken input, Ctrl-C or a tracker error ends it with every output closed and valid."""
    out = _Tracked()
    started = time.perf_counter()
    try:
        with _AtomicFrames() as interrupts:
            frames_in = _limited(iter(source), request.max_frames)
            for result in resolved.pipeline.track(frames_in, resolved.init_box):
                with interrupts.writing():
                    for row in formatter.rows(result):
                        csv.write(row)
                    if video is not None and annotator is not None:
                        assert result.frame is not None
                        video.write(result.frame, lambda planes, r=result: annotator.draw(
                            planes, r), time_s=result.time_s)
                    if result.state in out.states:
                        out.states[result.state] += 1
                    out.frames += 1
                if on_frame is not None:
                    on_frame(out.frames)
    except PartialInputError as exc:
        out.status, out.error = STATUS_PARTIAL, str(exc)
    except KeyboardInterrupt:
        out.status, out.error = STATUS_INTERRUPTED, "interrupted by the user"
    except Exception as exc:  # recorded in run.json, then raised again by run()
        out.status, out.error, out.failure = STATUS_FAILED, str(exc) or type(exc).__name__, exc
    finally:
        out.seconds = time.perf_counter() - started
        source.close()
        csv.close()
        if video is not None:
            video.close()
    return out


def _record(request: RunRequest, resolved: _Resolved, info: Any,
            formatter: _SingleTargetRows | _MultiTargetRows, csv_name: str,
            tracked: _Tracked) -> RunSummary:
    """Metrics, the summary and ``run.json`` (written last, atomically)."""
    status, error, frames, seconds = tracked.status, tracked.error, tracked.frames, tracked.seconds
    gt = resolved.gt
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
        error=error,
    )
    if frames == 0 and status == STATUS_COMPLETE:
        status = summary.status = STATUS_PARTIAL
        summary.error = error = f"{request.input}: no frame could be decoded"
    metrics: Mapping[str, Any] = {}
    if isinstance(formatter, _SingleTargetRows) and gt is not None:
        metrics = summarize(formatter.boxes, gt)
        summary.mean_overlap = metrics.get("mean_overlap")
        summary.auc = metrics.get("auc")
        summary.precision20 = metrics.get("precision20")
        if len(gt) != frames and status == STATUS_COMPLETE:
            side = "fewer" if len(gt) < frames else "more"
            note = (
                f"{request.gt_path}: ground truth has {len(gt)} boxes for {frames} frames "
                f"({side}); " + ("overlap is empty from frame "
                                 f"{len(gt)} on" if len(gt) < frames else "extra boxes ignored")
            )
            summary.warnings.append(note)
    elif isinstance(formatter, _MultiTargetRows) and resolved.mot_gt is not None:
        summary.mot = evaluate_mot(resolved.mot_gt, formatter.tracks, frames)
        metrics = dict(summary.mot)

    record = {
        "status": status,
        "error": error,
        "warnings": summary.warnings,
        "frames": frames,
        "input": info.to_dict(),
        "request": request.to_dict(),
        "init": list(resolved.init_box) if resolved.init_box is not None else None,
        "config": request.config.resolved(),
        "metrics": metrics,
        "summary": {k: v for k, v in summary.__dict__.items() if k not in ("warnings", "mot")},
        "timing": {
            "seconds": seconds,
            "fps": summary.fps,
            "stage_us_per_frame": resolved.pipeline.stage_microseconds_per_frame(),
        },
        "outputs": [csv_name] + (["annotated.mp4"] if request.video else []),
        "versions": versions(),
        "command": sys.argv,
    }
    write_json(request.out_dir / "run.json", record)
    return summary
