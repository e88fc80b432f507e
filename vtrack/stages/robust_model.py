"""The ``robust`` tracker's appearance model: colour conversion, target likelihood, template.

First link of the ``robust`` chain (``robust_model -> robust_search -> robust_failure ->
robust_motion``, see ``configs/robust.toml``). It keeps the design card's colour conversion and
back-projection, and makes them hold on footage they were never tuned for:

- **A fixed working resolution.** The search window is resampled so that the target box
  measures about ``working_size`` x ``working_size`` pixels (its aspect kept), as DAT and KCF do
  (Possegger et al., CVPR 2015, sec. 4; Henriques et al., TPAMI 2015): the work per frame is
  bounded whatever the target's size, and the template below keeps its size while the target
  grows or shrinks.
- **Colour that survives lighting** (issue item 2): a joint hue x saturation histogram for
  saturated pixels plus value (grey-level) bins for unsaturated ones, so grey and thermal targets
  get a model instead of a refusal; the histogram is smoothed over neighbouring hue (circular)
  and value bins, the kernel-density form of soft binning (Comaniciu, Ramesh, Meer, TPAMI 2003,
  sec. 4.1 use an Epanechnikov-weighted histogram for the same robustness).
- **Object against its surroundings** (issue item 1): the per-bin target likelihood is DAT's
  ``P(x in O | b) = H_O(b) / (H_O(b) + H_S(b))`` (Possegger et al. 2015, eq. 2) with ``H_S`` the
  histogram of the ring around the box; a colour the surroundings share scores ~0.5 or less,
  colours never seen score 0.5 (DAT's choice for unseen bins). ``surroundings = false`` gives
  the S0 back-projection ``H_O(b) / max H_O`` (ablation). ``distractors = true`` adds DAT's
  distractor-aware term (the same ratio against target-like regions of the window, mixed with
  weight ``1 - surround_weight``); it did not improve the real sequences, so it is off.
- **A window that may reach beyond the frame**: the part outside has likelihood 0, so a target
  leaving the view is followed out and seen to go (``robust_failure`` then says ``lost``).
- **A non-colour cue** (issue item 3): normalised cross-correlation of a grey template of the
  target over the window (``cv2.matchTemplate``, ``TM_CCOEFF_NORMED``), fused with the colour
  score per box placement as Staple does (Bertinetto et al., CVPR 2016, eq. 2:
  ``f = (1 - gamma) f_tmpl + gamma f_hist``, ``f_hist`` the box mean of the per-pixel
  likelihood from an integral image, their gamma = 0.3).
- **A model that follows slow change** (issue item 6): :meth:`RobustTarget.learn` blends the
  histograms and the template towards the current box with Staple's learning rates
  (``eta_hist = 0.04``, ``eta_tmpl = 0.01``); ``robust_failure`` calls it only on confident
  tracking frames, never while occluded.

Pipeline contract of stage ``robust_model``: reads ``ctx.frame``, ``ctx.box``,
``ctx.prediction`` and ``ctx.robust`` (the window size the motion model asks for; whether the
target is lost: then the whole frame is searched at a coarse resolution, issue item 7); writes
``ctx.window`` (the search window, frame pixels), ``ctx.likelihood`` (the window's per-pixel
target likelihood 0..1 at the working resolution), ``ctx.robust`` (created on the first frame:
the model, and this frame's working images and placement score maps) and the search-window
overlay.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from vtrack.errors import InputError
from vtrack.frame import Frame
from vtrack.geometry import Box, Window
from vtrack.histograms import hue_histogram
from vtrack.overlays import SearchWindow
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register

#: Saturation / value (0..255) below which a pixel counts as grey: it goes to a value bin.
#: The OpenCV CamShift tutorial's hue-validity thresholds (S >= 60, V >= 32), S0 uses the same.
GREY_SAT, GREY_VAL = 60, 32
#: Distractors: local maxima of the colour score at least this share of the target's, at most
#: this many (DAT sec. 3.2).
DISTRACTOR_SHARE, DISTRACTOR_COUNT = 0.5, 3
DOWNSCALE = cv2.INTER_LINEAR
#: Bin of the working pixels outside the frame (no colour bin reaches it: likelihood 0).
OUTSIDE = 255


@dataclass
class ColourModel:
    """Object and surroundings histograms over the joint bins, and the likelihood table."""

    hue_bins: int
    sat_bins: int
    grey_bins: int
    surroundings: bool
    #: Weight of the object-vs-surroundings likelihood against the object-vs-distractors one
    #: (DAT's lambda_p); 1 = no distractor term.
    surround_weight: float = 1.0
    object_hist: np.ndarray = field(default_factory=lambda: np.zeros(0))
    surround_hist: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: Histogram of the distractors seen so far (empty until there was one).
    distractor_hist: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: bin -> target likelihood 0..1 (float32, 256 entries for ``cv2.LUT``).
    table: np.ndarray = field(default_factory=lambda: np.zeros(256, np.float32))
    _luts: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = field(
        default=None, repr=False)
    _spreading: np.ndarray | None = field(default=None, repr=False)

    @property
    def bins(self) -> int:
        return self.hue_bins * self.sat_bins + self.grey_bins

    def quantise(self, bgr: np.ndarray) -> np.ndarray:
        """The joint bin (uint8) of every pixel of a BGR image (:meth:`quantise_hsv`)."""
        return self.quantise_hsv(cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV_FULL))

    def quantise_hsv(self, hsv: np.ndarray) -> np.ndarray:
        """The joint bin (uint8) of every pixel of an HSV image (``COLOR_BGR2HSV_FULL``).

        Saturated pixels: ``hue_bin * sat_bins + sat_bin``; grey pixels (S < 60 or V < 32):
        ``hue_bins * sat_bins + value_bin``. One table look-up per channel, no per-pixel
        Python: the saturation and value tables send a grey pixel's colour part to 255
        (uint8 additions saturate), and every value bin lies above every colour bin, so the
        smaller of the colour part and the value bin is the pixel's bin.
        """
        hue, sat, value = cv2.split(hsv)
        hue_part, sat_part, grey_flag, value_bin = self._tables()
        colour = cv2.add(cv2.add(cv2.LUT(hue, hue_part), cv2.LUT(sat, sat_part)),
                         cv2.LUT(value, grey_flag))
        return cv2.min(colour, cv2.LUT(value, value_bin))

    def _tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Channel value -> part of the joint bin (uint8 ``cv2.LUT`` tables, built once): hue
        -> ``hue_bin * sat_bins``; saturation -> ``sat_bin`` (255 below ``GREY_SAT``); value
        -> 255 below ``GREY_VAL`` (else 0); value -> its value bin."""
        if self._luts is None:
            levels = np.arange(256)
            hue = (levels * self.hue_bins >> 8) * self.sat_bins
            sat = np.where(levels >= GREY_SAT,
                           (levels - GREY_SAT) * self.sat_bins // (256 - GREY_SAT), 255)
            dark = np.where(levels >= GREY_VAL, 0, 255)
            grey = self.hue_bins * self.sat_bins + (levels * self.grey_bins >> 8)
            self._luts = (hue.astype(np.uint8), sat.astype(np.uint8), dark.astype(np.uint8),
                          grey.astype(np.uint8))
        return self._luts

    def histogram(self, bins: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """Normalised, smoothed histogram of a bin image (soft binning, see the module doc)."""
        return self.smoothed(self.counts(bins, mask))

    def counts(self, bins: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """Pixel count per joint bin (float32 holding whole numbers: sums and differences of
        counts are exact)."""
        return hue_histogram(bins, mask, self.bins, self.bins)

    def smoothed(self, counts: np.ndarray) -> np.ndarray:
        """Counts -> normalised histogram, smoothed over neighbouring bins (:meth:`spread`)."""
        if self._spreading is None:  # the spread is linear: one matrix product per histogram
            self._spreading = np.stack([self.spread(unit) for unit in np.eye(self.bins)])
        smooth = counts.astype(np.float64) @ self._spreading
        total = smooth.sum()
        return smooth / total if total > 0 else smooth

    def spread(self, counts: np.ndarray) -> np.ndarray:
        """[1 2 1] / 4 over neighbouring hue bins (circular) and value bins: each pixel also
        counts for the bins next to its own, so a lighting shift of a bin costs little."""
        colour = counts[: self.hue_bins * self.sat_bins].reshape(self.hue_bins, self.sat_bins)
        grey = counts[self.hue_bins * self.sat_bins :]
        colour = (2 * colour + np.roll(colour, 1, 0) + np.roll(colour, -1, 0)) / 4
        padded = np.concatenate([grey[:1], grey, grey[-1:]])
        grey = (padded[:-2] + 2 * grey + padded[2:]) / 4
        return np.concatenate([colour.ravel(), grey])

    def set(self, object_hist: np.ndarray, surround_hist: np.ndarray,
            distractor_hist: np.ndarray | None = None) -> None:
        """Adopt new histograms and rebuild the likelihood table."""
        self.object_hist, self.surround_hist = object_hist, surround_hist
        if distractor_hist is not None:
            self.distractor_hist = distractor_hist
        table = np.zeros(256, np.float64)
        if self.surroundings:
            # Possegger et al. 2015, eq. 2 with equal priors: H_O / (H_O + H_S); unseen -> 0.5
            likelihood = _ratio(object_hist, surround_hist)
            if self.distractor_hist.size and self.surround_weight < 1.0:
                # DAT sec. 3.2: the same ratio against the distractors' histogram, mixed in
                # with weight 1 - lambda_p
                likelihood = self.surround_weight * likelihood + (
                    1 - self.surround_weight) * _ratio(object_hist, self.distractor_hist)
            table[: self.bins] = likelihood
        else:
            top = object_hist.max()
            table[: self.bins] = object_hist / top if top > 0 else 0.0  # S0 eq. 4, scaled 0..1
        self.table = table.astype(np.float32)

    def likelihood(self, bins: np.ndarray) -> np.ndarray:
        """Per-pixel target likelihood 0..1 (float32): one table look-up per pixel."""
        return cv2.LUT(bins, self.table)


@dataclass
class RobustTarget:
    """What the ``robust`` stages share (the one typed context field ``ctx.robust``)."""

    model: ColourModel
    #: Grey template of the target (float32), at its size on the first frame's working scale.
    template: np.ndarray | None
    #: Staple's merge factor gamma: weight of the colour score against the template's.
    gamma: float
    # --- from the motion model, for the next frame's window ---------------------------------
    #: Uncertainty (1 sigma, frame pixels) of the predicted centre per axis.
    sigma: tuple[float, float] = (0.0, 0.0)
    # --- this frame's working images (set by robust_model) ----------------------------------
    #: The frame position of the working images' top-left corner (the search region may reach
    #: beyond the frame; the window itself is ``ctx.window``); the scale factors frame ->
    #: working pixels per axis.
    origin: tuple[float, float] = (0.0, 0.0)
    sx: float = 1.0
    sy: float = 1.0
    bins: np.ndarray | None = None  # joint colour bin per working pixel
    grey: np.ndarray | None = None  # grey level per working pixel
    #: Integral image (float64) of ``ctx.likelihood`` and ``grey`` as float32, set by _maps for
    #: robust_search (computed once a frame).
    integral: np.ndarray | None = None
    grey32: np.ndarray | None = None
    #: Box size in working pixels this frame's maps are for (the placements' size).
    size: tuple[int, int] = (1, 1)
    #: Placement score maps (top-left corner of a ``size`` box at each working pixel).
    colour_map: np.ndarray | None = None
    template_map: np.ndarray | None = None
    fused: np.ndarray | None = None
    #: Reference values of the template (NCC) and colour scores: their running means on
    #: confident frames (robust_failure); and this frame's values at the found box.
    references: tuple[float, float] = (1.0, 1.0)
    cues: tuple[float, float] = (1.0, 1.0)
    #: The cue values at the first frame's box (robust_failure's floor under the usual values).
    first_cues: tuple[float, float] = (1.0, 1.0)
    #: Colour contrast of the found box: its mean likelihood minus that of the ring around it
    #: (robust_search); and its value on the first frame, at the box the model was built on.
    contrast: float = 1.0
    first_contrast: float = 1.0
    #: Frames hidden in a row, and whether the next frame searches the whole frame
    #: (robust_failure: lost with re-detection on).
    hidden: int = 0
    search_all: bool = False
    #: Whether the next frame localises on the colour map alone (robust_failure's hold: the
    #: template is stale, the colour cue and the motion agree).
    colour_only: bool = False

    def to_working(self, x: float, y: float) -> tuple[float, float]:
        """Frame coordinates -> working-image coordinates of this frame's window."""
        return (x - self.origin[0]) * self.sx, (y - self.origin[1]) * self.sy

    def to_frame(self, x: float, y: float) -> tuple[float, float]:
        """Working-image coordinates -> frame coordinates."""
        return self.origin[0] + x / self.sx, self.origin[1] + y / self.sy

    def cues_at(self, px: int, py: int) -> tuple[float, float]:
        """The template (NCC; 1 without a template) and colour scores of a placement."""
        assert self.colour_map is not None
        colour = _clamped(self.colour_map, px, py)
        ncc = 1.0 if self.template_map is None else _clamped(self.template_map, px, py)
        return ncc, colour

    def confidence(self, cues: tuple[float, float], rule: str) -> float:
        """How target-like a placement with these cue values is, 0..1 (1: as usual).

        Each cue relative to its reference (capped at 1), then ``fused``: Staple's linear mix
        ``(1 - gamma) r_tmpl + gamma r_hist``; ``geometric``: ``r_tmpl^(1 - gamma) *
        r_hist^gamma``; ``min``: the lower of the two (a box must look right to both cues).
        """
        rt, rc = (min(max(v, 0.0) / max(r, 1e-6), 1.0)
                  for v, r in zip(cues, self.references, strict=True))
        if self.template_map is None or self.gamma >= 1.0:
            return rc
        if rule == "min":
            return min(rt, rc)
        if rule == "geometric":
            return rt ** (1 - self.gamma) * rc**self.gamma
        if rule == "balanced":
            return math.sqrt(rt * rc)
        return (1 - self.gamma) * rt + self.gamma * rc

    def template_at(self, w: int, h: int) -> np.ndarray | None:
        """The template resized to ``w`` x ``h`` working pixels (None without a template)."""
        if self.template is None:
            return None
        if self.template.shape == (h, w):
            return self.template
        return cv2.resize(self.template, (w, h), interpolation=cv2.INTER_AREA)

    def box_part(self, box: Box) -> tuple[slice, slice] | None:
        """Rows and columns of the working images a frame box covers (None if none)."""
        assert self.bins is not None
        x0, y0 = self.to_working(box.x, box.y)
        x1, y1 = self.to_working(box.x + box.w, box.y + box.h)
        rows, cols = self.bins.shape
        c0, r0 = max(int(round(x0)), 0), max(int(round(y0)), 0)
        c1, r1 = min(int(round(x1)), cols), min(int(round(y1)), rows)
        if c1 <= c0 or r1 <= r0:
            return None
        return slice(r0, r1), slice(c0, c1)

    def learn(self, box: Box, rate_hist: float, rate_template: float) -> None:
        """Blend the model towards this frame's ``box`` (Staple's linear interpolation, eq. 5-6
        of Bertinetto et al. 2016): histograms at ``rate_hist``, template at ``rate_template``;
        rate 1 replaces them (the first frame)."""
        assert self.bins is not None and self.grey is not None
        part = self.box_part(box)
        if part is None:
            return
        inside = self.model.counts(self.bins[part])
        obj = self.model.smoothed(inside)
        # DAT's surrounding region: the window around the box (Possegger et al. 2015, sec. 3.1),
        # counted as the whole window's counts less the box's (no masks)
        ring = self.model.smoothed(self.model.counts(self.bins) - inside)
        distractors = None
        if self.model.surround_weight < 1.0 and self.colour_map is not None:
            inside = np.zeros(self.bins.shape, np.uint8)
            inside[part] = 255
            mask = distractor_mask(self.colour_map, self.size, (part[1].start, part[0].start),
                                   DISTRACTOR_SHARE, DISTRACTOR_COUNT)
            if mask is not None and mask.shape == self.bins.shape:
                distractors = self.model.histogram(self.bins, cv2.bitwise_and(
                    mask, cv2.bitwise_not(inside)))
        old = self.model
        if rate_hist >= 1.0 or old.object_hist.size == 0:
            self.model.set(obj, ring, distractors)
            return self._learn_template(part, rate_template)
        if distractors is not None and old.distractor_hist.size:
            distractors = (1 - rate_hist) * old.distractor_hist + rate_hist * distractors
        self.model.set(
            (1 - rate_hist) * old.object_hist + rate_hist * obj,
            (1 - rate_hist) * old.surround_hist + rate_hist * ring,
            distractors,
        )
        self._learn_template(part, rate_template)

    def learn_template(self, box: Box, rate_template: float) -> None:
        """Blend only the template towards this frame's ``box`` at ``rate_template`` (the
        colour histograms are left as they are)."""
        part = self.box_part(box)
        if part is not None:
            self._learn_template(part, rate_template)

    def _learn_template(self, part: tuple[slice, slice], rate_template: float) -> None:
        """Blend the template towards the grey patch ``part`` at ``rate_template``."""
        assert self.grey is not None
        if self.template is None or rate_template <= 0:
            return
        patch = self.grey[part].astype(np.float32)
        current = cv2.resize(patch, (self.template.shape[1], self.template.shape[0]),
                             interpolation=cv2.INTER_AREA)
        if rate_template >= 1.0:
            self.template = current
        else:
            cv2.addWeighted(self.template, 1 - rate_template, current, rate_template, 0,
                            dst=self.template)


def _clamped(image: np.ndarray, x: int, y: int) -> float:
    """``image[y, x]`` with the indices clamped into the image."""
    rows, cols = image.shape
    return float(image[min(max(y, 0), rows - 1), min(max(x, 0), cols - 1)])


def _ratio(target: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Per bin ``target / (target + other)``, 0.5 where neither has mass (DAT eq. 2)."""
    total = target + other
    return np.divide(target, total, out=np.full(target.size, 0.5), where=total > 1e-12)


def distractor_mask(colour_map: np.ndarray, size: tuple[int, int], target: tuple[int, int],
                    share: float, count: int) -> np.ndarray | None:
    """Mask (uint8, the working image's shape) of up to ``count`` distractors: local maxima of
    the colour placement map at least ``share`` of the target's value, not overlapping the
    target's placement (DAT sec. 3.2: target-like regions of the surroundings). None if none."""
    w, h = size
    rows, cols = colour_map.shape
    tx, ty = min(max(target[0], 0), cols - 1), min(max(target[1], 0), rows - 1)
    level = share * float(colour_map[ty, tx])
    peaks = colour_map >= cv2.dilate(colour_map, np.ones((h, w), np.uint8))
    peaks &= colour_map >= level
    ys, xs = np.nonzero(peaks)
    far = (np.abs(xs - tx) >= w) | (np.abs(ys - ty) >= h)
    xs, ys = xs[far], ys[far]
    if xs.size == 0:
        return None
    order = np.argsort(colour_map[ys, xs])[::-1][:count]
    mask = np.zeros((rows + h - 1, cols + w - 1), np.uint8)
    for x, y in zip(xs[order], ys[order], strict=True):
        mask[y : y + h, x : x + w] = 255
    return mask


def ncc_map(image: np.ndarray, template: np.ndarray) -> np.ndarray:
    """Normalised cross-correlation (``TM_CCOEFF_NORMED``) of ``template`` at every placement
    in ``image`` (float32 both), 0..1: a flat patch (NaN) and anti-correlation count as 0."""
    ncc = cv2.matchTemplate(image, template, cv2.TM_CCOEFF_NORMED)
    cv2.patchNaNs(ncc, 0.0)
    return np.clip(ncc, 0.0, 1.0, out=ncc)


def working_scale(box: Box, size: float, upscale: float) -> float:
    """Frame -> working pixels factor that makes ``box`` about ``size`` x ``size`` in area."""
    return min(size / math.sqrt(max(box.w * box.h, 1.0)), upscale)


def place_window(
    center: Box, frame: Frame, padding: float, sigma: tuple[float, float], n_sigma: float,
    max_factor: float,
) -> tuple[float, float, float, float]:
    """The search region ``(x0, y0, x1, y1)`` in frame pixels, NOT clipped to the frame:
    ``padding`` x the box plus ``n_sigma`` predicted-centre standard deviations each side
    (issue item 4: sized from the predictor's uncertainty), at most ``max_factor`` x the box,
    centred on the box moved inside the frame (so the region always overlaps it)."""
    half_w = min(padding * center.w / 2 + n_sigma * sigma[0], max_factor * center.w / 2)
    half_h = min(padding * center.h / 2 + n_sigma * sigma[1], max_factor * center.h / 2)
    cx = min(max(center.cx, 0.0), float(frame.width))
    cy = min(max(center.cy, 0.0), float(frame.height))
    return cx - half_w, cy - half_h, cx + half_w, cy + half_h


def integral_box_means(table: np.ndarray, w: int, h: int) -> np.ndarray:
    """Mean of an image over every ``w`` x ``h`` placement (top-left at each pixel), from its
    integral ``table`` (float64): shape ``(rows - h + 1, cols - w + 1)``."""
    sums = table[h:, w:] - table[:-h, w:]  # in place from here: no temporaries, same order
    sums -= table[h:, :-w]
    sums += table[:-h, :-w]
    sums /= w * h
    return sums.astype(np.float32)


@register
class RobustModel(Stage):
    """Colour (hue x saturation + grey) object/surroundings likelihood and grey NCC template."""

    name = "robust_model"
    summary = ("robust: window at a fixed working resolution, object-vs-surroundings colour "
               "likelihood (DAT) fused with a grey NCC template (Staple)")
    params = (
        Param("working_size", int, 40,
              "the target is resampled to about this many pixels on a side (DAT/KCF-style "
              "fixed working resolution: bounded cost)", min=8, max=256),
        Param("upscale", float, 2.0, "largest enlargement of a small target", min=1.0, max=8.0),
        Param("hue_bins", int, 16, "hue bins of the joint colour histogram", min=2, max=48),
        Param("sat_bins", int, 4, "saturation bins of the joint colour histogram", min=1, max=4),
        Param("grey_bins", int, 16,
              "value bins for unsaturated pixels (grey and thermal targets)", min=1, max=32),
        Param("surroundings", bool, True,
              "likelihood H_O / (H_O + H_S) against the box's surroundings (DAT eq. 2); "
              "false: H_O / max H_O (S0's back-projection)"),
        Param("distractors", bool, False,
              "also weigh the target's colours against target-like regions of the window "
              "(DAT's distractor-aware model)"),
        Param("surround_weight", float, 0.5,
              "with distractors: weight of the surroundings likelihood against the "
              "distractors' (DAT's lambda_p)", min=0.0, max=1.0),
        Param("template", bool, True,
              "fuse a grey NCC template score with the colour score (Staple)"),
        Param("gamma", float, 0.3,
              "weight of the colour score in the fused score (Staple's merge factor)",
              min=0.0, max=1.0),
        Param("padding", float, 2.0, "search window as a multiple of the box, before the "
              "motion uncertainty is added", min=1.0, max=10.0),
        Param("n_sigma", float, 3.0, "predicted-centre standard deviations added to each "
              "side of the window", min=0.0, max=10.0),
        Param("max_window", float, 8.0, "largest search window as a multiple of the box",
              min=1.0, max=50.0),
        Param("adaptive_window", bool, True,
              "size the window from the motion model's uncertainty (false: padding x box)"),
        Param("lost_pixels", int, 40000,
              "while lost the whole frame is searched, resampled to at most this many pixels",
              min=1000, max=1_000_000),
        Param("max_pixels", int, 250_000,
              "the search window is resampled to at most this many working pixels (bounds "
              "per-frame work and memory whatever the box, max_window and working_size)",
              min=10_000, max=1_000_000),
    )
    requires = frozenset({"frame", "box", "prediction"})
    provides = frozenset({"window", "likelihood", "robust"})

    # Set from the parameters by Stage.__init__.
    working_size: int
    upscale: float
    hue_bins: int
    sat_bins: int
    grey_bins: int
    surroundings: bool
    distractors: bool
    surround_weight: float
    template: bool
    gamma: float
    padding: float
    n_sigma: float
    max_window: float
    adaptive_window: bool
    lost_pixels: int
    max_pixels: int

    def start(self, ctx: TrackContext) -> None:
        """Build the model from the first frame's box and its surroundings."""
        box = self.initial_box(ctx)
        if box.window(ctx.frame.width, ctx.frame.height) is None:
            raise InputError(f"robust_model: the initial box {box.text()} covers no pixel of "
                             "the frame")
        weight = self.surround_weight if self.distractors and self.surroundings else 1.0
        model = ColourModel(self.hue_bins, self.sat_bins, self.grey_bins, self.surroundings,
                            weight)
        target = RobustTarget(model=model, template=None, gamma=self.gamma if self.template
                              else 1.0)
        ctx.robust = target
        self._convert(ctx, box, self.padding * 1.5, lost=False)
        part = target.box_part(box)
        assert part is not None and target.grey is not None
        if self.template:
            target.template = target.grey[part].astype(np.float32)
        target.learn(box, 1.0, 1.0)
        ctx.likelihood = target.model.likelihood(target.bins)
        self._maps(ctx, box)
        x, y = (round(v) for v in target.to_working(box.x, box.y))
        target.references = target.first_cues = target.cues_at(x, y)

    def step(self, ctx: TrackContext) -> None:
        target = ctx.robust
        assert target is not None and ctx.box is not None
        center = ctx.search_center
        self._convert(ctx, center, self.padding, lost=target.search_all)
        self._maps(ctx, ctx.box)

    def _convert(self, ctx: TrackContext, center: Box, padding: float, lost: bool) -> None:
        """Place the window, resample it to the working resolution, quantise its colours."""
        target = ctx.robust
        assert target is not None
        frame = ctx.frame
        scale = working_scale(center, self.working_size, self.upscale)
        if lost:
            # the whole frame, and half a box beyond it: a target coming back into view is
            # found while still partly outside
            mx, my = center.w / 2, center.h / 2
            region = (-mx, -my, frame.width + mx, frame.height + my)
            scale = min(scale, math.sqrt(self.lost_pixels / (frame.width * frame.height)))
        else:
            sigma = target.sigma if self.adaptive_window else (0.0, 0.0)
            region = place_window(center, frame, padding, sigma, self.n_sigma, self.max_window)
            area = (region[2] - region[0]) * (region[3] - region[1])
            scale = min(scale, math.sqrt(self.max_pixels / max(area, 1.0)))
        window = Box(region[0], region[1], region[2] - region[0],
                     region[3] - region[1]).window(frame.width, frame.height)
        assert window is not None  # the region is centred inside the frame
        if scale < 1:
            # downscale by a whole factor k, the window trimmed to a multiple of k; bilinear
            # (2 x 2 averages, exact k x k averages for k = 2): INTER_AREA costs ~5x more at
            # k = 3 and the model and the template are sampled the same way
            k = max(math.ceil(1 / scale - 1e-9), 1)
            cols, rows = max(window.width // k, 1), max(window.height // k, 1)
            window = Window(window.x0, window.y0, window.x0 + min(cols * k, window.width),
                            window.y0 + min(rows * k, window.height))
            if k >= 3 and k % 2 and window.width == cols * k and window.height == rows * k:
                # at an odd whole factor the bilinear resize samples the centre pixel of each
                # k x k block: convert only those (same values, 1 / k^2 of the work)
                bgr = frame.bgr_sampled(window, k)
            else:
                bgr = frame.bgr(window)
                if k > 1:
                    bgr = cv2.resize(bgr, (cols, rows), interpolation=DOWNSCALE)
        else:
            cols = max(int(round(window.width * scale)), 1)
            rows = max(int(round(window.height * scale)), 1)
            bgr = cv2.resize(frame.bgr(window), (cols, rows), interpolation=cv2.INTER_LINEAR)
        sx, sy = cols / window.width, rows / window.height
        bins = target.model.quantise(bgr)
        grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
        # The part of the region outside the frame, in working pixels: a target leaving the
        # view can be followed out (its box partly outside), and seen to go. Outside pixels
        # get the OUTSIDE bin (likelihood 0) and the grey of the nearest border pixel.
        left = max(int(round((window.x0 - region[0]) * sx)), 0)
        top = max(int(round((window.y0 - region[1]) * sy)), 0)
        right = max(int(round((region[2] - window.x1) * sx)), 0)
        bottom = max(int(round((region[3] - window.y1) * sy)), 0)
        if left or top or right or bottom:
            bins = cv2.copyMakeBorder(bins, top, bottom, left, right, cv2.BORDER_CONSTANT,
                                      value=OUTSIDE)
            grey = cv2.copyMakeBorder(grey, top, bottom, left, right, cv2.BORDER_REPLICATE)
        target.origin = (window.x0 - left / sx, window.y0 - top / sy)
        target.sx, target.sy = sx, sy
        target.bins, target.grey = bins, grey
        ctx.window = window
        ctx.likelihood = target.model.likelihood(bins)
        ctx.overlays.append(SearchWindow(window.as_box()))

    def _maps(self, ctx: TrackContext, box: Box) -> None:
        """Placement score maps for a box of ``box``'s size: colour box mean, NCC, fused."""
        target = ctx.robust
        assert target is not None and ctx.likelihood is not None and target.grey is not None
        w = max(int(round(box.w * target.sx)), 2)
        h = max(int(round(box.h * target.sy)), 2)
        likelihood = ctx.likelihood
        grey = target.grey32 = target.grey.astype(np.float32)
        table = cv2.integral(likelihood, sdepth=cv2.CV_64F)
        target.integral = table
        rows, cols = grey.shape
        if rows < h + 1 or cols < w + 1:  # window clipped by the frame border: pad it
            bottom, right = max(h + 1 - rows, 0), max(w + 1 - cols, 0)
            likelihood = cv2.copyMakeBorder(likelihood, 0, bottom, 0, right,
                                            cv2.BORDER_CONSTANT, value=0)
            grey = cv2.copyMakeBorder(grey, 0, bottom, 0, right, cv2.BORDER_REPLICATE)
            table = cv2.integral(likelihood, sdepth=cv2.CV_64F)
        target.size = (w, h)
        # Staple eq. 2-3: f_hist = mean per-pixel likelihood over the box (integral image)
        target.colour_map = integral_box_means(table, w, h)
        template = target.template_at(w, h)
        if template is None or target.gamma >= 1.0:
            target.template_map = None
            target.fused = target.colour_map
            return
        ncc = target.template_map = ncc_map(grey, template)
        # Staple eq. 2: f = (1 - gamma) f_tmpl + gamma f_hist
        target.fused = cv2.addWeighted(ncc, 1 - target.gamma, target.colour_map, target.gamma, 0)
