"""Deep pictures (16-bit grey or colour PNG, TIFF, PGM, FFV1: a thermal or high-speed camera's,
a scanner's) read as 8-bit.

Trackers work on 8-bit pixels. A camera's 12- or 14-bit values stored in 16-bit files use only
the low bits, so FFmpeg's conversion (the top 8 of the 16 bits) would leave them 0..15 or
0..63: a picture near black, its contrast gone. A sequence (an image folder, a video) is
scaled instead by the bits its first picture uses: its largest value (of its three channels,
in colour) once isolated pixels (hot or dead pixels, a marker at 65535) are set aside by a 3x3
median, rounded up to a whole number of bits (at least 8), is mapped to 255; every picture of
the sequence is scaled alike (no gain that changes from frame to frame), a brighter value
clipping at 255.
"""

from __future__ import annotations

import av
import cv2
import numpy as np

#: The most bits a grey image's values use (16-bit files).
MAX_BITS = 16


def used_bits(pixels: np.ndarray) -> int:
    """The bits (8 to 16) a 16-bit grey or colour image's values use: those of its largest
    value (of any channel) once isolated pixels (hot pixels) are set aside by a 3x3 median,
    at least 8."""
    largest = int(cv2.medianBlur(pixels, 3).max()) if min(pixels.shape[:2]) >= 3 else \
        int(pixels.max())
    return min(MAX_BITS, max(8, largest.bit_length()))


def grey(fmt: av.VideoFormat) -> bool:
    """Whether pictures of pixel format ``fmt`` are grey (with or without alpha)."""
    return fmt.name.startswith(("gray", "ya"))


def deep(fmt: av.VideoFormat) -> bool:
    """Whether pictures of pixel format ``fmt`` hold grey or RGB values of 16 bits (a 16-bit
    PNG's ``gray16be`` or ``rgb48be``, FFV1's ``gray16le``, ``gbrp16le``): read by the bits
    they use, not FFmpeg's top 8. Formats of 9 to 15 bits (``gray12le``, ``gbrp10le``: FFV1,
    DPX, RGB HEVC) and YUV video of 10 bits declare their depth: FFmpeg's conversion
    serves."""
    return (grey(fmt) or fmt.is_rgb) and fmt.components[0].bits == MAX_BITS


def stored_pixels(picture: av.VideoFrame) -> np.ndarray:
    """``picture``'s pixels as stored: ``(h, w)`` when it is grey, else ``(h, w, 3)`` BGR;
    uint16 when :func:`deep`, else uint8 (:func:`layout` names them)."""
    fmt = picture.format
    return picture.to_ndarray(format=("gray16le" if deep(fmt) else "gray") if grey(fmt) else
                              "bgr48le" if deep(fmt) else "bgr24")


def layout(pixels: np.ndarray) -> str:
    """The pixel format of ``pixels`` as :func:`stored_pixels` gives them (``gray``,
    ``gray16le``, ``bgr24``, ``bgr48le``)."""
    deeper = pixels.dtype == np.uint16
    if pixels.ndim == 2:
        return "gray16le" if deeper else "gray"
    return "bgr48le" if deeper else "bgr24"


def first_bits(picture: av.VideoFrame) -> int | None:
    """The bits a stream whose first picture is ``picture`` is scaled by (:func:`used_bits`
    of it) when it is :func:`deep`; None when it is not (FFmpeg's conversion serves)."""
    return used_bits(stored_pixels(picture)) if deep(picture.format) else None


def eight_bit(pixels: np.ndarray, bits: int = MAX_BITS) -> np.ndarray:
    """``pixels`` as uint8: as they are when they are 8-bit, else 16-bit values of ``bits``
    bits scaled so that ``2**bits - 1`` is 255 (rounded; a larger value clips at 255)."""
    if pixels.dtype == np.uint8:
        return pixels
    return cv2.convertScaleAbs(pixels, alpha=255.0 / ((1 << bits) - 1))


def mixed_note(path: object, bits: int | None) -> str:
    """The warning of ``path``, an image of another depth than its sequence's first: 16-bit in
    a sequence of 8-bit images (``bits`` None), or 8-bit in one of 16-bit images whose values
    use ``bits`` bits; said once, of the first such image."""
    if bits is None:
        how = "among 8-bit ones: read as 16-bit values, 0..65535 scaled to 0..255"
    else:
        how = (f"among 16-bit ones (values of {bits} bits, 0..{(1 << bits) - 1} scaled to "
               "0..255): read as it is, 0..255")
    kind = "an 8-bit" if bits is not None else "a 16-bit"
    return (f"{path}: {kind} image {how} (the sequence's depth is its first image's; later "
            "images of another depth are not named)")


def depth_note(name: str, bits: int, what: str = "images", colour: bool = False) -> str:
    """The warning saying how ``name``'s 16-bit grey (or ``colour``) ``what`` (``images`` of a
    sequence, ``frames`` of a video), whose values use ``bits`` bits, were read."""
    top = (1 << bits) - 1
    shade = "colour" if colour else "grey"
    return (f"{name}: {MAX_BITS}-bit {shade} {what} whose values use {bits} bits (the first "
            f"{what[:-1]}'s, hot pixels aside): read as 8-bit {shade}, 0..{top} scaled to 0..255 "
            "(a brighter value clips at 255)")
