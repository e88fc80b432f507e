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


def _channel_gradients(channel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centred differences ([-1, 0, 1]) along x and y of one channel, float32."""
    return (cv2.Sobel(channel, cv2.CV_32F, 1, 0, ksize=1),
            cv2.Sobel(channel, cv2.CV_32F, 0, 1, ksize=1))


def _gradients(patch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gradient magnitude and angle (0..2*pi) of the strongest channel at every pixel (the
    first channel on a tie). NumPy's square root, not ``cv2.magnitude``, whose first call in
    a process rounds differently from the later ones."""
    # contiguous planes: OpenCV would copy each strided channel view itself, twice
    channels = (patch,) if patch.ndim == 2 else cv2.split(patch)
    best_x, best_y = _channel_gradients(channels[0])
    best = best_x * best_x + best_y * best_y
    energy = np.empty_like(best)
    squared = np.empty_like(best)
    for channel in channels[1:]:
        gx, gy = _channel_gradients(channel)
        np.multiply(gx, gx, out=energy)
        energy += np.multiply(gy, gy, out=squared)
        # OpenCV's masked copy: NumPy's ``copyto(..., where=)`` on this unpredictable mask
        # took ~10x longer than the whole rest of the gradient
        stronger = cv2.compare(energy, best, cv2.CMP_GT)
        cv2.copyTo(gx, stronger, best_x)
        cv2.copyTo(gy, stronger, best_y)
        np.maximum(best, energy, out=best)
    return np.sqrt(best, out=best), cv2.phase(best_x, best_y)


@lru_cache(maxsize=32)
def _cell_index(rows: int, cols: int, cell: int) -> np.ndarray:
    """Per pixel of a (rows*cell, cols*cell) patch: the index of its cell (row-major). Read
    only: every call with these arguments returns this one array (cached)."""
    r = np.arange(rows * cell) // cell
    c = np.arange(cols * cell) // cell
    index = (r[:, None] * cols + c[None, :]).astype(np.int32)
    index.setflags(write=False)
    return index


def fhog(patch: np.ndarray, cell: int = 4) -> np.ndarray:
    """31-channel fHOG of a grey (H, W) or colour (H, W, 3) patch: float32 (H//cell, W//cell,
    31). Values are in 0..~0.5 per channel; a flat patch gives zeros (texture channels too)."""
    height, width = patch.shape[:2]
    rows, cols = height // cell, width // cell
    if rows < 1 or cols < 1:
        raise ValueError(f"fhog needs at least {cell}x{cell} pixels, got {width}x{height}")
    mag, angle = _gradients(patch[: rows * cell, : cols * cell])
    # Hard orientation bin per pixel (Dollar's fhog: softBin = -1), magnitude as weight, summed
    # per cell in one bincount; bins outermost, so that every later step runs on whole planes.
    index = (angle * (SENSITIVE_BINS / (2 * np.pi))).astype(np.int32)
    cv2.min(index, SENSITIVE_BINS - 1, dst=index)  # (NumPy's minimum with a scalar: slower)
    index *= rows * cols
    index += _cell_index(rows, cols, cell)
    hist = np.bincount(index.ravel(), weights=mag.ravel(), minlength=rows * cols * SENSITIVE_BINS)
    return _normalise(hist.reshape(SENSITIVE_BINS, rows, cols).astype(np.float32))


def _normalise(hist: np.ndarray) -> np.ndarray:
    """Felzenszwalb's block normalisation of an 18-bin cell histogram (18, rows, cols): the
    (rows, cols, 31) features."""
    _, rows, cols = hist.shape
    bins = np.empty((27, rows, cols), np.float32)  # 18 sensitive, then 9 insensitive
    bins[:18] = hist
    np.add(hist[:9], hist[9:], out=bins[18:])
    energy = np.einsum("kij,kij->ij", bins[18:], bins[18:])
    padded = cv2.copyMakeBorder(energy, 1, 1, 1, 1, cv2.BORDER_REPLICATE)
    # Energy of the 2x2 block whose corner is cell (i, j) in each of the four directions.
    block = padded[:-1, :-1] + padded[1:, :-1] + padded[:-1, 1:] + padded[1:, 1:]
    inv = 1.0 / np.sqrt(block + np.float32(1e-4))
    out = np.zeros((CHANNELS, rows, cols), np.float32)
    normalised = np.empty_like(bins)
    planes = normalised.reshape(-1, cols)  # (the same memory, as OpenCV takes it)
    # the 27 bins under each of the 4 normalisations, clipped: summed (27 channels), and the
    # 18 sensitive ones summed per normalisation (4 texture channels)
    for n, (dr, dc) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
        np.multiply(bins, inv[dr:dr + rows, dc:dc + cols], out=normalised)
        # min(x, CLIP): OpenCV's truncation, ~10x faster than NumPy's minimum with a scalar
        cv2.threshold(planes, CLIP, 0, cv2.THRESH_TRUNC, dst=planes)
        out[:27] += normalised
        normalised[:18].sum(axis=0, out=out[27 + n])
    out[:27] *= 0.5
    out[27:] *= 0.2357
    return out.transpose(1, 2, 0)
