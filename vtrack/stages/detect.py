"""Detection stages: foreground segmentation of the whole frame, then blobs as measurements.

Detecting trackers (S3, S4) look for targets everywhere, so these stages work on the whole grey
frame (free for yuv420p input: it is the Y plane), with OpenCV doing every per-pixel step.

- ``background`` (S4 sec. 1.1-1.2): background ``B`` = mean of the first ``frames`` frames,
  foreground ``|D - B| >= Th``; or OpenCV's MOG2 for scenes where a fixed mean background fails.
- ``threshold`` (S3 sec. 2.1): adaptive grey threshold fed back from the previous frame's
  candidates, then a median filter.
- ``blobs`` (S3 sec. 2.1, S4 sec. 1.2): connected components -> :class:`Detection` list in
  ``ctx.detections``.
- ``largest_blob`` (S4 sec. 1.2): the largest blob becomes ``ctx.measurement`` for a single-target
  Kalman filter.

The segmenting stages hand over ``ctx.window`` (the whole frame), ``ctx.feature`` (its grey
image) and ``ctx.likelihood`` (the foreground: 0 = background, anything else = foreground).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, Protocol, TypeVar

import cv2
import numpy as np

from vtrack.errors import ConfigError
from vtrack.geometry import MAX_FRAME_PIXELS, Box, Window
from vtrack.params import MAX_TRACK_ID, Param
from vtrack.stages.base import Stage, TrackContext, TrackState, TrackStatus, register

#: What a segmenting stage hands over: the whole frame's grey image (256 levels, every pixel
#: valid) and its foreground.
_SEGMENTS = frozenset({"window", "feature", "feature_levels", "feature_mask", "likelihood",
                       "feature_scale"})


def _whole_grey_frame(ctx: TrackContext, shrunk: np.ndarray | None = None,
                      k: int = 1) -> np.ndarray:
    """Set the whole frame's grey image as this frame's window and feature; return it.
    ``shrunk``: that image shrunk by the whole factor ``k`` (``ctx.feature_scale``)."""
    grey = ctx.frame.gray() if shrunk is None else shrunk
    ctx.window = ctx.frame.full_window()
    ctx.feature = grey
    ctx.feature_levels = 256
    ctx.feature_mask = None
    ctx.feature_scale = float(k)
    return grey


@dataclass(frozen=True)
class Detection:
    """One measurement of a detecting stage, as found in ``ctx.detections``.

    ``box`` is the bounding box (pixels), ``(cx, cy)`` the centroid (a blob's pixel centroid, a
    detector box's centre), ``area`` the pixel count (the box area for detector boxes), ``grey``
    the mean grey of the blob's pixels (NaN when unknown), ``score`` the detector's confidence
    (NaN for blobs) and ``colours`` the normalised colour histogram of its pixels (None until
    ``detection_colours`` gives one).
    """

    box: Box
    cx: float
    cy: float
    area: float
    grey: float = math.nan
    score: float = math.nan
    colours: np.ndarray | None = field(default=None, compare=False, repr=False)


def mask_window(box: Box, scale: float, shape: tuple[int, ...]) -> Window:
    """The pixels of a foreground of ``shape`` (``scale`` frame pixels per pixel, as
    ``ctx.feature_scale`` says) that cover ``box`` (frame pixels); empty when none do."""
    x0, y0 = max(0, math.floor(box.x / scale)), max(0, math.floor(box.y / scale))
    x1 = min(shape[1], math.ceil((box.x + box.w) / scale))
    y1 = min(shape[0], math.ceil((box.y + box.h) / scale))
    return Window(x0, y0, x1, y1)


def foreground_under(box: Box, mask: np.ndarray, scale: float) -> tuple[Window, np.ndarray]:
    """The pixels of ``mask`` (a foreground, ``scale`` frame pixels per pixel) that cover
    ``box`` (:func:`mask_window`) and which of them are foreground (a bool array, empty when
    none cover it)."""
    covered = mask_window(box, scale, mask.shape)
    return covered, mask[covered.slices] > 0


def track_state(confirmed: bool, updated: bool) -> TrackStatus:
    """``confirmed`` (confirmed and measured this frame), ``coasting`` (confirmed, predicted
    only) or ``tentative`` (not confirmed yet)."""
    if not confirmed:
        return TrackStatus.TENTATIVE
    return TrackStatus.CONFIRMED if updated else TrackStatus.COASTING


class TrackIds:
    """The ids a multi-target stage gives the tracks it creates, in order, none twice: the
    run's first track id (:attr:`TrackContext.first_track_id`, 1 unless the run says
    otherwise), then each one more, up to :data:`~vtrack.params.MAX_TRACK_ID` (2**53: ids
    past it, read as doubles by MATLAB, pandas or JavaScript, would be read as another's).
    ``next()`` of a track that would need an id past it is a ConfigError naming the first id
    and the frame (0-based, as the run counts them, and tracks.csv's 1-based number; the run
    stops there, its records whole), never an id numbered past it;
    every later ``next()`` raises the same, at its own frame (never StopIteration)."""

    def __init__(self, ctx: TrackContext) -> None:
        self._ctx = ctx
        self._next = ctx.first_track_id

    def __next__(self) -> int:
        if self._next > MAX_TRACK_ID:
            raise ConfigError(
                f"the track ids from {self._ctx.first_track_id} are used up at frame "
                f"{self._ctx.frame.index} (frame {self._ctx.frame.index + 1} counted from 1, as "
                "tracks.csv and MOTChallenge number them): "
                f"a new track would be numbered past {MAX_TRACK_ID} "
                "(2^53, the largest id a double holds exactly: MATLAB, pandas and JavaScript "
                "would read it as another's); number the tracks from a smaller first id "
                "(--first-id N, first_track_id=N)")
        self._next += 1
        return self._next - 1


class _Coasting(Protocol):
    misses: int  # frames in a row without a measurement


_T = TypeVar("_T", bound=_Coasting)


def fewest_misses(tracks: list[_T], limit: int) -> list[_T]:
    """``tracks`` (each with an int ``misses``: frames in a row unmeasured) cut to at most
    ``limit``, those coasting longest dropped first; the kept ones in their order, ties kept
    by it (a multi-target stage's cap on its tracks, bounding a frame's work and memory)."""
    if len(tracks) <= limit:
        return tracks
    kept = {id(t) for t in sorted(tracks, key=lambda t: t.misses)[:limit]}
    return [t for t in tracks if id(t) in kept]


def centroids(detections: list[Detection]) -> np.ndarray:
    """The detections' centroids as an ``(M, 2)`` float array."""
    return np.array([(d.cx, d.cy) for d in detections], float).reshape(-1, 2)


def pairwise_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Euclidean distances between the points of ``a`` (N, 2) and ``b`` (M, 2): (N, M)."""
    return np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])


#: Largest morphology kernel applied at the working size (its cost grows with its area: 31 is
#: ~30 ms a frame at 1280x720); a larger one is applied to the mask shrunk by the factor that
#: brings it to this size, and the result enlarged again (blocky edges, bounded cost).
MAX_KERNEL = 31
#: Pixels MOG2/KNN work on at most, whatever ``max_pixels`` says (a quarter of a 1080p frame,
#: 960x540): their cost per pixel (several times the mean model's) must keep a frame's work
#: bounded (issue 21: no declared value over 10x the default's work).
ADAPTIVE_MAX_PIXELS = 1920 * 1080 // 4
#: ``gain`` starts once the model has learnt the scene's light: at the first frame its background
#: is not darker than by more than this share (the frame after the first, unless the scene grew
#: brighter between the two; after black first frames or a fade from black, once the model has
#: caught up with the lit scene). A scene that grows darker is no background still being learnt:
#: the gain undoes it at once.
GAIN_START = 0.05


def cleaning_steps(opening: float, closing: float, shrink: int) -> list[tuple[int, int, int]]:
    """The opening and the closing (sizes in frame pixels) on a mask of 1/``shrink`` of the
    frame's side, as (OpenCV operation, kernel side, factor): the kernel runs on the mask shrunk
    by ``factor`` so that it is at most ``MAX_KERNEL`` pixels; a size of one pixel or less is
    no step."""
    steps = []
    for operation, size in ((cv2.MORPH_OPEN, opening), (cv2.MORPH_CLOSE, closing)):
        k = max(1, round(size / shrink))  # in working pixels
        if k > 1:
            factor = -(-k // MAX_KERNEL)
            steps.append((operation, k // factor, factor))
    return steps


@functools.lru_cache(maxsize=64)
def _ellipse(size: int) -> np.ndarray:
    """OpenCV's elliptic structuring element of ``size`` x ``size`` pixels (made once)."""
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))


def _morphology(mask: np.ndarray, operation: int, kernel: np.ndarray,
                factor: int) -> np.ndarray:
    """``cv2.morphologyEx`` of a 0/255 mask, on the mask shrunk by ``factor`` when it is > 1
    (a pixel of the shrunk mask is set when at least half of its block is)."""
    if factor == 1:
        return cv2.morphologyEx(mask, operation, kernel)
    height, width = mask.shape
    small = cv2.resize(mask, (max(1, width // factor), max(1, height // factor)),
                       interpolation=cv2.INTER_AREA)
    small = cv2.threshold(small, 127, 255, cv2.THRESH_BINARY)[1]
    small = cv2.morphologyEx(small, operation, kernel)
    return cv2.resize(small, (width, height), interpolation=cv2.INTER_NEAREST)


def _median_grey(image: np.ndarray) -> float:
    """The median grey level of a uint8 grey or BGR image (from its 256-bin histogram)."""
    grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    counts = np.cumsum(cv2.calcHist([grey], [0], None, [256], [0, 256]).ravel())
    return float(np.searchsorted(counts, counts[-1] / 2))


def _foreground_at_least(image: np.ndarray, level: float) -> np.ndarray:
    """255 where the uint8 ``image`` is >= ``level``, else 0 (one OpenCV pass)."""
    return cv2.threshold(image, math.ceil(level) - 1, 255, cv2.THRESH_BINARY)[1]


@register
class Background(Stage):
    """S4 background subtraction: ``B`` = mean of the first frames, foreground ``|D - B| >= Th``;
    or an adaptive model (MOG2, KNN) for real scenes.

    ``method = "mean"`` is the document's: the first ``frames`` frames are averaged into ``B``
    (S4 eq. 1, kept as grey levels 0..255) and **nothing is detected during those frames**; from
    frame ``frames`` on (0-based), a pixel is foreground when ``|D - B| >= threshold`` (S4 eq. 2).
    ``B`` is never updated: it suits a static camera and constant lighting, as the document says;
    a target present during the first frames leaves a ghost in ``B`` where it was, which is
    detected for the rest of the run unless the target moved fast.

    The binary foreground can then be cleaned, S4's "simple processing" (section 1.2): an
    opening with an ``open`` x ``open`` ellipse removes specks, a closing with a ``close`` x
    ``close`` ellipse joins the fragments of one target (both off by default). Sizes in frame
    pixels suit targets of one size only: with ``open_share`` / ``close_share``, once the
    multi-target tracker after this stage has measured its confirmed targets
    (``ctx.target_shape``, from the previous frame; ``byte_tracks`` gives it), each size is that
    share of the targets' usual width, mixed with the given size as ``group_blobs`` mixes the
    aspect (the given one weighs :data:`vtrack.stages.base.PRIOR_SAMPLES` measured boxes).

    ``method = "mog2"`` uses OpenCV's adaptive Gaussian-mixture background (Zivkovic 2004),
    ``method = "knn"`` its K-nearest-neighbours one (Zivkovic & van der Heijden 2006): they learn
    continuously over ``history`` frames, so they follow lighting changes and absorb ghosts and
    objects that stop; they detect from the second frame on (on the first, everything is new).
    ``shadows`` turns on their shadow test (a pixel darker than the background by a ratio
    between ``shadow_ratio`` and 1, with its colour kept, is a shadow) and removes the shadows
    from the foreground; ``colour`` models the BGR image instead of the grey one (the shadow
    test then also checks the colour).

    ``gain`` (MOG2, KNN) undoes a global change of exposure or light before the model sees the
    frame: the frame is scaled by the ratio of the model's background image's median grey level
    to its own (medians, so targets covering less than half the frame do not move them). The
    pixel models alone call every pixel foreground when a camera's exposure or a cloud changes
    the whole scene's brightness faster than they learn (Toyama et al., Wallflower, ICCV 1999,
    add a frame level to pixel-level background models for such global changes). It starts once
    the model has learnt the scene's light (:data:`GAIN_START`): the model learns the frames as
    scaled, so frames scaled to a background learnt from black first frames would stay as dark.

    ``max_pixels`` (0: off; MOG2 and KNN at most ``ADAPTIVE_MAX_PIXELS`` in any case) makes the
    foreground at a reduced resolution: the frame is halved
    (each pixel the mean of a 2 x 2 block; halving is ~20x cheaper than any other shrink) until
    at most that many pixels are left, ``k`` times in each direction, and
    ``likelihood``/``feature`` are that reduced image (``ctx.feature_scale = k`` frame pixels
    per pixel; ``blobs`` maps back). The morphology sizes stay in frame pixels.

    Every frame gets a foreground ``ctx.likelihood``: while nothing can be detected (the mean's
    learning frames, the adaptive models' first frame) it is empty (all 0).
    """

    name = "background"
    summary = "S4 background subtraction (mean of the first frames, or MOG2/KNN) -> foreground"
    params = (
        Param(
            "method",
            str,
            "mean",
            "mean: S4's fixed background, mean of the first `frames` frames (no detection "
            "during them); mog2, knn: OpenCV's adaptive models, for changing backgrounds",
            choices=("mean", "mog2", "knn"),
        ),
        Param(
            "frames",
            int,
            30,
            "mean: frames averaged into the background (S4 eq. 1, N not given: 30, so that a "
            "target moving during them leaves only a faint ghost)",
            min=1, max=1000,
        ),
        Param(
            "threshold",
            float,
            25.0,
            "mean: a pixel is foreground when |frame - background| >= this, in grey levels "
            "(S4 eq. 2, Th not given: 25)",
            min=1.0,
            max=255.0,
        ),
        Param(
            "open",
            int,
            1,
            "size in frame pixels of a morphological opening of the foreground, removing "
            "specks (S4 sec. 1.2 'after simple processing'; 1 = none; above 31 working pixels it "
            "is applied to a shrunk mask, bounding its cost)",
            min=1, max=255,
        ),
        Param(
            "close",
            int,
            1,
            "size in frame pixels of a morphological closing after the opening, joining the "
            "fragments of one target (S4 sec. 1.2 'after simple processing'; 1 = none; above 31 "
            "working pixels applied to a shrunk mask)",
            min=1, max=255,
        ),
        Param(
            "open_share",
            float,
            0.0,
            "learn the opening from the scene's targets: once a multi-target tracker has "
            "measured its confirmed targets (ctx.target_shape, as group_blobs learns their "
            "aspect), the opening is this share of their usual width, mixed with `open` by "
            "the boxes measured (0: `open` always)",
            min=0.0, max=2.0,
        ),
        Param(
            "close_share",
            float,
            0.0,
            "the closing likewise: this share of the targets' usual width, mixed with `close` "
            "(0: `close` always)",
            min=0.0, max=2.0,
        ),
        Param(
            "history",
            int,
            500,
            "mog2, knn: frames the model remembers (OpenCV's default 500)",
            min=1, max=100000,
        ),
        Param(
            "var_threshold",
            float,
            16.0,
            "mog2: squared Mahalanobis distance to call a pixel foreground (OpenCV's default 16)",
            min=0.0, max=10000.0,
        ),
        Param(
            "background_ratio",
            float,
            0.9,
            "mog2: the background is the most frequent colours of a pixel making up this share "
            "of its history (OpenCV's default 0.9); lower: a target that stays over a pixel for "
            "more than 1 minus this of the history still is not learnt as background",
            min=0.01, max=1.0,
        ),
        Param(
            "dist2_threshold",
            float,
            400.0,
            "knn: squared distance to the nearest samples to call a pixel foreground (OpenCV's "
            "default 400)",
            min=0.0, max=1e6,
        ),
        Param(
            "shadows",
            bool,
            False,
            "mog2, knn: detect shadows (darker, same colour) and remove them from the foreground",
        ),
        Param(
            "shadow_ratio",
            float,
            0.5,
            "mog2, knn: a pixel is a shadow when it is between this share of the background's "
            "brightness and the background's (OpenCV's tau, default 0.5; higher: only light "
            "shadows, so dark clothes on a light ground stay foreground)",
            min=0.0, max=1.0,
        ),
        Param(
            "colour",
            bool,
            False,
            "mog2, knn: model the colour image, not the grey one (a colour input only)",
        ),
        Param(
            "gain",
            bool,
            False,
            "mog2, knn: scale each frame by the ratio of the background's median grey level to "
            "its own first, so a global change of exposure or light is not foreground; from the "
            f"first frame whose background is at most {GAIN_START:.0%} darker on (after black "
            "first frames or a fade from black, once the model has learnt the lit scene)",
        ),
        Param(
            "max_pixels",
            int,
            0,
            "make the foreground on the frame halved until at most this many pixels are left "
            "(0: full resolution); cost falls with it, targets must stay several pixels "
            f"across. mog2 and knn work on at most {ADAPTIVE_MAX_PIXELS:,} pixels whatever "
            "this says (a quarter of 1080p: their cost per pixel bounds a frame's work)",
            min=0, max=MAX_FRAME_PIXELS,
        ),
    )
    provides = _SEGMENTS
    needs_init_box = False

    def start(self, ctx: TrackContext) -> None:
        """Forget any previous run and start learning the background from this frame."""
        self._sum: np.ndarray | None = None
        self._seen = 0
        self._background: np.ndarray | None = None
        self._model: cv2.BackgroundSubtractor | None = None
        self._gain_started = False
        frame = ctx.frame
        pixels = frame.width * frame.height
        budget = self.max_pixels
        if self.method != "mean":  # the adaptive models cost several times the mean's per pixel
            budget = min(budget or ADAPTIVE_MAX_PIXELS, ADAPTIVE_MAX_PIXELS)
        self._shrink = 1  # halved until at most the budget is left (and at least 2 x 2)
        while (budget and pixels > budget * self._shrink ** 2
               and min(frame.width, frame.height) >= 4 * self._shrink):
            self._shrink *= 2
        if self.method == "mean":
            self.step(ctx)
            return
        if self.method == "mog2":
            model = cv2.createBackgroundSubtractorMOG2(
                history=self.history, varThreshold=self.var_threshold,
                detectShadows=self.shadows)
        else:
            model = cv2.createBackgroundSubtractorKNN(
                history=self.history, dist2Threshold=self.dist2_threshold,
                detectShadows=self.shadows)
        model.setShadowThreshold(self.shadow_ratio)
        if self.method == "mog2":
            model.setBackgroundRatio(self.background_ratio)
        self._model = model
        grey, image = self._images(ctx)
        model.apply(image)  # the first frame only starts the model
        ctx.likelihood = np.zeros_like(grey)  # nothing detected yet

    def step(self, ctx: TrackContext) -> None:
        grey, image = self._images(ctx)
        if self._model is not None:
            if self.gain:
                image = self._gain_compensated(image)
            mask = self._model.apply(image)
            if self.shadows:  # shadows are 127, the foreground 255
                mask = cv2.threshold(mask, 127, 255, cv2.THRESH_BINARY)[1]
        elif self._background is None:
            self._learn(grey)
            ctx.likelihood = np.zeros_like(grey)  # nothing detected while learning
            return
        else:
            difference = cv2.absdiff(grey, self._background)
            mask = _foreground_at_least(difference, self.threshold)  # S4 eq. 2
        opening, closing = float(self.open), float(self.close)
        learnt = ctx.target_shape
        if learnt is not None:  # TargetShape.mixed gives the given size until boxes are measured
            if self.open_share:
                opening = learnt.mixed(opening, self.open_share * learnt.width)
            if self.close_share:
                closing = learnt.mixed(closing, self.close_share * learnt.width)
        for operation, size, factor in cleaning_steps(opening, closing, self._shrink):
            mask = _morphology(mask, operation, _ellipse(size), factor)
        ctx.likelihood = mask

    def _images(self, ctx: TrackContext) -> tuple[np.ndarray, np.ndarray]:
        """This frame's grey image (also set as ``ctx.feature``) and the image the model
        learns (the grey one, or BGR with ``colour``), both at the working size."""
        frame, k = ctx.frame, self._shrink
        in_colour = self.colour and self.method != "mean"
        if k == 1:
            grey = _whole_grey_frame(ctx)
            colour = frame.bgr() if in_colour else None
        else:
            colour = frame.bgr_shrunk(k) if in_colour else None
            grey = (cv2.cvtColor(colour, cv2.COLOR_BGR2GRAY) if colour is not None
                    else frame.gray_shrunk(k))
            _whole_grey_frame(ctx, grey, k)
        return grey, grey if colour is None else colour

    def _gain_compensated(self, image: np.ndarray) -> np.ndarray:
        """``image`` scaled (saturating at 255) so that its median grey level is the
        background's; unchanged within half a percent, and until the model has learnt the
        scene's light: until, for the first time, its background's median is at most
        :data:`GAIN_START` darker than a frame's (KNN's background is black for its first
        frames; after black first frames or a fade from black, MOG2's is darker than the
        scene). Scaled to a background learnt from them, every later frame would be as dark,
        for good: the model learns the scaled frames."""
        assert self._model is not None
        background = _median_grey(self._model.getBackgroundImage())
        ratio = background / max(_median_grey(image), 1.0)
        if not self._gain_started:
            if ratio < 1.0 - GAIN_START:  # a background darker than the scene: still learning
                return image
            self._gain_started = True
        if background < 1.0 or abs(ratio - 1.0) < 0.005:
            return image
        return cv2.convertScaleAbs(image, alpha=ratio)

    def _learn(self, grey: np.ndarray) -> None:
        """Add one frame to the mean background (S4 eq. 1); finish it after ``frames`` frames."""
        if self._sum is None:
            self._sum = np.zeros(grey.shape, np.float64)
        cv2.accumulate(grey, self._sum)
        self._seen += 1
        if self._seen == self.frames:
            self._background = np.clip(np.rint(self._sum / self.frames), 0, 255).astype(np.uint8)
            self._sum = None


@register
class AdaptiveThreshold(Stage):
    """S3 adaptive segmentation + median filter.

    The threshold for frame k+1 is the mean grey of the candidates ``blobs`` found in frame k
    minus ``offset`` (S3 sec. 2.1; on the first frame, and after a frame without candidates, it is
    ``initial``, and it never goes below ``floor``). Pixels below it become 0, the others keep
    their grey; a ``median`` x ``median`` median filter then removes the fragments the
    segmentation leaves around targets (S3 sec. 2.1, Fig. 2c).
    """

    name = "threshold"
    summary = "S3 adaptive grey threshold from the last frame's candidates + median filter"
    params = (
        Param(
            "offset",
            float,
            60.0,
            "threshold = mean grey of the last frame's candidates minus this (S3 section 2.1, "
            "value not given: 60 grey levels)",
            min=0.0,
            max=255.0,
        ),
        Param(
            "initial",
            float,
            100.0,
            "threshold when there are no candidates to learn from (first frame, or none found; "
            "not given by S3: 100)",
            min=1.0,
            max=255.0,
        ),
        Param(
            "floor",
            float,
            40.0,
            "lowest threshold the feedback may reach, so dim clutter cannot pull it into the "
            "noise (not in S3: 40)",
            min=1.0,
            max=255.0,
        ),
        Param(
            "median",
            int,
            3,
            "median filter kernel size in pixels (S3 section 2.1 'median filter', size not "
            "given: 3; 1 = off)",
            choices=(1, 3, 5, 7),
        ),
    )
    provides = _SEGMENTS
    needs_init_box = False

    def step(self, ctx: TrackContext) -> None:
        grey = _whole_grey_frame(ctx)
        level = self.threshold(ctx.candidate_grey)
        # S3 section 2.1: below the threshold -> 0, the rest keeps its grey.
        kept = cv2.threshold(grey, math.ceil(level) - 1, 0, cv2.THRESH_TOZERO)[1]
        ctx.likelihood = kept if self.median == 1 else cv2.medianBlur(kept, self.median)

    def threshold(self, candidate_grey: float | None) -> float:
        """This frame's threshold from the last frame's mean candidate grey (None: none)."""
        if candidate_grey is None:
            return self.initial
        return max(candidate_grey - self.offset, self.floor)


#: Side in pixels of the tiles of the coarse pass that finds where the foreground is.
_TILE = 16
_TILE_KERNEL = cv2.getStructuringElement(cv2.MORPH_RECT, (_TILE, _TILE))
#: With more separate foreground regions than this, the whole frame is labelled at once.
_MAX_REGIONS = 256


def foreground_regions(mask: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
    """Parts of ``mask`` (non-zero = foreground) that hold all its foreground: ``(x, y, part)``
    with ``part`` the sub-image whose top-left pixel is ``(x, y)``.

    Labelling connected components costs a pass over every pixel with a label image as large as
    the frame (~10 ms at 1080p), while targets cover a tiny part of it. So the mask is first
    reduced to ``_TILE`` x ``_TILE`` tiles (a tile is set when any of its pixels is); connected
    tiles form a region, cut from the mask as its tiles' bounding box, with other regions' tiles
    inside that box cleared. Two 8-adjacent foreground pixels lie in the same or 8-adjacent set
    tiles, so every connected component of the mask lies whole in exactly one part. A mask
    without foreground has no part; one with more than ``_MAX_REGIONS`` regions (dense clutter)
    is returned whole.
    """
    tiles = (cv2.dilate(mask, _TILE_KERNEL, anchor=(0, 0))[::_TILE, ::_TILE] > 0).view(np.uint8)
    count, regions, stats, _ = cv2.connectedComponentsWithStats(tiles, connectivity=8)
    if count - 1 > _MAX_REGIONS:
        return [(0, 0, mask)]
    parts = []
    for region in range(1, count):
        tx, ty, tw, th = (int(v) for v in stats[region, :4])
        x, y = tx * _TILE, ty * _TILE
        part = mask[y : (ty + th) * _TILE, x : (tx + tw) * _TILE]
        owners = regions[ty : ty + th, tx : tx + tw]
        if (owners[owners != 0] != region).any():  # another region's tiles inside the box
            own = np.repeat(np.repeat(owners == region, _TILE, axis=0), _TILE, axis=1)
            part = np.where(own[: part.shape[0], : part.shape[1]], part, 0).astype(np.uint8)
        parts.append((x, y, part))
    return parts


@register
class Blobs(Stage):
    """Connected foreground regions -> :class:`Detection` (centroid, box, area, mean grey).

    8-connected components of ``ctx.likelihood`` (non-zero = foreground) with ``min_area`` <=
    area <= ``max_area`` pixels (with ``min_area_share``, a smaller least area once a
    multi-target tracker after this stage has measured targets so small that ``min_area``
    would drop them whole: the noise floor follows the targets down, never up, since fragments
    of large targets must reach ``group_blobs``); at most ``max_blobs`` of them, the largest, so
    a cluttered frame costs a bounded amount downstream. Only the parts of the frame that hold
    foreground are labelled (see :func:`foreground_regions`). A foreground made at a reduced
    resolution (``ctx.feature_scale`` > 1) is mapped back: boxes, centroids and areas are in
    frame pixels. Publishes the candidates' mean grey for ``threshold``'s next frame (S3 sec.
    2.1). Detections are ordered by their box's top edge, then its left edge.
    """

    name = "blobs"
    summary = "connected components of the foreground -> detections (centroid, box, area, grey)"
    params = (
        Param("min_area", int, 4, "smallest blob kept, in pixels (smaller: noise)",
              min=1, max=MAX_FRAME_PIXELS),
        Param("min_area_share", float, 0.0,
              "lower the smallest blob for small targets: once a multi-target tracker has "
              "measured its confirmed targets (ctx.target_shape), a blob of this share of their "
              "usual box area (mixed with `min_area` by the boxes measured) is kept even when "
              "under `min_area` (0: `min_area` always)", min=0.0, max=1.0),
        Param("max_area", int, 0, "largest blob kept, in pixels (0: no limit)",
              min=0, max=MAX_FRAME_PIXELS),
        Param(
            "max_blobs",
            int,
            100,
            "at most this many blobs per frame, the largest (bounds the trackers' work)",
            min=1, max=1000,
        ),
    )
    requires = _SEGMENTS
    provides = frozenset({"detections", "candidate_grey"})
    needs_init_box = False
    rules = ("min_area <= max_area when max_area is set (not 0)",)

    @classmethod
    def values_problem(cls, values: dict[str, Any]) -> str | None:
        """A least blob larger than the largest (``max_area`` set): no blob could be kept."""
        least, most = values["min_area"], values["max_area"]
        if most and least > most:
            return (f"min_area ({least}) is larger than max_area ({most}): no blob would be "
                    "kept; lower min_area, or raise max_area (0: no limit)")
        return None

    def step(self, ctx: TrackContext) -> None:
        ctx.candidate_grey = None
        assert ctx.likelihood is not None and ctx.window is not None and ctx.feature is not None
        found = []  # (area, part's x, part's y, part's labels, label, stats row, centroid)
        scale = ctx.feature_scale
        pixel_area = scale * scale
        least = float(self.min_area)
        learnt = ctx.target_shape
        if self.min_area_share and learnt is not None:
            least = min(least, learnt.mixed(least, self.min_area_share * learnt.area))
        for px, py, part in foreground_regions(ctx.likelihood):
            count, labels, stats, centres = cv2.connectedComponentsWithStats(
                part, connectivity=8, ltype=cv2.CV_32S
            )
            areas = stats[1:count, cv2.CC_STAT_AREA] * pixel_area
            keep = areas >= least
            if self.max_area:
                keep &= areas <= self.max_area
            for label in np.flatnonzero(keep) + 1:
                found.append((float(areas[label - 1]), px, py, labels, label, stats[label],
                              centres[label]))
        if len(found) > self.max_blobs:
            found = sorted(found, key=lambda f: -f[0])[: self.max_blobs]
        x0, y0 = ctx.window.x0, ctx.window.y0
        blobs = []
        for area, px, py, labels, label, (x, y, w, h, _), (cx, cy) in found:
            inside = labels[y : y + h, x : x + w] == label
            grey = ctx.feature[py + y : py + y + h, px + x : px + x + w][inside].mean()
            if scale != 1.0:  # pixel j of the reduced image covers [j s, (j + 1) s)
                box = Box((px + x) * scale + x0, (py + y) * scale + y0, w * scale, h * scale)
                cx, cy = (px + cx + 0.5) * scale - 0.5, (py + cy + 0.5) * scale - 0.5
            else:
                box = Box(float(px + x + x0), float(py + y + y0), float(w), float(h))
                cx, cy = px + cx, py + cy
            blobs.append(Detection(box, float(cx + x0), float(cy + y0), area, float(grey)))
        blobs.sort(key=lambda d: (d.box.y, d.box.x))
        ctx.detections.extend(blobs)
        ctx.detections.sort(key=lambda d: (d.box.y, d.box.x))
        if blobs:  # S3 sec. 2.1: the mean grey of this stage's own candidates
            ctx.candidate_grey = float(np.mean([d.grey for d in blobs]))


@register
class LargestBlob(Stage):
    """S4 sec. 1.2: the largest detection is this frame's measurement of the single target.

    ``ctx.measurement`` is its bounding box centred on its centroid (S4: 'the centre and size of
    the detected target'), and the state is ``tracking``. When nothing was detected the
    measurement is None (a Kalman stage coasts) and the state is ``occluded`` once a target has
    been seen (``ctx.box`` set), ``lost`` before (no box is output, e.g. while ``background``
    learns).
    """

    name = "largest_blob"
    summary = "the largest detection becomes the single-target measurement (S4)"
    requires = frozenset({"detections"})
    provides = frozenset({"measurement", "state"})
    needs_init_box = False

    def step(self, ctx: TrackContext) -> None:
        if ctx.detections:
            best = max(ctx.detections, key=lambda d: d.area)
            ctx.measurement = best.box.moved_to(best.cx, best.cy)
            ctx.state = TrackState.TRACKING
        else:
            ctx.state = TrackState.LOST if ctx.box is None else TrackState.OCCLUDED
