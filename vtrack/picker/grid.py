"""A light pixel grid with scale labels over a frame, to read box coordinates off an image."""

from __future__ import annotations

import cv2
import numpy as np

STEPS = (5, 10, 20, 25, 50, 100, 200, 250, 500)


def grid_step(width: int, height: int, lines: int = 16) -> int:
    """The round step (px) giving about ``lines`` lines across the longer side."""
    side = max(width, height)
    return next((s for s in STEPS if side / s <= lines), STEPS[-1])


def draw_grid(bgr: np.ndarray, step: int | None = None, alpha: float = 0.3) -> np.ndarray:
    """A copy of ``bgr`` with a grid every ``step`` px (every 5th line stronger) blended in at
    ``alpha``, labelled in pixels along the top and left edges (label = the line's x or y)."""
    height, width = bgr.shape[:2]
    step = step or grid_step(width, height)
    lines = bgr.copy()
    for x in range(0, width, step):
        cv2.line(lines, (x, 0), (x, height - 1), (255, 255, 255), 2 if x % (5 * step) == 0 else 1)
    for y in range(0, height, step):
        cv2.line(lines, (0, y), (width - 1, y), (255, 255, 255), 2 if y % (5 * step) == 0 else 1)
    out = cv2.addWeighted(lines, alpha, bgr, 1.0 - alpha, 0.0)
    scale = max(0.35, min(width, height) / 900)
    thickness = max(1, round(scale * 2))
    (text_w, text_h), _ = cv2.getTextSize(str(max(width, height)), cv2.FONT_HERSHEY_SIMPLEX,
                                          scale, thickness)
    top = text_h + 4
    x_every = step * -(-(text_w + 8) // step)  # labels never overlap
    y_every = step * -(-(text_h + 8) // step)
    for x in range(0, width - text_w, x_every):
        _label(out, str(x), (x + 2, top), scale, thickness)
    first_y = y_every * -(-(top + text_h + 4) // y_every)  # below the x labels
    for y in range(first_y, height, y_every):
        _label(out, str(y), (2, y - 3), scale, thickness)
    return out


def _label(image: np.ndarray, text: str, origin: tuple[int, int], scale: float,
           thickness: int) -> None:
    """Text readable on any background: dark outline, white fill."""
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), thickness + 2,
                cv2.LINE_AA)
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), thickness,
                cv2.LINE_AA)
