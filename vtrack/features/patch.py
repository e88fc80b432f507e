"""Cutting a region of a frame out at a fixed working resolution.

A correlation tracker sees its target through a patch of fixed size (KCF/DSST/Staple's "fixed
area"): the region around the target is resampled to it whatever the target's size in the frame,
so the cost per frame does not depend on the frame's or the target's size. Only the region's
pixels are converted from the decoded frame (never the whole frame), and a region that reaches
past the frame's edge is filled by replicating the edge, as those trackers do.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import cv2
import numpy as np

from vtrack.frame import Frame, GrayFrame
from vtrack.geometry import Window

#: A region more than this many times the frame's size is cut by :func:`_bounded_patch`.
FAR = 2.0


class ConvertedWindow(NamedTuple):
    """A window of a frame already converted to BGR, for :func:`region_patch` to cut several
    regions inside it from (each then converts nothing)."""

    window: Window
    bgr: np.ndarray

    @classmethod
    def around(cls, frame: Frame, cx: float, cy: float, width: float,
               height: float) -> ConvertedWindow | None:
        """The frame's pixels that the region (as :func:`region_patch` takes it) covers,
        converted; None for a grey frame or a far region (nothing to save)."""
        if isinstance(frame, GrayFrame) or width > FAR * frame.width \
                or height > FAR * frame.height:
            return None
        window = _reach(frame, cx, cy, width, height)[2]
        return cls(window, frame.bgr(window))

    @classmethod
    def spanning(cls, frame: Frame, regions: Sequence[tuple[float, float, float, float]],
                 out_w: int, out_h: int) -> ConvertedWindow | None:
        """The frame's pixels that all of ``regions`` (each ``(cx, cy, width, height)`` as
        :func:`region_patch` cuts it to ``out_w`` x ``out_h``) cover, converted once, when
        that converts no more pixels than the regions would one by one (overlapping regions;
        a region :func:`region_patch` reads every ``k``-th pixel of counts 1/``k``^2 of its
        own); None otherwise, and for a grey frame or a far region."""
        if isinstance(frame, GrayFrame):
            return None
        windows, own = [], 0
        for cx, cy, width, height in regions:
            if width > FAR * frame.width or height > FAR * frame.height:
                return None
            _, _, window = _reach(frame, cx, cy, width, height)
            k = _subsampling(width / out_w, height / out_h, window)
            own += window.width * window.height / (k * k)
            windows.append(window)
        if not windows:
            return None
        union = Window.union(windows)
        if union.width * union.height > own:
            return None
        return cls(union, frame.bgr(union))

    def covers_region(self, frame: Frame, cx: float, cy: float, width: float,
                      height: float) -> bool:
        """Whether the frame's pixels of the region (as :func:`region_patch` and
        :meth:`around` take it) are here."""
        return self.covers(_reach(frame, cx, cy, width, height)[2])

    def covers(self, window: Window) -> bool:
        return (self.window.x0 <= window.x0 and self.window.y0 <= window.y0
                and window.x1 <= self.window.x1 and window.y1 <= self.window.y1)

    def sampled(self, window: Window, k: int) -> np.ndarray:
        """``frame.bgr(window)`` (``k`` 1) or ``frame.bgr_sampled(window, k)``: the same
        values, cut from the converted pixels: a view, strided for ``k`` > 1 (OpenCV copies
        it where it must; the single-precision copy of :func:`area_resized` reads it as it
        is)."""
        o = (k - 1) // 2
        return self.bgr[window.y0 - self.window.y0 + o: window.y1 - self.window.y0: k,
                        window.x0 - self.window.x0 + o: window.x1 - self.window.x0: k]


def region_patch(frame: Frame, cx: float, cy: float, width: float, height: float,
                 out_w: int, out_h: int, converted: ConvertedWindow | None = None) -> np.ndarray:
    """The ``width`` x ``height`` region centred on (``cx``, ``cy``) (frame pixels, may reach
    past the frame), resampled to ``out_w`` x ``out_h``: uint8, (out_h, out_w, 3) BGR, or
    (out_h, out_w) grey for a grey frame (its three BGR channels would be equal). Work and
    memory are bounded by the patch and a few frames' worth of pixels. Pixels inside
    ``converted`` are cut from it rather than converted again (the same values)."""
    if width > FAR * frame.width or height > FAR * frame.height:
        return _bounded_patch(frame, cx, cy, width, height, out_w, out_h)
    x0, y0, inside = _reach(frame, cx, cy, width, height)
    # the whole pixels the region spans (past the frame too) and those of the frame it covers
    ix0, iy0 = math.floor(x0), math.floor(y0)
    ix1, iy1 = max(math.ceil(x0 + width), ix0 + 1), max(math.ceil(y0 + height), iy0 + 1)
    # A region much larger than the patch: take every k-th pixel first (k odd, at most half the
    # downscale, so an area resample still averages 2x2 or more), so a big target costs about
    # its patch, not its area.
    k = _subsampling(width / out_w, height / out_h, inside)
    pixels = (converted.sampled(inside, k) if converted is not None and converted.covers(inside)
              else _sampled(frame, inside, k))
    pad = (max(inside.y0 - iy0, 0), max(iy1 - inside.y1, 0),
           max(inside.x0 - ix0, 0), max(ix1 - inside.x1, 0))
    if any(pad):
        pad = tuple(-(-p // k) for p in pad)
        pixels = cv2.copyMakeBorder(pixels, *pad, cv2.BORDER_REPLICATE)
    sx = (ix1 - ix0) / pixels.shape[1]
    sy = (iy1 - iy0) / pixels.shape[0]
    scale_x, scale_y = width / sx / out_w, height / sy / out_h
    if min(scale_x, scale_y) > 1.5:
        # An area average of the whole pixels the region spans: its sub-pixel offset (under a
        # pixel) is dropped and the span is up to two pixels wider. An exact average (offset
        # and border pixels weighted) lowered the check sequences (benchmarks/RESULTS.md
        # section 8, stop 59).
        return area_resized(pixels, out_w, out_h)
    # The sub-pixel offset of the region inside the cut pixels, then one resample.
    off_x, off_y = (x0 - ix0) / sx, (y0 - iy0) / sy
    matrix = np.array([[scale_x, 0.0, off_x + 0.5 * scale_x - 0.5],
                       [0.0, scale_y, off_y + 0.5 * scale_y - 0.5]])
    return cv2.warpAffine(pixels, matrix, (out_w, out_h),
                          flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)


def area_resized(pixels: np.ndarray, out_w: int, out_h: int) -> np.ndarray:
    """``cv2.resize(pixels, (out_w, out_h), interpolation=cv2.INTER_AREA)`` of uint8 pixels,
    the same values, in a sixth to a quarter less time: OpenCV averages areas in single
    precision either way, and its single-precision input path is the faster one. (Whole
    reductions along both axes take OpenCV's own integer path, which rounds halves up.)"""
    if pixels.shape[1] % out_w == 0 and pixels.shape[0] % out_h == 0:
        return cv2.resize(pixels, (out_w, out_h), interpolation=cv2.INTER_AREA)
    area = cv2.resize(pixels.astype(np.float32), (out_w, out_h), interpolation=cv2.INTER_AREA)
    return np.rint(area, out=area).astype(np.uint8)


def _bounded_patch(frame: Frame, cx: float, cy: float, width: float, height: float,
                 out_w: int, out_h: int) -> np.ndarray:
    """:func:`region_patch` for a region far larger than the frame (only extreme parameter
    values get there): the frame's part averaged down first, then placed with replicated
    edges, so work and memory are bounded by the patch and the frame. (Slightly softer than
    :func:`region_patch`'s single resample, which tracking prefers.)"""
    x0, y0 = cx - width / 2, cy - height / 2
    step_x, step_y = width / out_w, height / out_h  # frame pixels per output pixel
    inside = _overlap(frame, x0, y0, width, height)
    # A region much larger than the patch: take every k-th pixel first (k odd, at most half the
    # downscale), then average down to the patch's resolution, so a big target costs about its
    # patch, not its area.
    k = _subsampling(step_x, step_y, inside)
    pixels = _sampled(frame, inside, k)
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


def _reach(frame: Frame, cx: float, cy: float, width: float,
           height: float) -> tuple[float, float, Window]:
    """The top-left corner :func:`region_patch` places the region at (:func:`_within_reach`)
    and the frame's pixels it covers there."""
    x0 = _within_reach(cx - width / 2, width, frame.width)
    y0 = _within_reach(cy - height / 2, height, frame.height)
    return x0, y0, _overlap(frame, x0, y0, width, height)


def _within_reach(start: float, size: float, extent: int) -> float:
    """``start`` of a region ``size`` long on an axis of ``extent`` pixels, moved by whole
    pixels to at most a pixel past the frame's far side, or to end at most a pixel before its
    near side: the patch is the same (every pixel of a region that far outside replicates the
    edge; the sub-pixel offset is kept), but the edge replicated to fill it never spans more
    than the region itself, however far the region is."""
    if start > extent:
        return start - math.floor(start - extent)
    if start + size < 0:
        return start + math.floor(-(start + size))
    return start


def _overlap(frame: Frame, x0: float, y0: float, width: float, height: float) -> Window:
    """The frame's pixels the region covers (at least the nearest one, for a region entirely
    outside the frame: its edge is what replication would show)."""
    ix0 = min(max(math.floor(x0), 0), frame.width - 1)
    iy0 = min(max(math.floor(y0), 0), frame.height - 1)
    ix1 = max(min(math.ceil(x0 + width), frame.width), ix0 + 1)
    iy1 = max(min(math.ceil(y0 + height), frame.height), iy0 + 1)
    return Window(ix0, iy0, ix1, iy1)


def _sampled(frame: Frame, inside: Window, k: int) -> np.ndarray:
    """Every ``k``-th pixel (``k`` odd, the centre of each block) of the frame's ``inside``
    window: grey for a grey frame, BGR otherwise."""
    if isinstance(frame, GrayFrame):
        grey = frame.gray(inside)
        return grey[k // 2::k, k // 2::k] if k > 1 else grey
    return frame.bgr_sampled(inside, k) if k > 1 else frame.bgr(inside)


def _subsampling(step_x: float, step_y: float, inside: Window) -> int:
    """The odd pixel step to read ``inside`` with when each output pixel spans ``step_x`` x
    ``step_y`` frame pixels: at most half the downscale (an area resample still averages 2x2 or
    more), 1 below a downscale of 6, never more than the window."""
    reduce = min(step_x, step_y) / 2
    k = max(int((reduce - 1) // 2) * 2 + 1, 1) if reduce >= 3 else 1
    return max(min(k, inside.width, inside.height), 1)
