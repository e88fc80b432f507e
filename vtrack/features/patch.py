"""Cutting a region of a frame out at a fixed working resolution.

A correlation tracker sees its target through a patch of fixed size (KCF/DSST/Staple's "fixed
area"): the region around the target is resampled to it whatever the target's size in the frame,
so the cost per frame does not depend on the frame's or the target's size. Only the region's
pixels are converted from the decoded frame (never the whole frame), and a region that reaches
past the frame's edge is filled by replicating the edge, as those trackers do.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from vtrack.frame import Frame, GrayFrame
from vtrack.geometry import Window


def region_patch(frame: Frame, cx: float, cy: float, width: float, height: float,
                 out_w: int, out_h: int) -> np.ndarray:
    """The ``width`` x ``height`` region centred on (``cx``, ``cy``) (frame pixels, may reach
    past the frame), resampled to ``out_w`` x ``out_h``: uint8, (out_h, out_w, 3) BGR, or
    (out_h, out_w) grey for a grey frame (its three BGR channels would be equal). Work and
    memory are bounded by the output and the frame, however large the region."""
    x0, y0 = cx - width / 2, cy - height / 2
    step_x, step_y = width / out_w, height / out_h  # frame pixels per output pixel
    inside = _overlap(frame, x0, y0, width, height)
    # A region much larger than the patch: take every k-th pixel first (k odd, at most half the
    # downscale), then average down to the patch's resolution, so a big target costs about its
    # patch, not its area.
    reduce = min(step_x, step_y) / 2
    k = max(int((reduce - 1) // 2) * 2 + 1, 1) if reduce >= 3 else 1
    k = max(min(k, inside.width, inside.height), 1)
    if isinstance(frame, GrayFrame):
        pixels = frame.gray(inside)[k // 2::k, k // 2::k] if k > 1 else frame.gray(inside)
    else:
        pixels = frame.bgr_sampled(inside, k) if k > 1 else frame.bgr(inside)
    target_w = max(round(inside.width / step_x), 1)
    target_h = max(round(inside.height / step_y), 1)
    if target_w * 1.5 < pixels.shape[1] or target_h * 1.5 < pixels.shape[0]:
        pixels = cv2.resize(pixels, (target_w, target_h), interpolation=cv2.INTER_AREA)
    # output pixel (u, v) shows frame point (x0 + (u + 0.5) step_x, ...); in `pixels`' units:
    per_x = inside.width / pixels.shape[1]
    per_y = inside.height / pixels.shape[0]
    matrix = np.array([
        [step_x / per_x, 0.0, (x0 - inside.x0 + 0.5 * step_x) / per_x - 0.5],
        [0.0, step_y / per_y, (y0 - inside.y0 + 0.5 * step_y) / per_y - 0.5]])
    return cv2.warpAffine(pixels, matrix, (out_w, out_h),
                          flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)


def _overlap(frame: Frame, x0: float, y0: float, width: float, height: float) -> Window:
    """The frame's pixels the region covers (at least the nearest one, for a region entirely
    outside the frame: its edge is what replication would show)."""
    ix0 = min(max(math.floor(x0), 0), frame.width - 1)
    iy0 = min(max(math.floor(y0), 0), frame.height - 1)
    ix1 = max(min(math.ceil(x0 + width), frame.width), ix0 + 1)
    iy1 = max(min(math.ceil(y0 + height), frame.height), iy0 + 1)
    return Window(ix0, iy0, ix1, iy1)
