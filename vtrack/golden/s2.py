"""S2 (Di & Zhu 2008) sec. 3: the integer-only DSP loop.

All integer NumPy (int64). The document's steps, with what it leaves open stated:

- feature: 8-bit grey ``(77 R + 150 G + 29 B + 128) >> 8`` quantised to ``m`` levels
  ``b = grey * m >> 8`` (sec. 6.1: m = 16);
- step 1 (eq. 1, 3): ``q_u = sum K [b = u]``, ``C = sum K``, ``K = h_x - |x*| + h_y - |y*|`` on the
  pixels ``|x*| <= h_x``, ``|y*| <= h_y`` about the centre pixel, ``h = w // 2`` (undivided);
- step 3: ``K = h_x - |dx| * 10000 // s_t + h_y - |dy| * 10000 // s_t`` with ``s_t = 9, 10, 11``
  times ``s_(k-1)`` (``s`` from 1000), on the pixels where both terms are ``>= 0``. ``H`` is read
  as the initial bandwidth: ``s`` carries the whole scale (the printed ``H_k = s_k H_(k-1) /
  1000`` would apply it twice);
- step 4: ``w_u = (q_u << F) // p_u`` (``F`` fractional bits, declared; 0 where ``p_u = 0``);
- step 5: ``Y' = Y + round(sum w_i (X_i - Y) / sum w_i)`` per axis, rounding declared;
- step 6: repeat while ``Y' != Y`` (``|dx| >= 1`` or ``|dy| >= 1``), then
  ``rho = sum_u min(q_u, C p_u // C')`` at the converged ``Y'``;
- step 7 / note 2: the scale with the largest ``rho`` (strictly larger replaces),
  ``s_k = (s_t + 90 s_(k-1)) // 100``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vtrack.golden.s0 import divide


def gray8(r: np.ndarray, g: np.ndarray, b: np.ndarray) -> np.ndarray:
    """8-bit grey from RGB in integers: ``(77 R + 150 G + 29 B + 128) >> 8`` (BT.601 weights in
    8 fractional bits, rounded to nearest)."""
    return ((77 * r + 150 * g + 29 * b + 128) >> 8).astype(np.uint8)


def kernel_axis(h: int, s_t: int) -> np.ndarray:
    """One axis of the step-3 kernel, ``h - |d| * 10000 // s_t`` for ``d = -R .. R``, ``R`` the
    largest offset whose term is ``>= 0`` (step 1 is ``s_t = 10000``: ``h - |d|``)."""
    reach = ((h + 1) * s_t - 1) // 10000
    d = np.abs(np.arange(-reach, reach + 1, dtype=np.int64))
    return h - d * 10000 // s_t


@dataclass(frozen=True)
class Sample:
    """A kernel histogram about the pixel ``(x, y)``: bins of the in-frame pixels, their kernel
    and pixel offsets, ``p_u`` (int64) and ``C' = sum K``."""

    x: int
    y: int
    bins: np.ndarray
    kernel: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    hist: np.ndarray
    total: int


def sample(bins_image: np.ndarray, x: int, y: int, hx: int, hy: int, s_t: int,
           m: int) -> Sample | None:
    """Step 3 (step 1 with ``s_t = 10000``) about pixel ``(x, y)`` of the frame whose bins are
    ``bins_image``; None when no pixel of the window is in the frame or ``C' = 0``."""
    kx, ky = kernel_axis(hx, s_t), kernel_axis(hy, s_t)
    rx, ry = kx.size // 2, ky.size // 2
    height, width = bins_image.shape
    x0, x1 = max(x - rx, 0), min(x + rx + 1, width)
    y0, y1 = max(y - ry, 0), min(y + ry + 1, height)
    if x1 <= x0 or y1 <= y0:
        return None
    kernel = ky[y0 - y + ry : y1 - y + ry, None] + kx[None, x0 - x + rx : x1 - x + rx]
    part = bins_image[y0:y1, x0:x1]
    # bincount sums in float64: exact for integer sums below 2^53 (here < 2^40)
    hist = np.bincount(part.ravel(), weights=kernel.ravel(), minlength=m).astype(np.int64)
    total = int(kernel.sum())
    if total <= 0:
        return None
    dx = np.arange(x0, x1, dtype=np.int64) - x
    dy = np.arange(y0, y1, dtype=np.int64) - y
    return Sample(x, y, part, kernel, dx, dy, hist, total)


def weights(q: np.ndarray, p: np.ndarray, frac_bits: int) -> np.ndarray:
    """Step 4 as a table per bin: ``(q_u << F) // p_u``, 0 where ``p_u = 0``."""
    out = np.zeros_like(q)
    seen = p > 0
    out[seen] = (q[seen] << frac_bits) // p[seen]
    return out


def shift(smp: Sample, table: np.ndarray, rounding: str) -> tuple[int, int, int, int, int]:
    """Step 5: ``(step_x, step_y, sum_w, sum_w_dx, sum_w_dy)`` with the step rounded; a
    window with ``sum_w = 0`` does not move."""
    w = table[smp.bins]
    cols, rows = w.sum(axis=0), w.sum(axis=1)
    total = int(cols.sum())
    sx, sy = int(cols @ smp.dx), int(rows @ smp.dy)
    if total == 0:
        return 0, 0, 0, sx, sy
    return divide(sx, total, rounding), divide(sy, total, rounding), total, sx, sy


def intersection(q: np.ndarray, c: int, p: np.ndarray, c_prime: int) -> int:
    """Step 6 / eq. 11 as in note 4: ``sum_u min(q_u, C p_u // C')``."""
    return int(np.minimum(q, c * p // c_prime).sum())
