"""The stage contract: what a stage declares, what it shares with the others, how it is found.

A stage is a small object that does one job per frame. Stages do not call each other: they read
and write fields of one shared :class:`TrackContext`, in the order the config lists them. Each
stage class declares, once:

- ``name``: the key used in configs (``[[stage]] name = "meanshift"``) and ``--set name.param=``;
- ``summary``: one line for ``vtrack stages``;
- ``params``: its :class:`~vtrack.params.Param` declarations (validation, CLI, docs);
- ``requires`` / ``provides``: context fields it reads / writes, so an impossible chain (a stage
  before the one that produces its input) is rejected when the config is loaded;
- ``columns``: extra ``track.csv`` columns it fills through ``ctx.extras``.

Lifecycle: ``start(ctx)`` once on the first frame (``ctx.box`` holds the initial box, may be None
for detecting trackers), then ``step(ctx)`` on every later frame. The first frame's output is the
initial box; later frames' output is ``ctx.box`` / ``ctx.state`` / ``ctx.score`` after the
last stage.
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from vtrack.errors import ConfigError
from vtrack.frame import Frame
from vtrack.geometry import Box, Window
from vtrack.params import Param

if TYPE_CHECKING:
    from vtrack.stages.robust_model import RobustTarget

TRACKING, OCCLUDED, LOST = "tracking", "occluded", "lost"
STATES = (TRACKING, OCCLUDED, LOST)

#: Context fields the pipeline itself provides before the first stage runs.
PIPELINE_PROVIDES = frozenset({"frame", "box", "prediction", "state", "rng"})


@dataclass
class Track:
    """One target of a multi-target tracker, as written to ``tracks.csv`` (ids start at 1)."""

    id: int
    box: Box
    confidence: float
    state: str  # "tentative" | "confirmed" | "coasting" ...; only confirmed tracks are drawn


@dataclass
class TrackContext:
    """Per-run state shared by the stages; per-frame fields are reset by ``new_frame``."""

    frame: Frame
    rng: np.random.Generator
    #: Current estimate of the target box (single-target). The pipeline's output for the frame.
    box: Box | None = None
    #: Where this frame's search starts: set by a predictor on the previous frame (None: use box).
    prediction: Box | None = None
    #: tracking | occluded | lost.
    state: str = TRACKING
    #: Tracker-specific quality of this frame's estimate (similarity, weight, bp mass ...).
    score: float = float("nan")
    #: Multiplier on the search window, raised by occlusion/lost logic while the target is away.
    search_growth: float = 1.0
    # --- per frame, reset by new_frame -------------------------------------------------------
    #: Search window of this frame (integer pixels inside the frame).
    window: Window | None = None
    #: Feature image of ``window`` (hue 0..255, quantised grey ...), same shape as the window.
    feature: np.ndarray | None = None
    #: Target likelihood of ``window`` (back-projection, 0..255 uint8 or float weights).
    likelihood: np.ndarray | None = None
    #: This frame's measurement of the target (None: nothing to feed the filter).
    measurement: Box | None = None
    #: Values of the stage-declared extra CSV columns for this frame.
    extras: dict[str, Any] = field(default_factory=dict)
    #: Multi-target output of this frame.
    tracks: list[Track] = field(default_factory=list)
    #: Measurements from detection stages (multi-target): boxes with extra attributes.
    detections: list[Any] = field(default_factory=list)
    #: Extra things to draw (e.g. particles): list of (kind, payload) for the annotator.
    overlays: list[tuple[str, Any]] = field(default_factory=list)
    #: Shared long-lived values stages publish for later stages (target model, initial mass ...).
    memory: dict[str, Any] = field(default_factory=dict)
    #: The ``robust`` tracker's shared state (model, working images, uncertainty), long-lived.
    robust: RobustTarget | None = None

    def new_frame(self, frame: Frame) -> None:
        self.frame = frame
        self.window = None
        self.feature = None
        self.likelihood = None
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
    #: True when the chain can start without an initial box (detecting trackers).
    needs_init_box: ClassVar[bool] = True

    def __init__(self, **values: Any) -> None:
        """``values`` are validated (see :func:`build_stage`); missing ones take defaults."""
        for param in self.params:
            setattr(self, param.name, values.get(param.name, param.default))

    def settings(self) -> dict[str, Any]:
        return {p.name: getattr(self, p.name) for p in self.params}

    def start(self, ctx: TrackContext) -> None:
        """Called on the first frame. Default: same as ``step``."""
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        raise NotImplementedError

    def prepare(self, ctx: TrackContext) -> None:
        """Called on every frame after the first, before any stage's ``step``, once the new
        frame is in ``ctx.frame``: a stage whose output for this frame depends on the frame's
        timestamp (a predictor) can revise it here. Default: nothing."""


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


def stage_class(name: str, where: str) -> type[Stage]:
    stages = all_stages()
    if name not in stages:
        raise ConfigError(
            f"{where}: unknown stage {name!r} (known stages: {', '.join(stages)})"
        )
    return stages[name]


def build_stage(name: str, values: dict[str, Any], where: str) -> Stage:
    """Validate ``values`` against the stage's declaration and construct it."""
    cls = stage_class(name, where)
    declared = {p.name: p for p in cls.params}
    where = f"{where}: stage '{name}'"
    checked = {}
    for key, value in values.items():
        if key not in declared:
            known = ", ".join(declared) or "none"
            raise ConfigError(f"{where}: unknown parameter {key!r} (parameters: {known})")
        checked[key] = declared[key].validate(value, where)
    return cls(**checked)
