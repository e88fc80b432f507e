"""S0 golden model (configs/s0-fixed.toml): each integer / float32 step against an independent
computation written another way - the hue on all 2^24 RGB values, BP and the window sums of a
generated frame, the Kalman float32 sequence - and the chain end to end on generated scenes."""

from __future__ import annotations

import itertools
import math
import struct
from fractions import Fraction

import numpy as np
import pytest

from vtrack.config import load_config
from vtrack.frame import BgrFrame
from vtrack.geometry import Box, iou
from vtrack.golden import s0
from vtrack.pipeline import Pipeline
from vtrack.stages.base import TrackContext


def hue_by_sextant(r: np.ndarray, g: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Eq. 1 another way: H_deg = 60 * h6 / d with h6 the position in sixths of the circle,
    ``(G - B) mod 6d``, ``(B - R) + 2d``, ``(R - G) + 4d``; H8 = floor(255 h6 / (6 d))."""
    hi = np.maximum(np.maximum(r, g), b)
    d = hi - np.minimum(np.minimum(r, g), b)
    h6 = np.select([hi == r, hi == g], [np.mod(g - b, 6 * np.maximum(d, 1)), b - r + 2 * d],
                   r - g + 4 * d)
    return np.where(d == 0, 0, (255 * h6) // (6 * np.maximum(d, 1)))


def hue_fraction(r: int, g: int, b: int) -> int:
    """Eq. 1 with Python fractions, branch by branch as printed (G branch: B - R)."""
    hi, lo = max(r, g, b), min(r, g, b)
    if hi == lo:
        return 0
    d = hi - lo
    if hi == r:
        h = Fraction(60 * (g - b), d) + (0 if b <= g else 360)
    elif hi == g:
        h = Fraction(60 * (b - r), d) + 120
    else:
        h = Fraction(60 * (r - g), d) + 240
    return math.floor(h * 255 / 360)


def test_integer_hue_equals_eq1_on_every_rgb_value() -> None:
    """All 2^24 colours, in 16 blocks of R: the model's hue against the sextant formula, and
    against float64 + exact fractions wherever float64 is within 1e-6 of a bin edge."""
    levels = np.arange(256, dtype=np.int64)
    g, b = (a.ravel() for a in np.meshgrid(levels, levels, indexing="ij"))
    edges_checked = 0
    for r0 in range(0, 256, 16):
        r = np.repeat(np.arange(r0, r0 + 16, dtype=np.int64), g.size)
        gg, bb = np.tile(g, 16), np.tile(b, 16)
        ours = s0.hue8(r, gg, bb).astype(np.int64)
        np.testing.assert_array_equal(ours, hue_by_sextant(r, gg, bb))
        # float64 route: H_deg * 255 / 360, floored; near an integer, fractions decide
        hi = np.maximum(np.maximum(r, gg), bb)
        d = (hi - np.minimum(np.minimum(r, gg), bb)).astype(np.float64)
        with np.errstate(invalid="ignore", divide="ignore"):
            deg = np.select([hi == r, hi == gg], [60 * (gg - bb) / d, 60 * (bb - r) / d + 120],
                            60 * (r - gg) / d + 240)
        deg = np.where(d == 0, 0.0, np.where(deg < 0, deg + 360, deg))
        scaled = deg * 255 / 360
        near = np.abs(scaled - np.rint(scaled)) < 1e-6
        far = ~near
        np.testing.assert_array_equal(ours[far], np.floor(scaled[far]).astype(np.int64))
        for i in np.flatnonzero(near)[::97]:  # a sample of the exact-edge cases, in fractions
            assert ours[i] == hue_fraction(int(r[i]), int(gg[i]), int(bb[i]))
            edges_checked += 1
    assert edges_checked > 100


def test_fixed_point_divider_option_is_a_truncating_reciprocal() -> None:
    """hue_divider_bits = k: never above the exact hue, and equal to it with enough bits."""
    rng = np.random.default_rng(1)
    r, g, b = (rng.integers(0, 256, 100_000) for _ in range(3))
    exact = s0.hue8(r, g, b).astype(int)
    coarse = s0.hue8(r, g, b, divider_bits=12).astype(int)
    assert (coarse <= exact).all() and (coarse < exact).any()
    # with 40 bits the reciprocal is short only where the quotient is a whole number
    fine = s0.hue8(r, g, b, divider_bits=40).astype(int)
    hi = np.maximum(np.maximum(r, g), b)
    d = np.maximum(hi - np.minimum(np.minimum(r, g), b), 1)
    h6 = np.select([hi == r, hi == g], [np.mod(g - b, 6 * d), b - r + 2 * d], r - g + 4 * d)
    whole = (255 * h6) % (6 * d) == 0
    np.testing.assert_array_equal(fine[~whole], exact[~whole])
    assert (exact[whole] - fine[whole] <= 1).all()


def _frames(scene_factory, scenario: str, frames: int = 40):
    scene = scene_factory(scenario, frames=150)
    images = itertools.islice(scene.frames(), frames)
    return scene, [BgrFrame(i, i / 30.0, bgr.copy()) for i, bgr in enumerate(images)]


def test_bp_and_window_sums_recomputed_pixel_by_pixel(scene_factory) -> None:
    """Histogram, BP and the eq. 6-7 sums of frame 1 recomputed with Python ints per pixel."""
    scene, frames = _frames(scene_factory, "smooth", 3)
    stages = load_config("s0-fixed").build()
    record = [ctx.fixed for ctx in run_chain(stages, frames, scene.boxes[0])][-1]
    # the model, recounted from the first frame's box
    box = scene.boxes[0]
    w, h = max(round(box.w), 1), max(round(box.h), 1)
    x0, y0 = math.floor(box.cx) - w // 2, math.floor(box.cy) - h // 2
    first = frames[0].bgr()
    counts = [0] * 256
    for yy in range(y0, y0 + h):
        for xx in range(x0, x0 + w):
            bb, gg, rr = (int(v) for v in first[yy, xx])
            counts[hue_fraction(rr, gg, bb)] += 1
    top = max(counts)
    # frame 2's window and sums (the last frame run): re-derive them from its trace
    wx, wy, ww, wh = record.window
    ref_x, ref_y = wx + ww // 2, wy + wh // 2
    image = frames[2].bgr()
    sum_bp = sum_dx = sum_dy = 0
    for yy in range(max(wy, 0), min(wy + wh, image.shape[0])):
        for xx in range(max(wx, 0), min(wx + ww, image.shape[1])):
            bb, gg, rr = (int(v) for v in image[yy, xx])
            bp = counts[hue_fraction(rr, gg, bb)] * 255 // top  # eq. 4
            assert record.bp[yy - max(wy, 0), xx - max(wx, 0)] == bp
            sum_bp += bp
            sum_dx += bp * (xx - ref_x)
            sum_dy += bp * (yy - ref_y)
    trace = record.trace
    assert trace["measured"] == 1
    assert (trace["sum_bp"], trace["sum_bp_dx"], trace["sum_bp_dy"]) == (sum_bp, sum_dx, sum_dy)
    # the step: round half away from zero of sum_bp_dx / sum_bp, in whole pixels
    def nearest(num: int, den: int) -> int:
        q = math.floor(Fraction(abs(num), den) + Fraction(1, 2))
        return q if num >= 0 else -q
    assert (trace["step_x"], trace["step_y"]) == (nearest(sum_dx, sum_bp), nearest(sum_dy, sum_bp))
    assert top == record.hist_max and sum_bp > 0


def run_chain(stages, frames, box: Box):
    """The chain frame by frame as the pipeline runs it; yields the context after each frame."""
    ctx = TrackContext(frame=frames[0], seed=0, box=box)
    ctx.new_frame(frames[0])
    for stage in stages:
        stage.start(ctx)
    yield ctx
    for frame in frames[1:]:
        ctx.new_frame(frame)
        for stage in stages:
            stage.step(ctx)
        yield ctx


def _f32(x: float) -> float:
    """Round a Python float to the nearest float32 (an IEEE op on two float32 values computed in
    float64 and rounded once is the correctly rounded float32 result for + - * /)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def test_kalman_float32_sequence_reproduced_step_by_step(scene_factory) -> None:
    """The filter's every value on a tracked scene, against plain floats rounded to float32
    after each operation, in the order of eq. 10-17."""
    scene, frames = _frames(scene_factory, "smooth", 30)
    stages = load_config("s0-fixed").build()
    rows = [dict(ctx.fixed.trace) for ctx in run_chain(stages, frames, scene.boxes[0])]
    for axis in "xy":
        x, dx = float(rows[0][f"k{axis}_x"]), 0.0
        p11, p12, p21, p22 = 100.0, 0.0, 0.0, 100.0
        for row in rows[1:]:
            l1, l2 = _f32(x + dx), dx  # eq. 10
            m11 = _f32(_f32(_f32(_f32(p11 + p21) + p12) + p22) + 1.0)  # eq. 12
            m12, m21, m22 = _f32(p12 + p22), _f32(p21 + p22), _f32(p22 + 1.0)
            if row["measured"]:
                den = _f32(m11 + 1.0)
                k1, k2 = _f32(m11 / den), _f32(m21 / den)  # eq. 14
                z = float(row[f"cand_{axis}"] + row[f"step_{axis}"])
                e = _f32(z - l1)
                x, dx = _f32(l1 + _f32(k1 * e)), _f32(l2 + _f32(k2 * e))  # eq. 15
                p11, p12 = _f32(m11 - _f32(k1 * m11)), _f32(m12 - _f32(k1 * m12))  # eq. 17
                p21, p22 = _f32(m21 - _f32(k2 * m11)), _f32(m22 - _f32(k2 * m12))
            else:
                x, dx, p11, p12, p21, p22 = l1, l2, m11, m12, m21, m22
            got = [row[f"k{axis}_{k}"] for k in ("x", "dx", "p11", "p12", "p21", "p22")]
            assert got == [x, dx, p11, p12, p21, p22]
            assert row[f"k{axis}_x_hex"] == struct.pack(">f", x).hex()
    assert sum(r["measured"] for r in rows) == len(rows)


@pytest.mark.parametrize("scenario", ["smooth", "occlusion"])
def test_s0_fixed_tracks_like_s0(scene_factory, scenario: str) -> None:
    """End to end: the fixed chain keeps the target (mean IoU), and rides the occlusion."""
    scene, frames = _frames(scene_factory, scenario, 150)
    boxes = [r.box for r in Pipeline(load_config("s0-fixed").build()).track(frames,
                                                                              scene.boxes[0])]
    scores = [iou(b, t) if b is not None and t is not None else 0.0
              for b, t in zip(boxes, scene.boxes, strict=True)]
    assert sum(scores) / len(scores) > 0.5
    assert isinstance(boxes[1], Box)
