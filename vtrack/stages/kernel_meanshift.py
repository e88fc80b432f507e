"""Kernel mean shift with scale adaptation and Kalman failure logic (S2).

Di Nan, Zhu Ming, "An algorithm for real-time tracking target in complex environment", Journal of
Image and Graphics 13(9), 2008 (S2).
A Comaniciu-style kernel tracker simplified for a fixed-point DSP: pyramid kernel, undivided
histograms, weights ``q_u / p_u`` (no square root), histogram intersection instead of the
Bhattacharyya coefficient, three bandwidths per frame, and a Kalman predictor that tells fast
motion from full occlusion.

Pipeline contract (chain ``kernel_meanshift -> kalman(model="ca")``):

- reads ``ctx.box`` (last frame's position: the measurement, or the Kalman prediction after an
  occlusion, so the next frame starts there) and ``ctx.prediction`` (the Kalman prediction for
  this frame, None while the predictor is starting: then the result is accepted);
- writes ``ctx.measurement`` (the mean-shift box; on full occlusion the prediction, so that
  the predictor runs on every frame's position as in eq. 14 and its state coasts, or None with
  ``occluded_update = "none"``), ``ctx.box``, ``ctx.state`` (``tracking`` / ``occluded``),
  ``ctx.score`` (similarity ``rho`` in 0..1 of the kept search; on occlusion, of the search
  from the prediction) and the extras ``decision`` (``accept`` / ``fast_motion`` /
  ``occlusion``), ``scale`` (box size over the initial box size) and ``iterations`` (mean-shift
  steps this frame, all bandwidths and the rerun from the prediction included).

Implementation notes:

- Only the window of each candidate box is read from the frame (``frame.gray(window)`` or the
  hue of ``frame.bgr(window)``); everything on it is vectorised NumPy: a cached kernel grid per
  window size, ``np.bincount`` for the kernel-weighted histogram, a table look-up for the weights.
- A candidate's window is the box at the current bandwidth placed on the pixel grid (its corner
  rounded to whole pixels, as on the document's integer DSP); the centre ``Y`` itself stays
  sub-pixel. The kernel grid is centred on the window, so it is the same array for every window
  of that size (sliced where the frame border clips the window).
- The document's integer forms (scales 9/10/11 with ``s`` starting at 1000, distances times
  10000 / s_t, undivided ``q_u`` and ``C``) are fixed-point encodings of the same quantities;
  this module computes them in floating point: ``scale_step = 0.1`` is the 9/10/11 and
  ``scale_smoothing = 0.1`` is ``s_k = (s_t + 90 s_(k-1)) / 100``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from vtrack.errors import FirstFrameError
from vtrack.frame import Frame
from vtrack.geometry import Box, Window
from vtrack.histograms import bhattacharyya
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, TrackState, register

ACCEPT, FAST_MOTION, OCCLUSION = "accept", "fast_motion", "occlusion"

#: Values of both features: 8-bit grey, and 8-bit hue (``COLOR_BGR2HSV_FULL``: 0..255 = 0..360 deg).
_LEVELS = 256


#: Window area one bandwidth's mean-shift steps may cover per frame, in frames (each step covers
#: its window once, reading every pixel up to SAMPLED_ABOVE of the frame): 20 steps (the
#: default) over a box of up to a tenth of the frame stay exact; a larger box gets fewer steps
#: (whole frame: 2), bounding a frame's work whatever max_iterations and epsilon say (at
#: 1280x720, with SAMPLED_ABOVE, about 5x the default box's frame at most).
ITERATION_BUDGET = 2

#: Windows larger than this share of the frame read every s-th row and column, with the smallest
#: stride s that brings them under it (a whole-frame box: every second row and column). Smaller
#: windows, every box of the real sequences included, read every pixel as the document does.
SAMPLED_ABOVE = 0.5


def sampling_stride(window_pixels: int, frame_pixels: int) -> int:
    """Read every s-th row and column of a window: 1 up to SAMPLED_ABOVE of the frame, else the
    smallest s that brings the pixels read under it (bounded work per mean-shift step)."""
    share = window_pixels / (SAMPLED_ABOVE * frame_pixels)
    return 1 if share <= 1.0 else math.ceil(math.sqrt(share))


def step_limit(max_iterations: int, window_pixels: int, frame_pixels: int) -> int:
    """Mean-shift steps one bandwidth may take: ``max_iterations``, fewer for a window so large
    that its steps would cover more than ITERATION_BUDGET frames (at least one)."""
    return min(max_iterations, max(1, ITERATION_BUDGET * frame_pixels // window_pixels))


@lru_cache(maxsize=32)
def kernel_grid(kernel: str, width: int, height: int) -> np.ndarray:
    """Kernel values at the pixel centres of a ``height`` x ``width`` window centred on the box.

    ``x*, y*`` are the pixel centres relative to the window centre, ``h_x, h_y`` the half sizes.
    The array is read-only (it is shared between calls).
    """
    hx, hy = width / 2.0, height / 2.0
    xs = np.abs(np.arange(width) + 0.5 - hx)
    ys = np.abs(np.arange(height) + 0.5 - hy)
    if kernel == "pyramid":
        # S2 eq. 3: K(X*, H) = h_x - |x*| + h_y - |y*| (plane approximation of eq. 2; >= 0 on
        # the box, 0 only at its corners)
        grid = (hx - xs)[None, :] + (hy - ys)[:, None]
    elif kernel == "epanechnikov":
        # S2 eq. 2 (Epanechnikov without its constant): 1 - (x*/h_x)^2 - (y*/h_y)^2, 0 outside
        grid = np.maximum(1.0 - (xs / hx)[None, :] ** 2 - (ys / hy)[:, None] ** 2, 0.0)
    else:  # flat: a plain (unweighted) histogram of the box
        grid = np.ones((height, width))
    grid.setflags(write=False)
    return grid


@dataclass(frozen=True)
class _Search:
    """Where one search ended: centre, bandwidth scale, similarity, mean-shift steps taken."""

    cx: float
    cy: float
    scale: float
    rho: float
    iterations: int


@dataclass(frozen=True)
class _Sample:
    """One candidate window: where it is, the bin of each pixel read (every ``stride``-th row
    and column), its histogram."""

    window: Window
    stride: int
    bins: np.ndarray
    hist: np.ndarray


@register
class KernelMeanShift(Stage):
    """S2: kernel mean shift on a quantised-grey (or hue) histogram, three bandwidths a frame."""

    name = "kernel_meanshift"
    summary = (
        "Kernel mean shift (pyramid kernel, q/p weights, histogram intersection), 3 scales, "
        "Kalman-prediction failure logic (S2)"
    )
    params = (
        Param("feature", str, "gray16",
              "pixel feature: gray16 = grey level quantised to `bins` levels (S2: m = 16), "
              "hue = 8-bit hue (0..255 = 0..360 deg) quantised to `bins`",
              choices=("gray16", "hue")),
        Param("bins", int, 16, "histogram bins m (S2: 16 grey levels)", min=2, max=256),
        Param("kernel", str, "pyramid",
              "profile of the histogram kernel: pyramid = h_x-|x*|+h_y-|y*| (S2 eq. 3), "
              "epanechnikov = 1-(x*/h_x)^2-(y*/h_y)^2 (S2 eq. 2), flat = plain histogram",
              choices=("pyramid", "epanechnikov", "flat")),
        Param("weights", str, "ratio",
              "mean-shift pixel weight: ratio = q_u/p_u (S2 sec. 2.4), "
              "sqrt = sqrt(q_u/p_u) (Comaniciu, S2 eq. 9)",
              choices=("ratio", "sqrt")),
        Param("similarity", str, "intersection",
              "histogram similarity rho that picks the scale: intersection = sum min(q_u, "
              "C p_u/C') (S2 eq. 11), bhattacharyya = sum sqrt(q_u p_u) (S2 eq. 5)",
              choices=("intersection", "bhattacharyya")),
        Param("max_iterations", int, 20,
              "cap on mean-shift steps per bandwidth (the document iterates to convergence)",
              min=1, max=100,
          ),
        Param("epsilon", float, 1.0,
              "convergence: stop when the centre moves less than this in x and in y (S2: 1 px)",
              min=0.0, max=100.0,
          ),
        Param("scale_step", float, 0.1,
              "bandwidths tried each frame: (1 - step, 1, 1 + step) x the previous one "
              "(S2: 0.9, 1.0, 1.1); 0 keeps a fixed box (one search per frame)",
              min=0.0, max=0.5),
        Param("scale_smoothing", float, 0.1,
              "gamma in s_k = gamma s_best + (1 - gamma) s_(k-1) (S2: 0.1)", min=0.0, max=1.0),
        Param("failure_logic", bool, True,
              "compare with the Kalman prediction: accept / fast motion (rerun from the "
              "prediction) / full occlusion (S2 sec. 5)"),
        Param("distance", float, 0.4,
              "threshold D on r = |x_ms - x_pred| + |y_ms - y_pred| (S2 eq. 17), in "
              "`distance_unit`s (S2 fig. 1(d): 18 <= D < 23 px for a 30x20 target, 0.4 box)",
              min=0.0, max=1e5,
          ),
        Param("distance_unit", str, "box",
              "unit of `distance`: box = the current box's width + height (D = 20 px for the "
              "document's 30x20 target, and in proportion for others), px = pixels",
              choices=("box", "px")),
        Param("occluded_update", str, "prediction",
              "what the predictor is fed on a full-occlusion frame: prediction = the frame's "
              "position, which is the prediction (S2 sec. 5 (2)(2) with eq. 14: the predictor "
              "runs on every frame's position; zero innovation, so the state coasts and V "
              "shrinks as in eq. 16), none = no measurement (the filter coasts, its covariance "
              "grows)",
              choices=("prediction", "none")),
    )
    requires = frozenset({"frame", "box", "prediction"})
    provides = frozenset({"box", "measurement", "state", "score"})
    columns = ("decision", "scale", "iterations")

    # Set from the parameters by Stage.__init__.
    feature: str
    bins: int
    kernel: str
    weights: str
    similarity: str
    max_iterations: int
    epsilon: float
    scale_step: float
    scale_smoothing: float
    failure_logic: bool
    distance: float
    distance_unit: str
    occluded_update: str

    def start(self, ctx: TrackContext) -> None:
        """Build the target model on the first frame's box (S2 algorithm step 1)."""
        box = self.initial_box(ctx)
        # S2 sec. 6.1: m levels of an 8-bit value, b(X) = value * m / 256
        self._lut = (np.arange(_LEVELS) * self.bins // _LEVELS).astype(np.uint8)
        # Trying 1.0 first and replacing only on a strictly larger rho keeps the scale on ties
        # (a window inside a uniform target scores the same at every bandwidth); the document's
        # order 9, 10, 11 with a strict "<" would keep 0.9 on ties and shrink the box.
        step = self.scale_step
        self._factors = (1.0,) if step == 0 else (1.0, 1.0 - step, 1.0 + step)
        self._size0 = (box.w, box.h)
        self._scale = 1.0
        sample = self._sample(ctx.frame, box.cx, box.cy, 1.0)
        if sample is None:
            raise FirstFrameError(f"{self.name}: the initial box {box.text()} puts no frame pixel "
                             "under S2's kernel (move it further into the frame)")
        # S2 step 1 (eqs. 1 and 3): q_u = sum K(X_i*) [b(X_i) = u] and C = sum K, not divided
        self._q = sample.hist
        self._q_norm = sample.hist / sample.hist.sum()  # q_u / C
        ctx.measurement = box
        ctx.state = TrackState.TRACKING
        ctx.score = 1.0
        ctx.extras.update(decision=ACCEPT, scale=1.0, iterations=0)

    def step(self, ctx: TrackContext) -> None:
        """Track one frame: search from the last position, then the S2 sec. 5 decision."""
        assert ctx.box is not None
        frame, prediction = ctx.frame, ctx.prediction
        limit = self.distance  # D in pixels; in box units, for the box of the last frame
        if self.distance_unit == "box":
            limit *= sum(self._box_size())
        found = self._search(frame, ctx.box.cx, ctx.box.cy)
        iterations = found.iterations
        decision = ACCEPT
        if self.failure_logic and prediction is not None and _r(found, prediction) > limit:
            # S2 sec. 5 (2): r > D, rerun the search starting at the prediction -> r'
            found = self._search(frame, prediction.cx, prediction.cy)
            iterations += found.iterations
            decision = FAST_MOTION if _r(found, prediction) <= limit else OCCLUSION
        if decision == OCCLUSION:
            # S2 sec. 5 (2)(2): full occlusion, the position is the prediction (the next frame
            # starts there) and the scale is kept. Eq. 14 runs on every frame's position x_(k-1),
            # so the predictor is fed the prediction itself (occluded_update = "prediction");
            # "none" gives it no measurement.
            assert prediction is not None
            ctx.box = Box.from_center(prediction.cx, prediction.cy, *self._box_size())
            ctx.measurement = ctx.box if self.occluded_update == "prediction" else None
            ctx.state = TrackState.OCCLUDED
        else:
            self._scale = found.scale
            ctx.box = Box.from_center(found.cx, found.cy, *self._box_size())
            ctx.measurement = ctx.box
            ctx.state = TrackState.TRACKING
        ctx.score = found.rho
        ctx.extras.update(decision=decision, scale=self._scale, iterations=iterations)

    # --- the optimised algorithm of S2 sec. 3 -------------------------------------------------

    def _search(self, frame: Frame, cx: float, cy: float) -> _Search:
        """Steps 2-7: converge at each bandwidth from (cx, cy), keep the best rho, update s."""
        best: _Search | None = None
        iterations = 0
        for factor in self._factors:
            found = self._converge(frame, cx, cy, self._scale * factor)
            iterations += found.iterations
            if best is None or found.rho > best.rho:
                best = found
        assert best is not None
        # S2 step 7 / note 2: s_k = 0.1 s_best + 0.9 s_(k-1)
        gamma = self.scale_smoothing
        scale = gamma * best.scale + (1.0 - gamma) * self._scale
        # Bounded work and memory (docs/stages.md, Limits): the box never outgrows the frame.
        scale = min(scale, frame.width / self._size0[0], frame.height / self._size0[1])
        return _Search(best.cx, best.cy, scale, best.rho, iterations)

    def _converge(self, frame: Frame, cx: float, cy: float, scale: float) -> _Search:
        """Steps 3-6 at one bandwidth: mean-shift steps from (cx, cy) until it moves < epsilon."""
        sample = self._sample(frame, cx, cy, scale)
        iterations, limit = 0, self.max_iterations
        if sample is not None:  # bounded work: at most ITERATION_BUDGET frames of window area
            limit = step_limit(limit, sample.window.width * sample.window.height,
                               frame.width * frame.height)
        while sample is not None and iterations < limit:
            iterations += 1
            # S2 step 4: w_i = q_u / p_u(Y) for the bin u of pixel i (sec. 2.4: the square of
            # Comaniciu's eq. 9 weight); the undivided C/C' factor cancels in step 5
            table = np.divide(self._q, sample.hist, out=np.zeros_like(self._q),
                              where=sample.hist > 0)
            if self.weights == "sqrt":
                table = np.sqrt(table)  # S2 eq. 9
            # table[sample.bins], by OpenCV's lookup (a 256-entry table; the same values)
            w = cv2.LUT(sample.bins, np.pad(table, (0, _LEVELS - table.size)))
            column_sums, row_sums = w.sum(axis=0), w.sum(axis=1)
            total = column_sums.sum()
            if total <= 0:  # no pixel of the window carries a model bin: no mean-shift vector
                break
            # S2 step 5 (eq. 10 with g = 1): Y' = sum X_i w_i / sum w_i. Eq. 10's g = -k' is 1
            # for the Epanechnikov profile; the pyramid (and flat) kernels have no radial profile
            # (the pyramid's derivative is a constant-magnitude sign), so, as the document does,
            # every kernel steps with g = 1: the kernel shapes the histograms, the step is the
            # weighted mean of the window's pixel centres X_i.
            window, stride = sample.window, sample.stride
            nx = float(column_sums @ (np.arange(window.x0, window.x1, stride) + 0.5)) / total
            ny = float(row_sums @ (np.arange(window.y0, window.y1, stride) + 0.5)) / total
            # S2 step 6: go on while |dx| >= 1 or |dy| >= 1 pixel
            moved = abs(nx - cx) >= self.epsilon or abs(ny - cy) >= self.epsilon
            cx, cy = nx, ny
            sample = self._sample(frame, cx, cy, scale, reuse=sample)
            if not moved:
                break
        rho = 0.0 if sample is None else self._rho(sample.hist)
        return _Search(cx, cy, scale, rho, iterations)

    def _rho(self, hist: np.ndarray) -> float:
        """Similarity of a candidate histogram to the model, 0..1 (1: same distribution)."""
        if self.similarity == "bhattacharyya":
            return bhattacharyya(hist, self._q)  # S2 eq. 5
        # S2 step 6 / eq. 11: histogram intersection sum min(q_u, C p_u / C'), divided by C
        return float(np.minimum(self._q_norm, hist / hist.sum()).sum())

    def _box_size(self, scale: float | None = None) -> tuple[float, float]:
        """The box size at ``scale`` (default: the current scale) x the initial box size."""
        scale = self._scale if scale is None else scale
        return self._size0[0] * scale, self._size0[1] * scale

    def _sample(
        self, frame: Frame, cx: float, cy: float, scale: float, reuse: _Sample | None = None
    ) -> _Sample | None:
        """Kernel-weighted histogram of the box at ``scale`` centred on (cx, cy); None if the box
        is outside the frame. ``reuse`` is returned as it is when the window did not change."""
        bw, bh = self._box_size(scale)
        width, height = max(round(bw), 1), max(round(bh), 1)
        x0, y0 = math.floor(cx - width / 2 + 0.5), math.floor(cy - height / 2 + 0.5)
        window = Box(x0, y0, width, height).window(frame.width, frame.height)
        if window is None:
            return None
        if reuse is not None and reuse.window == window:
            return reuse
        stride = sampling_stride(window.width * window.height, frame.width * frame.height)
        grid = kernel_grid(self.kernel, width, height)
        grid = grid[window.y0 - y0 : window.y1 - y0 : stride,
                    window.x0 - x0 : window.x1 - x0 : stride]
        if self.feature == "hue":
            values = cv2.cvtColor(_every(frame.bgr(window), stride),
                                  cv2.COLOR_BGR2HSV_FULL)[:, :, 0]
        else:
            values = _every(frame.gray(window), stride)
        bins = cv2.LUT(values, self._lut)  # b(X_i) of S2 eq. 1 (as self._lut[values])
        # S2 step 3 (eqs. 3 and 4): p_u(Y) = sum K(X_i*) [b(X_i) = u], undivided
        hist = np.bincount(bins.ravel(), weights=grid.ravel(), minlength=self.bins)
        if hist.sum() <= 0:
            return None
        return _Sample(window, stride, bins, hist)


def _every(pixels: np.ndarray, stride: int) -> np.ndarray:
    """Every ``stride``-th row and column of ``pixels`` (the array itself for stride 1), laid
    out as OpenCV reads it."""
    return pixels if stride == 1 else np.ascontiguousarray(pixels[::stride, ::stride])


def _r(found: _Search, prediction: Box) -> float:
    """S2 eq. 17: r = |x_ms - x_pred| + |y_ms - y_pred| (centres).

    A search that saw no pixel of a model bin (``rho = 0``: its window is outside the frame or
    holds none of the target's values) has no mean-shift position: it did not move because it
    could not, not because it agrees with the prediction. Its ``r`` is infinite, the failure the
    document defines (sec. 5: the window holds no target information).
    """
    if found.rho <= 0:
        return math.inf
    return abs(found.cx - prediction.cx) + abs(found.cy - prediction.cy)
