"""Staple's colour model: object and surroundings histograms, and the per-pixel likelihood.

Bertinetto et al., "Staple: complementary learners for real-time tracking", CVPR 2016, section
4: an RGB histogram (``bins`` per channel) of the object (the box shrunk by ``inner_padding`` of
its mean side) and one of its surroundings (the search region without the box), each a
normalised density learnt with rate ``rate``; a pixel's object likelihood is
``p_obj / (p_obj + p_bg)`` (eq. 11-12, 0 where neither has seen the colour), and a placement's
colour score the mean likelihood over a target-sized box (their integral-image "response").
Grey frames give a histogram of grey levels (all three channels equal), which is what a thermal
target needs.
"""

from __future__ import annotations

import cv2
import numpy as np


class ColourHistograms:
    """Object and surroundings densities over joint colour bins, learnt on patches."""

    def __init__(self, bins: int, inner_padding: float, rate: float) -> None:
        self.bins = bins
        self.inner_padding = inner_padding
        self.rate = rate
        self.shift = 8 - int(np.log2(bins))
        self.object: np.ndarray | None = None
        self.surroundings: np.ndarray | None = None

    def bin_image(self, patch: np.ndarray) -> np.ndarray:
        """Joint bin index of every pixel (grey patches: the grey level's bin)."""
        q = np.right_shift(patch, self.shift).astype(np.int32)
        if q.ndim == 2:
            return q
        return (q[..., 0] * self.bins + q[..., 1]) * self.bins + q[..., 2]

    def learn(self, patch: np.ndarray, box: tuple[float, float, float, float],
              first: bool = False) -> None:
        """Fold the patch's object (inside ``box`` = x, y, w, h in patch pixels, shrunk by the
        inner padding) and surroundings (outside ``box``) into the densities."""
        index = self.bin_image(patch)
        size = self.bins ** (1 if patch.ndim == 2 else 3)
        x, y, w, h = box
        pad = (w + h) / 2 * self.inner_padding
        inner = _mask(index.shape, x + pad / 2, y + pad / 2, max(w - pad, 2), max(h - pad, 2))
        outer = ~_mask(index.shape, x, y, w, h)
        obj = np.bincount(index[inner], minlength=size).astype(np.float64)
        bg = np.bincount(index[outer], minlength=size).astype(np.float64)
        obj /= max(obj.sum(), 1.0)
        bg /= max(bg.sum(), 1.0)
        if first or self.object is None or self.surroundings is None:
            self.object, self.surroundings = obj, bg
            return
        self.object = (1 - self.rate) * self.object + self.rate * obj
        self.surroundings = (1 - self.rate) * self.surroundings + self.rate * bg

    def likelihood(self, patch: np.ndarray) -> np.ndarray:
        """Object likelihood of every pixel, float32 in 0..1 (Staple eq. 12)."""
        assert self.object is not None and self.surroundings is not None
        index = self.bin_image(patch)
        obj = self.object[index]
        total = obj + self.surroundings[index]
        return np.divide(obj, total, out=np.zeros_like(obj), where=total > 0).astype(np.float32)


def box_mean(likelihood: np.ndarray, w: float, h: float) -> np.ndarray:
    """Mean of ``likelihood`` over the ``w`` x ``h`` box centred on every pixel (0 outside)."""
    size = (max(int(round(w)), 1), max(int(round(h)), 1))
    return cv2.boxFilter(likelihood, -1, size, normalize=True, borderType=cv2.BORDER_CONSTANT)


def _mask(shape: tuple[int, ...], x: float, y: float, w: float, h: float) -> np.ndarray:
    mask = np.zeros(shape[:2], bool)
    mask[max(int(y), 0): max(int(y + h) + 1, 0), max(int(x), 0): max(int(x + w) + 1, 0)] = True
    return mask
