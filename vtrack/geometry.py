"""Boxes and windows: the geometry every stage, reader, writer and metric shares.

A box is ``(x, y, w, h)`` in pixels with ``(x, y)`` its top-left corner (floats allowed, the
tracker works sub-pixel). A window is an integer pixel region ``(x0, y0, x1, y1)``, half-open,
already clipped to the frame, used to cut the part of a frame a stage works on.
"""

from __future__ import annotations

import math
from typing import NamedTuple


class Box(NamedTuple):
    """Axis-aligned box; ``(x, y)`` is the top-left corner."""

    x: float
    y: float
    w: float
    h: float

    @property
    def cx(self) -> float:
        return self.x + self.w / 2.0

    @property
    def cy(self) -> float:
        return self.y + self.h / 2.0

    @property
    def area(self) -> float:
        return max(self.w, 0.0) * max(self.h, 0.0)

    @classmethod
    def from_center(cls, cx: float, cy: float, w: float, h: float) -> Box:
        return cls(cx - w / 2.0, cy - h / 2.0, w, h)

    def moved_to(self, cx: float, cy: float) -> Box:
        """The same size, centred on ``(cx, cy)``."""
        return Box.from_center(cx, cy, self.w, self.h)

    def is_valid(self) -> bool:
        return all(math.isfinite(v) for v in self) and self.w > 0 and self.h > 0

    def window(self, width: int, height: int) -> Window | None:
        """The integer pixels this box covers inside a ``width`` x ``height`` frame, or None."""
        x0 = max(int(math.floor(self.x)), 0)
        y0 = max(int(math.floor(self.y)), 0)
        x1 = min(int(math.ceil(self.x + self.w)), width)
        y1 = min(int(math.ceil(self.y + self.h)), height)
        if x1 <= x0 or y1 <= y0:
            return None
        return Window(x0, y0, x1, y1)


class Window(NamedTuple):
    """Half-open integer pixel region ``[x0, x1) x [y0, y1)`` inside a frame."""

    x0: int
    y0: int
    x1: int
    y1: int

    @property
    def width(self) -> int:
        return self.x1 - self.x0

    @property
    def height(self) -> int:
        return self.y1 - self.y0

    @property
    def slices(self) -> tuple[slice, slice]:
        """Row and column slices for indexing an image array: ``image[window.slices]``."""
        return slice(self.y0, self.y1), slice(self.x0, self.x1)

    def as_box(self) -> Box:
        return Box(float(self.x0), float(self.y0), float(self.width), float(self.height))


def iou(a: Box, b: Box) -> float:
    """Intersection over union of two boxes, 0..1 (0 when either is empty)."""
    ix = min(a.x + a.w, b.x + b.w) - max(a.x, b.x)
    iy = min(a.y + a.h, b.y + b.h) - max(a.y, b.y)
    if ix <= 0 or iy <= 0:
        return 0.0
    inter = ix * iy
    union = a.area + b.area - inter
    return inter / union if union > 0 else 0.0


def center_error(a: Box, b: Box) -> float:
    """Euclidean distance between the two boxes' centres, in pixels."""
    return math.hypot(a.cx - b.cx, a.cy - b.cy)
