"""Target model and back-projection (S0 sec. 2.2, eq. 2-4).

Liu et al. 2022 (sec. 2.2): the
target model is the histogram of the hue inside the initial box, counted once on the first frame
(eq. 2-3), with its largest bin ``max`` kept; every later frame is back-projected as
``BP(p) = histogram[hue(p)] * 255 / max`` (eq. 4), a 0..255 likelihood map, on the search window
only. ``hist * 255 / max`` is exactly what the OpenCV CamShift tutorial's
``cv2.normalize(hist, hist, 0, 255, cv2.NORM_MINMAX)`` gives whenever some bin is empty (min 0);
values are rounded to the nearest integer, as ``cv2.calcBackProject`` does.

Pipeline contract of stage ``backproject``:

- reads ``ctx.window``, ``ctx.feature`` with ``ctx.feature_levels`` (how many values the feature
  takes) and ``ctx.feature_mask`` (0 = pixel not valid, or None), which come with the feature;
- writes ``ctx.likelihood`` (uint8 back-projection of the window; masked pixels are 0);
- on the first frame sets ``ctx.target_model`` (:class:`~vtrack.stages.base.TargetModel`): the
  histogram (float64, ``bins`` counts of the initial box's valid pixels), ``bp_initial`` (mean
  back-projection inside the initial box, 0..255) and ``bp_background`` (mean back-projection of
  the rest of the first window, at most half ``bp_initial``): the references of the ``bp_mass``
  signal (:func:`bp_mass`).

The helpers :func:`box_slices`, :func:`box_mean`, :func:`hue_histogram` and :func:`bp_mass` are
shared with the mean-shift and occlusion stages.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from vtrack.errors import FirstFrameError
from vtrack.geometry import Box, Window
from vtrack.histograms import hue_histogram
from vtrack.params import Param
from vtrack.stages.base import Stage, TargetModel, TrackContext, register


def box_slices(window: Window, box: Box) -> tuple[slice, slice] | None:
    """Row and column slices of an image of ``window`` covering the pixels ``box`` touches.

    None when the box and the window have no pixel in common.
    """
    x0 = max(math.floor(box.x), window.x0)
    y0 = max(math.floor(box.y), window.y0)
    x1 = min(math.ceil(box.x + box.w), window.x1)
    y1 = min(math.ceil(box.y + box.h), window.y1)
    if x1 <= x0 or y1 <= y0:
        return None
    return slice(y0 - window.y0, y1 - window.y0), slice(x0 - window.x0, x1 - window.x0)


def box_mean(image: np.ndarray, window: Window, box: Box) -> float:
    """Mean of ``image`` (an image of ``window``) over the box's pixels inside it; 0 if none."""
    part = box_slices(window, box)
    return 0.0 if part is None else float(cv2.mean(image[part])[0])


def bp_mass(ctx: TrackContext, box: Box) -> float:
    """Back-projection mass of ``box`` relative to the initial box's, above the background's.

    ``(mean BP in box - background) / (mean BP in initial box - background)``, where the means
    run over the box's pixels in the search window and ``background`` is the first frame's mean
    BP in the search window around the initial box, at most half the initial mean
    (``ctx.target_model``). 1 on the first frame; about the
    fraction of the target's colour still seen, 0 when the box shows no more of it than the
    surroundings did. The background term removes the floor that hue noise of grey pixels (any
    hue at low saturation) gives without a saturation mask, which differs from scene to scene.
    """
    model = ctx.target_model
    assert ctx.likelihood is not None and ctx.window is not None and model is not None
    background = model.bp_background
    contrast = model.bp_initial - background
    return (box_mean(ctx.likelihood, ctx.window, box) - background) / contrast


@register
class BackProject(Stage):
    """Hue histogram of the initial box (S0 eq. 2-3); its back-projection on each window (eq. 4)."""

    name = "backproject"
    summary = ("hue histogram of the first frame's box, back-projected as hist*255/max "
               "(S0 sec. 2.2, eq. 2-4)")
    params = (
        Param(
            "bins", int, 256,
            "histogram bins over the feature's range (S0: 256 on hue 0..255; tutorial: 180)",
            min=1, max=256,
        ),
    )
    requires = frozenset({"window", "feature", "feature_levels", "feature_mask"})
    provides = frozenset({"likelihood", "target_model"})

    # Set from the parameters by Stage.__init__.
    bins: int

    def start(self, ctx: TrackContext) -> None:
        """Count the target model once, on the first frame's box (S0 eq. 2-3)."""
        assert ctx.window is not None and ctx.feature is not None
        box = ctx.box
        part = None if box is None or not box.is_valid() else box_slices(ctx.window, box)
        if box is None or part is None:
            shown = box.text() if box is not None else None
            raise FirstFrameError(f"backproject: the initial box {shown} covers no pixel of the "
                                  "frame")
        levels = ctx.feature_levels
        mask = ctx.feature_mask
        part_mask = None if mask is None else mask[part]
        hist = hue_histogram(ctx.feature[part], part_mask, self.bins, levels).astype(np.float64)
        top = float(hist.max())
        if top == 0:
            raise FirstFrameError(
                f"backproject: no pixel of the initial box {box.text()} passes the hue stage's "
                "saturation/value mask: the target has no colour for a hue tracker (grey footage? "
                "try --config robust or s2, or lower hue.sat_min / hue.val_min)"
            )
        # S0 eq. 4: CalcBackData = histogram[hue] * 255 / max, as a table hue value -> BP
        # (256 entries for cv2.LUT; values >= levels never occur and map to 0)
        values = np.arange(levels)
        self._lut = np.zeros(256, np.uint8)
        self._lut[:levels] = np.rint(hist[values * self.bins // levels] * 255.0 / top)
        self.step(ctx)
        assert ctx.likelihood is not None
        inside = ctx.likelihood[part]
        outside = ctx.likelihood.size - inside.size
        total = float(cv2.sumElems(ctx.likelihood)[0])
        initial = float(cv2.mean(inside)[0])
        background = (total - initial * inside.size) / outside if outside else 0.0
        # capped at half the initial mass, so the signal keeps a scale (and is 1 on frame 0)
        # even when the surroundings are as target-coloured as the target
        ctx.target_model = TargetModel(hist, initial, min(background, initial / 2.0))

    def step(self, ctx: TrackContext) -> None:
        """Back-project the window: one table look-up per pixel (S0 eq. 4)."""
        assert ctx.feature is not None
        likelihood = cv2.LUT(ctx.feature, self._lut)
        mask = ctx.feature_mask
        if mask is not None:
            np.bitwise_and(likelihood, mask, out=likelihood)  # masked pixels -> 0
        ctx.likelihood = likelihood
