"""Histograms of a feature image and their similarity, shared by the colour trackers."""

from __future__ import annotations

import cv2
import numpy as np

from vtrack.errors import FirstFrameError


def hue_histogram(
    feature: np.ndarray, mask: np.ndarray | None, bins: int, levels: int
) -> np.ndarray:
    """Counts of the feature values ``0 .. levels - 1`` in ``bins`` equal bins (S0 eq. 3).

    ``feature`` is a one-channel image, or a multi-channel one whose channel 0 is counted (e.g.
    ``COLOR_BGR2HSV_FULL`` output). Only pixels where ``mask`` is non-zero are counted (all of
    them when ``mask`` is None). Bin ``u`` holds the values ``v`` with ``v * bins // levels == u``.
    Returns a float32 array of length ``bins``.
    """
    # S0 eq. 3: histogram[hue] = histogram[hue] + 1 for every pixel of the box
    return cv2.calcHist([feature], [0], mask, [bins], [0, levels]).ravel()


def bhattacharyya(p: np.ndarray, q: np.ndarray) -> float:
    """Bhattacharyya coefficient ``sum_u sqrt(p_u q_u)`` of two histograms, each normalised to
    sum 1 here; 1.0 means identical distributions, 0.0 no common bin (or an empty histogram)."""
    return float(bhattacharyya_rows(p[np.newaxis], q)[0])


def bhattacharyya_rows(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """:func:`bhattacharyya` of each row of ``p`` (shape (n, bins)) with ``q``, at once."""
    totals = np.sqrt(p.sum(axis=1) * q.sum())
    overlap = np.sqrt(p * q).sum(axis=1)
    return np.divide(overlap, totals, out=np.zeros_like(overlap), where=totals > 0)


def refuse_colourless(bgr: np.ndarray, stage: str, box_text: str) -> None:
    """FirstFrameError when no pixel of ``bgr`` (the initial box's pixels, BGR or grey) has a hue:
    every pixel's three channels are equal (grey footage), so a hue histogram holds one bin
    whatever the target is, and a hue tracker follows nothing while it reports tracking."""
    if bgr.ndim == 3 and bgr.shape[2] == 3:
        blue, green, red = cv2.split(bgr)
        if cv2.countNonZero(cv2.absdiff(blue, green)) or cv2.countNonZero(cv2.absdiff(green, red)):
            return
    raise FirstFrameError(
        f"{stage}: no pixel of the initial box {box_text} has a colour (grey footage?): a hue "
        "tracker has nothing to follow; try --config robust or s2")
