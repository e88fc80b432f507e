"""Mean shift on the back-projection (S0 sec. 2.3) and OpenCV's CamShift.

Liu et al. 2022 (sec. 2.3): the
mean-shift vector over a rectangular window ``S_r`` centred at ``(x, y)`` is
``A_x = 1/(n*255) * sum BP_i (x_i - x)`` and likewise ``A_y`` (eq. 6-7), ``n`` the window's pixel
count. Instead of iterating to convergence inside a frame, the window is placed at the Kalman
prediction and ONE step is taken per frame; "the iteration continues between frames" (item 5).

Method ``meanshift``:

- ``normalization = "weighted"`` (default) divides by ``sum BP_i`` instead of ``n * 255``: the
  step goes to the back-projection's weighted centroid (the usual mean shift);
  ``"paper"`` is eq. 6-7 as printed, a step damped by the window's mean back-projection / 255.
- ``region`` is the window ``S_r`` the sums run over. ``"target"`` (default): a target-sized box
  centred at ``(x, y)``. This is the document's reading: the search window is the tracking box
  placed at the Kalman prediction ("每帧画面的 Mean Shift 计算使用 ... Kalman 滤波预测值作为
  搜索窗口"), and it keeps the centroid on the target when something of its hue is near (the
  generated "distractor" scene: mean IoU 0.98 against 0.43-0.78). ``"window"``: a box the size
  of the whole search window (``ctx.window``): a larger capture range for a single step, but
  any back-projection in the window (a look-alike, unmasked grey) pulls the centroid to it.
  Either way the sums only see the back-projected window ``ctx.window`` (the region is clipped
  to it) and are image moments (``cv2.moments``) of that slice: no per-pixel Python.
- ``iterations`` steps at most (S0: 1); with more, stop early once a step is shorter than
  ``epsilon`` pixels (the classic converge-per-frame mean shift).

Method ``camshift``: ``cv2.CamShift`` on the window's back-projection, starting from the box,
criteria ``(iterations, epsilon)``; the new box is CamShift's axis-aligned ``track_window`` (the
window the OpenCV tutorial feeds into the next frame), so the box size adapts.

Pipeline contract of stage ``meanshift``:

- reads ``ctx.window``, ``ctx.likelihood``, ``ctx.search_box`` (where the search starts, from
  the hue stage) and ``ctx.target_model`` (the references of ``bp_mass``);
- writes ``ctx.measurement`` and ``ctx.box`` (the new box: the mean-shift result is the position
  unless a later stage - occlusion, kalman - decides otherwise), ``ctx.score`` (= ``bp_mass``)
  and the extras ``iterations`` (mean-shift steps taken; empty for camshift, which does not
  report them) and ``bp_mass`` (back-projection mass of the new box relative to the initial
  box's, see :func:`vtrack.stages.backproject.bp_mass`).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from vtrack.geometry import Box, Window
from vtrack.params import Param
from vtrack.stages.backproject import box_slices, bp_mass
from vtrack.stages.base import Stage, TrackContext, register


def mean_shift(
    likelihood: np.ndarray,
    window: Window,
    center: tuple[float, float],
    size: tuple[float, float],
    iterations: int,
    epsilon: float,
    paper: bool,
) -> tuple[float, float, int]:
    """Mean-shift steps from ``center`` on ``likelihood`` (a 0..255 image of ``window``).

    Each step sums over a ``size`` box centred on the current centre (clipped to the window);
    pixel ``(i, j)`` of the frame has its centre at ``(j + 0.5, i + 0.5)``. Stops after
    ``iterations`` steps, after a step shorter than ``epsilon``, or when the region holds no
    back-projection (no shift). Returns the new centre and the number of steps taken.
    """
    cx, cy = center
    steps = 0
    while steps < iterations:
        part = box_slices(window, Box.from_center(cx, cy, size[0], size[1]))
        if part is None:
            break
        region = likelihood[part]
        moments = cv2.moments(region)
        mass = moments["m00"]  # sum BP_i
        if mass <= 0:
            break
        # pixel centres of the region's first column / row, in frame coordinates
        left = window.x0 + part[1].start + 0.5
        top = window.y0 + part[0].start + 0.5
        # S0 eq. 6-7: sum BP_i (x_i - x) and sum BP_i (y_i - y) over the region
        sum_x = moments["m10"] + mass * (left - cx)
        sum_y = moments["m01"] + mass * (top - cy)
        # weighted: / sum BP_i (centroid); paper: / (n * 255), eq. 6-7 as printed
        norm = region.size * 255.0 if paper else mass
        dx, dy = sum_x / norm, sum_y / norm
        cx, cy = cx + dx, cy + dy
        steps += 1
        if math.hypot(dx, dy) < epsilon:
            break
    return cx, cy, steps


@register
class MeanShift(Stage):
    """One (or a few) mean-shift steps per frame on the back-projection (S0 sec. 2.3), or
    CamShift."""

    name = "meanshift"
    summary = "mean shift on the back-projection, one step per frame (S0 sec. 2.3), or cv2.CamShift"
    params = (
        Param(
            "method", str, "meanshift",
            "meanshift = S0 eq. 6-7 steps; camshift = cv2.CamShift (the box size adapts)",
            choices=("meanshift", "camshift"),
        ),
        Param(
            "iterations", int, 1,
            "steps per frame at most (S0: 1, iterating between frames; tutorial CamShift: 10)",
            min=1, max=100,
        ),
        Param(
            "epsilon", float, 1.0,
            "stop iterating within a frame once a step is shorter than this (pixels)",
            min=0.0, max=100.0,
        ),
        Param(
            "normalization", str, "weighted",
            "weighted = step to the BP-weighted centroid; paper = 1/(n*255) sum BP_i (x_i - x) "
            "as printed in S0 eq. 6-7 (a damped step)",
            choices=("weighted", "paper"),
        ),
        Param(
            "region", str, "target",
            "what the sums run over: target = a target-sized box at the centre (S0's search "
            "window); window = a box the size of the whole search window",
            choices=("target", "window"),
        ),
    )
    requires = frozenset({"window", "likelihood", "search_box", "target_model"})
    provides = frozenset({"measurement", "box", "score"})
    columns = ("iterations", "bp_mass")

    # Set from the parameters by Stage.__init__.
    method: str
    iterations: int
    epsilon: float
    normalization: str
    region: str

    def start(self, ctx: TrackContext) -> None:
        """The first frame's box is the given one: it is the measurement, with mass 1."""
        ctx.measurement = ctx.box
        ctx.score = 1.0
        ctx.extras["iterations"] = 0
        ctx.extras["bp_mass"] = 1.0

    def step(self, ctx: TrackContext) -> None:
        start = ctx.search_box
        assert ctx.window is not None and ctx.likelihood is not None and start is not None
        if self.method == "camshift":
            box = self._camshift(ctx.likelihood, ctx.window, start)
        else:
            if self.region == "target":
                size = (start.w, start.h)
            else:
                size = (float(ctx.window.width), float(ctx.window.height))
            cx, cy, steps = mean_shift(
                ctx.likelihood, ctx.window, (start.cx, start.cy), size,
                self.iterations, self.epsilon, self.normalization == "paper",
            )
            box = start.moved_to(cx, cy)
            ctx.extras["iterations"] = steps
        mass = bp_mass(ctx, box)
        ctx.measurement = ctx.box = box
        ctx.score = mass
        ctx.extras["bp_mass"] = mass

    def _camshift(self, likelihood: np.ndarray, window: Window, start: Box) -> Box:
        """``cv2.CamShift`` from ``start``; ``start`` itself when there is nothing to follow."""
        part = box_slices(window, start)
        if part is None:
            return start
        rows, cols = part
        track = (cols.start, rows.start, cols.stop - cols.start, rows.stop - rows.start)
        criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, self.iterations, self.epsilon)
        rotated, (x, y, w, h) = cv2.CamShift(likelihood, track, criteria)
        if rotated[1][0] <= 0 or w <= 0 or h <= 0:  # no back-projection under the window
            return start
        return Box(float(window.x0 + x), float(window.y0 + y), float(w), float(h))
