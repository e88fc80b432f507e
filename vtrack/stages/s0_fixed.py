"""S0 in the FPGA's own arithmetic (``configs/s0-fixed.toml``): the golden model of an RTL design.

Liu et al. 2022 (S0), with the arithmetic of
:mod:`vtrack.golden.s0`: integers end to end except the Kalman filter, which is IEEE float32
as the document's floating-point IP computes it (sec. 3, fig. 13-14). Three stages:

- ``hue_bp_fixed``: the search window is the target-sized box centred on an integer pixel
  (sec. 1: the Kalman prediction "is the search window"): ``win = c - w // 2``. Its exact 8-bit
  hue (eq. 1), on the first frame the 256 integer counters of eq. 2-3 over the initial box and
  the table of eq. 4, ``BP = floor(hist * 255 / max)``; an integer S/V mask as an option (the
  document has none);
- ``meanshift_fixed``: the integer sums of eq. 6-7 about ``ref = win + w // 2`` and one step per
  frame (sec. 2.3), ``weighted`` (/ sum_bp) or ``paper`` (/ (n * 255)), in units of
  ``2^-step_frac_bits`` pixel with a declared rounding; occlusion (S0 sec. 3, not specified by
  the document) as an integer comparison of ``sum_bp`` with the first frame's;
- ``kalman_f32``: eq. 10-17 per axis in float32 (:class:`vtrack.golden.s0.KalmanF32`); the
  prediction, rounded to the nearest pixel, centres the next window.

Coordinates: the hardware's integer pixel index ``c``; a vtrack box centre is ``c + 0.5`` (pixel
``i`` covers ``[i, i + 1)``). What the stages share is :class:`vtrack.golden.record.FixedRecord`
in ``ctx.fixed``; ``ctx.fixed.trace`` is the frame's row of ``vtrack vectors``' trace.csv.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from vtrack.errors import FirstFrameError
from vtrack.geometry import Box, Window
from vtrack.golden import s0
from vtrack.golden.record import FixedRecord
from vtrack.histograms import refuse_colourless
from vtrack.overlays import SearchWindow
from vtrack.params import Param
from vtrack.stages.base import ONE_RECORD_RULE, Stage, TrackContext, TrackState, register
from vtrack.stages.occlusion import best_placement


def integer_window(box: Box) -> tuple[int, int, int, int, int, int]:
    """The document's integer window of ``box``: ``(x, y, w, h, cx, cy)`` with ``(cx, cy)``
    the pixel holding the box centre and ``x = cx - w // 2`` (``w = max(round(box.w), 1)``)."""
    w, h = max(round(box.w), 1), max(round(box.h), 1)
    cx, cy = math.floor(box.cx), math.floor(box.cy)
    return cx - w // 2, cy - h // 2, w, h, cx, cy


#: The rule of a stage reading hue_bp_fixed's S0 record (:func:`_s0_record_problem`).
_S0_RECORD_RULE = "hue_bp_fixed before this stage (it reads its S0 fixed-point record)"


def _s0_record_problem(before: list[str]) -> str | None:
    """Why a stage reading hue_bp_fixed's S0 record cannot follow the stages ``before`` (the
    chain's fixed-point record is then another document's, S2's; None: it can)."""
    if "hue_bp_fixed" not in before:
        return ("it reads the S0 fixed-point record of hue_bp_fixed, which must come before "
                "it (kernel_meanshift_int keeps S2's, another model)")
    return None


def _record(ctx: TrackContext) -> FixedRecord:
    """The S0 record of ``hue_bp_fixed`` (a chain's check refuses one without it, or with
    another model's record: config.check_chain, Pipeline)."""
    assert ctx.fixed is not None and ctx.fixed.model == "s0", "S0's record: checked chain"
    return ctx.fixed


@register
class HueBpFixed(Stage):
    """S0 sec. 2.1-2.2 in integers: exact 8-bit hue, 20-bit histogram, BP = floor(hist*255/max)."""

    name = "hue_bp_fixed"
    summary = ("S0 sec. 2.1-2.2 bit-exact: integer hue (eq. 1), histogram (eq. 2-3), BP (eq. 4) "
               "on the window")
    params = (
        Param("hist_bits", int, 20,
              "width of each of the 256 histogram counters; they saturate at 2^bits - 1 (S0 "
              "eq. 2: reg[19:0], 20 bits)", min=1, max=40),
        Param("hue_divider_bits", int, 0,
              "0 = exact divider (floor of the rational); k > 0 = truncating fixed-point "
              "reciprocal of k fractional bits, floor(17 N floor(2^k / 24d) / 2^k)",
              min=0, max=40),
        Param("sat_min", int, 0,
              "integer mask: pixels with 255 (max - min) < sat_min * max are left out of the "
              "model and back-project to 0 (S0: none, 0; the shipped s0: 60)", min=0, max=255),
        Param("val_min", int, 0,
              "integer mask: pixels with max(R, G, B) < val_min are left out (S0: 0; s0: 32)",
              min=0, max=255),
    )
    requires = frozenset({"frame", "box", "prediction"})
    provides = frozenset({"window", "feature", "likelihood", "fixed"})
    rules = (ONE_RECORD_RULE,)

    hist_bits: int
    hue_divider_bits: int
    sat_min: int
    val_min: int
    #: The record of the current run (None before the first frame).
    record: FixedRecord | None = None

    def start(self, ctx: TrackContext) -> None:
        """Frame 0: the window is the initial box; count the model over it (eq. 2-3)."""
        box = self.initial_box(ctx)
        record = FixedRecord(model="s0", sat_min=self.sat_min, val_min=self.val_min,
                             hue_divider_bits=self.hue_divider_bits)
        ctx.fixed = self.record = record  # the record is also the stage's (vtrack vectors)
        x, y, w, h, cx, cy = integer_window(box)
        record.size = (w, h)
        hue, mask = self._window(ctx, record, x, y, w, h, cx, cy)
        assert ctx.window is not None
        refuse_colourless(ctx.frame.bgr(ctx.window), self.name, box.text())
        record.hist = s0.histogram(hue, mask, self.hist_bits)
        record.hist_max = int(record.hist.max())
        if record.hist_max == 0:
            raise FirstFrameError(
                f"hue_bp_fixed: no pixel of the initial box {box.text()} passes the S/V mask "
                "(lower hue_bp_fixed.sat_min / val_min)"
            )
        record.bp_lut = s0.bp_table(record.hist)
        self._backproject(ctx, record, hue, mask)

    def step(self, ctx: TrackContext) -> None:
        """Later frames: the window at the pixel the Kalman prediction (or the last box) names."""
        record = _record(ctx)
        assert ctx.box is not None
        width, height = ctx.frame.width, ctx.frame.height
        # the target size, widened (in permille) while the target is hidden
        w, h = (max(side * record.growth // 1000, 1) for side in record.size)
        centre = ctx.search_center
        cx, cy = math.floor(centre.cx), math.floor(centre.cy)
        # a centre outside the frame is moved to its nearest pixel (the window keeps looking at
        # the border the target left by)
        cx, cy = min(max(cx, 0), width - 1), min(max(cy, 0), height - 1)
        hue, mask = self._window(ctx, record, cx - w // 2, cy - h // 2, w, h, cx, cy)
        self._backproject(ctx, record, hue, mask)

    def _window(self, ctx: TrackContext, record: FixedRecord, x: int, y: int, w: int, h: int,
                cx: int, cy: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Set the window, compute its hue (and mask); returns both."""
        frame = ctx.frame
        window = Box(x, y, w, h).window(frame.width, frame.height)
        if window is None:
            window = Window(min(max(cx, 0), frame.width - 1), min(max(cy, 0), frame.height - 1),
                            min(max(cx, 0), frame.width - 1) + 1,
                            min(max(cy, 0), frame.height - 1) + 1)
        record.window = (x, y, w, h)
        record.ref = (x + w // 2, y + h // 2)
        r, g, b = s0.split_rgb(frame.bgr(window))
        hue = s0.hue8(r, g, b, self.hue_divider_bits)  # eq. 1
        mask = s0.optional_mask(r, g, b, self.sat_min, self.val_min)
        ctx.window = window
        ctx.feature = hue
        ctx.overlays.append(SearchWindow(window.as_box()))
        record.trace = {"frame": frame.index, "win_x": x, "win_y": y, "win_w": w, "win_h": h}
        return hue, mask

    def _backproject(self, ctx: TrackContext, record: FixedRecord, hue: np.ndarray,
                     mask: np.ndarray | None) -> None:
        assert record.bp_lut is not None
        record.bp = ctx.likelihood = s0.back_project(record.bp_lut, hue, mask)  # eq. 4


@register
class MeanShiftFixed(Stage):
    """S0 sec. 2.3 and sec. 3's occlusion in integers: eq. 6-7 sums about win + w//2, one rounded
    step per frame."""

    name = "meanshift_fixed"
    summary = ("S0 sec. 2.3 bit-exact: integer sums of eq. 6-7, one rounded step; integer "
               "occlusion test")
    params = (
        Param("normalization", str, "weighted",
              "step = sum_bp_dx / sum_bp (weighted centroid, the usual mean-shift step) or "
              "sum_bp_dx / (n * 255) (paper: eq. 6-7 as printed)",
              choices=("weighted", "paper")),
        Param("step_frac_bits", int, 0,
              "fractional bits of the step and of the measured centre (0: whole pixels)",
              min=0, max=16),
        Param("rounding", str, "nearest",
              "integer division of the step: nearest (half away from zero), floor, trunc "
              "(toward zero, Verilog /)", choices=("nearest", "floor", "trunc")),
        Param("occlusion_permille", int, 150,
              "hidden when 1000 sum_bp < this x the first frame's sum_bp (S0 sec. 3; the "
              "document gives no rule; 0 = never)", min=0, max=1000),
        Param("recover_permille", int, 250,
              "visible again when 1000 sum_bp >= this x the first frame's (hysteresis)",
              min=0, max=1000),
        Param("lost_after", int, 60,
              "hidden frames after which the state is lost, not occluded (frames given, as "
              "s0's occlusion counts them)", min=1,
              max=100000),
        Param("growth_permille", int, 1100,
              "while hidden the window widens by this / 1000 per frame (integer, floor), and "
              "the target's return is looked for at the target-sized box of largest sum_bp "
              "in it (not in S0; as the float s0's occlusion stage)", min=1000, max=4000),
        Param("search_permille", int, 2000,
              "while hidden the window starts at this size, permille of the target size (the "
              "float s0's hue.search_scale = 2.0)", min=1000, max=10000),
        Param("max_growth_permille", int, 3000,
              "largest widening while hidden, permille of search_permille", min=1000,
              max=10000),
    )
    requires = frozenset({"window", "likelihood", "fixed"})
    provides = frozenset({"measurement", "box", "state", "score"})
    columns = ("sum_bp", "step_x", "step_y")
    rules = (_S0_RECORD_RULE,)

    @classmethod
    def chain_problem(cls, values: dict[str, Any], before: list[str]) -> str | None:
        return _s0_record_problem(before)

    normalization: str
    step_frac_bits: int
    rounding: str
    occlusion_permille: int
    recover_permille: int
    lost_after: int
    growth_permille: int
    search_permille: int
    max_growth_permille: int

    def start(self, ctx: TrackContext) -> None:
        """Frame 0: the sums over the initial box are the occlusion reference; no step."""
        record = _record(ctx)
        sums = self._sums(record)
        record.initial_sum = sums.sum_bp
        self._hidden = 0
        record.trace.update(cand_x=record.ref[0], cand_y=record.ref[1], cand_sum=sums.sum_bp)
        self._write(ctx, record, sums, (0, 0), record.ref)
        record.trace["measured"] = 1
        ctx.measurement = ctx.box
        ctx.state = TrackState.TRACKING
        ctx.score = 1.0

    def step(self, ctx: TrackContext) -> None:
        record = _record(ctx)
        sums = self._sums(record)
        w, h = record.size
        if ctx.state == TrackState.TRACKING:
            shift = s0.step(sums, self.normalization, self.step_frac_bits, self.rounding)
            centre, mass = record.ref, sums.sum_bp
        else:  # hidden: the target-sized box of the (widened) window with the largest sum_bp
            shift = (0, 0)
            centre, mass = self._best_box(ctx, record)
        measured = self._visible(ctx, record, mass)
        record.trace.update(cand_x=centre[0], cand_y=centre[1], cand_sum=mass)
        self._write(ctx, record, sums, shift, centre)
        record.trace["measured"] = int(measured)
        ctx.score = mass / record.initial_sum if record.initial_sum else 0.0
        if measured:
            record.growth = 1000
            one = 1 << self.step_frac_bits
            cx = centre[0] + shift[0] / one + 0.5
            cy = centre[1] + shift[1] / one + 0.5
            ctx.measurement = ctx.box = Box.from_center(cx, cy, w, h)
        else:
            # S0 sec. 3: the measurement is not used; the position is the window (prediction)
            record.growth = min(
                max(record.growth, self.search_permille) * self.growth_permille // 1000,
                self.search_permille * self.max_growth_permille // 1000)
            ctx.measurement = None
            ctx.box = Box(record.ref[0] - w // 2, record.ref[1] - h // 2, w, h)

    def _sums(self, record: FixedRecord) -> s0.WindowSums:
        assert record.bp is not None
        x, y, w, h = record.window
        ref_x, ref_y = record.ref
        # the in-frame part of the window starts at its clipped corner
        x0, y0 = max(x, 0), max(y, 0)
        return s0.window_sums(record.bp, x0, y0, ref_x, ref_y)

    def _best_box(self, ctx: TrackContext, record: FixedRecord) -> tuple[tuple[int, int], int]:
        """Centre pixel and sum_bp of the target-sized box of largest sum_bp in the window
        (first in raster order on ties), from an exact summed-area table."""
        assert record.bp is not None and ctx.window is not None
        rows, cols = record.bp.shape
        w, h = min(record.size[0], cols), min(record.size[1], rows)
        left, top, total = best_placement(record.bp, w, h)
        return (ctx.window.x0 + left + w // 2, ctx.window.y0 + top + h // 2), int(total)

    def _visible(self, ctx: TrackContext, record: FixedRecord, mass: int) -> bool:
        """Hysteresis on 1000 sum_bp against permille x the first frame's sum_bp."""
        scaled, initial = 1000 * mass, record.initial_sum
        if ctx.state == TrackState.TRACKING:
            visible = scaled >= self.occlusion_permille * initial
        else:
            visible = scaled >= max(self.recover_permille, self.occlusion_permille) * initial
        if visible and mass > 0:
            self._hidden = 0
            ctx.state = TrackState.TRACKING
            return True
        self._hidden += 1
        ctx.state = TrackState.LOST if self._hidden > self.lost_after else TrackState.OCCLUDED
        return False

    def _write(self, ctx: TrackContext, record: FixedRecord, sums: s0.WindowSums,
               shift: tuple[int, int], centre: tuple[int, int]) -> None:
        record.trace.update(sum_bp=sums.sum_bp, sum_bp_dx=sums.sum_bp_dx,
                            sum_bp_dy=sums.sum_bp_dy, n=sums.n, step_x=shift[0], step_y=shift[1])
        record.measured_fixed = (
            (centre[0] << self.step_frac_bits) + shift[0],
            (centre[1] << self.step_frac_bits) + shift[1],
            self.step_frac_bits,
        )
        ctx.extras.update(sum_bp=sums.sum_bp, step_x=shift[0], step_y=shift[1])


@register
class KalmanF32Stage(Stage):
    """S0 sec. 3 in IEEE float32, eq. 10-17 operation by operation, one filter per axis."""

    name = "kalman_f32"
    summary = ("S0 sec. 3 bit-exact: per-axis (x, dx) Kalman in float32, eq. 10-17 in the "
               "paper's order")
    params = (
        Param("q", float, 1.0, "Q = q I (S0 eq. 11: I)", min=0.0, max=1e6),
        Param("r", float, 1.0, "R (S0 eq. 13: 1)", min=1e-6, max=1e6),
        Param("p0", float, 100.0, "P0 = p0 I (not given in S0; 100 I)", min=0.0, max=1e6),
    )
    requires = frozenset({"measurement", "box", "fixed"})
    provides = frozenset({"box", "prediction"})
    columns = ("pred_cx", "pred_cy")
    rules = (_S0_RECORD_RULE,)

    @classmethod
    def chain_problem(cls, values: dict[str, Any], before: list[str]) -> str | None:
        return _s0_record_problem(before)

    q: float
    r: float
    p0: float

    def start(self, ctx: TrackContext) -> None:
        """Start each axis at the initial window's reference pixel, at rest, P = p0 I."""
        record = _record(ctx)
        self._axes = tuple(s0.KalmanF32(c, self.p0, self.q, self.r) for c in record.ref)
        self._finish(ctx, record, measured=False)

    def step(self, ctx: TrackContext) -> None:
        record = _record(ctx)
        if ctx.prediction is not None:
            ctx.extras.update(pred_cx=ctx.prediction.cx, pred_cy=ctx.prediction.cy)
        measured = ctx.measurement is not None
        if measured:
            fx, fy, bits = record.measured_fixed
            one = s0.F32(1 << bits)
            for axis, value in zip(self._axes, (fx, fy), strict=True):
                axis.update(s0.F32(value) / one)  # exact: |value| < 2^24, one a power of 2
        else:
            for axis in self._axes:
                axis.coast()
        for axis in self._axes:
            axis.predict()
        self._finish(ctx, record, measured)

    def _finish(self, ctx: TrackContext, record: FixedRecord, measured: bool) -> None:
        """Trace the filter and place the next window at the rounded prediction."""
        for name, axis in zip("xy", self._axes, strict=True):
            for key, value in axis.values.items():
                record.trace[f"k{name}_{key}"] = float(value)
                record.trace[f"k{name}_{key}_hex"] = s0.f32_hex(value)
        px, py = (s0.f32_to_int(axis.values["l1"]) for axis in self._axes)
        record.trace.update(pred_x=px, pred_y=py)
        assert ctx.box is not None
        ctx.prediction = Box.from_center(px + 0.5, py + 0.5, ctx.box.w, ctx.box.h)
        box = ctx.box
        record.trace.update(box_x=box.x, box_y=box.y, box_w=box.w, box_h=box.h)
