"""I420 buffers: views of their Y, U and V planes, and rotation by quarter turns (of them and
of any picture: a display matrix's, as a phone's video or photo carries it).

An I420 buffer is the ``(h * 3 // 2, w)`` uint8 array PyAV's ``to_ndarray()`` returns for a
yuv420p frame (and :class:`~vtrack.frame.I420Frame` holds): the ``h x w`` Y plane, then the
``h/2 x w/2`` U and V planes laid out row after row. Width and height are even.
"""

from __future__ import annotations

import cv2
import numpy as np

from vtrack.frame import i420_planes

#: Counter-clockwise quarter turns (degrees) -> ``cv2.rotate`` code.
ROTATE_CODES = {
    90: cv2.ROTATE_90_COUNTERCLOCKWISE,
    180: cv2.ROTATE_180,
    270: cv2.ROTATE_90_CLOCKWISE,
}


def quarter_turns(degrees: float) -> int:
    """A display-matrix angle (PyAV's ``VideoFrame.rotation``) as 0, 90, 180 or 270 degrees
    counter-clockwise."""
    return int(round(degrees / 90.0)) % 4 * 90


def turned(pixels: np.ndarray, degrees: int) -> np.ndarray:
    """``pixels`` (a picture of any channels) turned ``degrees`` (0, 90, 180, 270)
    counter-clockwise; the same array for 0."""
    return cv2.rotate(pixels, ROTATE_CODES[degrees]) if degrees else pixels


def rotate_i420(buffer: np.ndarray, width: int, height: int, degrees: int) -> np.ndarray:
    """A new I420 buffer holding ``buffer`` turned ``degrees`` (90, 180, 270) counter-clockwise."""
    code = ROTATE_CODES[degrees]
    out_w, out_h = (height, width) if degrees in (90, 270) else (width, height)
    out = np.empty((out_h * 3 // 2, out_w), np.uint8)
    for src, dst in zip(
        i420_planes(buffer, width, height), i420_planes(out, out_w, out_h), strict=True
    ):
        cv2.rotate(src, code, dst=dst)
    return out
