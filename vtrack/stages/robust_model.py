"""The ``robust`` tracker's appearance: what the target looks like, cut out at a fixed size.

First link of the ``robust`` chain (colour conversion -> likelihood -> search -> Kalman ->
occlusion logic). The target is seen through a search region of the box plus ``padding`` of its
mean side on every side (Staple: ``bg_area = target + (w + h) / 2``, padding 1; the config
``robust`` uses KCF's 1.5), resampled to a patch of
about ``working_area`` pixels (Staple's fixed area, 150^2), so the cost per frame does not
depend on the frame's or the target's size. On that patch:

- the texture features of a correlation filter: Felzenszwalb's fHOG (31 channels on
  ``cell``-pixel cells, :mod:`vtrack.features.fhog`) plus the cell's mean grey level, as Staple
  and ECO-HC use; the filter itself is :class:`vtrack.features.dcf.CorrelationFilter` (DSST
  eqs. 4-6) with a cosine window and a Gaussian label of ``sqrt(w h) / 16`` (KCF/Staple);
- the colour likelihood of every pixel against the surroundings (Staple's histograms,
  :mod:`vtrack.features.colour`): ``ctx.likelihood``.

While the target is lost it cuts more regions for the same filter to score: a growing ring of
them around the search centre, and (``filter_redetect``) one where the merged response over the
whole frame (the filter's, scored at once in the Fourier domain at the filter's working scale,
with the colour response, Staple's merge) peaks; that one also on a frame after one whose
colours were not the target's (``robust_failure.redetect_on_colour``).

It holds the learnt models for the other links (``ctx.robust``, :class:`RobustTarget`); it
learns nothing after the first frame itself: ``robust_failure`` decides when the models learn.

Pipeline contract of stage ``robust_model``: reads ``ctx.frame``, ``ctx.box`` (or, after a frame
whose reported box was the motion model's extrapolation, ``ctx.robust``'s peak there),
``ctx.state``, ``ctx.prediction`` (the search centre while the target is lost),
``ctx.search_growth``;
writes ``ctx.robust``, ``ctx.window`` (the region's part inside the frame), ``ctx.likelihood``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from vtrack.errors import FirstFrameError
from vtrack.features.colour import ColourHistograms, cell_response
from vtrack.features.dcf import CorrelationFilter, gaussian_label, hann2d, shift_spectrum
from vtrack.features.fhog import fhog
from vtrack.features.patch import ConvertedWindow, region_patch
from vtrack.features.scale import ScaleFilter
from vtrack.frame import Frame
from vtrack.geometry import Box, Window
from vtrack.overlays import SearchWindow
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, TrackState, register

#: Re-detection reaches at most this many rings of regions around the search centre.
MAX_RINGS = 4
#: Regions searched a frame while lost besides the centre one (the cost is bounded).
REGIONS_PER_FRAME = 8
#: Frame-wide re-detection reads the frame this many times smaller than the working scale where
#: that scale enlarges the frame as much (a small target): the frame's own detail, on the same
#: cells (of 1/this the pixels).
WIDE_REDUCTION = 2
#: ... and scores it with the filter's kernel reduced to this many channels (its leading
#: singular vectors; ECO-HC compresses fHOG to 10, Danelljan et al., CVPR 2017): the
#: transforms of 10 channels, not 32.
WIDE_RANK = 10
#: ... over at most this many working pixels (width x height; a larger frame: a window of that
#: area around the search centre). 1024x576 cost a lost 640x480 frame ~10 tracked ones and
#: scored no better on the real sequences; 512x288 lost targets faster than the generated
#: `fast` scene's (benchmarks/RESULTS.md section 8, twenty-third round).
WIDE_WINDOW = (768, 432)
MAX_WIDE_PIXELS = WIDE_WINDOW[0] * WIDE_WINDOW[1]
#: KCF/DSST/Staple's label width: sqrt(target area) / 16 (in working pixels).
LABEL_SIGMA_FACTOR = 1 / 16


@dataclass
class Region:
    """One search region of a frame: centre (frame pixels), size in frame pixels, the frame ->
    working pixels factor, its patch and the spectrum of its filter features."""

    cx: float
    cy: float
    width: float
    height: float
    factor: float
    patch: np.ndarray
    spectrum: np.ndarray
    #: Cut where the frame-wide response peaks while the target is not lost
    #: (``robust_failure.redetect_on_colour``): it competes only with a usual peak or more.
    far: bool = False

    def window(self, frame: Frame) -> Window | None:
        return Box.from_center(self.cx, self.cy, self.width, self.height).window(
            frame.width, frame.height)


@dataclass
class RobustTarget:
    """What the ``robust`` stages share (the one typed context field ``ctx.robust``)."""

    #: The first frame's target size (frame pixels) and the current size multiplier.
    base_w: float
    base_h: float
    scale: float
    #: Search region at scale 1 (frame pixels) and the patch it is resampled to (cells).
    region_w: float
    region_h: float
    cols: int
    rows: int
    cell: int
    grey_channel: bool
    #: Learn from the chosen region moved in the Fourier domain (ECO) when the found centre is
    #: at most this many cells from the region's centre (0: always cut the region again).
    shift_within: float
    translation: CorrelationFilter
    cosine: np.ndarray
    colour: ColourHistograms | None
    #: DSST's scale filter (``robust_search``; None: the size is kept), and this frame's scale
    #: samples with the box they were taken around: when the size did not change, the same
    #: samples are what learning would take again.
    scale_filter: ScaleFilter | None = None
    scale_samples: tuple[Box, np.ndarray] | None = None
    #: The size multiplier before this frame's scale estimate (``robust_failure`` keeps it when
    #: the frame's response says the target is hidden).
    previous_scale: float = 1.0
    #: This frame's regions: the first is centred on the search centre; while lost,
    #: ``robust_model`` adds more around it (re-detection).
    regions: list[Region] = field(default_factory=list)
    #: The region chosen by ``robust_search`` and the peak there (frame pixels).
    chosen: Region | None = None
    #: Confidence of this frame's response (LMCF's APCE and peak) and their means over the
    #: frames so far (``robust_failure``).
    apce: float = 0.0
    peak: float = 0.0
    #: Peak-to-sidelobe ratio of this frame's response (MOSSE).
    psr: float = 0.0
    #: The colour response (Staple's mean likelihood over a target-sized box) at the chosen
    #: peak (1 without colour), and its mean so far, whose first term is the response at the
    #: given box on the first frame (``colour_frames`` terms; 0: no colour response).
    colour_peak: float = 1.0
    usual_apce: float = 0.0
    usual_peak: float = 0.0
    usual_colour: float = 0.0
    response_frames: int = 0
    colour_frames: int = 0
    #: Whole frames elapsed since the last frame that saw the target (``robust_failure``; 0
    #: while it is seen), and the frame clock's whole frame on that frame
    #: (:attr:`vtrack.clock.FrameClock.frame`; 0: the first).
    hidden_frames: int = 0
    seen_at: int = 0
    #: The next frame also searches where the merged response peaks over the whole frame
    #: (``robust_failure.redetect_on_colour``: this frame's colours at the peak are not the
    #: target's).
    search_wide: bool = False
    #: Neither learner sees the target on this frame (``robust_failure.coast_unseen``): the box
    #: reported is ``robust_motion``'s extrapolation, and ``peak_box`` the response's peak,
    #: where the next frame's search is still centred.
    unseen: bool = False
    peak_box: Box | None = None
    #: A box with less than this share of its area inside the frame is leaving the view
    #: (``robust_failure``: half, or half of the first box's share inside while a target given
    #: entering the view comes in).
    least_inside: float = 0.5
    #: The colour response's weight in the merged response (``robust_search``; 0: none).
    merge: float = 0.0
    #: The frame whose pixels ``robust_model`` converted once for the frame's regions, and
    #: those pixels (:meth:`convert`); the frame's other cuts take them where they reach.
    #: None between frames (:meth:`frame_done`).
    converted: tuple[Frame, ConvertedWindow | None] | None = None

    def merged(self, response: np.ndarray, colour: np.ndarray) -> np.ndarray:
        """Staple's merge of the filter's response with the colour response (eq. 21)."""
        return (1 - self.merge) * response + self.merge * colour

    @property
    def size(self) -> tuple[float, float]:
        """Current target size (frame pixels)."""
        return self.base_w * self.scale, self.base_h * self.scale

    def features(self, patch: np.ndarray) -> np.ndarray:
        """Filter features of a patch: fHOG (+ the cells' mean grey), under the cosine window."""
        return self.plain_features(patch) * self.cosine

    def plain_features(self, patch: np.ndarray, cell: int | None = None) -> np.ndarray:
        """fHOG (+ the cells' mean grey) of a patch of any size, without the cosine window, on
        cells of ``cell`` pixels (default: the filter's)."""
        hog = fhog(patch, cell or self.cell)
        if self.grey_channel:
            grey = patch if patch.ndim == 2 else cv2.cvtColor(patch, cv2.COLOR_BGR2GRAY)
            means = cv2.resize(grey, (hog.shape[1], hog.shape[0]), interpolation=cv2.INTER_AREA)
            hog = np.concatenate([hog, (means.astype(np.float32) / 255 - 0.5)[..., None]], axis=2)
        return hog

    @property
    def factor(self) -> float:
        """Working pixels a frame pixel at the current scale (the search region's patch is
        ``cols x cell`` working pixels across)."""
        return self.cols * self.cell / (self.region_w * self.scale)

    def convert(self, frame: Frame, centres: list[tuple[float, float]]) -> None:
        """Convert the frame's pixels under the search regions centred on ``centres`` (at the
        current scale) once, where that converts no more than cutting each would
        (:meth:`ConvertedWindow.spanning`): this frame's regions, learning sample and scale
        samples are cut from them where they reach (the same values)."""
        width, height = self.region_w * self.scale, self.region_h * self.scale
        self.converted = (frame, ConvertedWindow.spanning(
            frame, [(cx, cy, width, height) for cx, cy in centres], self.cols * self.cell,
            self.rows * self.cell))

    def frame_done(self) -> None:
        """Let go of the pixels :meth:`convert` converted, and of their frame, once the frame's
        last cut is done (``robust_failure``'s learning): they are not held while the next
        frame is read, nor after the track ends."""
        self.converted = None

    def converted_pixels(self, frame: Frame) -> ConvertedWindow | None:
        """The pixels :meth:`convert` converted, if it did on ``frame``."""
        return self.converted[1] if self.converted is not None and self.converted[0] is frame \
            else None

    def region(self, frame: Frame, cx: float, cy: float) -> Region:
        """The search region centred on (cx, cy) at the current scale, its patch and features."""
        width, height = self.region_w * self.scale, self.region_h * self.scale
        patch = region_patch(frame, cx, cy, width, height, self.cols * self.cell,
                             self.rows * self.cell, self.converted_pixels(frame))
        return Region(cx, cy, width, height, self.factor, patch,
                      self.translation.spectrum(self.features(patch)))

    def learn(self, frame: Frame, box: Box, rate: float, first: bool = False) -> None:
        """Fold the region around ``box`` into the filter (learning rate ``rate``), the colour
        histograms and the scale filter (their own rates): Staple's running averages;
        ``first``: replace."""
        region, spectrum = self._learning_sample(frame, box, first)
        self.translation.learn_spectrum(spectrum, 1.0 if first else rate)
        if self.colour is not None:
            w, h = box.w * region.factor, box.h * region.factor
            x = region.patch.shape[1] / 2 + (box.cx - region.cx) * region.factor - w / 2
            y = region.patch.shape[0] / 2 + (box.cy - region.cy) * region.factor - h / 2
            self.colour.learn(region.patch, (x, y, w, h), first=first)
        if self.scale_filter is not None:
            cached = self.scale_samples
            samples = (cached[1] if cached is not None and cached[0] == box
                       else self.scale_filter.samples(frame, box.cx, box.cy, box.w, box.h,
                                                      self.converted_pixels(frame)))
            self.scale_filter.learn(samples, first=first)

    def _learning_sample(self, frame: Frame, box: Box, first: bool) -> tuple[Region, np.ndarray]:
        """The region to learn ``box`` from and its features' spectrum, centred on ``box``.
        Near the chosen region's centre that is the chosen region's own spectrum moved there
        (ECO, Danelljan et al., CVPR 2017: no new cut, features nor transform), when the found
        centre is at most ``shift_within`` cells away: within a cell the moved sample differs
        from a new cut only by less than a cell of the cosine window's placement. Farther, the
        window's offset and the circular wrap matter with Staple's small padding (moving by
        any distance lowered the check sequences' mean AUC, benchmarks/RESULTS.md section 8):
        the region is cut again."""
        region = self.chosen
        if not first and region is not None:
            step = self.cell / region.factor  # frame pixels a cell
            dy, dx = (box.cy - region.cy) / step, (box.cx - region.cx) / step
            if self.shift_within > 0 and max(abs(dy), abs(dx)) <= self.shift_within:
                return region, shift_spectrum(region.spectrum, dy, dx, self.cols)
        region = self.region(frame, box.cx, box.cy)
        return region, region.spectrum


@register
class RobustModel(Stage):
    """fHOG correlation-filter features and colour likelihood of a fixed-size search patch."""

    name = "robust_model"
    summary = ("robust: cuts the search region (box + padding) at a fixed working size; fHOG "
               "features for the correlation filter and the colour likelihood (Staple)")
    params = (
        Param("working_area", int, 150, "side of the square whose area the search patch is "
              "resampled to, in pixels (Staple: 150; ECO: up to 250)", min=32, max=250),
        Param("padding", float, 1.0, "search region = box + padding x the box's mean side "
              "(Staple: 1)", min=0.2, max=4.0),
        Param("cell", int, 4, "fHOG cell size in working pixels (KCF/Staple: 4)", min=3, max=8),
        Param("grey_channel", bool, True, "add each cell's mean grey level to fHOG's 31 "
              "channels (Staple)"),
        Param("lam", float, 1e-3, "correlation filter regulariser lambda (DSST eq. 6)",
              min=1e-6, max=1.0),
        Param("colour", bool, True, "learn the colour histograms (off: texture only)"),
        Param("bins", int, 32, "colour histogram bins per channel (Staple: 32)",
              choices=(8, 16, 32, 64)),
        Param("inner_padding", float, 0.2, "the object histogram is learnt inside the box "
              "shrunk by this share of its mean side (Staple: 0.2)", min=0.0, max=0.9),
        Param("motion_region", bool, True, "also search a region centred on the motion "
              "model's prediction when it is more than a cell from the last box"),
        Param("filter_redetect", bool, False, "while the target is lost (and after a frame "
              "whose colours are not the target's, robust_failure.redetect_on_colour), also "
              "search a region centred where the merged response peaks over the whole frame, "
              f"on the filter's cells through its {WIDE_RANK} leading channels (a larger "
              "frame: a window of "
              f"{WIDE_WINDOW[0]}x{WIDE_WINDOW[1]} working pixels' area around the search "
              "centre)"),
        Param("shift_within", float, 0.0, "learn from the chosen region's sample moved to the "
              "found centre in the Fourier domain (ECO) when that is at most this many cells "
              "away; farther, cut and describe the region again (0: always cut again)",
              min=0.0, max=4.0),
        Param("colour_rate", float, 0.04, "colour histograms' learning rate (Staple: 0.04)",
              min=0.0, max=1.0),
        Param("first_support", float, 0.0, "the first frame's filter is constrained to a "
              "support of the box scaled by this, centred on it (CSR-DCF/BACF, solved by "
              "ADMM): background around the target, however textured, is no evidence for it "
              "(0: DSST's unconstrained filter)", min=0.0, max=3.0),
    )
    requires = frozenset({"frame", "box", "state", "prediction", "search_growth"})
    provides = frozenset({"robust", "window", "likelihood"})

    working_area: int
    padding: float
    cell: int
    grey_channel: bool
    lam: float
    colour: bool
    bins: int
    inner_padding: float
    motion_region: bool
    filter_redetect: bool
    shift_within: float
    colour_rate: float
    first_support: float

    def start(self, ctx: TrackContext) -> None:
        box = self.initial_box(ctx)
        if box.outside(ctx.frame.width, ctx.frame.height):
            raise FirstFrameError(f"robust_model: the initial box {box.text()} is outside the "
                                  "frame")
        side = (box.w + box.h) / 2 * self.padding
        region_w, region_h = box.w + side, box.h + side
        factor = self.working_area / math.sqrt(region_w * region_h)
        cols = max(int(region_w * factor / self.cell), 4)
        rows = max(int(region_h * factor / self.cell), 4)
        sigma = math.sqrt(box.w * box.h) * factor * LABEL_SIGMA_FACTOR / self.cell
        colour = (ColourHistograms(self.bins, self.inner_padding, self.colour_rate)
                  if self.colour else None)
        target = RobustTarget(
            base_w=box.w, base_h=box.h, scale=1.0, region_w=region_w, region_h=region_h,
            cols=cols, rows=rows, cell=self.cell, grey_channel=self.grey_channel,
            shift_within=self.shift_within,
            translation=CorrelationFilter(gaussian_label(rows, cols, sigma), self.lam, 0.0),
            cosine=hann2d(rows, cols), colour=colour)
        target.learn(ctx.frame, box, 1.0, first=True)
        #: Counts the frames given (from the first one's number): the turn of the regions a
        #: lost target's ring search visits (frame numbers with gaps skipped some for good).
        self._turn = ctx.frame.index
        if self.first_support > 0:
            target.translation.constrain(support_mask(
                rows, cols, box.w * factor / self.cell * self.first_support,
                box.h * factor / self.cell * self.first_support))
        ctx.robust = target

    def step(self, ctx: TrackContext) -> None:
        target = ctx.robust
        assert target is not None
        self._turn += 1
        # The region is centred on the last box: on hand-held or panning footage the filter's
        # own last peak is a better prior than a motion model (on the tune sequences the
        # prediction as the only centre lowered the mean AUC from 0.60 to 0.50). Where the
        # motion model predicts the target elsewhere (a fast or hidden target), a second region
        # is searched there, and the higher peak wins (robust_search; this raised the mean AUC
        # of ten tune sequences from 0.61 to 0.67). A lost target is searched around where the
        # motion model last had it.
        if target.peak_box is not None:  # the last box reported was extrapolated (not lost)
            centre = target.peak_box
        elif ctx.state != TrackState.LOST and ctx.box is not None:
            centre = ctx.box
        else:
            centre = ctx.search_center
        centres = [(centre.cx, centre.cy)]
        predicted = ctx.prediction
        if (self.motion_region and predicted is not None and ctx.state != TrackState.LOST
                and math.hypot(predicted.cx - centre.cx, predicted.cy - centre.cy)
                > target.cell / target.factor):
            centres.append((predicted.cx, predicted.cy))
        target.convert(ctx.frame, centres)
        target.regions = [target.region(ctx.frame, cx, cy) for cx, cy in centres]
        region = target.regions[0]
        if self.filter_redetect and (ctx.state == TrackState.LOST or target.search_wide):
            wide = target.region(ctx.frame, *_filter_peak(ctx.frame, target, centre.cx,
                                                          centre.cy))
            wide.far = ctx.state != TrackState.LOST
            target.regions.append(wide)
        if ctx.search_growth > 1.0:
            target.regions.extend(self._around(ctx, target, region, self._turn))
        target.chosen = None
        ctx.window = region.window(ctx.frame)
        if target.colour is not None:
            ctx.likelihood = target.colour.likelihood(region.patch)
        if ctx.window is not None:
            ctx.overlays.append(SearchWindow(ctx.window.as_box()))

    @staticmethod
    def _around(ctx: TrackContext, target: RobustTarget, centre: Region,
                turn: int) -> list[Region]:
        """Re-detection while lost: the regions of a ring around the search centre, one region
        apart, as far out as ``ctx.search_growth`` regions (the same filter over a wider
        window; at most 8 more regions a frame, nearest first, from the ``turn``-th group on:
        consecutive turns visit them all)."""
        reach = int(min(ctx.search_growth - 1, MAX_RINGS))
        offsets = sorted(((dx, dy) for dy in range(-reach, reach + 1)
                          for dx in range(-reach, reach + 1) if (dx, dy) != (0, 0)),
                         key=lambda d: max(abs(d[0]), abs(d[1])))  # nearest ring first
        out = [(cx, cy) for cx, cy in ((centre.cx + dx * centre.width * 0.75,
                                        centre.cy + dy * centre.height * 0.75)
                                       for dx, dy in offsets)
               if 0 <= cx < ctx.frame.width and 0 <= cy < ctx.frame.height]
        # a bounded cost per frame: the ring's regions are visited in turn over the frames
        if not out:
            return []
        start = (turn * REGIONS_PER_FRAME) % len(out)
        picked = (out + out)[start:start + min(REGIONS_PER_FRAME, len(out))]
        return [target.region(ctx.frame, cx, cy) for cx, cy in picked]


def support_mask(rows: int, cols: int, width: float, height: float) -> np.ndarray:
    """(rows, cols) 0/1: the cells of a ``width`` x ``height`` (cells) box centred on the
    sample's centre cell (at least that cell)."""
    r = np.abs(np.arange(rows) - rows // 2)[:, None]
    c = np.abs(np.arange(cols) - cols // 2)[None, :]
    return ((r <= height / 2) & (c <= width / 2)).astype(np.float32)


def _filter_peak(frame: Frame, target: RobustTarget, cx: float, cy: float) -> tuple[float, float]:
    """The frame point (x, y) where the merged response (the filter's and, with colour, the
    colour response, Staple's merge) peaks over the whole frame (or over the window of at most
    ``MAX_WIDE_PIXELS`` working pixels around (``cx``, ``cy``)), on the filter's cells: the
    "whole frame at a coarse scale" of a correlation tracker's re-detection. Where the working
    scale enlarges the frame ``k`` = 2 times or more (a small target), the features are taken
    from the patch at 1/``k`` of it with cells of 1/``k`` the pixels (:func:`_wide_reduction`):
    the same cells, from the frame's own detail, at 1/``k``^2 the gradients' cost. The filter
    scores them through ``WIDE_RANK`` channels (the region cut at the peak is then scored by
    the whole filter, ``robust_search``)."""
    cell = target.cell
    factor = target.factor
    shrink = min(1.0, math.sqrt(MAX_WIDE_PIXELS / (frame.width * frame.height * factor**2)))
    # sizes the DFT is fast on (the window may reach a little past the frame: replicated)
    cols = cv2.getOptimalDFTSize(max(int(frame.width * shrink * factor / cell), target.cols))
    rows = cv2.getOptimalDFTSize(max(int(frame.height * shrink * factor / cell), target.rows))
    width, height = cols * cell / factor, rows * cell / factor
    # the window inside the frame where it can be, around the search centre
    wx = min(max(cx, width / 2), max(frame.width - width / 2, width / 2))
    wy = min(max(cy, height / 2), max(frame.height - height / 2, height / 2))
    k = _wide_reduction(factor, cell)
    read_cell = cell // k  # the filter's cells, in the pixels of the patch as read
    patch = region_patch(frame, wx, wy, width, height, cols * read_cell, rows * read_cell)
    features = target.plain_features(patch, read_cell)
    response = target.translation.respond_wide(features, WIDE_RANK)
    # index p scores a target at p + the learnt samples' centre cell (wrapped): rolled, index
    # p scores a target at p
    response = np.roll(response, (target.rows // 2, target.cols // 2), axis=(0, 1))
    if target.colour is not None and target.merge > 0:
        # Staple's merge (eq. 21), as robust_search scores a region: the filter alone took
        # static background, which it learnt as context, for a target that had moved away
        w, h = target.size
        colour = cell_response(target.colour.likelihood(patch), w * factor / k,
                               h * factor / k, rows, cols, read_cell)
        response = target.merged(response, colour)
    row, col = np.unravel_index(int(np.argmax(response)), response.shape)
    step = cell / factor
    return wx + (col - cols // 2) * step, wy + (row - rows // 2) * step


def _wide_reduction(factor: float, cell: int) -> int:
    """How many times smaller than the working scale the frame-wide search samples the frame:
    ``WIDE_REDUCTION`` where the working scale (``factor`` working pixels a frame pixel)
    enlarges the frame at least that many times and a cell divides, else 1."""
    k = WIDE_REDUCTION
    return k if factor >= k and cell % k == 0 else 1
