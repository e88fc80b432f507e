"""The one description of a run: what ``vtrack run``, ``vtrack batch``, ``vtrack.track`` and
``run.json`` share.

:class:`RunRequest` is built by the CLI (``vtrack run``; ``vtrack batch`` builds one per input x
config from a template), recorded in ``run.json`` as ``"request"`` through :meth:`to_dict`, read
back with :meth:`from_dict`, and compared whole by batch's resume test (:meth:`same_run`): a
result is reused only if every field of the request that made it is the same (but for the
results folder's own place: a batch folder moved whole resumes; and the config's source, how
its file was named: the same file named another way is the same chain).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from vtrack.config import Config, config_from_resolved
from vtrack.errors import ConfigError, cut, real_or_nan
from vtrack.evaluate.groundtruth import MAX_TARGET
from vtrack.geometry import Box, as_box
from vtrack.io import RawFormat
from vtrack.io.files import path_text
from vtrack.io.identity import file_identity
from vtrack.io.source import frame_at_time
from vtrack.io.video import FFmpegInput, checked_ffmpeg
from vtrack.io.videowriter import video_out_problem
from vtrack.params import (
    MAX_CRF,
    MAX_FRAME_NUMBER,
    MAX_SECONDS,
    X264_PRESETS,
    check_flag,
    check_seed,
    check_whole,
    checked_seconds,
    shown,
)
from vtrack.pipeline import check_first_track_id
from vtrack.stages.base import stage_class


@dataclass(frozen=True)
class RunRequest:
    """Everything one run needs. Paths are used as given (the CLI resolves defaults).

    ``init_box`` None takes the input's sidecar box (``NAME.init.txt``, :mod:`vtrack.io.sidecar`)
    or else the first ground-truth box (single-target configs); ``gt_origin`` 1
    reads 1-based (MATLAB) ground-truth boxes; ``gt_first`` is the frame (0-based, as
    ``start``) the single-target ground truth's first box belongs to (its frames before it
    have none and are not scored; a multi-target config refuses it: MOTChallenge rows number
    their frames); ``raw`` describes raw-frame input (None: a video
    file or image folder); ``video`` writes ``annotated.mp4`` with ``preset``/``crf``; ``seed``
    seeds the stochastic stages; ``start`` is the first frame tracked (the input's 0-based
    frame number; an MP4 or MOV file of constant frame rate is read from the key frame at or
    before it, an image folder from its image, other inputs (MKV, WebM, MPEG-TS, AVI,
    fragmented MP4, a variable frame rate, streams, raw frames) decode the frames before it and
    skip them, as ``ffmpeg -ss`` skips time);
    ``start_s``, when set, gives it as a time instead (``--start 2.5s``): the first frame whose
    timestamp is at or after that many seconds (found as the run reads the input; a variable
    frame rate is followed);
    ``max_frames`` stops after that many tracked frames; ``max_s``, when set, gives that as a
    duration instead (``--frames 10s``): the frames whose timestamp is less than ``max_s``
    past the first tracked one's (a variable frame rate is followed; at least one frame);
    ``first_track_id`` is the id a multi-target config gives the first track it creates, the
    next ones following on (a run taken up again after an interruption: the first run's
    highest + 1, so that no id is used twice); a single-target config takes only 1.
    """

    input: str
    out_dir: Path
    config: Config
    init_box: Box | None = None
    gt_path: Path | None = None
    gt_origin: int = 0
    #: ``--gt-first N``: the 0-based frame of the ground truth's first box (0 to
    #: :data:`~vtrack.params.MAX_FRAME_NUMBER`).
    gt_first: int = 0
    raw: RawFormat | None = None
    #: Frame rate of an image folder (None: 30); refused for a video file (raw: in ``raw``).
    fps: float | None = None
    video: bool = True
    preset: str = "ultrafast"
    crf: int = 23
    seed: int = 0
    max_frames: int | None = None
    start: int = 0
    start_s: float | None = None
    max_s: float | None = None
    #: Where ``init_box`` came from when the caller read it from a file (batch: the input's
    #: sidecar ``NAME.init.txt``); None: given directly (``--init``, the library).
    init_from: str | None = None
    #: ``--stream``: write a flushed JSON line per frame to this path, or ``-`` for stdout (a
    #: pathlib.Path is kept as its text).
    stream: str | None = None
    #: ``--format``, ``--input-option``, ``--timeout``, ``--follow``: how FFmpeg opens the input.
    ffmpeg: FFmpegInput = field(default_factory=FFmpegInput)
    #: ``--live``/``--no-live``: track only the newest frame when busy (None: for stream URLs
    #: and capture devices, :func:`vtrack.io.specs.is_live`).
    live: bool | None = None
    #: ``--video-out URL``: the annotated video goes to this live output instead of a file.
    video_out: str | None = None
    #: Which target of an OTB sequence of several (``groundtruth_rect.N.txt``: N, at least 0)
    #: the run tracks, its input then named ``SEQ-N`` (``vtrack batch`` takes each as an input;
    #: ``vtrack run SEQ --gt SEQ/groundtruth_rect.N.txt`` sets it); None: the input's only one.
    target: int | None = None
    #: ``--first-id N``: a multi-target config numbers its tracks from this id (1 to
    #: :data:`~vtrack.params.MAX_TRACK_ID`; a single-target config takes only 1:
    #: :func:`vtrack.pipeline.check_first_track_id`).
    first_track_id: int = 1

    def __post_init__(self) -> None:
        """Check the values the CLI checks before it makes a request (one made in Python
        too): ConfigError naming the field for a value out of its range, TypeError for a
        ``config`` that is not a :class:`Config` and for a path or text field of another type;
        a box given as 4 numbers becomes a Box, a path given as text a Path (``input`` and
        ``stream`` text); ``video`` and ``live`` take 1 and 0 for True and False."""
        for name in ("input", "out_dir", "gt_path"):  # (str or pathlib.Path, as the library)
            value = getattr(self, name)
            if value is None and name == "gt_path":
                continue
            if not isinstance(value, str | os.PathLike):
                raise TypeError(f"{name}: expected a path (str or pathlib.Path), got "
                                f"{type(value).__name__}")
            object.__setattr__(self, name, path_text(value, name) if name == "input"
                               else Path(value))
        if isinstance(self.stream, os.PathLike):  # (a file: a path as the others; "-" stdout)
            object.__setattr__(self, "stream", os.fspath(self.stream))
        for name in ("stream", "init_from", "video_out"):
            if getattr(self, name) is not None and not isinstance(getattr(self, name), str):
                raise TypeError(f"{name}: expected text or None, got "
                                f"{type(getattr(self, name)).__name__}")
        if self.stream is not None and not self.stream.strip():  # (as --stream refuses it)
            raise ConfigError("stream: empty; give a file or - (stdout)")
        problem = None if self.video_out is None else video_out_problem(self.video_out,
                                                                        "out_dir")
        if problem:
            raise ConfigError(f"video_out {cut(self.video_out)}: {problem}")
        object.__setattr__(self, "video", check_flag(self.video, "video"))
        if self.live is not None:
            object.__setattr__(self, "live", check_flag(self.live, "live"))
        if self.preset not in X264_PRESETS:
            raise ConfigError(f"preset {shown(self.preset)}: must be one of "
                              f"{', '.join(X264_PRESETS)} (the annotated video's x264 "
                              "preset)")
        if not isinstance(self.config, Config):
            raise TypeError(f"config: expected a vtrack.Config (vtrack.load_config(name)), got "
                            f"{type(self.config).__name__}")
        self.config.check_files_named()
        if self.init_box is not None:
            object.__setattr__(self, "init_box", as_box(self.init_box))
        # (fps: checked as the input opens, where --fps applies)
        object.__setattr__(self, "seed", check_seed(self.seed))
        object.__setattr__(self, "first_track_id", check_first_track_id(
            self.first_track_id, self.config.multi_target, self.config.name))
        fps = real_or_nan(self.fps)
        if self.fps is not None and math.isfinite(fps):
            object.__setattr__(self, "fps", fps)  # (a Decimal: a number)
        if self.raw is not None:
            if not isinstance(self.raw, RawFormat):
                raise TypeError(f"raw: expected a vtrack.io.RawFormat, got "
                                f"{type(self.raw).__name__}")
            object.__setattr__(self, "raw", self.raw.checked())
        object.__setattr__(self, "ffmpeg", checked_ffmpeg(self.ffmpeg))
        for name, least, most, meaning in _WHOLE_NUMBERS:  # (a NumPy int: an int)
            if name not in _OPTIONAL or getattr(self, name) is not None:
                object.__setattr__(self, name, check_whole(name, getattr(self, name), least,
                                                           most, meaning))
        for name, above in (("start_s", False), ("max_s", True)):
            if getattr(self, name) is not None:  # (a NumPy or Decimal number: a float)
                object.__setattr__(self, name, checked_seconds(
                    name, getattr(self, name), 0, MAX_SECONDS, above, " (a year)"))
        # files a stage reads (mot_detections' det.txt) relative to the folder the request was
        # made in, not the one a worker runs in (a Dask worker's: another file, or none)
        object.__setattr__(self, "config", _absolute_files(self.config))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (``run.json``'s ``"request"``): the config as its resolved chain
        (every parameter, defaults included), paths as strings, boxes as lists."""
        return {
            "input": self.input,
            "out_dir": str(self.out_dir),
            "config": self.config.resolved(),
            "init": None if self.init_box is None else list(self.init_box),
            "gt": None if self.gt_path is None else str(self.gt_path),
            "gt_origin": self.gt_origin,
            "gt_first": self.gt_first,
            "raw": None if self.raw is None else asdict(self.raw),
            "fps": self.fps,
            "video": self.video,
            "preset": self.preset,
            "crf": self.crf,
            "seed": self.seed,
            "max_frames": self.max_frames,
            "start": self.start,
            "start_s": self.start_s,
            "max_s": self.max_s,
            "init_from": self.init_from,
            "stream": self.stream,
            "ffmpeg": {**{k: v for k, v in asdict(self.ffmpeg).items() if k != "timeout_option"},
                       "options": dict(self.ffmpeg.options)},
            "live": self.live,
            "video_out": self.video_out,
            "target": self.target,
            "first_track_id": self.first_track_id,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RunRequest:
        """The request :meth:`to_dict` described (KeyError/ValueError/ConfigError if it is not
        one). A field recorded since a later version (:data:`_RECORDED_LATER`), absent or
        null, is what a record without it meant."""
        data = _with_recorded_later(data)
        return cls(
            input=str(data["input"]),
            out_dir=Path(data["out_dir"]),
            config=config_from_resolved(data["config"]),
            init_box=None if data["init"] is None else Box(*map(float, data["init"])),
            gt_path=None if data["gt"] is None else Path(data["gt"]),
            gt_origin=int(data["gt_origin"]),
            gt_first=int(data["gt_first"]),
            raw=None if data["raw"] is None else RawFormat(**data["raw"]),
            fps=None if data.get("fps") is None else float(data["fps"]),
            video=bool(data["video"]),
            preset=str(data["preset"]),
            crf=int(data["crf"]),
            seed=int(data["seed"]),
            max_frames=None if data["max_frames"] is None else int(data["max_frames"]),
            start=int(data.get("start", 0)),
            start_s=None if data.get("start_s") is None else float(data["start_s"]),
            max_s=None if data.get("max_s") is None else float(data["max_s"]),
            init_from=data.get("init_from"),
            stream=data.get("stream"),
            ffmpeg=_ffmpeg_input(data.get("ffmpeg")),
            live=data.get("live"),
            video_out=data.get("video_out"),
            target=None if data["target"] is None else int(data["target"]),
            first_track_id=int(data["first_track_id"]),
        )

    @property
    def starts_later(self) -> bool:
        """Whether ``--start`` names a point after the input's first frame: a frame number
        or a time above 0 (timestamps count from the first frame, so ``--start 0s`` is its
        beginning, as ``--start 0`` is). Such a start is settled in the opened input (a time
        in its frames' timestamps, a frame past the frames it states refused at once), and a
        sidecar box, frame 0's, is then not the target's first box."""
        return bool(self.start or self.start_s)

    def start_estimate(self, fps: float | None) -> int:
        """The first frame tracked as a progress bar can tell before the frames are read:
        ``start``, or for ``start_s`` the first frame at or after that time at ``fps`` frames a
        second (0 without a frame rate). Exact for a constant rate; the run itself takes the
        first frame whose timestamp is at or after ``start_s``."""
        if self.start_s is None:
            return self.start
        return frame_at_time(self.start_s, fps)

    def frames_expected(self, frame_count: int | None, fps: float | None) -> int | None:
        """The frames the run will track, as far as the input's ``frame_count`` (None:
        unknown) and frame rate tell a progress bar: the count less the frames before
        ``--start`` (:meth:`start_estimate`), at most ``--frames`` given as a count (that alone
        when the count is unknown); None when nothing tells."""
        total = None
        if frame_count is not None:
            total = max(frame_count - self.start_estimate(fps), 0) or None
        if self.max_frames is not None:
            total = min(total, self.max_frames) if total else self.max_frames
        return total

    def file_identities(self) -> dict[str, Any]:
        """The identity (:func:`~vtrack.io.identity.file_identity`) of the input, the ground
        truth and the files the config's stages read (``"files"``, by path, when there are
        any: a ``det.txt``) as they are now: ``run.json`` records it, batch's resume compares
        it."""
        identities = {"input": file_identity(self.input), "gt": file_identity(self.gt_path)}
        files = {path: file_identity(path) for path in _stage_files(self.config)}
        return {**identities, "files": files} if files else identities

    def same_run(self, recorded: Any) -> bool:
        """Whether ``recorded`` (a ``run.json`` ``"request"``) describes exactly this request,
        wherever its results folder was then (``out_dir``: a results folder moved or copied
        whole holds the same runs)."""
        return not self.differences(recorded)

    def differences(self, recorded: Any) -> list[str]:
        """What a user changed between ``recorded`` (a ``run.json`` ``"request"``) and this
        request, each field by the option that sets it (``--no-video``, ``--set or the
        config``, ...; ``out_dir`` is not compared, see :meth:`same_run`); empty when they are
        the same run."""
        if not isinstance(recorded, dict):
            return ["the whole request (run.json records none)"]
        mine = _compared(json.loads(json.dumps(self.to_dict())))
        recorded = _compared(_with_recorded_later(recorded))
        moot = _moot(mine) & _moot(recorded)
        keys = [k for k in dict.fromkeys([*mine, *recorded])
                if k != "out_dir" and k not in moot
                and mine.get(k, _ABSENT) != recorded.get(k, _ABSENT)]
        return list(dict.fromkeys(_SETTING_NAMES.get(key, key) for key in keys))


def _moot(request: dict[str, Any]) -> set[str]:
    """The fields of ``request`` (a ``run.json`` ``"request"``) that change nothing in its run:
    the video's ``--preset`` and ``--crf`` when no video is made (``--no-video``),
    ``--gt-origin`` and ``--gt-first`` without ground truth, and ``--seed`` for a chain no
    stage of which draws random numbers (none ``requires`` the run's ``rng``: all but the
    particle filter). Two requests that both leave one moot are the same run whatever it
    says."""
    moot = set()
    if request.get("video") is False:
        moot |= {"preset", "crf"}
    if request.get("gt") is None:
        moot |= {"gt_origin", "gt_first"}
    config = request.get("config")
    stages = config.get("stages") if isinstance(config, dict) else None
    if isinstance(stages, list) and all(isinstance(s, dict) for s in stages):
        try:
            if not any("rng" in stage_class(str(s.get("name")), "run.json").requires
                       for s in stages):
                moot.add("seed")
        except ConfigError:  # (a stage this vtrack does not know: the config differs)
            pass
    return moot


#: (A field missing from one of two requests compared.)
_ABSENT = object()
#: Fields ``run.json`` records since a later version, with what a record without one (or with
#: null) meant: a run of an input's only target, its tracks numbered from 1 (a ``run.json``
#: written before there was a first track id), its ground truth's first box frame 0's; its
#: results still resume.
_RECORDED_LATER: dict[str, Any] = {"target": None, "first_track_id": 1, "gt_first": 0}


def _with_recorded_later(request: dict[str, Any]) -> dict[str, Any]:
    """``request`` (a ``run.json`` ``"request"``) with each field of :data:`_RECORDED_LATER`
    it lacks or holds as null set to what a record without it meant."""
    return {**request, **{k: v for k, v in _RECORDED_LATER.items() if request.get(k) is None}}


def _compared(request: dict[str, Any]) -> dict[str, Any]:
    """``request`` (a ``run.json`` ``"request"``) as two runs are compared: its config without
    its ``source``, the config's name as it was typed (``-c det.toml``, ``-c /abs/det.toml`` or
    ``-c ../det.toml`` from a folder below are one file, one run); the config's name,
    description and every stage's every parameter still are."""
    config = request.get("config")
    if not isinstance(config, dict) or "source" not in config:
        return request
    return {**request, "config": {k: v for k, v in config.items() if k != "source"}}


#: How a user sets each field of :meth:`RunRequest.to_dict` (named when it differs).
_SETTING_NAMES = {
    "input": "the input's path", "config": "the config (its file or a --set)",
    "init": "the first box (--init or NAME.init.txt)", "gt": "the ground truth (--gt)",
    "gt_origin": "--gt-origin", "gt_first": "--gt-first", "raw": "--raw/--pix-fmt", "fps": "--fps",
    "video": "--no-video", "preset": "--preset", "crf": "--crf", "seed": "--seed",
    "max_frames": "--frames", "max_s": "--frames", "start": "--start", "start_s": "--start",
    "init_from": "the first box (--init or NAME.init.txt)", "stream": "--stream",
    "ffmpeg": "the input options (--input-option ...)", "live": "--live",
    "video_out": "--video-out", "target": "the target (--gt SEQ/groundtruth_rect.N.txt)",
    "first_track_id": "--first-id",
}


def _file_values(config: Config) -> Iterator[tuple[int, str, str]]:
    """(stage index, parameter, path) of each file a stage of ``config`` reads (the non-empty
    values of its ``file_params``)."""
    for index, _, name, value in config.file_values():
        if isinstance(value, str) and value:
            yield index, name, value


def _stage_files(config: Config) -> list[str]:
    """The files the stages of ``config`` read."""
    return [path for _, _, path in _file_values(config)]


#: The whole-number fields of a RunRequest: (field, least, most, what the number is).
_WHOLE_NUMBERS = (
    ("start", 0, MAX_FRAME_NUMBER, "the first frame tracked, 0-based"),
    ("max_frames", 1, MAX_FRAME_NUMBER, "how many frames to track; None: to the end"),
    ("crf", 0, MAX_CRF, "the annotated video's x264 quality"),
    ("gt_origin", 0, 1, "1: the ground truth's boxes are 1-based"),
    ("gt_first", 0, MAX_FRAME_NUMBER, "the frame of the ground truth's first box, 0-based"),
    ("target", 0, MAX_TARGET, "the N of the target's groundtruth_rect.N.txt"),
)
#: The whole numbers of :data:`_WHOLE_NUMBERS` that may be None.
_OPTIONAL = ("max_frames", "target")


def _absolute_files(config: Config) -> Config:
    """``config`` with each relative file a stage reads made absolute against the current
    folder."""
    relative = [(i, name, path) for i, name, path in _file_values(config)
                if not os.path.isabs(path)]
    if not relative:
        return config
    stages = [(stage, dict(values)) for stage, values in config.stages]
    for index, name, path in relative:
        stages[index][1][name] = os.path.abspath(path)
    return Config(config.name, config.source, config.description, stages)


def _ffmpeg_input(data: dict[str, Any] | None) -> FFmpegInput:
    """The :class:`FFmpegInput` :meth:`RunRequest.to_dict` recorded (the default if none)."""
    if data is None:
        return FFmpegInput()
    follow = data.get("follow_s")
    return FFmpegInput(format=data.get("format"),
                       options=tuple((str(k), str(v)) for k, v in data["options"].items()),
                       timeout_s=float(data["timeout_s"]),
                       follow_s=None if follow is None else float(follow))
