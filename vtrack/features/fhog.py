"""Felzenszwalb's HOG (fHOG) on 4-pixel cells, vectorised over the whole patch.

Felzenszwalb, Girshick, McAllester and Ramanan, "Object detection with discriminatively trained
part-based models", TPAMI 2010, section 6.3: per pixel the gradient of the strongest colour
channel; 18 contrast-sensitive orientation bins accumulated per cell; each cell normalised by
the energy of the four 2x2-cell blocks around it, clipped at 0.2; out come 18 sensitive + 9
insensitive orientation channels and 4 texture (block energy) channels, 31 in all. This
follows Dollar's ``fhog`` (Piotr's toolbox), which KCF, DSST, Staple and ECO-HC use, with no
Python loop over pixels: the cell histograms are one ``bincount`` (each pixel counts in its own
cell: no bilinear spreading).
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

#: Orientation bins over 0..2*pi (the contrast-insensitive 9 are their opposite pairs summed).
SENSITIVE_BINS = 18
#: Channels per cell: 18 sensitive + 9 insensitive + 4 texture.
CHANNELS = 31
#: Felzenszwalb's clipping of normalised values.
CLIP = 0.2


def _gradients(patch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gradient magnitude and angle (0..2*pi) of the strongest channel at every pixel (centred
    differences, [-1, 0, 1])."""
    img = patch.astype(np.float32)
    gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=1)
    gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=1)
    mag2 = gx * gx + gy * gy
    if img.ndim == 3:
        m0, m1, m2 = mag2[..., 0], mag2[..., 1], mag2[..., 2]
        first = (m0 >= m1) & (m0 >= m2)
        second = ~first & (m1 >= m2)
        gx = np.where(first, gx[..., 0], np.where(second, gx[..., 1], gx[..., 2]))
        gy = np.where(first, gy[..., 0], np.where(second, gy[..., 1], gy[..., 2]))
        mag2 = np.where(first, m0, np.where(second, m1, m2))
    return np.sqrt(mag2), cv2.phase(gx, gy)


@lru_cache(maxsize=32)
def _cell_index(rows: int, cols: int, cell: int) -> np.ndarray:
    """Per pixel of a (rows*cell, cols*cell) patch: its cell's index times the bin count."""
    r = np.arange(rows * cell) // cell
    c = np.arange(cols * cell) // cell
    return ((r[:, None] * cols + c[None, :]) * SENSITIVE_BINS).astype(np.int64)


def fhog(patch: np.ndarray, cell: int = 4) -> np.ndarray:
    """31-channel fHOG of a grey (H, W) or colour (H, W, 3) patch: float32 (H//cell, W//cell,
    31). Values are in 0..~0.5 per channel; a flat patch gives zeros (texture channels too)."""
    height, width = patch.shape[:2]
    rows, cols = height // cell, width // cell
    if rows < 1 or cols < 1:
        raise ValueError(f"fhog needs at least {cell}x{cell} pixels, got {width}x{height}")
    mag, angle = _gradients(patch[: rows * cell, : cols * cell])
    # Hard orientation bin per pixel (Dollar's fhog: softBin = -1), magnitude as weight, summed
    # per cell in one bincount.
    obin = np.minimum((angle * (SENSITIVE_BINS / (2 * np.pi))).astype(np.int64), SENSITIVE_BINS - 1)
    index = _cell_index(rows, cols, cell) + obin
    hist = np.bincount(index.ravel(), weights=mag.ravel(), minlength=rows * cols * SENSITIVE_BINS)
    return _normalise(hist.reshape(rows, cols, SENSITIVE_BINS).astype(np.float32))


def _normalise(hist: np.ndarray) -> np.ndarray:
    """Felzenszwalb's block normalisation of an 18-bin cell histogram (rows, cols, 18)."""
    rows, cols, _ = hist.shape
    insensitive = hist[..., :9] + hist[..., 9:]
    energy = np.einsum("ijk,ijk->ij", insensitive, insensitive)
    padded = np.pad(energy, 1, mode="edge")
    # Energy of the 2x2 block whose corner is cell (i, j) in each of the four directions.
    block = padded[:-1, :-1] + padded[1:, :-1] + padded[:-1, 1:] + padded[1:, 1:]
    norms = np.stack([block[:-1, :-1], block[:-1, 1:], block[1:, :-1], block[1:, 1:]], axis=-1)
    inv = (1.0 / np.sqrt(norms + 1e-4)).astype(np.float32)  # (rows, cols, 4)
    # the 18 sensitive and 9 insensitive bins under each of the 4 normalisations, clipped
    clipped = np.concatenate([hist, insensitive], axis=2)[..., None, :] * inv[..., :, None]
    np.minimum(clipped, CLIP, out=clipped)
    out = np.empty((rows, cols, CHANNELS), np.float32)
    np.multiply(clipped.sum(axis=2), 0.5, out=out[..., :27])
    np.multiply(clipped[..., :18].sum(axis=3), 0.2357, out=out[..., 27:])
    return out
