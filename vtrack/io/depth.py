"""Deep grey images (16-bit PNG, TIFF, PGM: a thermal or high-speed camera's) read as 8-bit.

Trackers work on 8-bit pixels. A camera's 12- or 14-bit values stored in 16-bit files use only
the low bits, so FFmpeg's conversion (the top 8 of the 16 bits) would leave them 0..15 or
0..63: a picture near black, its contrast gone. A sequence is scaled instead by the bits its
first image uses: its largest value once isolated pixels (hot or dead pixels, a marker at
65535) are set aside by a 3x3 median, rounded up to a whole number of bits (at least 8), is
mapped to 255; every image of the sequence is scaled alike (no gain that changes from frame to
frame), a brighter value clipping at 255.
"""

from __future__ import annotations

import cv2
import numpy as np

#: The most bits a grey image's values use (16-bit files).
MAX_BITS = 16


def used_bits(pixels: np.ndarray) -> int:
    """The bits (8 to 16) a 16-bit grey image's values use: those of its largest value once
    isolated pixels (hot pixels) are set aside by a 3x3 median, at least 8."""
    largest = int(cv2.medianBlur(pixels, 3).max()) if min(pixels.shape[:2]) >= 3 else \
        int(pixels.max())
    return min(MAX_BITS, max(8, largest.bit_length()))


def eight_bit(pixels: np.ndarray, bits: int = MAX_BITS) -> np.ndarray:
    """``pixels`` as uint8: as they are when they are 8-bit, else 16-bit values of ``bits``
    bits scaled so that ``2**bits - 1`` is 255 (rounded; a larger value clips at 255)."""
    if pixels.dtype == np.uint8:
        return pixels
    return cv2.convertScaleAbs(pixels, alpha=255.0 / ((1 << bits) - 1))


def depth_note(name: str, bits: int) -> str:
    """The warning saying how a sequence of 16-bit grey images ``name`` was read."""
    top = (1 << bits) - 1
    return (f"{name}: 16-bit grey images whose values use {bits} bits (the first image's, hot "
            f"pixels aside): read as 8-bit grey, 0..{top} scaled to 0..255 (a brighter value "
            "clips at 255)")
