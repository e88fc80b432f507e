"""S2's integer-only DSP loop (``configs/s2-fixed.toml``): the golden model of a fixed-point port.

Di & Zhu 2008 (S2, sec. 3 and 5) with the integer
arithmetic of :mod:`vtrack.golden.s2`: integer kernel, undivided ``q_u`` and ``C``, weights
``(q_u << F) // p_u``, a rounded integer step, histogram intersection ``sum min(q_u, C p_u //
C')``, scales 9/10/11 with ``s`` from 1000 and ``s_k = (s_t + 90 s_(k-1)) // 100``. Positions
are integer pixels (a vtrack box centre is the pixel + 0.5). The Kalman predictor of sec. 5 runs
on the document's second DSP and is given no integer form: the chain keeps the float
``kalman(model = "ca")`` stage, whose prediction enters the integer loop as the pixel holding it.

Stage ``kernel_meanshift_int``: reads ``ctx.box`` (last position) and ``ctx.prediction``;
writes ``ctx.box``, ``ctx.measurement``, ``ctx.state``, ``ctx.score`` (rho / C, 0..1) and
``ctx.fixed`` (trace row per frame, ``iterations`` per mean-shift iteration for
``vtrack vectors``).
"""

from __future__ import annotations

import math

import numpy as np

from vtrack.errors import FirstFrameError
from vtrack.frame import Frame
from vtrack.geometry import Box
from vtrack.golden import s2
from vtrack.golden.record import FixedRecord
from vtrack.golden.s0 import split_rgb
from vtrack.params import Param
from vtrack.stages.base import ONE_RECORD_RULE, Stage, TrackContext, TrackState, register
from vtrack.stages.kernel_meanshift import SAMPLED_ABOVE, step_limit

ACCEPT, FAST_MOTION, OCCLUSION = "accept", "fast_motion", "occlusion"
#: r of a search with no position (rho = 0): above any D (empty in the trace).
NO_POSITION = 1 << 62


@register
class KernelMeanShiftInt(Stage):
    """S2 sec. 3 in integers: pyramid kernel, q/p weights, intersection, scales 9/10/11."""

    name = "kernel_meanshift_int"
    summary = "S2 bit-exact: the integer DSP loop (scales 9/10/11 of s from 1000), failure logic"
    params = (
        Param("bins", int, 16, "grey levels m, b = grey * m >> 8 (S2 sec. 6.1: 16)",
              min=2, max=256),
        Param("weight_frac_bits", int, 8,
              "F in w_u = (q_u << F) // p_u (the document divides integers and gives no "
              "scale; 0 = plain integer quotient)", min=0, max=24),
        Param("rounding", str, "nearest",
              "integer division of the step: nearest (half away from zero), floor, trunc",
              choices=("nearest", "floor", "trunc")),
        Param("max_iterations", int, 20,
              "cap on mean-shift steps per scale (the document iterates until |d| < 1)", min=1,
              max=100),
        Param("scale_order", str, "keep",
              "order the scales are tried, a strictly larger rho replaces: keep = 10, 9, 11 "
              "(ties keep the scale, as the float s2); document = 9, 10, 11 (ties shrink)",
              choices=("keep", "document")),
        Param("failure_logic", bool, True,
              "S2 sec. 5: accept / fast motion (rerun from the prediction) / full occlusion"),
        Param("distance", int, 400,
              "D of eq. 17 on the integer r = |x - x_pred| + |y - y_pred|: permille of the "
              "box's w + h (distance_unit = box; 400 = the float s2's 0.4) or pixels (px)",
              min=0, max=100000),
        Param("distance_unit", str, "box", "box = permille of w + h; px = pixels",
              choices=("box", "px")),
    )
    requires = frozenset({"frame", "box", "prediction"})
    provides = frozenset({"box", "measurement", "state", "score", "fixed"})
    columns = ("decision", "scale", "iterations")
    rules = (ONE_RECORD_RULE,)

    bins: int
    weight_frac_bits: int
    rounding: str
    max_iterations: int
    scale_order: str
    failure_logic: bool
    distance: int
    distance_unit: str
    #: The record of the current run (None before the first frame).
    record: FixedRecord | None = None

    def start(self, ctx: TrackContext) -> None:
        """Step 1: the model q_u, C over the initial box, centre pixel, h = size // 2, s = 1000."""
        box = self.initial_box(ctx)
        self.record = ctx.fixed = FixedRecord(model="s2")
        self._size0 = (box.w, box.h)
        self._h = (max(round(box.w), 1) // 2, max(round(box.h), 1) // 2)
        self._s = 1000
        self._pos = (math.floor(box.cx), math.floor(box.cy))
        self._frame_bins = None
        model = self._sample(ctx.frame, *self._pos, 10000)
        if model is None:
            raise FirstFrameError(f"{self.name}: the initial box {box.text()} puts no frame pixel "
                             "under S2's kernel (move it further into the frame)")
        self._q, self._c = model.hist, model.total
        self.record.hist, self.record.hist_max = model.hist, int(model.hist.max())
        self.record.iterations = []
        self._trace(ctx, ACCEPT, None, self._pos, 0, -1, -1, self._c)
        ctx.measurement = box
        ctx.state = TrackState.TRACKING
        ctx.score = 1.0
        ctx.extras.update(decision=ACCEPT, scale=1.0, iterations=0)

    def step(self, ctx: TrackContext) -> None:
        """Steps 2-7 from the last position, then the sec. 5 decision (eq. 17)."""
        record = ctx.fixed = self.record
        assert record is not None
        record.iterations = []
        self._frame_bins = None  # this frame's grey bins, made on the first sample
        prediction = ctx.prediction
        pred = None if prediction is None else (math.floor(prediction.cx),
                                                  math.floor(prediction.cy))
        limit = self.distance
        if self.distance_unit == "box":
            w, h = self._box_size()
            limit = self.distance * (round(w) + round(h)) // 1000
        pos, s_new, rho, steps = self._search(ctx.frame, self._pos, 0)
        decision, r, r2 = ACCEPT, -1, -1
        if self.failure_logic and pred is not None:
            r = _r(pos, rho, pred)
            if r > limit:  # sec. 5 (2): rerun from the prediction
                pos, s_new, rho, more = self._search(ctx.frame, pred, 1)
                steps += more
                r2 = _r(pos, rho, pred)
                decision = FAST_MOTION if r2 <= limit else OCCLUSION
        if decision == OCCLUSION:
            assert pred is not None
            self._pos = pred  # sec. 5 (2)(2): the prediction; the scale is kept
            ctx.state = TrackState.OCCLUDED
        else:
            self._pos, self._s = pos, s_new
            ctx.state = TrackState.TRACKING
        ctx.box = Box.from_center(self._pos[0] + 0.5, self._pos[1] + 0.5, *self._box_size())
        ctx.measurement = ctx.box
        ctx.score = rho / self._c
        self._trace(ctx, decision, pred, pos, steps, r, r2, rho)
        ctx.extras.update(decision=decision, scale=self._s / 1000, iterations=steps)

    # --- the loop of sec. 3 ------------------------------------------------------------------

    def _search(self, frame: Frame, start: tuple[int, int],
                search: int) -> tuple[tuple[int, int], int, int, int]:
        """Steps 2-7 from ``start``: each scale converges, the largest rho is kept, s updated.
        Returns ``(position, s_k, rho, iterations)``."""
        factors = (10, 9, 11) if self.scale_order == "keep" else (9, 10, 11)
        best: tuple[tuple[int, int], int, int] | None = None  # position, s_temp, rho
        steps = 0
        for factor in factors:
            s_t = factor * self._s
            pos, rho, n = self._converge(frame, start, s_t, search)
            steps += n
            if best is None or rho > best[2]:  # step 6: rho_temp < rho
                best = (pos, s_t + 90 * self._s, rho)  # s_temp = s_t + 90 s
        assert best is not None
        return best[0], best[1] // 100, best[2], steps  # s_k = s_temp / 100

    def _converge(self, frame: Frame, start: tuple[int, int], s_t: int,
                  search: int) -> tuple[tuple[int, int], int, int]:
        """Steps 3-6 at scale ``s_t``: returns the converged pixel, its rho, the steps taken."""
        x, y = start
        smp = self._sample(frame, x, y, s_t)
        steps, limit = 0, self.max_iterations
        frame_pixels = frame.width * frame.height
        if smp is not None and smp.bins.size > SAMPLED_ABOVE * frame_pixels:
            # bounded work for a window over half the frame, as the float s2 (smaller windows,
            # those of every real sequence, step as the DSP loop does, bit for bit)
            limit = step_limit(limit, smp.bins.size, frame_pixels)
        row: dict[str, object] = {}
        while smp is not None and steps < limit:
            steps += 1
            table = s2.weights(self._q, smp.hist, self.weight_frac_bits)  # step 4
            dx, dy, total, sx, sy = s2.shift(smp, table, self.rounding)  # step 5
            row = {"frame": frame.index, "search": search, "s_t": s_t, "iteration": steps,
                   "x": x, "y": y, "c_prime": smp.total, "sum_w": total, "sum_w_dx": sx,
                   "sum_w_dy": sy, "new_x": x + dx, "new_y": y + dy, "rho": ""}
            assert self.record is not None
            self.record.iterations.append(row)
            x, y = x + dx, y + dy
            if dx == 0 and dy == 0:  # step 6: |dx| < 1 and |dy| < 1
                break
            smp = self._sample(frame, x, y, s_t)
        rho = 0 if smp is None else s2.intersection(self._q, self._c, smp.hist, smp.total)
        if row:
            row["rho"] = rho
        return (x, y), rho, steps

    def _sample(self, frame: Frame, x: int, y: int, s_t: int) -> s2.Sample | None:
        if self._frame_bins is None:
            # the grey bins of the whole frame (cheap next to the loop; a window-only read
            # would re-convert overlapping windows every iteration)
            r, g, b = split_rgb(frame.bgr())
            self._frame_bins = (s2.gray8(r, g, b).astype(np.int64) * self.bins) >> 8
        return s2.sample(self._frame_bins, x, y, *self._h, s_t, self.bins)

    def _box_size(self) -> tuple[float, float]:
        return self._size0[0] * self._s / 1000, self._size0[1] * self._s / 1000

    def _trace(self, ctx: TrackContext, decision: str, pred: tuple[int, int] | None,
               found: tuple[int, int], steps: int, r: int, r2: int, rho: int) -> None:
        assert self.record is not None
        box = Box.from_center(self._pos[0] + 0.5, self._pos[1] + 0.5, *self._box_size())
        self.record.trace = {
            "frame": ctx.frame.index, "pred_x": "" if pred is None else pred[0],
            "pred_y": "" if pred is None else pred[1], "found_x": found[0], "found_y": found[1],
            "r": "" if r < 0 or r >= NO_POSITION else r,
            "r_prime": "" if r2 < 0 or r2 >= NO_POSITION else r2, "decision": decision,
            "x": self._pos[0], "y": self._pos[1], "s": self._s, "rho": rho, "c": self._c,
            "iterations": steps, "box_x": box.x, "box_y": box.y, "box_w": box.w, "box_h": box.h,
        }


def _r(pos: tuple[int, int], rho: int, pred: tuple[int, int]) -> int:
    """Eq. 17 in integers; a search that saw no model bin (rho = 0) has no position: r is
    larger than any D (as the float s2)."""
    if rho <= 0:
        return NO_POSITION
    return abs(pos[0] - pred[0]) + abs(pos[1] - pred[1])

