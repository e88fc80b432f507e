"""The ``robust`` tracker's localisation: mean shift to convergence from the prediction, scale.

Second link of the ``robust`` chain. Input: the fused placement score map of ``robust_model``
(colour box mean + NCC, one value per top-left placement of a target-sized box in the working
window). Localisation (issue item 4):

- a motion prior, a Gaussian around the Kalman prediction whose width is the target's size
  (``prior_sigma``) plus the predictor's own uncertainty (DAT weighs its vote map with a motion
  prior the same way, Possegger et al., CVPR 2015, sec. 3.3); while the target is lost the prior
  is flat (re-detection over the whole frame, issue item 7);
- mean shift iterated to convergence (Comaniciu, Ramesh, Meer, TPAMI 2003; S0 eq. 6-7 in its
  weighted form, :func:`vtrack.stages.meanshift.mean_shift`) on the prior-weighted map's top
  (values above 0.8 of its peak, 3 x 3 kernel: sub-pixel mode), started from the prediction
  and from the map's peak: the peak start keeps motion faster than a target width per frame
  inside the search, the prediction start keeps a nearby mode when two are equal; the start
  whose mode scores higher wins;
- relocation: when that mode does not look like the target (score below ``relocate_below``),
  the window's best placement without the prior is taken if its score is clearly higher.

Score (issue item 8): each cue at the found placement (template NCC, colour box mean)
relative to its usual value (:attr:`RobustTarget.references`, learnt by ``robust_failure``),
capped at 1, combined by ``confidence``: ``geometric`` (default) ``r_tmpl^(1 - gamma) *
r_hist^gamma``, ``fused`` Staple's linear mix, ``balanced`` or ``min``. Sizes are estimated only
on frames whose score reaches ``scale_above``.

Colour contrast (for ``robust_failure``): the found box's mean likelihood minus that of the ring
``ring`` times its size around it (:func:`contrast`), in ``ctx.robust.contrast``; the first
frame's value, at the box the model was built on, is ``ctx.robust.first_contrast``.

Scale (issue item 5, ``scale = true``): the box is tried at ``1 / scale_step``, 1 and
``scale_step`` times its size around the found centre; each size is scored by Staple's fusion of
the template's NCC (the template resized to that size: a three-level template pyramid) and the
colour *contrast* of the box, its mean likelihood minus that of the ring around it. The ring
term is the guard against the shrink bias of histogram similarity (a box inside the target keeps
a high mean likelihood, but its ring then lies on the target too; cf. Ning et al., "Robust mean
shift tracking with corrected background-weighted histogram", IET CV 2012, on background pixels
inside the box). The smaller size has its score multiplied by ``scale_penalty`` (SiamFC's scale
penalty, Bertinetto et al., ECCV-W 2016, which penalises both sizes): shrinking is the risky
direction (the shrink bias, a partly covered target), while a box that lost size must regain it
on equal evidence (penalising growth too kept boxes undersized: `grow` 0.83 -> 0.86 mean IoU,
real mean AUC 0.592 -> 0.602); the size moves ``scale_rate`` of the way towards the best one each
frame.

Pipeline contract of stage ``robust_search``: reads ``ctx.robust`` (maps, window, motion
uncertainty, usual cue values), ``ctx.prediction``, ``ctx.box``; writes ``ctx.measurement`` and
``ctx.box`` (the found box), ``ctx.score`` (0..1, see above; ``robust_failure`` decides what it
means), ``ctx.robust.cues`` and ``ctx.robust.contrast``, and the extras ``ncc``, ``colour``
(the raw cue values).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from vtrack.geometry import Box, Window
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register
from vtrack.stages.meanshift import mean_shift
from vtrack.stages.robust_model import RobustTarget, ncc_map

#: Share of the map's peak below which placements do not pull the mean shift.
PEAK_SHARE = 0.8
#: Placements either side of the found one over which each size's NCC is maximised.
NEAR = 2
#: Confidence margin by which the window's best placement overrides the motion prior's choice.
CLEARLY_BETTER = 0.1


def motion_prior(
    shape: tuple[int, int], size: tuple[int, int], center: tuple[float, float],
    sigma: tuple[float, float],
) -> np.ndarray:
    """Gaussian weight of every placement (top-left at each cell of a ``shape`` map, boxes of
    ``size``) by the distance of its centre from ``center``; ``sigma`` per axis (working px)."""
    rows, cols = shape
    xs = (np.arange(cols, dtype=np.float32) + size[0] / 2.0 - center[0]) / sigma[0]
    ys = (np.arange(rows, dtype=np.float32) + size[1] / 2.0 - center[1]) / sigma[1]
    return np.outer(np.exp(-0.5 * ys * ys), np.exp(-0.5 * xs * xs))


def contrast(table: np.ndarray, cx: float, cy: float, w: float, h: float, ring: float) -> float:
    """Mean of an image over the ``w`` x ``h`` box at ``(cx, cy)`` minus its mean over the ring
    between that box and the box ``ring`` times larger (``table``: the image's integral)."""
    rows, cols = table.shape[0] - 1, table.shape[1] - 1

    def region(rw: float, rh: float) -> tuple[float, float]:
        x0 = min(max(int(round(cx - rw / 2)), 0), cols)
        x1 = min(max(int(round(cx + rw / 2)), 0), cols)
        y0 = min(max(int(round(cy - rh / 2)), 0), rows)
        y1 = min(max(int(round(cy + rh / 2)), 0), rows)
        total = table[y1, x1] - table[y0, x1] - table[y1, x0] + table[y0, x0]
        return float(total), float((x1 - x0) * (y1 - y0))

    inner, inner_n = region(w, h)
    outer, outer_n = region(w * ring, h * ring)
    if inner_n <= 0:
        return 0.0
    ring_n = outer_n - inner_n
    ring_mean = (outer - inner) / ring_n if ring_n > 0 else 0.0
    return inner / inner_n - ring_mean


@register
class RobustSearch(Stage):
    """Mean shift to convergence on the fused map from the prediction; scale from a pyramid."""

    name = "robust_search"
    summary = ("robust: mean shift to convergence on the fused colour+template map from the "
               "Kalman prediction, motion prior from its uncertainty; scale every frame")
    params = (
        Param("prior_sigma", float, 1.0,
              "motion prior width in target sizes (plus the predictor's uncertainty)",
              min=0.05, max=100.0),
        Param("iterations", int, 20, "mean-shift steps at most (to convergence)",
              min=1, max=200),
        Param("epsilon", float, 0.05, "converged once a step is shorter (working pixels)",
              min=0.0, max=10.0),
        Param("confidence", str, "geometric",
              "the score: each cue relative to its usual value, then fused = Staple's linear "
              "mix, geometric = weighted geometric mean, min = the lower (both must agree)",
              choices=("fused", "geometric", "balanced", "min")),
        Param("relocate_below", float, 0.5,
              "when the motion prior's choice scores below this, the window's best placement "
              "is taken if it scores clearly higher (0: never)", min=0.0, max=1.0),
        Param("scale", bool, True, "estimate the scale every frame"),
        Param("scale_above", float, 0.7,
              "the size is estimated only when the relative score is at least this",
              min=0.0, max=1.0),
        Param("scale_contrast", float, 0.6,
              "the box shrinks only while its colour contrast is at least this share of the "
              "first frame's (a partly covered target would shrink it to its visible part; "
              "0: off)", min=0.0, max=1.0),
        Param("scale_step", float, 1.05, "ratio between the sizes tried", min=1.001, max=1.5),
        Param("scale_rate", float, 0.6, "share of the way to the best size moved per frame",
              min=0.0, max=1.0),
        Param("scale_cue", str, "fused",
              "what scores a size: fused = Staple's mix of colour contrast and template NCC; "
              "colour = colour contrast only; template = NCC only",
              choices=("fused", "colour", "template")),
        Param("scale_penalty", float, 0.99,
              "score factor of the smaller size tried (Bertinetto et al., SiamFC 2016, "
              "penalise both: 0.9745): a box shrinks only on better evidence",
              min=0.5, max=1.0),
        Param("ring", float, 1.6,
              "the contrast ring reaches this multiple of the box (the scale's shrink-bias "
              "guard, and the failure logic's colour contrast)",
              min=1.05, max=4.0),
    )
    requires = frozenset({"robust", "prediction", "box"})
    provides = frozenset({"measurement", "box", "score"})
    columns = ("ncc", "colour")

    # Set from the parameters by Stage.__init__.
    prior_sigma: float
    iterations: int
    epsilon: float
    confidence: str
    relocate_below: float
    scale: bool
    scale_above: float
    scale_contrast: float
    scale_step: float
    scale_rate: float
    scale_cue: str
    scale_penalty: float
    ring: float

    def start(self, ctx: TrackContext) -> None:
        """The first frame's box is the measurement, with full confidence."""
        ctx.measurement = ctx.box
        ctx.score = 1.0
        target = ctx.robust
        assert target is not None and target.integral is not None and ctx.box is not None
        cx, cy = target.to_working(ctx.box.cx, ctx.box.cy)
        target.contrast = target.first_contrast = contrast(
            target.integral, cx, cy, *target.size, self.ring)
        ctx.extras["ncc"] = 1.0
        ctx.extras["colour"] = 1.0

    def step(self, ctx: TrackContext) -> None:
        target = ctx.robust
        assert target is not None and target.fused is not None and ctx.box is not None
        center = ctx.search_center
        fused = target.fused
        if target.colour_only and target.colour_map is not None:
            fused = target.colour_map  # the template is stale (robust_failure's hold)
        w, h = target.size
        pcx, pcy = target.to_working(center.cx, center.cy)
        if target.search_all:
            weighted = fused
        else:
            side = math.sqrt(w * h) * self.prior_sigma
            sigma = (side + target.sigma[0] * target.sx, side + target.sigma[1] * target.sy)
            weighted = fused * motion_prior(fused.shape, (w, h), (pcx, pcy), sigma)
        px, py = self._locate(weighted, (w, h), (pcx - w / 2.0, pcy - h / 2.0))
        ix, iy = int(round(px)), int(round(py))
        target.cues = target.cues_at(ix, iy)
        score = target.confidence(target.cues, self.confidence)
        if weighted is not fused and score < self.relocate_below:
            # the prior's choice does not look like the target: a placement elsewhere in the
            # window that looks clearly more like it wins (a motion faster than the predictor
            # expected, or a prediction that went astray)
            peak = int(np.argmax(fused))
            qx, qy = peak % fused.shape[1], peak // fused.shape[1]
            cues = target.cues_at(qx, qy)
            other = target.confidence(cues, self.confidence)
            if other > score + CLEARLY_BETTER:
                px, py, ix, iy, score, target.cues = qx, qy, qx, qy, other, cues
        cx, cy = px + w / 2.0, py + h / 2.0
        target.contrast = contrast(target.integral, cx, cy, w, h, self.ring)
        bw, bh = ctx.box.w, ctx.box.h
        if self.scale and score >= self.scale_above:
            # sizes are measured on a clearly seen target only: a partly covered one would
            # shrink the box to its visible part
            factor = self._scale(target, cx, cy, w, h)
            if factor >= 1.0 or target.contrast >= self.scale_contrast * target.first_contrast:
                # ... and its score may stay fair while the usual cue values follow it down:
                # a box shrinks only while its colour contrast holds (an undersized box, its
                # ring on the target, has a low contrast too: it may always grow)
                bw, bh = bw * factor, bh * factor
        fx, fy = target.to_frame(cx, cy)
        box = Box.from_center(fx, fy, bw, bh)
        ctx.measurement = ctx.box = box
        ctx.score = score
        ctx.extras["ncc"] = target.cues[0] if target.template_map is not None else float("nan")
        ctx.extras["colour"] = target.cues[1]

    def _locate(self, weighted: np.ndarray, size: tuple[int, int],
                predicted: tuple[float, float]) -> tuple[float, float]:
        """Mode of ``weighted`` found by mean shift from the prediction and from the peak."""
        rows, cols = weighted.shape
        peak_index = int(np.argmax(weighted))
        peak = float(weighted.flat[peak_index])
        if peak <= 0:
            return predicted
        # mean shift on the map's values above PEAK_SHARE of its peak, with a 3 x 3 kernel: it
        # climbs to the mode (sub-pixel), not to the centroid of a broad, lopsided hill
        weights = cv2.threshold(weighted, PEAK_SHARE * peak, 0, cv2.THRESH_TOZERO)[1]
        grid = Window(0, 0, cols, rows)
        kernel = (3.0, 3.0)
        starts = [(peak_index % cols + 0.5, peak_index // cols + 0.5),
                  (predicted[0] + 0.5, predicted[1] + 0.5)]
        best, best_value = (starts[0][0] - 0.5, starts[0][1] - 0.5), -1.0
        for sx, sy in starts:
            mx, my, _ = mean_shift(weights, grid, (sx, sy), kernel, self.iterations,
                                   self.epsilon, paper=False)
            x, y = mx - 0.5, my - 0.5  # cell centres -> placement index
            value = float(weighted[min(max(int(round(y)), 0), rows - 1),
                                   min(max(int(round(x)), 0), cols - 1)])
            if value > best_value:
                best, best_value = (x, y), value
        return best

    def _scale(self, target: RobustTarget, cx: float, cy: float, w: int, h: int) -> float:
        """Size factor for the box this frame (1 = unchanged), see the module doc."""
        assert target.integral is not None and target.grey32 is not None
        table, grey = target.integral, target.grey32  # the likelihood's integral, from _maps
        scores = []
        factors = (1.0 / self.scale_step, 1.0, self.scale_step)
        for k in factors:
            kw, kh = max(int(round(w * k)), 2), max(int(round(h * k)), 2)
            # the current size's contrast and NCC are the found box's (measured by step() and
            # in robust_model's map)
            colour = target.contrast if k == 1.0 else contrast(table, cx, cy, kw, kh, self.ring)
            if target.template_map is None or self.scale_cue == "colour":
                score = colour
            else:
                x0, y0 = int(round(cx - kw / 2)), int(round(cy - kh / 2))
                if k == 1.0:
                    ncc = _best_near(target.template_map, x0, y0)
                else:
                    template = target.template_at(kw, kh)
                    assert template is not None
                    ncc = _ncc_near(grey, template, x0, y0)
                score = ncc if self.scale_cue == "template" else (
                    target.gamma * colour + (1 - target.gamma) * ncc)
            if k < 1.0 and score > 0:
                # SiamFC's scale penalty, on the smaller size only: shrinking is the risky
                # direction (histogram shrink bias, a partly covered target) and must earn it; a
                # box that lost size must be able to regain it on equal evidence
                score *= self.scale_penalty
            scores.append(score)
        best = int(np.argmax(scores))
        return 1.0 + self.scale_rate * (factors[best] - 1.0)


def _best_near(scores: np.ndarray, x0: int, y0: int, margin: int = NEAR) -> float:
    """Best of a placement map within ``margin`` placements of ``(x0, y0)`` (0 if none)."""
    near = scores[max(y0 - margin, 0) : y0 + margin + 1, max(x0 - margin, 0) : x0 + margin + 1]
    return float(near.max()) if near.size else 0.0


def _ncc_near(grey: np.ndarray, template: np.ndarray, x0: int, y0: int,
              margin: int = NEAR) -> float:
    """Best NCC (:func:`ncc_map`) of ``template`` with its top-left corner within ``margin``
    pixels of ``(x0, y0)`` (``grey``: float32); 0 if it fits nowhere there."""
    th, tw = template.shape
    rows, cols = grey.shape
    x0c, y0c = max(x0 - margin, 0), max(y0 - margin, 0)
    x1c, y1c = min(x0 + margin + tw, cols), min(y0 + margin + th, rows)
    if x1c - x0c < tw or y1c - y0c < th:
        return 0.0
    return float(ncc_map(grey[y0c:y1c, x0c:x1c], template).max())
