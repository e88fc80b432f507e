"""S0 (Liu et al. 2022) in the FPGA's arithmetic, bit for bit.

Every function here is integer NumPy (int32/int64) except :class:`KalmanF32`, which is IEEE
float32 scalar arithmetic in the order the paper writes eq. 10-17 (sec. 3: "32 bit single
precision floating-point IP"). Widths and roundings are stated where they happen; the manifest of
``vtrack vectors`` repeats them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Eq. 1 scaled to 8 bits: H8 = floor(H_deg * 255 / 360) = floor(H_deg * 17 / 24).
HUE_NUM, HUE_DEN = 17, 24


def split_rgb(bgr: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(R, G, B)`` int32 planes of a uint8 BGR image (OpenCV order)."""
    planes = bgr.astype(np.int32)
    return planes[..., 2], planes[..., 1], planes[..., 0]


def hue8(r: np.ndarray, g: np.ndarray, b: np.ndarray, divider_bits: int = 0) -> np.ndarray:
    """8-bit hue of eq. 1 in exact integer arithmetic: ``floor(H_deg * 255 / 360)``.

    ``H_deg`` is eq. 1's rational (``max == min`` -> 0; ties of the maximum take the first
    branch printed: R, then G, then B). Eq. 1's G branch prints ``(B - G)``, a typo for the
    usual ``(B - R)`` (with ``max = G`` the printed form would never leave 60..120 deg).
    Writing ``H_deg = (60 * num + off * d) / d`` (``d = max - min``, ``off`` 0/360/120/240 deg):
    ``H8 = floor(17 * (60 * num + off * d) / (24 * d))``; the numerator is < 2^21, int32.

    ``divider_bits > 0`` models the paper's "scale up, integer divide, scale down" with a
    fixed-point reciprocal instead of the exact divider: ``q = floor(2^k / (24 d))`` (k =
    ``divider_bits``), ``H8 = min(floor(17 N q / 2^k), 255)``: a truncating reciprocal divider
    of ``k`` fractional bits (int64 products).
    """
    r = np.asarray(r, np.int32)
    g = np.asarray(g, np.int32)
    b = np.asarray(b, np.int32)
    hi = np.maximum(np.maximum(r, g), b)
    d = hi - np.minimum(np.minimum(r, g), b)
    is_r = hi == r
    is_g = ~is_r & (hi == g)
    # eq. 1 branch by branch: 60 (G-B)/d (+360 if G < B), 60 (B-R)/d + 120, 60 (R-G)/d + 240
    num = np.where(is_r, g - b, np.where(is_g, b - r, r - g))
    off = np.where(is_r, np.where(g < b, 360, 0), np.where(is_g, 120, 240))
    top = HUE_NUM * (60 * num + off * d)  # 17 * H_deg * d, >= 0, < 17 * 360 * 255 < 2^21
    safe = np.maximum(d, 1)
    if divider_bits:
        recip = (np.int64(1) << divider_bits) // (HUE_DEN * safe.astype(np.int64))
        h = np.minimum((top.astype(np.int64) * recip) >> divider_bits, 255)
    else:
        h = top // (HUE_DEN * safe)
    return np.where(d == 0, 0, h).astype(np.uint8)


def sv_mask(r: np.ndarray, g: np.ndarray, b: np.ndarray, sat_min: int, val_min: int) -> np.ndarray:
    """True where ``S >= sat_min`` and ``V >= val_min`` (0..255 scales), without a divider.

    ``V = max``; ``S = 255 (max - min) / max`` compared by cross-multiplication:
    ``255 (max - min) >= sat_min * max`` (a grey pixel, ``max = 0``, has S = 0).
    """
    hi = np.maximum(np.maximum(r, g), b)
    lo = np.minimum(np.minimum(r, g), b)
    sat_ok = (255 * (hi - lo) >= sat_min * hi) & ((hi > 0) | (sat_min == 0))
    return sat_ok & (hi >= val_min)


def optional_mask(r: np.ndarray, g: np.ndarray, b: np.ndarray, sat_min: int, val_min: int
                  ) -> np.ndarray | None:
    """:func:`sv_mask`, or None when both thresholds are 0 (no mask: every pixel counts)."""
    return sv_mask(r, g, b, sat_min, val_min) if sat_min or val_min else None


def back_project(lut: np.ndarray, hue: np.ndarray, mask: np.ndarray | None) -> np.ndarray:
    """Eq. 4 per pixel, ``BP = lut[hue]`` (uint8), 0 where ``mask`` is False."""
    bp = lut[hue]  # one table look-up per pixel
    return bp if mask is None else np.where(mask, bp, 0).astype(np.uint8)


def histogram(hue: np.ndarray, mask: np.ndarray | None, bits: int) -> np.ndarray:
    """Eq. 2-3: 256 counters of ``bits`` bits (``reg[19:0] histogram_cnt[255:0]``: 20),
    ``histogram[hue] += 1`` per (unmasked) pixel, saturating at ``2^bits - 1``. int64."""
    values = hue.ravel() if mask is None else hue[mask]
    counts = np.bincount(values.astype(np.intp), minlength=256).astype(np.int64)
    return np.minimum(counts, (1 << bits) - 1)


def bp_table(hist: np.ndarray) -> np.ndarray:
    """Eq. 4 as a 256-entry table: ``BP = floor(hist[h] * 255 / max)`` (uint8; ``max > 0``)."""
    top = int(hist.max())
    return (hist * 255 // top).astype(np.uint8)


@dataclass(frozen=True)
class WindowSums:
    """Eq. 6-7 numerators over a window: ``sum bp``, ``sum bp (x_i - ref_x)``, ``... y``, and
    ``n`` the number of pixels summed (the window's pixels inside the frame)."""

    sum_bp: int
    sum_bp_dx: int
    sum_bp_dy: int
    n: int


def window_sums(bp: np.ndarray, x0: int, y0: int, ref_x: int, ref_y: int) -> WindowSums:
    """Eq. 6-7 sums of ``bp`` (a uint8 image whose top-left pixel is frame pixel ``(x0, y0)``).

    ``x_i - ref_x`` is a signed pixel offset; the sums are exact int64 (for a window of
    ``n`` pixels ``|sum_bp_dx| < 255 n w / 2``).
    """
    v = bp.astype(np.int64)
    cols = v.sum(axis=0)
    rows = v.sum(axis=1)
    dx = np.arange(x0, x0 + bp.shape[1], dtype=np.int64) - ref_x
    dy = np.arange(y0, y0 + bp.shape[0], dtype=np.int64) - ref_y
    return WindowSums(int(cols.sum()), int(cols @ dx), int(rows @ dy), int(bp.size))


def divide(num: int, den: int, rounding: str) -> int:
    """Integer ``num / den`` (``den > 0``): ``floor``, ``trunc`` (toward zero, a C/Verilog
    ``/``) or ``nearest`` (half away from zero)."""
    if rounding == "floor":
        return num // den
    q = abs(num) // den if rounding == "trunc" else (2 * abs(num) + den) // (2 * den)
    return q if num >= 0 else -q


def step(sums: WindowSums, normalization: str, frac_bits: int, rounding: str) -> tuple[int, int]:
    """The mean-shift step in units of ``2^-frac_bits`` pixel (eq. 6-7).

    ``weighted``: ``sum_bp_dx * 2^f / sum_bp`` (the weighted centroid, the usual mean-shift step);
    ``paper``: ``sum_bp_dx * 2^f / (n * 255)`` as printed. Rounded by ``rounding``; a window
    with ``sum_bp = 0`` does not move.
    """
    den = sums.sum_bp if normalization == "weighted" else sums.n * 255
    if sums.sum_bp == 0 or den == 0:
        return 0, 0
    scale = 1 << frac_bits
    return (divide(sums.sum_bp_dx * scale, den, rounding),
            divide(sums.sum_bp_dy * scale, den, rounding))


F32 = np.float32

#: Names of one axis's float32 values in trace order: prior (eq. 10, 12), gain (eq. 14),
#: posterior (eq. 15, 17).
KALMAN_FIELDS = ("l1", "l2", "pm11", "pm12", "pm21", "pm22", "k1", "k2",
                 "x", "dx", "p11", "p12", "p21", "p22")


class KalmanF32:
    """One axis of S0's filter, eq. 10-17 element by element in IEEE float32 (round to nearest
    even, no fused multiply-add), additions left to right as printed. Q = q I, R = r.

    :meth:`predict` is eq. 10-12, :meth:`update` eq. 14-17 (with the prior), :meth:`coast` takes
    the prior as the posterior (no measurement: S0 sec. 3). ``values`` holds the latest of every
    :data:`KALMAN_FIELDS` entry.
    """

    def __init__(self, x0: float, p0: float, q: float = 1.0, r: float = 1.0) -> None:
        self.q, self.r = F32(q), F32(r)
        zero, p = F32(0.0), F32(p0)
        self.values: dict[str, np.float32] = dict.fromkeys(KALMAN_FIELDS, zero)
        self.values.update(x=F32(x0), dx=zero, p11=p, p22=p)
        self.predict()

    def predict(self) -> np.float32:
        """Eq. 10-12 from the posterior; returns the predicted position ``l1``."""
        v = self.values
        v["l1"] = v["x"] + v["dx"]  # eq. 10
        v["l2"] = v["dx"]
        v["pm11"] = v["p11"] + v["p21"] + v["p12"] + v["p22"] + self.q  # eq. 12, left to right
        v["pm12"] = v["p12"] + v["p22"]
        v["pm21"] = v["p21"] + v["p22"]
        v["pm22"] = v["p22"] + self.q
        return v["l1"]

    def update(self, z: np.float32) -> None:
        """Eq. 14-17 with the measurement ``z`` (a float32)."""
        v = self.values
        den = v["pm11"] + self.r  # eq. 14: p11- + R
        v["k1"] = v["pm11"] / den
        v["k2"] = v["pm21"] / den
        e = F32(z) - v["l1"]  # eq. 15: x_k - l1
        v["x"] = v["l1"] + v["k1"] * e
        v["dx"] = v["l2"] + v["k2"] * e
        v["p11"] = v["pm11"] - v["k1"] * v["pm11"]  # eq. 17
        v["p12"] = v["pm12"] - v["k1"] * v["pm12"]
        v["p21"] = v["pm21"] - v["k2"] * v["pm11"]
        v["p22"] = v["pm22"] - v["k2"] * v["pm12"]

    def coast(self) -> None:
        """No measurement: the posterior is the prior (gains recorded as 0)."""
        v = self.values
        v["k1"] = v["k2"] = F32(0.0)
        v["x"], v["dx"] = v["l1"], v["l2"]
        v["p11"], v["p12"], v["p21"], v["p22"] = v["pm11"], v["pm12"], v["pm21"], v["pm22"]


def f32_hex(value: np.float32) -> str:
    """The IEEE-754 bit pattern of a float32 as 8 hex digits (``3f800000`` for 1.0)."""
    return f"{int(np.asarray(value, np.float32).view(np.uint32)):08x}"


def f32_to_int(value: np.float32) -> int:
    """Float32 -> integer pixel as the fixed-point converter rounds it: nearest, half up
    (``floor(v + 0.5)`` in float32)."""
    return int(np.floor(F32(value) + F32(0.5)))
