"""The stage contract: what a stage declares, what it shares with the others, how it is found.

A stage is a small object that does one job per frame. Stages do not call each other: they read
and write fields of one shared :class:`TrackContext`, in the order the config lists them. Each
stage class declares, once:

- ``name``: the key used in configs (``[[stage]] name = "meanshift"``) and ``--set name.param=``;
- ``summary``: one line for ``vtrack stages``;
- ``params``: its :class:`~vtrack.params.Param` declarations (validation, CLI, docs);
- ``requires`` / ``provides``: names of the :class:`TrackContext` fields it reads / writes, so
  an impossible chain (a stage before the one that produces its input) is rejected when the
  config is loaded. Every value stages share is a typed field of the context (no free-form
  dict): a stage that needs another stage's value names that field in ``requires``, and
  :func:`vtrack.config.check_chain` refuses the chain unless an earlier stage ``provides`` it
  (``PIPELINE_PROVIDES`` are there from the start);
- ``columns``: extra ``track.csv`` columns it fills through ``ctx.extras``.

Lifecycle: ``start(ctx)`` once on the first frame (``ctx.box`` holds the initial box, may be None
for detecting trackers), then ``step(ctx)`` on every later frame. The first frame's output is the
initial box; later frames' output is ``ctx.box`` / ``ctx.state`` / ``ctx.score`` after the
last stage.
"""

from __future__ import annotations

import importlib
import math
import pkgutil
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from vtrack.clock import FrameClock
from vtrack.errors import ConfigError, FirstFrameError, did_you_mean
from vtrack.frame import Frame
from vtrack.geometry import Box, Window
from vtrack.overlays import Overlay
from vtrack.params import Param, shown

if TYPE_CHECKING:
    from vtrack.golden.record import FixedRecord
    from vtrack.stages.robust_model import RobustTarget


class TrackState(StrEnum):
    """State of the single target (``track.csv``'s ``state`` column is the value)."""

    TRACKING = "tracking"
    OCCLUDED = "occluded"
    #: No box is claimed: the output box is None, nothing is drawn, the metrics count a failure.
    LOST = "lost"


class TrackStatus(StrEnum):
    """State of one track of a multi-target tracker (``tracks.csv``'s ``state`` column)."""

    #: Not confirmed yet.
    TENTATIVE = "tentative"
    #: Confirmed and measured this frame: the only tracks written to ``tracks.csv`` and drawn.
    CONFIRMED = "confirmed"
    #: Confirmed, predicted only this frame.
    COASTING = "coasting"


#: Context fields the pipeline itself provides before the first stage runs.
PIPELINE_PROVIDES = frozenset({"frame", "clock", "box", "prediction", "state", "rng",
                               "search_growth", "first_track_id"})

#: The rule of a stage keeping the chain's fixed-point record (``provides = {"fixed"}``:
#: hue_bp_fixed's S0 one, kernel_meanshift_int's S2 one), which config._check_tracks keeps.
ONE_RECORD_RULE = ("no other stage keeping a fixed-point record (hue_bp_fixed, "
                   "kernel_meanshift_int) in the chain: a chain computes one")

#: Fields computed from another field: a stage that sets the key field without setting these
#: leaves them describing an older value, so later stages may not read them (a new search
#: window has no back-projection until a stage makes one).
DERIVED: dict[str, frozenset[str]] = {
    "window": frozenset({"feature", "feature_levels", "feature_mask", "likelihood",
                         "feature_scale"}),
    "feature": frozenset({"feature_levels", "feature_mask", "likelihood"}),
}


@dataclass
class Track:
    """One target of a multi-target tracker, as written to ``tracks.csv`` (ids start at the
    run's first track id, 1 unless it says otherwise: :attr:`TrackContext.first_track_id`)."""

    id: int
    box: Box
    confidence: float
    state: TrackStatus

    def plain(self) -> Track:
        """This track with its id a Python ``int`` and its box and confidence Python
        ``float``s (a stage's NumPy numbers taken as their values): what the public results
        hold. Built directly (``dataclasses.replace`` takes several times as long, once per
        track and frame)."""
        return Track(int(self.id), self.box.plain(), float(self.confidence), self.state)


#: A value given for a scene's targets (an aspect, a size) weighs as many measured boxes as this
#: when mixed with the one learnt from them (:meth:`TargetShape.mixed`).
PRIOR_SAMPLES = 50


@dataclass(frozen=True)
class TargetShape:
    """The usual shape of a scene's confirmed targets, as a multi-target tracker measured it:
    ``aspect`` = median height / width, ``area`` = median box area in pixels, from ``samples``
    measured boxes."""

    aspect: float
    area: float
    samples: int

    @property
    def width(self) -> float:
        """The usual width in pixels (the box of the usual area at the usual aspect)."""
        return math.sqrt(self.area / self.aspect)

    def mixed(self, given: float, learnt: float) -> float:
        """``given`` (a value the configuration states) and ``learnt`` (the same value read
        from this shape) averaged by their weights: the given one counts as
        :data:`PRIOR_SAMPLES` measured boxes, so it gives way as the scene shows its targets."""
        weight = self.samples / (self.samples + PRIOR_SAMPLES)
        return (1 - weight) * given + weight * learnt


#: Boxes a learnt shape is the median of (the tracker's confirmed boxes, ``group_blobs``'
#: persistent blobs): a passing pair of targets, one box for a while, does not outweigh the rest.
SHAPE_SAMPLES = 500


class ShapeSamples:
    """The height/width and area of the last :data:`SHAPE_SAMPLES` boxes added, and their
    usual shape."""

    def __init__(self) -> None:
        self._aspects: deque[float] = deque(maxlen=SHAPE_SAMPLES)
        self._areas: deque[float] = deque(maxlen=SHAPE_SAMPLES)

    def add(self, box: Box) -> None:
        """Take ``box``'s height/width and area as a sample (the oldest goes past
        :data:`SHAPE_SAMPLES`)."""
        self._aspects.append(box.h / box.w)
        self._areas.append(box.area)

    def shape(self) -> TargetShape | None:
        """Median height/width and area of the samples (None: none yet)."""
        if not self._areas:
            return None
        return TargetShape(float(np.median(self._aspects)), float(np.median(self._areas)),
                           len(self._areas))


@dataclass(frozen=True)
class TargetModel:
    """What a colour tracker learnt about its target on the first frame (S0 sec. 2.2), built by
    ``backproject`` and read by ``meanshift`` and ``occlusion``.

    ``histogram``: float64 counts of the initial box's valid feature values, ``bins`` long;
    ``bp_initial``: mean back-projection (0..255) inside the initial box; ``bp_background``:
    mean back-projection of the rest of the first search window, at most ``bp_initial / 2``.
    The last two are the references of the ``bp_mass`` signal
    (:func:`vtrack.stages.backproject.bp_mass`).
    """

    histogram: np.ndarray
    bp_initial: float
    bp_background: float


@dataclass
class TrackContext:
    """Per-run state shared by the stages; per-frame fields are reset by ``new_frame``."""

    frame: Frame
    #: The frames elapsed since the first frame, and from the frame before to this one (made
    #: on the first frame, :attr:`frame` when the context is made; the pipeline moves it on to
    #: each later frame before :meth:`new_frame`). Counts time where calls would not: frames
    #: missing from the input count as elapsed.
    clock: FrameClock = field(init=False)
    #: Seed of :attr:`rng`.
    seed: int = 0
    #: The id a multi-target tracker gives the first track it creates, the next ones following
    #: on (1 unless the run says otherwise: ``--first-id``, a resumed run's ids after the first
    #: run's); :class:`vtrack.stages.detect.TrackIds` counts from it.
    first_track_id: int = 1
    #: Current estimate of the target box (single-target). The pipeline's output for the frame.
    box: Box | None = None
    #: Where this frame's search starts: set by a predictor on the previous frame (None: use box).
    prediction: Box | None = None
    #: Set by a predictor whose prediction depends on when the next frame comes: the prediction
    #: for a frame. :meth:`new_frame` replaces ``prediction`` with ``forecast(frame)`` (the
    #: :attr:`clock` already moved on to it).
    forecast: Callable[[Frame], Box | None] | None = None
    state: TrackState = TrackState.TRACKING
    #: Tracker-specific quality of this frame's estimate (similarity, weight, bp mass ...).
    score: float = float("nan")
    #: Multiplier on the search window, raised by occlusion/lost logic while the target is away.
    search_growth: float = 1.0
    #: The target's model, from the first frame (``backproject``); None before it is built.
    target_model: TargetModel | None = None
    #: Mean grey of the detections ``blobs`` found in the last frame (None: none), fed back to
    #: ``threshold`` for the next frame (S3 sec. 2.1). Read from the previous frame, so optional.
    candidate_grey: float | None = None
    #: What a multi-target tracker has learnt about its confirmed targets' shape (None: nothing
    #: yet), fed back to the stages that group blobs into targets on the next frame. Read from
    #: the previous frame, so optional.
    target_shape: TargetShape | None = None
    # --- per frame, reset by new_frame -------------------------------------------------------
    #: Search window of this frame (integer pixels inside the frame).
    window: Window | None = None
    #: Feature image of ``window`` (hue 0..255, quantised grey ...), same shape as the window.
    feature: np.ndarray | None = None
    #: How many values ``feature`` takes (256, or 180 for OpenCV's hue); part of ``feature``.
    feature_levels: int = 256
    #: uint8 image of ``window``: 0 where ``feature`` is not valid (e.g. grey pixels have no
    #: hue), 255 elsewhere; None = every pixel valid. Part of ``feature``.
    feature_mask: np.ndarray | None = None
    #: The target-sized box this frame's search starts from (``hue``: the search centre).
    search_box: Box | None = None
    #: Target likelihood of ``window`` (back-projection, 0..255 uint8 or float weights).
    likelihood: np.ndarray | None = None
    #: Frame pixels per pixel of ``feature`` and ``likelihood`` (a segmenting stage that works
    #: on a reduced image sets it above 1). Part of ``window``.
    feature_scale: float = 1.0
    #: This frame's measurement of the target (None: nothing to feed the filter).
    measurement: Box | None = None
    #: Values of the stage-declared extra CSV columns for this frame.
    extras: dict[str, Any] = field(default_factory=dict)
    #: Multi-target output of this frame.
    tracks: list[Track] = field(default_factory=list)
    #: Measurements from detection stages (multi-target): boxes with extra attributes.
    detections: list[Any] = field(default_factory=list)
    #: Extra things to draw (search window, particles) for the annotator.
    overlays: list[Overlay] = field(default_factory=list)
    #: Fixed-point chains (s0-fixed, s2-fixed): model and this frame's integer/float32 values,
    #: created by the chain's first stage (``provides = {"fixed"}``); see vtrack.golden.record.
    fixed: FixedRecord | None = None
    #: The ``robust`` tracker's shared state (model, working images, uncertainty), long-lived.
    robust: RobustTarget | None = None

    _rng: np.random.Generator | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.clock = FrameClock(self.frame)

    @property
    def rng(self) -> np.random.Generator:
        """The run's random generator (particle filters), made from :attr:`seed` on first
        use: a run that draws nothing does not pay for importing NumPy's random module
        (~9 ms of start-up)."""
        if self._rng is None:
            self._rng = np.random.default_rng(self.seed)
        return self._rng

    def new_frame(self, frame: Frame) -> None:
        """Start ``frame``: reset the per-frame fields; ask the ``forecast`` for its prediction."""
        self.frame = frame
        if self.forecast is not None:
            self.prediction = self.forecast(frame)
        self.window = None
        self.feature = None
        self.feature_levels = 256
        self.feature_mask = None
        self.search_box = None
        self.likelihood = None
        self.feature_scale = 1.0
        self.measurement = None
        self.extras = {}
        self.tracks = []
        self.detections = []
        self.overlays = []

    @property
    def search_center(self) -> Box:
        """The box this frame's search is centred on: the prediction if any, else the last box."""
        assert self.box is not None or self.prediction is not None
        return self.prediction if self.prediction is not None else self.box  # type: ignore[return-value]


class Stage:
    """Base class; subclasses set the class attributes below and implement ``start``/``step``."""

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    params: ClassVar[tuple[Param, ...]] = ()
    requires: ClassVar[frozenset[str]] = frozenset()
    provides: ClassVar[frozenset[str]] = frozenset()
    columns: ClassVar[tuple[str, ...]] = ()
    #: True for stages that produce ``ctx.tracks`` (multi-target output: ``tracks.csv``).
    multi_target: ClassVar[bool] = False
    #: False when the stage can start without an initial box (detecting trackers, and stages
    #: that read ``ctx.box`` only if it is set). A chain needs one when any of its stages does.
    needs_init_box: ClassVar[bool] = True
    #: Parameters naming a file the stage reads (``mot_detections``' det.txt): a relative path
    #: is the folder's the run was requested in, and the file counts among a run's inputs.
    file_params: ClassVar[tuple[str, ...]] = ()
    #: What :meth:`values_problem` and :meth:`chain_problem` refuse beyond each parameter's own
    #: range, one rule a line as ``vtrack stages`` lists it (tests check a stage with either
    #: declares its rules).
    rules: ClassVar[tuple[str, ...]] = ()

    def __init__(self, **values: Any) -> None:
        """``values`` are validated (see :func:`build_stage`); missing ones take defaults."""
        for param in self.params:
            setattr(self, param.name, values.get(param.name, param.default))

    @classmethod
    def chain_problem(cls, values: dict[str, Any], before: list[str]) -> str | None:
        """Why this stage, with these explicitly set parameter ``values``, cannot come after the
        stages named in ``before`` beyond what ``requires`` says (None: it can)."""
        return None

    @classmethod
    def values_problem(cls, values: dict[str, Any]) -> str | None:
        """Why these values of every parameter (checked one by one, defaults for those not
        set) contradict each other, naming the parameters (None: they do not)."""
        return None

    def initial_box(self, ctx: TrackContext) -> Box:
        """The first frame's box this stage starts from; FirstFrameError naming the stage when there
        is none or it is not a finite box of positive size."""
        box = ctx.box
        if box is None or not box.is_valid():
            shown = box.text() if box is not None else None
            raise FirstFrameError(f"{self.name} needs a valid initial box, got {shown}")
        return box

    def settings(self) -> dict[str, Any]:
        return {p.name: getattr(self, p.name) for p in self.params}

    def start(self, ctx: TrackContext) -> None:
        """Called on the first frame. Default: same as ``step``."""
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        raise NotImplementedError

    def notes(self) -> list[str]:
        """What the stage warns of about the frames it has processed since ``start`` (one line
        each; a run prints them and records them in ``run.json``). Default: nothing."""
        return []

    def past_end_notes(self) -> list[str]:
        """What the stage warns of about what it was given against the input's whole length
        (rows of a file past the input's end, or a file ending well before it); a run asks only
        when it read its input to the end (complete, no ``--frames``). Default: nothing."""
        return []



_REGISTRY: dict[str, type[Stage]] = {}


def register(cls: type[Stage]) -> type[Stage]:
    """Class decorator: make a stage available to configs under ``cls.name``."""
    if not cls.name:
        raise TypeError(f"{cls.__qualname__} has no name")
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise TypeError(f"two stages are named {cls.name!r}")
    names = [p.name for p in cls.params]
    if len(names) != len(set(names)):
        raise TypeError(f"stage {cls.name!r} declares a parameter twice")
    _REGISTRY[cls.name] = cls
    return cls


def all_stages() -> dict[str, type[Stage]]:
    """Every registered stage by name (imports every module of ``vtrack.stages`` once)."""
    import vtrack.stages as package

    for module in pkgutil.iter_modules(package.__path__):
        importlib.import_module(f"{package.__name__}.{module.name}")
    return dict(sorted(_REGISTRY.items()))


def _find_stage(name: str) -> None:
    """Import modules of ``vtrack.stages`` until one registers ``name``: first the module named
    like the stage, then the others in order. A run imports only the stages of its chain (each
    module costs start-up time); :func:`all_stages` still imports every one."""
    import vtrack.stages as package

    modules = sorted(m.name for m in pkgutil.iter_modules(package.__path__))
    for module in sorted(modules, key=lambda m: m != name):  # stable: `name` first
        importlib.import_module(f"{package.__name__}.{module}")
        if name in _REGISTRY:
            return


def stage_class(name: str, where: str) -> type[Stage]:
    """The stage class registered as ``name``; a ConfigError listing every stage otherwise
    (ending with the near name, :func:`~vtrack.errors.did_you_mean`, for a near miss)."""
    if name not in _REGISTRY:
        _find_stage(name)
    if name not in _REGISTRY:
        known = all_stages()
        raise ConfigError(f"{where}: unknown stage {shown(name)} (known stages: "
                          f"{', '.join(known)}){did_you_mean(str(name), known)}")
    return _REGISTRY[name]


def build_stage(name: str, values: dict[str, Any], where: str) -> Stage:
    """Validate ``values`` against the stage's declaration and construct it."""
    return stage_class(name, where)(**checked_values(name, values, where))


def declared_param(where: str, name: str, key: object, declared: dict[str, Param]) -> Param:
    """Parameter ``key`` of stage ``name`` (``declared``: its parameters by name); ConfigError
    "WHERE: stage 'NAME': unknown parameter 'KEY' (parameters: ...)" with the near name for a
    near miss when the stage has none of that name."""
    if not isinstance(key, str) or key not in declared:
        known = ", ".join(declared) or "none"
        raise ConfigError(f"{where}: stage '{name}': unknown parameter {shown(key)} "
                          f"(parameters: {known}){did_you_mean(str(key), declared)}")
    return declared[key]


def checked_values(name: str, values: dict[str, Any], where: str) -> dict[str, Any]:
    """``values`` of stage ``name`` each as its parameter's type (:meth:`Param.validate`: a
    NumPy number as a Python one); ConfigError naming ``where``, the stage and the parameter
    for one the stage does not declare (with the near name for a near miss) or whose value it
    refuses, and the parameters of a pair that contradict each other
    (:meth:`Stage.values_problem`)."""
    cls = stage_class(name, where)
    declared = {p.name: p for p in cls.params}
    place = f"{where}: stage '{name}'"
    checked = {key: declared_param(where, name, key, declared).validate(value, place)
               for key, value in values.items()}
    problem = cls.values_problem({p.name: checked.get(p.name, p.default) for p in cls.params})
    if problem:
        raise ConfigError(f"{place}: {problem}")
    return checked
