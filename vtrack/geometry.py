"""Boxes and windows: the geometry every stage, reader, writer and metric shares.

A box is ``(x, y, w, h)`` in pixels with ``(x, y)`` its top-left corner (floats allowed, the
tracker works sub-pixel). A window is an integer pixel region ``(x0, y0, x1, y1)``, half-open,
already clipped to the frame, used to cut the part of a frame a stage works on.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, NamedTuple

from vtrack.errors import ConfigError, is_real, number_text, quoted
from vtrack.params import shown

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import ArrayLike

#: Largest frame side vtrack accepts, checked before any frame is allocated (a 16384 x 16384
#: bgr24 frame is 768 MiB; nothing a user tracks is bigger). See README, value ranges.
MAX_FRAME_SIDE = 16384
MAX_FRAME_PIXELS = MAX_FRAME_SIDE * MAX_FRAME_SIDE
#: Smallest initial box side: a mean-shift window or a histogram needs a few pixels.
MIN_BOX_SIDE = 4.0


def frame_size_problem(width: int, height: int, named: bool = False) -> str | None:
    """Why a ``width`` x ``height`` frame cannot be tracked (None: it can); ``named``: the
    message's subject already shows the size (``--raw 50000x50000``), which is not repeated."""
    if width <= 0 or height <= 0:
        return "empty" if named else f"the frame size {shown(width)}x{shown(height)} is empty"
    if width > MAX_FRAME_SIDE or height > MAX_FRAME_SIDE:
        limit = f"{MAX_FRAME_SIDE}x{MAX_FRAME_SIDE}"
        if named:
            return f"larger than vtrack accepts (at most {limit})"
        return f"the frames are {shown(width)}x{shown(height)}; vtrack accepts at most {limit}"
    return None


class Box(NamedTuple):
    """Axis-aligned box; ``(x, y)`` is the top-left corner."""

    x: float
    y: float
    w: float
    h: float

    @property
    def cx(self) -> float:
        """The centre's x: ``x + w / 2``."""
        return self.x + self.w / 2.0

    @property
    def cy(self) -> float:
        """The centre's y: ``y + h / 2``."""
        return self.y + self.h / 2.0

    @property
    def area(self) -> float:
        """``w * h`` in square pixels (0 for a negative width or height)."""
        return max(self.w, 0.0) * max(self.h, 0.0)

    def plain(self) -> Box:
        """This box with each value a Python ``float`` (a NumPy number a stage computed it
        with taken as its value): what the public results hold."""
        return Box(float(self.x), float(self.y), float(self.w), float(self.h))

    @classmethod
    def from_center(cls, cx: float, cy: float, w: float, h: float) -> Box:
        """The ``w`` x ``h`` box centred on ``(cx, cy)``."""
        return cls(cx - w / 2.0, cy - h / 2.0, w, h)

    def moved_to(self, cx: float, cy: float) -> Box:
        """The same size, centred on ``(cx, cy)``."""
        return Box.from_center(cx, cy, self.w, self.h)

    def is_valid(self) -> bool:
        """True when every value is finite and the width and height are above 0."""
        return all(math.isfinite(v) for v in self) and self.w > 0 and self.h > 0

    def text(self) -> str:
        """``x,y,w,h`` as ``--init`` takes it (2 decimals at most): how a message shows a box.
        A value that rounds to zero shows as ``0``, never ``-0`` (``-1e-9``, ``-0.004``)."""
        return ",".join(f"{round(v, 2) + 0.0:g}" for v in self)

    def outside(self, width: int, height: int) -> bool:
        """True when no part of the box lies in a ``width`` x ``height`` frame (a NaN box is
        outside too)."""
        inside = (self.x < width and self.x + self.w > 0
                  and self.y < height and self.y + self.h > 0)
        return not inside

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

    @classmethod
    def union(cls, windows: Sequence[Window]) -> Window:
        """The smallest window holding every one of ``windows`` (at least one)."""
        return cls(min(w.x0 for w in windows), min(w.y0 for w in windows),
                   max(w.x1 for w in windows), max(w.y1 for w in windows))


def iou(a: Box, b: Box) -> float:
    """Intersection over union of two boxes, 0..1 (0 when either is empty)."""
    ix = min(a.x + a.w, b.x + b.w) - max(a.x, b.x)
    iy = min(a.y + a.h, b.y + b.h) - max(a.y, b.y)
    if ix <= 0 or iy <= 0:
        return 0.0
    inter = ix * iy
    union = a.area + b.area - inter
    # rounding can put the intersection a hair above the union of two equal boxes
    return min(inter / union, 1.0) if union > 0 else 0.0


def iou_matrix(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """IoU of every box of ``a`` with every box of ``b`` (boxes, or ``(N, 4)`` and ``(M, 4)``
    arrays of x, y, w, h): an ``(N, M)`` float array whose every value is, bit for bit, what
    :func:`iou` gives for the pair (finite boxes), computed for all pairs at once."""
    import numpy as np  # here: `vtrack.Box` alone loads no numpy

    p = np.asarray(a, float).reshape(-1, 1, 4)
    q = np.asarray(b, float).reshape(1, -1, 4)
    ix = np.minimum(p[..., 0] + p[..., 2], q[..., 0] + q[..., 2]) - np.maximum(p[..., 0],
                                                                              q[..., 0])
    iy = np.minimum(p[..., 1] + p[..., 3], q[..., 1] + q[..., 3]) - np.maximum(p[..., 1],
                                                                              q[..., 1])
    inter = ix * iy
    union = (np.maximum(p[..., 2], 0.0) * np.maximum(p[..., 3], 0.0)
             + np.maximum(q[..., 2], 0.0) * np.maximum(q[..., 3], 0.0) - inter)
    overlapping = (ix > 0) & (iy > 0) & (union > 0)
    ratio = np.where(overlapping, inter / np.where(overlapping, union, 1.0), 0.0)
    return np.minimum(ratio, 1.0)  # as iou: never a hair above 1 (two equal boxes)


def center_error(a: Box, b: Box) -> float:
    """Euclidean distance between the two boxes' centres, in pixels."""
    return math.hypot(a.cx - b.cx, a.cy - b.cy)


def box_from_parts(parts: Sequence[str], where: str, expected: str, shown: str,
                   error: type[Exception]) -> Box:
    """The box ``x, y, w, h`` of 4 number texts (``-0`` read as 0): all finite, ``w, h > 0``.
    Otherwise raises ``error`` naming ``where`` and showing ``shown`` (what the user wrote):
    "expected ``expected``" when the numbers are not 4 finite ones, else that width and height
    must be positive. One rule for ``--init`` and sidecar files."""
    try:  # (+ 0.0: "-0" is the number 0, recorded and echoed as 0, not -0)
        values = [float(part) + 0.0 for part in parts]
    except ValueError:
        values = []
    if len(values) != 4 or not all(math.isfinite(v) for v in values):
        raise error(f"{where}: expected {expected}, got {quoted(shown)}")
    box = Box(*values)
    if box.w <= 0 or box.h <= 0:
        raise error(f"{where}: width and height must be positive, got {quoted(shown)}")
    return box


#: The forms a box is written in, by ``--init`` and in a sidecar file (:func:`parse_box_text`),
#: as a message about a bad one lists them.
BOX_FORMS = "x,y,w,h or x y w h (4 numbers separated by commas, spaces or tabs)"


def parse_box_text(text: str, where: str, error: type[Exception],
                   expected: str = BOX_FORMS) -> Box:
    """The box of ``text``: 4 finite numbers separated by commas, spaces or tabs (``x,y,w,h``,
    ``x, y, w, h``, ``x y w h``), ``w, h > 0``; otherwise ``error`` naming ``where`` and
    saying what was ``expected`` (:func:`box_from_parts`). One parser for ``--init`` and the
    sidecar file, so both take the same forms."""
    # an empty field ("1,,2,3,4", "1,2,3,4,") stays a part: no number, refused
    parts = re.split(r"\s*,\s*|\s+", text.strip())
    return box_from_parts(parts, where, expected, text, error)


def as_box(box: Box | Any, where: str = "init_box") -> Box:
    """A :class:`Box` from a ``Box`` or any 4 numbers ``(x, y, w, h)`` (real numbers:
    :func:`~vtrack.errors.is_real`); ConfigError naming ``where`` otherwise (what ``--init``
    raises). Whether it can be tracked in a frame is :func:`check_init_box`'s to say."""
    try:  # a Box too: Box("10", 1, 2, 3) is built without a check
        if isinstance(box, str | bytes):  # "1234" would be 4 digits
            raise TypeError
        items = tuple(box)
        if not all(is_real(v) for v in items):
            raise TypeError  # True is not the number 1, nor '10' the number 10
        values = tuple(float(v) for v in items)
    except OverflowError:  # (an int or Decimal beyond any float: beyond any frame too)
        raise ConfigError(f"{where}: {shown(box)}: a number beyond a float's range (x, y, w, "
                          "h are pixels of the frame)") from None
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: expected (x, y, w, h) numbers, got {shown(box)}") from None
    if len(values) != 4:
        raise ConfigError(f"{where}: expected 4 numbers (x, y, w, h), got {len(values)}")
    return Box(*values)


def check_init_box(box: Box, width: int, height: int, where: str, frame_note: str = "") -> None:
    """Refuse an initial box the trackers cannot start from: not finite, empty, smaller than
    ``MIN_BOX_SIDE`` pixels, larger than the frame, or not overlapping it. The message shows
    the box's numbers as given (rounding could put one onto the limit it breaks); the last two
    end with ``frame_note`` (what made the frame that size: an input's rotation)."""
    shown = ",".join(number_text(v) for v in box)
    if not all(math.isfinite(v) for v in box):
        raise ConfigError(f"{where}: the box {shown} holds a value that is not a finite number")
    if not box.is_valid():
        raise ConfigError(f"{where}: the box {shown} is empty (width and height must be > 0)")
    if box.w < MIN_BOX_SIDE or box.h < MIN_BOX_SIDE:
        raise ConfigError(
            f"{where}: the box {shown} is smaller than {MIN_BOX_SIDE:g}x{MIN_BOX_SIDE:g} "
            "pixels, too small to track"
        )
    if box.w > width or box.h > height:
        raise ConfigError(f"{where}: the box {shown} is larger than the {width}x{height} frame"
                          f"{frame_note}")
    if box.window(width, height) is None:
        raise ConfigError(f"{where}: the box {shown} lies outside the {width}x{height} frame"
                          f"{frame_note}")
