"""Colour features: the hue of this frame's search window (S0 sec. 2.1, eq. 1).

Liu et al. 2022 (S0) track on the
hue H of HSV only, computed from RGB888 by the piecewise formula of their eq. (1) (``max == min``
-> 0) and scaled from 0..360 degrees to an 8-bit 0..255 value. OpenCV's ``COLOR_BGR2HSV_FULL``
is that formula on that scale; ``hue_scale = "opencv"`` gives OpenCV's usual 0..179 (degrees / 2)
used by the CamShift tutorial.

Pipeline contract of stage ``hue``:

- reads ``ctx.frame``, ``ctx.search_center`` (``ctx.prediction`` if a predictor set one, else
  ``ctx.box``) and ``ctx.search_growth``;
- writes ``ctx.window`` (the search window: ``search_scale`` x the target box x
  ``search_growth``, centred on the search centre, clipped to the frame; or the whole frame with
  ``full_frame``), ``ctx.feature`` (uint8 hue of the window, values ``0 .. levels - 1``) and the
  overlay ``SearchWindow``;
- ``ctx.search_box``: the target-sized box this frame's search starts from (the search centre);
- ``ctx.feature_levels``: how many values the feature takes (256 or 180);
- ``ctx.feature_mask``: uint8 array of the window's shape, 255 where saturation >= ``sat_min``
  and value >= ``val_min``, 0 elsewhere; None when no pixel is masked (both thresholds 0) or
  when ``mask_model_only`` leaves later frames unmasked.
"""

from __future__ import annotations

import cv2

from vtrack.geometry import Box, Window
from vtrack.overlays import SearchWindow
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register

#: Hue values per scale: the document's 8-bit 0..255, OpenCV's 0..179.
HUE_LEVELS = {"full": 256, "opencv": 180}
_CONVERSION = {"full": cv2.COLOR_BGR2HSV_FULL, "opencv": cv2.COLOR_BGR2HSV}


def search_window(center: Box, scale: float, width: int, height: int) -> Window:
    """The ``scale`` x ``center`` box clipped to a ``width`` x ``height`` frame, never empty.

    A centre outside the frame (a prediction coasting past the border) is first moved to the
    nearest point of the frame, so the search keeps looking at the border the target left by.
    """
    cx = min(max(center.cx, 0.0), float(width))
    cy = min(max(center.cy, 0.0), float(height))
    window = Box.from_center(cx, cy, center.w * scale, center.h * scale).window(width, height)
    assert window is not None  # a positive-size box centred inside the frame covers a pixel
    return window


@register
class Hue(Stage):
    """Hue of the search window (S0 eq. 1), with an optional saturation/value validity mask."""

    name = "hue"
    summary = "hue (H of HSV) of the search window around the prediction or the last box (S0 eq. 1)"
    params = (
        Param(
            "search_scale", float, 2.0,
            "search window size as a multiple of the target box",
            min=1.0, max=16.0,
        ),
        Param(
            "hue_scale", str, "full",
            "hue values: full = 0..255 as in S0 eq. 1; opencv = 0..179 (the OpenCV tutorial)",
            choices=tuple(HUE_LEVELS),
        ),
        Param(
            "sat_min", int, 0,
            "pixels with saturation below this are masked out (S0: 0, no mask; tutorial: 60)",
            min=0, max=255,
        ),
        Param(
            "val_min", int, 0,
            "pixels with value (brightness) below this are masked out (S0: 0; tutorial: 32)",
            min=0, max=255,
        ),
        Param(
            "mask_model_only", bool, False,
            "apply the S/V mask to the first frame's model only (the OpenCV tutorial), not to "
            "later back-projections (OpenCV's camshift.py sample)",
        ),
        Param(
            "full_frame", bool, False,
            "convert the whole frame every frame, not just the search window (tutorial CamShift)",
        ),
    )
    requires = frozenset({"frame", "box", "prediction", "search_growth"})
    provides = frozenset({"window", "feature", "feature_levels", "feature_mask", "search_box"})

    # Set from the parameters by Stage.__init__.
    search_scale: float
    hue_scale: str
    sat_min: int
    val_min: int
    mask_model_only: bool
    full_frame: bool

    def start(self, ctx: TrackContext) -> None:
        """First frame: the mask (if any thresholds are set) always applies to the model."""
        self._convert(ctx, masked=self.sat_min > 0 or self.val_min > 0)

    def step(self, ctx: TrackContext) -> None:
        """Later frames: masked too unless ``mask_model_only``."""
        masked = (self.sat_min > 0 or self.val_min > 0) and not self.mask_model_only
        self._convert(ctx, masked)

    def _convert(self, ctx: TrackContext, masked: bool) -> None:
        frame = ctx.frame
        center = ctx.search_center
        if self.full_frame:
            window = frame.full_window()
        else:
            scale = self.search_scale * ctx.search_growth
            window = search_window(center, scale, frame.width, frame.height)
        # S0 eq. 1: H from the piecewise RGB formula, 0..360 degrees scaled to 0..255 (HSV_FULL)
        hsv = cv2.cvtColor(frame.bgr(window), _CONVERSION[self.hue_scale])
        ctx.window = window
        if masked:
            # One split gives the hue and the two planes the mask tests (cheaper than
            # extractChannel + a 3-channel inRange): 255 where S >= sat_min and V >= val_min.
            hue, sat, val = cv2.split(hsv)
            mask = cv2.compare(sat, self.sat_min, cv2.CMP_GE)
            cv2.bitwise_and(mask, cv2.compare(val, self.val_min, cv2.CMP_GE), dst=mask)
        else:
            hue, mask = cv2.extractChannel(hsv, 0), None
        ctx.feature = hue
        ctx.search_box = center
        ctx.feature_levels = HUE_LEVELS[self.hue_scale]
        ctx.feature_mask = mask
        ctx.overlays.append(SearchWindow(window.as_box()))
