"""Deep pictures (16-bit grey or colour PNG, TIFF, PGM, FFV1: a thermal or high-speed camera's,
a scanner's) read as 8-bit.

Trackers work on 8-bit pixels. A camera's 12- or 14-bit values stored in 16-bit files use only
the low bits, so FFmpeg's conversion (the top 8 of the 16 bits) would leave them 0..15 or
0..63: a picture near black, its contrast gone. A sequence (an image folder, a video) is
scaled instead by the bits its first picture uses: its largest value (of its three channels,
in colour) once isolated pixels (hot or dead pixels, a marker at 65535) are set aside by a 3x3
median, rounded up to a whole number of bits (at least 8), is mapped to 255. The pictures
after it are scaled alike (no gain that follows each frame's brightness) until one uses more
bits (a dark or dim first frame: a lens cap, a fade-in, a thermal camera's shutter): the
scale rises to them from that picture on, with a warning, and never falls; isolated pixels
brighter than the scale clip at 255.
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
    wide = deep(fmt)
    return picture.to_ndarray(format=("gray16le" if wide else "gray") if grey(fmt) else
                              "bgr48le" if wide else "bgr24")


def layout(pixels: np.ndarray) -> str:
    """The pixel format of ``pixels`` as :func:`stored_pixels` gives them (``gray``,
    ``gray16le``, ``bgr24``, ``bgr48le``)."""
    deeper = pixels.dtype == np.uint16
    if pixels.ndim == 2:
        return "gray16le" if deeper else "gray"
    return "bgr48le" if deeper else "bgr24"


def eight_bit(pixels: np.ndarray, bits: int = MAX_BITS) -> np.ndarray:
    """``pixels`` as uint8: as they are when they are 8-bit, else 16-bit values of ``bits``
    bits scaled so that ``2**bits - 1`` is 255 (rounded; a larger value clips at 255)."""
    if pixels.dtype == np.uint8:
        return pixels
    return cv2.convertScaleAbs(pixels, alpha=255.0 / ((1 << bits) - 1))


def mixed_note(path: object, bits: int | None, what: str = "image") -> str:
    """The warning of ``path``, an image (or a video's frame: ``what``) of another depth than
    its sequence's first: 16-bit in a sequence of 8-bit ones (``bits`` None), or 8-bit in one
    of 16-bit ones whose values use ``bits`` bits; said once, of the first such one."""
    if bits is None:
        how = "among 8-bit ones: read as 16-bit values, 0..65535 scaled to 0..255"
    else:
        how = (f"among 16-bit ones (values of {bits} bits, 0..{(1 << bits) - 1} scaled to "
               "0..255): read as it is, 0..255")
    kind = "an 8-bit" if bits is not None else "a 16-bit"
    return (f"{path}: {kind} {what} {how} (the sequence's depth is its first {what}'s; later "
            f"{what}s of another depth are not named)")


def as_kind(pixels: np.ndarray, colour: bool) -> np.ndarray:
    """8-bit ``pixels`` (grey ``(h, w)`` or BGR ``(h, w, 3)``) as ``colour`` (BGR) or grey
    ones: a sequence is grey or colour as its first picture is."""
    if colour and pixels.ndim == 2:
        return cv2.cvtColor(pixels, cv2.COLOR_GRAY2BGR)
    if not colour and pixels.ndim == 3:
        return cv2.cvtColor(pixels, cv2.COLOR_BGR2GRAY)
    return pixels


class DepthScale:
    """How the pictures of a sequence (an image folder's ``images``, a video's ``frames``:
    ``what``) named ``name``, whose first picture as stored (:func:`stored_pixels`) is
    ``first``, are read as 8-bit: the 16-bit ones by the bits the first one uses
    (:func:`used_bits`; 16 when the first is 8-bit), raised from a later one whose values use
    more bits on, 8-bit ones as they are. Its :attr:`notes` (frame index, warning) say so: the
    depth of a 16-bit sequence, each rise, and the first picture of another depth than the
    first's."""

    def __init__(self, name: str, first: np.ndarray, what: str = "images") -> None:
        self.name, self.what = name, what
        #: Whether the sequence is 16-bit (its first picture is), and grey or colour.
        self.deep = first.dtype == np.uint16
        self.colour = first.ndim == 3
        #: The bits 16-bit values are scaled by: the first picture's, then those of a later one
        #: whose values use more (the scale rises, never falls).
        self.bits = used_bits(first) if self.deep else MAX_BITS
        self.notes: list[tuple[int, str]] = []
        if self.deep:
            self.notes.append((0, depth_note(name, self.bits, what, self.colour)))
        self._mixed = False  # a picture of another depth than the first's was noted

    def frame(self, pixels: np.ndarray, index: int, path: object = None) -> np.ndarray:
        """``pixels``, picture ``index`` as stored (``path``, the image it was read from;
        None: a frame of ``name``), as uint8, grey or BGR as they are (:func:`as_kind`
        matches them to the sequence's)."""
        subject = path if path is not None else self.name
        deeper = pixels.dtype == np.uint16
        if not self._mixed and deeper != self.deep:
            self._mixed = True
            self.notes.append((index, mixed_note(
                path if path is not None else f"{self.name}: frame {index}",
                self.bits if self.deep else None, self.what[:-1])))
        elif deeper and self.deep and (bits := self._bits_over(pixels)) > self.bits:
            self.bits = bits
            top = (1 << self.bits) - 1
            self.notes.append((index, (
                f"{subject}: frame {index}'s values use {self.bits} bits, more than before: "
                f"scaled 0..{top} to 0..255 from this {self.what[:-1]} on")))
        return eight_bit(pixels, self.bits)

    def _bits_over(self, pixels: np.ndarray) -> int:
        """The bits 16-bit ``pixels`` use (:func:`used_bits`, hot pixels aside) when their
        plain largest value (cheap: looked at first) is above the scale; else the scale's."""
        top = (1 << self.bits) - 1
        largest = cv2.minMaxLoc(pixels.reshape(pixels.shape[0], -1))[1]
        # A 3x3 median exceeds ``top`` only where 5 of its 9 values do, and one pixel fills at
        # most 4 of a window's (at a corner, the border replicated): one stuck pixel above the
        # scale (a marker at 65535) asks for no median, on every frame (a picture too small
        # for the median is read by its plain largest value: used_bits).
        if largest <= top:
            return self.bits
        if min(pixels.shape[:2]) >= 3:
            above = (pixels > top).reshape(-1, pixels.shape[2] if pixels.ndim == 3 else 1)
            if int(above.sum(axis=0).max()) < 2:
                return self.bits
        return used_bits(pixels)

    def news(self) -> list[tuple[int, str]]:
        """The :attr:`notes` added since the last call (handed on: they are let go)."""
        new, self.notes = self.notes, []
        return new


def depth_note(name: str, bits: int, what: str = "images", colour: bool = False) -> str:
    """The warning saying how ``name``'s 16-bit grey (or ``colour``) ``what`` (``images`` of a
    sequence, ``frames`` of a video), whose first one's values use ``bits`` bits (8: 8 or
    fewer, read as they are), are read."""
    shade = "colour" if colour else "grey"
    how = (f"{bits} bits (the first {what[:-1]}'s, hot pixels aside): read as 8-bit {shade}, "
           f"0..{(1 << bits) - 1} scaled to 0..255" if bits > 8 else
           f"8 bits or fewer (the first {what[:-1]}'s, hot pixels aside): read as 8-bit "
           f"{shade}, 0..255 as they are")
    return (f"{name}: {MAX_BITS}-bit {shade} {what} whose values use {how} (a later "
            f"{what[:-1]} whose values use more bits scales by them from it on, with a warning; "
            "isolated brighter pixels clip at 255)")
