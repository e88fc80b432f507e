"""Occlusion and loss: whether this frame's measurement may reach the filter (S0 sec. 3).

Liu et al. 2022 (sec. 1 and 3):
"when the target is completely occluded, the Kalman prediction is used, so that the window does
not drift away and get lost". The document does not say how full occlusion is detected; this
stage thresholds a declared signal measured on a box:

- ``bp_mass`` (default): the box's back-projection mass relative to the initial box's, above the
  first frame's background level (:func:`vtrack.stages.backproject.bp_mass`): about the fraction
  of the target's colour in view, 1 on the first frame, ~0 when fully hidden;
- ``similarity``: the Bhattacharyya coefficient ``sum_u sqrt(p_u q_u)`` between the normalised
  target model ``q`` and the hue histogram ``p`` of the box (masked pixels left out). It grows
  like the square root of the visible fraction and, without a saturation mask, greyish
  occluders (random hue) still score high against a model with a background share: use it with
  ``hue(sat_min=...)`` and a threshold around 0.5.

States:

- ``tracking``: the signal is measured on the mean-shift box (``ctx.measurement``); below
  ``threshold`` the target is hidden.
- hidden (``occluded``, then ``lost`` after ``lost_after`` hidden frames): the measurement is
  withheld so the Kalman filter coasts and the box follows the prediction (S0 sec. 3). The
  search window widens by ``growth`` per hidden frame up to ``max_growth`` (the prediction's
  uncertainty grows with every coasted frame: a velocity learnt while the target was being
  covered - mean shift follows its visible part - is off), and the target's return is looked
  for at the most target-like box of the window: the target-sized box with the largest
  back-projection sum (an integral-image search, all placements at once). When its signal
  reaches ``recover`` (hysteresis; a ``recover`` below ``threshold`` acts as ``threshold``) that
  box is the measurement, the state is ``tracking`` and the window is reset.

Pipeline contract of stage ``occlusion`` (it runs BEFORE ``kalman``, which it tells whether to
update or coast):

- reads ``ctx.measurement``, ``ctx.window``, ``ctx.likelihood``, ``ctx.target_model`` (the
  ``bp_mass`` references; the model histogram for ``similarity``, with ``ctx.feature``,
  ``ctx.feature_mask``, ``ctx.feature_levels``) and ``ctx.search_box`` (where the search
  started: the prediction, or the held box);
- writes ``ctx.state``, ``ctx.score`` (the signal), ``ctx.search_growth`` and ``ctx.measurement``
  / ``ctx.box``: None / the search box while hidden, the re-found box on recovery.
"""

from __future__ import annotations

import cv2
import numpy as np

from vtrack.geometry import Box, Window
from vtrack.histograms import bhattacharyya, hue_histogram
from vtrack.params import Param
from vtrack.stages.backproject import box_slices, bp_mass
from vtrack.stages.base import Stage, TrackContext, TrackState, register


def best_placement(image: np.ndarray, w: int, h: int) -> tuple[int, int, float]:
    """``(left, top, sum)`` of the ``w`` x ``h`` placement of largest sum in ``image`` (the
    first in raster order on ties), every placement scored at once from one integral image
    (float64: exact for integer images below 2^53, no int32 overflow on large windows)."""
    table = cv2.integral(image, sdepth=cv2.CV_64F)
    sums = table[h:, w:] - table[:-h, w:] - table[h:, :-w] + table[:-h, :-w]
    top, left = np.unravel_index(int(np.argmax(sums)), sums.shape)
    return int(left), int(top), float(sums[top, left])


def best_box(likelihood: np.ndarray, window: Window, target: Box) -> Box:
    """The box of ``target``'s size inside ``window`` with the largest back-projection sum.

    ``likelihood`` is an image of ``window``; all placements on the pixel grid are scored at
    once from its integral image. A window smaller than the box gives the box on the window.
    """
    rows, cols = likelihood.shape
    w = min(max(round(target.w), 1), cols)
    h = min(max(round(target.h), 1), rows)
    left, top, _ = best_placement(likelihood, w, h)
    return Box.from_center(window.x0 + left + w / 2.0, window.y0 + top + h / 2.0,
                           target.w, target.h)


@register
class Occlusion(Stage):
    """Tracking / occluded / lost from a target-presence signal; coasting while hidden (S0
    sec. 3)."""

    name = "occlusion"
    summary = ("occluded/lost detection: withhold the measurement so the Kalman filter coasts "
               "(S0 sec. 3)")
    params = (
        Param(
            "signal", str, "bp_mass",
            "bp_mass = back-projection mass of the box relative to the first frame's, above "
            "the background; similarity = Bhattacharyya coefficient of box and model hues",
            choices=("bp_mass", "similarity"),
        ),
        Param(
            "threshold", float, 0.05,
            "hidden below this: bp_mass is the visible share of the target's colour, ~0 when "
            "fully hidden with a saturation mask (without one, grey's random hue: use ~0.15)",
            min=0.0, max=100.0,
        ),
        Param(
            "recover", float, 0.05,
            "tracking again at or above this (hysteresis, >= threshold; without a saturation "
            "mask the best box of a widened window reaches ~0.1 by chance: use ~0.25)",
            min=0.0, max=100.0,
        ),
        Param(
            "lost_after", int, 60,
            "hidden frames after which the state is lost, not occluded (1 s at 60 fps; frames "
            "given: S0 steps a frame at a time, frames missing from the input do not count)",
            min=1, max=100000,
        ),
        Param(
            "growth", float, 1.1, "search window widening factor per hidden frame",
            min=1.0, max=4.0,
        ),
        Param(
            "max_growth", float, 3.0, "largest widening of the search window",
            min=1.0, max=16.0,
        ),
    )
    requires = frozenset(
        {"measurement", "window", "feature", "feature_levels", "feature_mask", "likelihood",
         "search_box", "target_model"}
    )
    provides = frozenset({"measurement", "box", "state", "score", "search_growth"})

    # Set from the parameters by Stage.__init__.
    signal: str
    threshold: float
    recover: float
    lost_after: int
    growth: float
    max_growth: float

    def start(self, ctx: TrackContext) -> None:
        """The first frame's box is the target: tracking."""
        ctx.state = TrackState.TRACKING
        ctx.search_growth = 1.0
        self._hidden = 0  # consecutive hidden frames

    def step(self, ctx: TrackContext) -> None:
        search_box = ctx.search_box
        assert ctx.window is not None and ctx.likelihood is not None and search_box is not None
        if ctx.state == TrackState.TRACKING:
            candidate = ctx.measurement
            level = self.threshold
        else:
            candidate = best_box(ctx.likelihood, ctx.window, search_box)
            level = max(self.recover, self.threshold)
        value = 0.0 if candidate is None else self._signal(ctx, candidate)
        ctx.score = value
        if value >= level:
            ctx.state = TrackState.TRACKING
            ctx.search_growth = 1.0
            ctx.measurement = ctx.box = candidate
            self._hidden = 0
            return
        self._hidden += 1
        ctx.state = TrackState.LOST if self._hidden > self.lost_after else TrackState.OCCLUDED
        ctx.search_growth = min(ctx.search_growth * self.growth, self.max_growth)
        # S0 sec. 3: under full occlusion the measurement is not used; the position is the
        # prediction (the search box), so the window does not drift away
        ctx.measurement = None
        ctx.box = search_box

    def _signal(self, ctx: TrackContext, box: Box) -> float:
        if self.signal == "bp_mass":
            return bp_mass(ctx, box)
        assert ctx.window is not None and ctx.feature is not None and ctx.target_model is not None
        part = box_slices(ctx.window, box)
        if part is None:
            return 0.0
        model = ctx.target_model.histogram
        mask = ctx.feature_mask
        seen = hue_histogram(
            ctx.feature[part], None if mask is None else mask[part], model.size,
            ctx.feature_levels,
        )
        return bhattacharyya(seen, model)
