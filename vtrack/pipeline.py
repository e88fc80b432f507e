"""Run a chain of stages over frames: a generator of per-frame results.

``Pipeline(stages).track(frames, init_box)`` yields one :class:`FrameResult` per frame, in order.
Stage timings are accumulated in ``pipeline.stage_seconds`` for ``run.json``. It is the layer
under :class:`vtrack.Tracker`: its frames are :class:`Frame` objects (the Tracker also takes
NumPy images and ``av.VideoFrame``); its first box is checked as the Tracker's is, its stages
as a config's chain is (:func:`vtrack.config.check_stages`).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from vtrack.config import check_stages
from vtrack.errors import ConfigError, FirstFrameError, InputError
from vtrack.frame import Frame, GrayFrame
from vtrack.geometry import Box, as_box, check_init_box
from vtrack.overlays import Overlay
from vtrack.params import MAX_TRACK_ID, check_seed, check_whole, shown
from vtrack.stages.base import Stage, Track, TrackContext, TrackState

#: A box that lies entirely outside the frame for more than this many frames in a row is
#: reported ``lost`` (no box is claimed) until it overlaps the frame again: a predictor coasting
#: away (S2 at x = -457996 in a 640x480 frame, issue 11 item 8) is not a target still tracked.
#: Frames elapsed, not frames given (``ctx.clock``: frames missing from the input count, by
#: the frame numbers or the timestamps): a camera that delivers every other frame loses the box
#: after the same time as one that delivers all. The first frame given with the box outside
#: counts one, and each after it the whole frames the clock says have elapsed since that one
#: (:attr:`vtrack.clock.FrameClock.frame`: timestamps a fraction of a frame off count no frame
#: more; on an input without gaps the count is the frames given, as it always was). One rule for
#: every single-target tracker,
#: applied to the output; the stages keep their own state. README and docs/architecture.md
#: state it.
OFF_FRAME_FRAMES = 10


@dataclass
class FrameResult:
    """What the tracker says about one frame (``track.csv``'s row of it, unrounded).

    ``index``: the frame's number (0-based, ``track.csv``'s ``frame``: the input's, a
    :class:`vtrack.Frame`'s own, or for an image given to :class:`vtrack.Tracker` one after the
    previous frame's); ``time_s``: its time in seconds (its timestamp, or for a NumPy image
    ``index / fps``, counted on from the last frame timed by a camera's clock); ``box``: the
    target's :class:`Box` ``(x, y, w, h)`` of Python floats (whatever the config),
    None while ``lost``; ``state``: ``TrackState.TRACKING``, ``OCCLUDED`` or ``LOST`` (a ``str``
    enum: ``result.state == "lost"`` works); ``score``: the tracker's confidence in its box, a
    ``float`` never negative (0 for none, 1 as sure as on the first frame), NaN for a chain that
    gives none (s4); ``prediction``: the box where the next frame's search starts (floats too), or
    None; ``extras``: the stages' own values (``track.csv``'s extra columns, by name); ``tracks``:
    for the multi-target configs, every track held, each with ``id`` (an ``int``), ``box`` and
    ``confidence`` (Python floats too) and ``state`` (``tentative``, ``confirmed``: measured this
    frame, the only ones ``tracks.csv`` writes and draws, or ``coasting``); ``overlays``: what the
    annotated video draws beside the box (search window, particles); ``frame``: the decoded frame,
    kept only when asked (``keep_frames=True``), else None.
    """

    index: int
    time_s: float
    box: Box | None
    state: TrackState
    #: The tracker's confidence in its box, never negative (``ctx.score`` floored at 0; NaN
    #: where a chain gives none).
    score: float
    prediction: Box | None
    extras: dict[str, Any] = field(default_factory=dict)
    tracks: list[Track] = field(default_factory=list)
    overlays: list[Overlay] = field(default_factory=list)
    #: The frame this result is about (writers take its pixels from here); the pipeline always
    #: sets it, results built by hand (e.g. to test drawing) may leave it out.
    frame: Frame | None = None


def first_box_refused(name: str, instead: str) -> ConfigError:
    """The error for a first box given to a multi-target chain (``name``: the config's, with
    where the box came from), which would ignore it; ``instead`` says what to do."""
    return ConfigError(f"{name} finds its targets itself (it tracks several, each from where it "
                       f"is detected) and takes no first box; {instead}")


def check_first_track_id(value: object, multi_target: bool, chain: str,
                         name: str = "first_track_id") -> int:
    """``value``, the id a multi-target chain gives its first new track, as an ``int``:
    ConfigError naming ``name`` (the caller's: ``--first-id``, ``first_track_id``) for one that
    is not a whole number from 1 to :data:`~vtrack.params.MAX_TRACK_ID`, and for one other than
    1 given to a single-target chain (``chain``: its name), which numbers no tracks."""
    first = check_whole(name, value, 1, MAX_TRACK_ID, "the id of the first new track")
    if first != 1 and not multi_target:
        raise ConfigError(f"{name} {first}: {chain} tracks one target and numbers no tracks; "
                          "only a multi-target config (s3, s4_multi, fixed_camera, ...: "
                          "vtrack stages lists the shipped configs) takes a first track id")
    return first


class Pipeline:
    """An ordered chain of stages sharing one :class:`TrackContext`."""

    def __init__(self, stages: list[Stage], seed: int = 0, first_track_id: int = 1) -> None:
        """``stages`` built stages (``load_config(...).build()``), checked as a config's chain
        is (ConfigError naming ``pipeline``); TypeError for anything else. ``first_track_id``:
        the id a multi-target chain gives its first new track, the later ones following on
        (:func:`check_first_track_id`)."""
        check_seed(seed)
        if not isinstance(stages, list | tuple) or not all(isinstance(s, Stage) for s in stages):
            raise TypeError("stages: expected a list of built stages (e.g. "
                            f"vtrack.load_config(name).build()), got {shown(stages)}")
        if not stages:
            raise ConfigError("a pipeline needs at least one stage")
        check_stages("pipeline", [type(s) for s in stages], [s.settings() for s in stages])
        self.stages = stages
        self.seed = seed
        self.first_track_id = check_first_track_id(first_track_id, self.multi_target,
                                                   "this chain")
        self.stage_seconds = {s.name: 0.0 for s in stages}
        self.frames_done = 0
        #: Whether :meth:`begin` started a track (a chain that needs a box cannot start without)
        self._begun = False
        self._init_box: Box | None = None
        self._ctx: TrackContext | None = None
        #: (width, height, grey) of the track's first frame: every later one must match
        self._shape: tuple[int, int, bool] | None = None
        #: the clock's whole frame at the first of the frames in a row whose box lies entirely
        #: outside the frame (None: the last frame's box was not; OFF_FRAME_FRAMES)
        self._off_since: int | None = None

    @property
    def multi_target(self) -> bool:
        """True for a chain that detects several targets (its results' ``tracks``)."""
        return any(s.multi_target for s in self.stages)

    @property
    def needs_init_box(self) -> bool:
        """True for a chain that starts from the target's first box (all but the detecting
        ones: s3, s4, ...)."""
        return any(s.needs_init_box for s in self.stages)

    def refuse_a_first_box(self, name: str, instead: str) -> None:
        """ConfigError for a first box given to a multi-target chain (``name``: the config's),
        which would ignore it; ``instead`` says what to do."""
        if self.multi_target:
            raise first_box_refused(name, instead)

    @property
    def gives_score(self) -> bool:
        """Whether a stage of the chain sets the score (provides it; else every result's is
        NaN: S4, whose document defines no confidence)."""
        return any("score" in s.provides for s in self.stages)

    @property
    def columns(self) -> tuple[str, ...]:
        """Extra CSV columns declared by the stages, in chain order, without repeats."""
        seen: dict[str, None] = {}
        for stage in self.stages:
            for column in stage.columns:
                seen.setdefault(column)
        return tuple(seen)

    def track(self, frames: Iterable[Frame], init_box: Box | Sequence[float] | None = None
              ) -> Iterator[FrameResult]:
        """Yield one result per frame (:class:`Frame` objects). ``init_box`` (a :class:`Box` or
        ``(x, y, w, h)``) is required unless the chain detects targets; ConfigError for one the
        first frame cannot start from, as :func:`check_init_box` says."""
        self.begin(init_box)
        for frame in frames:
            yield self.process(frame)

    def begin(self, init_box: Box | Sequence[float] | None = None) -> None:
        """Start a new track: the next frame given to :meth:`process` is the first, and
        ``init_box`` is the target's box in it (required unless the chain detects targets;
        checked against that frame by :meth:`process`). The track before ends here, also when
        ``init_box`` is refused (ConfigError): no track is going then, as after
        :meth:`vtrack.Tracker.reset`."""
        self._ctx, self._shape, self._off_since, self._begun, self._init_box = (
            None, None, None, False, None)
        if init_box is None and self.needs_init_box:
            raise ConfigError("this tracker needs an initial box: give init_box (x, y, w, h)")
        self._init_box = None if init_box is None else as_box(init_box)
        self._begun = True

    def process(self, frame: Frame) -> FrameResult:
        """Track ``frame`` (the next :class:`Frame` after :meth:`begin`; TypeError for anything
        else) and return what is said about it. Before :meth:`begin`, a chain that starts from
        the target's box is a ConfigError saying to call it, and a detecting one begins its
        track here (as :meth:`vtrack.Tracker.update` does). InputError for a frame of another
        size than the track's first, or grey after colour (or colour after grey): its stages'
        windows, models and boxes are those of the first frame's pictures."""
        if not isinstance(frame, Frame):
            raise TypeError(f"Pipeline takes vtrack.Frame objects (BgrFrame, GrayFrame, "
                            f"I420Frame), got {type(frame).__name__}; vtrack.Tracker and "
                            "vtrack.track also take NumPy images and av.VideoFrame")
        if not self._begun:  # as Tracker.update: a detecting chain may start here
            if self.needs_init_box:
                raise ConfigError("pipeline: no track begun: call begin((x, y, w, h)) with the "
                                  "target's box in the first frame, then process(frame)")
            self.begin(None)
        self._check_shape(frame)
        timer = time.perf_counter
        ctx = self._ctx
        if ctx is None:
            init_box = self._init_box
            if init_box is not None:
                check_init_box(init_box, frame.width, frame.height, "init_box")
            ctx = TrackContext(frame=frame, seed=self.seed, box=init_box,
                               first_track_id=self.first_track_id)
            ctx.new_frame(frame)
            try:
                for stage in self.stages:
                    started = timer()
                    stage.start(ctx)
                    self.stage_seconds[stage.name] += timer() - started
            except FirstFrameError as exc:  # a stage that cannot start: which frame it refused
                exc.frame_index = frame.index  # (raised as it is: its class, the stage's line)
                raise
            if init_box is not None:
                ctx.box = init_box  # the first frame's answer is the box we were given
            # the track's first frame, once it started there: a frame refused as the first
            # (its box outside it, a stage that cannot start) sets nothing
            self._ctx, self._shape = ctx, _shape(frame)
        else:
            ctx.clock.advance(frame)  # before the forecast and the stages: they read it
            ctx.new_frame(frame)
            for stage in self.stages:
                started = timer()
                stage.step(ctx)
                self.stage_seconds[stage.name] += timer() - started
        self.frames_done += 1
        state = ctx.state
        if ctx.box is not None and ctx.box.outside(frame.width, frame.height):
            if self._off_since is None:
                self._off_since = ctx.clock.frame
            if ctx.clock.frame - self._off_since + 1 > OFF_FRAME_FRAMES:
                state = TrackState.LOST
        else:
            self._off_since = None
        return FrameResult(
            index=frame.index,
            time_s=frame.time_s,
            frame=frame,
            # lost: no box is claimed; a stage's NumPy numbers are the public result's floats
            box=None if state == TrackState.LOST or ctx.box is None else ctx.box.plain(),
            state=state,
            score=float(max(ctx.score, 0.0)),  # a signal below its reference is no evidence: 0
            prediction=None if ctx.prediction is None else ctx.prediction.plain(),
            extras=ctx.extras,
            tracks=[track.plain() for track in ctx.tracks],
            overlays=ctx.overlays,
        )

    def _check_shape(self, frame: Frame) -> None:
        """InputError naming ``frame`` when its size or kind (grey, colour) is not the track's
        first frame's (none yet: any frame may be the first)."""
        shape = _shape(frame)
        if self._shape is not None and shape != self._shape:
            raise InputError(f"frame {frame.index}: {_looks(shape)}, the first frame was "
                             f"{_looks(self._shape)} (one track follows one sequence: "
                             "Tracker.reset() or Pipeline.begin() starts another)")

    def stage_microseconds_per_frame(self) -> dict[str, float]:
        """Each stage's mean wall time per frame processed so far, in microseconds, by stage
        name (``run.json``'s ``timing.stage_us_per_frame``)."""
        n = max(self.frames_done, 1)
        return {name: seconds * 1e6 / n for name, seconds in self.stage_seconds.items()}


def _shape(frame: Frame) -> tuple[int, int, bool]:
    """(width, height, grey) of ``frame``: what every frame of a track must share."""
    return frame.width, frame.height, isinstance(frame, GrayFrame)


def _looks(shape: tuple[int, int, bool]) -> str:
    width, height, grey = shape
    return f"{width}x{height} {'grey' if grey else 'colour'}"
