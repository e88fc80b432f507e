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
    (out_h, out_w) grey for a grey frame (its three BGR channels would be equal)."""
    x0, y0 = cx - width / 2, cy - height / 2
    ix0, iy0 = math.floor(x0), math.floor(y0)
    ix1, iy1 = max(math.ceil(x0 + width), ix0 + 1), max(math.ceil(y0 + height), iy0 + 1)
    inside = Window(min(max(ix0, 0), frame.width - 1), min(max(iy0, 0), frame.height - 1),
                    max(min(ix1, frame.width), 1), max(min(iy1, frame.height), 1))
    if inside.x1 <= inside.x0:
        inside = inside._replace(x1=inside.x0 + 1)
    if inside.y1 <= inside.y0:
        inside = inside._replace(y1=inside.y0 + 1)
    # A region much larger than the patch: take every k-th pixel first (k odd, at most half the
    # downscale, so an area resample still averages 2x2 or more), so a big target costs about
    # its patch, not its area.
    reduce = min(width / out_w, height / out_h) / 2
    k = max(int((reduce - 1) // 2) * 2 + 1, 1) if reduce >= 3 else 1
    k = max(min(k, inside.width, inside.height), 1)
    if isinstance(frame, GrayFrame):
        pixels = frame.gray(inside)[k // 2::k, k // 2::k] if k > 1 else frame.gray(inside)
    else:
        pixels = frame.bgr_sampled(inside, k) if k > 1 else frame.bgr(inside)
    pad = (max(inside.y0 - iy0, 0), max(iy1 - inside.y1, 0),
           max(inside.x0 - ix0, 0), max(ix1 - inside.x1, 0))
    if any(pad):
        pad = tuple(-(-p // k) for p in pad)
        pixels = cv2.copyMakeBorder(pixels, *pad, cv2.BORDER_REPLICATE)
    # The sub-pixel offset of the region inside the cut pixels, then one resample.
    sx = (ix1 - ix0) / pixels.shape[1]
    sy = (iy1 - iy0) / pixels.shape[0]
    scale_x, scale_y = width / sx / out_w, height / sy / out_h
    off_x, off_y = (x0 - ix0) / sx, (y0 - iy0) / sy
    matrix = np.array([[scale_x, 0.0, off_x + 0.5 * scale_x - 0.5],
                       [0.0, scale_y, off_y + 0.5 * scale_y - 0.5]])
    interpolation = cv2.INTER_AREA if min(scale_x, scale_y) > 1.5 else cv2.INTER_LINEAR
    if interpolation == cv2.INTER_AREA and abs(off_x) < 1 and abs(off_y) < 1:
        return cv2.resize(pixels, (out_w, out_h), interpolation=cv2.INTER_AREA)
    return cv2.warpAffine(pixels, matrix, (out_w, out_h),
                          flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)
