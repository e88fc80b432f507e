"""Each detection's colours: ``detection_colours``.

Blobs say where targets are, not who they are: two people crossing merge into one blob and come
apart again, and the association after the split has only their motion to go by. This stage
gives every detection of ``ctx.detections`` a colour histogram of its own foreground pixels
(those of ``ctx.likelihood`` inside its box, so the ground around a person does not count):
hue x saturation x value (OpenCV's full-range HSV) in ``hue_bins`` x ``saturation_bins`` x
``value_bins`` bins, normalised to sum 1, in ``Detection.colours``. A detection of fewer than
``min_pixels`` foreground pixels gets none: so few pixels spread over 128 bins differ from frame
to frame by more than two people's clothes do (small warm targets in the ``multi`` scene at
640x480, ~20 pixels each, lost their tracks to a colour gate). ``byte_tracks`` compares it
with each track's own (its ``colour_gate``), as DeepSORT (Wojke et al., ICIP 2017) gates pairs
on an appearance distance; a colour histogram is the classic appearance model of colour
trackers (Comaniciu et al., CVPR 2000), with no network.

Work per frame: each detection's box, at the foreground's resolution (``ctx.feature_scale``).
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from vtrack.geometry import Window
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register
from vtrack.stages.detect import Detection, foreground_under


@register
class DetectionColours(Stage):
    """A colour histogram (HSV) of each detection's foreground pixels."""

    name = "detection_colours"
    summary = ("each detection's colour histogram (HSV, its foreground pixels only), for "
               "byte_tracks' colour gate")
    params = (
        Param("hue_bins", int, 8, "hue bins of the histogram", min=1, max=64),
        Param("saturation_bins", int, 4, "saturation bins", min=1, max=64),
        Param("value_bins", int, 4, "value (brightness) bins", min=1, max=64),
        Param("min_pixels", int, 100, "a detection with fewer foreground pixels (at the "
              "foreground's resolution) gets no histogram: too few to compare", min=1,
              max=1_000_000),
    )
    requires = frozenset({"frame", "detections", "likelihood", "feature_scale"})
    provides = frozenset({"detections"})
    needs_init_box = False

    hue_bins: int
    saturation_bins: int
    value_bins: int
    min_pixels: int

    def step(self, ctx: TrackContext) -> None:
        assert ctx.likelihood is not None
        ctx.detections = [replace(d, colours=self._histogram(ctx, d)) for d in ctx.detections]

    def _histogram(self, ctx: TrackContext, detection: Detection) -> np.ndarray | None:
        """The normalised histogram of the detection's foreground pixels (None: it has none)."""
        mask, scale = ctx.likelihood, ctx.feature_scale
        assert mask is not None
        covered, foreground = foreground_under(detection.box, mask, scale)
        if covered.width <= 0 or covered.height <= 0:
            return None
        inside = foreground.astype(np.uint8)
        window = Window(round(covered.x0 * scale), round(covered.y0 * scale),
                        min(round(covered.x1 * scale), ctx.frame.width),
                        min(round(covered.y1 * scale), ctx.frame.height))
        pixels = ctx.frame.bgr(window)
        if pixels.shape[:2] != inside.shape:  # the frame's pixels at the foreground's resolution
            pixels = cv2.resize(pixels, (inside.shape[1], inside.shape[0]),
                                interpolation=cv2.INTER_AREA)
        hsv = cv2.cvtColor(pixels, cv2.COLOR_BGR2HSV_FULL)
        counts = cv2.calcHist([hsv], [0, 1, 2], inside,
                              [self.hue_bins, self.saturation_bins, self.value_bins],
                              [0, 256, 0, 256, 0, 256]).ravel()
        total = float(counts.sum())
        return counts / total if total >= self.min_pixels else None
