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

from functools import lru_cache

import cv2
import numpy as np


class ColourHistograms:
    """Object and surroundings densities over joint colour bins, learnt on patches."""

    def __init__(self, bins: int, inner_padding: float, rate: float) -> None:
        self.bins = bins
        self.inner_padding = inner_padding
        self.rate = rate
        self.object: np.ndarray | None = None
        self.surroundings: np.ndarray | None = None
        self.shift = 8 - int(np.log2(bins))
        #: Per bin (flat), the object likelihood p_obj / (p_obj + p_bg) (eq. 12).
        self._likelihood: np.ndarray | None = None

    def _density(self, patch: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """Normalised joint histogram of the patch's pixels under ``mask`` (uint8, 0 = out)."""
        channels = [0] if patch.ndim == 2 else [0, 1, 2]
        hist = cv2.calcHist([patch], channels, mask, [self.bins] * len(channels),
                            [0, 256] * len(channels))
        return hist / max(float(hist.sum()), 1.0)

    def learn(self, patch: np.ndarray, box: tuple[float, float, float, float],
              first: bool = False) -> None:
        """Fold the patch's object (inside ``box`` = x, y, w, h in patch pixels, shrunk by the
        inner padding) and surroundings (outside ``box``) into the densities."""
        x, y, w, h = box
        pad = (w + h) / 2 * self.inner_padding
        inner = _mask(patch.shape, x + pad / 2, y + pad / 2, max(w - pad, 2), max(h - pad, 2))
        outer = 255 - _mask(patch.shape, x, y, w, h)
        obj, bg = self._density(patch, inner), self._density(patch, outer)
        if first or self.object is None or self.surroundings is None:
            self.object, self.surroundings = obj, bg
        else:
            self.object = (1 - self.rate) * self.object + self.rate * obj
            self.surroundings = (1 - self.rate) * self.surroundings + self.rate * bg
        total = self.object + self.surroundings
        self._likelihood = np.divide(self.object, total, out=np.zeros_like(total),
                                     where=total > 0).ravel()

    def likelihood(self, patch: np.ndarray) -> np.ndarray:
        """Object likelihood of every pixel, float32 in 0..1 (Staple eq. 12)."""
        assert self._likelihood is not None
        q = np.right_shift(patch, self.shift)
        if q.ndim == 2:
            return self._likelihood.take(q)
        index = q[..., 0].astype(np.int32) * self.bins
        index += q[..., 1]
        index *= self.bins
        index += q[..., 2]
        return self._likelihood.take(index)


def cell_response(likelihood: np.ndarray, w: float, h: float, rows: int, cols: int,
                  cell: int) -> np.ndarray:
    """Staple's colour response on a grid of ``rows`` x ``cols`` cells of ``cell`` pixels
    whose middle cell is the patch's middle: at each cell's displacement, the mean likelihood
    over the ``w`` x ``h`` box centred there (cells past the patch read its edge)."""
    mean = box_mean(likelihood, w, h)
    return mean.take(_cell_centres(mean.shape[0], mean.shape[1], rows, cols, cell))


@lru_cache(maxsize=32)
def _cell_centres(height: int, width: int, rows: int, cols: int, cell: int) -> np.ndarray:
    """(rows, cols) flat indices into a ``height`` x ``width`` image of the pixels
    :func:`cell_response` reads: each cell's displacement from the middle pixel (clipped to
    the image). Read only: every call with these arguments returns this one array (cached)."""
    ys = np.clip(height // 2 + (np.arange(rows) - rows // 2) * cell, 0, height - 1)
    xs = np.clip(width // 2 + (np.arange(cols) - cols // 2) * cell, 0, width - 1)
    centres = ys[:, None] * width + xs[None, :]
    centres.setflags(write=False)
    return centres


def box_mean(likelihood: np.ndarray, w: float, h: float) -> np.ndarray:
    """Mean of ``likelihood`` over the ``w`` x ``h`` box centred on every pixel (0 outside)."""
    size = (max(int(round(w)), 1), max(int(round(h)), 1))
    return cv2.boxFilter(likelihood, -1, size, normalize=True, borderType=cv2.BORDER_CONSTANT)


def _mask(shape: tuple[int, ...], x: float, y: float, w: float, h: float) -> np.ndarray:
    """uint8 mask of ``shape[:2]``: 255 on the pixels of the box (x, y, w, h), 0 elsewhere."""
    mask = np.zeros(shape[:2], np.uint8)
    mask[max(int(y), 0): max(int(y + h) + 1, 0), max(int(x), 0): max(int(x + w) + 1, 0)] = 255
    return mask
