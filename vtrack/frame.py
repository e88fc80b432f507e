"""Frames as the readers hand them over: pixels in their native layout, converted per window.

Stages ask a frame for the window they need (``frame.bgr(window)``, ``frame.gray(window)``); only
that window is converted, so a 1080p frame decoded as yuv420p never becomes a full BGR image on
the tracking path. Writers ask for ``frame.i420()`` (planar Y, U, V stacked as one
``(h * 3 // 2, w)`` array), which is free for yuv420p input.
"""

from __future__ import annotations

import copy
import math
from abc import ABC, abstractmethod

import cv2
import numpy as np

from vtrack.errors import is_real, real_or_nan
from vtrack.geometry import Window, frame_size_problem
from vtrack.params import shown


def i420_planes(buffer: np.ndarray, width: int, height: int) -> tuple[np.ndarray, ...]:
    """Writable, contiguous views ``(y, u, v)`` of an I420 buffer (no copy)."""
    flat = buffer.reshape(-1)
    luma = width * height
    quarter = luma // 4
    y = flat[:luma].reshape(height, width)
    u = flat[luma : luma + quarter].reshape(height // 2, width // 2)
    v = flat[luma + quarter : luma + 2 * quarter].reshape(height // 2, width // 2)
    return y, u, v


def halved(image: np.ndarray, k: int) -> np.ndarray:
    """``image`` (its sides multiples of ``k``, a power of two) shrunk by ``k``: halved
    ``log2 k`` times, each pixel the mean of a 2 x 2 block (``cv2.INTER_AREA``)."""
    while k > 1:
        image = cv2.resize(image, (image.shape[1] // 2, image.shape[0] // 2),
                           interpolation=cv2.INTER_AREA)
        k //= 2
    return image


def check_index(index: object) -> None:
    """Nothing when ``index`` is a whole number >= 0 (a frame's 0-based number; a NumPy
    integer too); TypeError for one that is no whole number, ValueError for a negative one, in
    one wording. The message shows a number, else only the type: an image given in its place
    (arguments swapped) is not printed."""
    expected = "frame index: expected a whole number >= 0 (the frame's 0-based number, the " \
               "first argument), got"
    if isinstance(index, bool) or not isinstance(index, int | np.integer):
        raise TypeError(f"{expected} {type(index).__name__}")
    if index < 0:
        raise ValueError(f"{expected} {index}")


def check_pixels(index: int, pixels: object, ndim: int, layout: str) -> None:
    """TypeError naming frame ``index`` unless ``pixels`` is a uint8 NumPy array of ``ndim``
    dimensions (3: the last one of 3 channels), the ``layout`` a message names ("HxWx3 BGR");
    TypeError (ValueError: a negative one) first for an ``index`` that is not a frame number
    (:func:`check_index`).
    A few attribute checks, no pixel is read: the frames' constructors call it per frame."""
    check_index(index)
    if not isinstance(pixels, np.ndarray):
        raise TypeError(f"frame {index}: expected a NumPy {layout} image, got "
                        f"{type(pixels).__name__}")
    if pixels.dtype != np.uint8:
        raise TypeError(f"frame {index}: expected uint8 pixels, got {pixels.dtype}")
    if pixels.ndim != ndim or (ndim == 3 and pixels.shape[2] != 3):
        raise TypeError(f"frame {index}: expected an {layout} image, got shape {pixels.shape}")


class Frame(ABC):
    """One picture of the input. ``index`` is 0-based; ``time_s`` comes from its timestamp.

    The constructors refuse what cannot be a frame: an ``index`` that is not a whole number
    (TypeError) or is negative (ValueError), pixels that are not uint8 or not in the class's
    layout (TypeError), a size
    :func:`frame_size_problem` refuses or a ``time_s`` that is not finite (ValueError; one
    that is not a real number, True included, a TypeError), each naming the frame (``frame
    3: ...``). They are kept as a Python ``int`` and ``float`` whatever number types they were
    given as (NumPy's too).
    """

    __slots__ = ("index", "time_s", "width", "height")

    def __init__(self, index: int, time_s: float, width: int, height: int) -> None:
        # (the index was checked with the pixels, check_pixels, before any size was read)
        problem = frame_size_problem(width, height)
        if problem:
            raise ValueError(f"frame {index}: {problem}")
        if not is_real(time_s):  # None, text, True: no time
            raise TypeError(f"frame {index}: time_s {shown(time_s)} is not a number")
        seconds = real_or_nan(time_s)  # (NaN for a Decimal beyond a float's range)
        if not math.isfinite(seconds):
            raise ValueError(f"frame {index}: time_s {shown(time_s)} is not a finite number")
        # a Python int and float, whatever number type was given: results and the frames
        # numbered after this one compute with them (an np.uint8 255 + 1 would be 0)
        self.index = int(index)
        self.time_s = seconds
        self.width = width
        self.height = height

    def full_window(self) -> Window:
        """The window of the whole frame (``bgr()`` and ``gray()`` without one)."""
        return Window(0, 0, self.width, self.height)

    def kept(self) -> Frame:
        """This frame with pixels of its own, to keep past the next frame: a reader may fill
        the next frames into the buffers this one's pixels are in (raw input's ring of
        buffers, a camera's), and the caller may reuse the array it gave."""
        twin = copy.copy(self)
        for cls in type(self).__mro__:
            for name in getattr(cls, "__slots__", ()):
                value = getattr(self, name, None)
                if isinstance(value, np.ndarray):
                    setattr(twin, name, value.copy())
        return twin

    @abstractmethod
    def bgr(self, window: Window | None = None) -> np.ndarray:
        """The window (default: whole frame) as a ``uint8`` BGR array of shape (h, w, 3)."""

    def bgr_sampled(self, window: Window, k: int) -> np.ndarray:
        """The centre pixel of every ``k`` x ``k`` block of ``window`` (``k`` odd), as BGR:
        ``bgr(window)[o::k, o::k]`` with ``o = (k - 1) // 2``, the same values (what
        ``cv2.resize`` with ``INTER_LINEAR`` gives at an odd whole factor)."""
        o = (k - 1) // 2
        return np.ascontiguousarray(self.bgr(window)[o::k, o::k])

    def shrunk_size(self, k: int) -> tuple[int, int]:
        """Width and height of the frame shrunk by ``k`` (a power of two, :meth:`bgr_shrunk`):
        ``width // k`` and ``height // k``, each rounded down to an even number."""
        return (self.width // k) & ~1, (self.height // k) & ~1

    def bgr_shrunk(self, k: int) -> np.ndarray:
        """The frame shrunk by ``k`` (a power of two) as BGR, halved again and again (each
        halving averages 2 x 2 blocks: ~20x cheaper than averaging 4 x 4 blocks at once), the
        size :meth:`shrunk_size` (right and bottom pixels beyond whole blocks left out)."""
        w, h = self.shrunk_size(k)
        return halved(self.bgr(Window(0, 0, w * k, h * k)), k)

    def gray_shrunk(self, k: int) -> np.ndarray:
        """As :meth:`bgr_shrunk`, grey (luma)."""
        w, h = self.shrunk_size(k)
        return halved(self.gray(Window(0, 0, w * k, h * k)), k)

    @abstractmethod
    def gray(self, window: Window | None = None) -> np.ndarray:
        """The window (default: whole frame) as a ``uint8`` grey (luma) array of shape (h, w)."""

    @abstractmethod
    def i420(self) -> np.ndarray:
        """The whole frame as I420 (``(h * 3 // 2, w)`` uint8); width and height must be even."""


class BgrFrame(Frame):
    """A frame held as a BGR array (image files, raw bgr24/rgb24 input, odd-sized video)."""

    __slots__ = ("_bgr",)

    def __init__(self, index: int, time_s: float, bgr: np.ndarray) -> None:
        check_pixels(index, bgr, 3, "HxWx3 BGR")
        super().__init__(index, time_s, bgr.shape[1], bgr.shape[0])
        self._bgr = bgr

    def bgr(self, window: Window | None = None) -> np.ndarray:
        return self._bgr if window is None else self._bgr[window.slices]

    def gray(self, window: Window | None = None) -> np.ndarray:
        return cv2.cvtColor(self.bgr(window), cv2.COLOR_BGR2GRAY)

    def i420(self) -> np.ndarray:
        return cv2.cvtColor(self._bgr, cv2.COLOR_BGR2YUV_I420)


class GrayFrame(Frame):
    """A single-channel frame (raw gray input, grey image sequences, thermal footage)."""

    __slots__ = ("_gray",)

    def __init__(self, index: int, time_s: float, gray: np.ndarray) -> None:
        check_pixels(index, gray, 2, "HxW grey")
        super().__init__(index, time_s, gray.shape[1], gray.shape[0])
        self._gray = gray

    def bgr(self, window: Window | None = None) -> np.ndarray:
        return cv2.cvtColor(self.gray(window), cv2.COLOR_GRAY2BGR)

    def gray(self, window: Window | None = None) -> np.ndarray:
        return self._gray if window is None else self._gray[window.slices]

    def bgr_sampled(self, window: Window, k: int) -> np.ndarray:
        """As :meth:`Frame.bgr_sampled`, converting only the sampled pixels."""
        o = (k - 1) // 2
        sampled = self._gray[window.y0 + o:window.y1:k, window.x0 + o:window.x1:k]
        return cv2.cvtColor(np.ascontiguousarray(sampled), cv2.COLOR_GRAY2BGR)

    def i420(self) -> np.ndarray:
        out = np.full((self.height * 3 // 2, self.width), 128, np.uint8)
        out[: self.height] = self._gray
        return out


#: Full-range ("JPEG", yuvj420p) luma and chroma levels -> video range (luma 16..235, chroma
#: 16..240 around 128), the range OpenCV's YUV -> BGR conversions take.
_VIDEO_LUMA = np.round(16 + np.arange(256) * 219 / 255).astype(np.uint8)
_VIDEO_CHROMA = np.round(128 + (np.arange(256) - 128) * 224 / 255).astype(np.uint8)


def _rgb_to_ycbcr(kr: float, kb: float) -> np.ndarray:
    """RGB -> (Y, Cb, Cr) of the standard with luma weights ``kr``, ``kb`` (normalised)."""
    kg = 1 - kr - kb
    return np.array([[kr, kg, kb],
                     [-kr / (2 * (1 - kb)), -kg / (2 * (1 - kb)), 0.5],
                     [0.5, -kg / (2 * (1 - kr)), -kb / (2 * (1 - kr))]])


def _bt709_to_601_transforms() -> tuple[np.ndarray, np.ndarray]:
    """OpenCV ``transform`` matrices on (U, V) code values for BT.709 -> BT.601 (the standard
    OpenCV's conversions assume): the new (U, V), and luma's change + 128. Grey stays grey, so
    chroma does not depend on luma; luma gains ``219 / 224`` of a chroma term (their code
    ranges)."""
    m = _rgb_to_ycbcr(0.299, 0.114) @ np.linalg.inv(_rgb_to_ycbcr(0.2126, 0.0722))
    chroma, luma = m[1:, 1:], m[0, 1:] * 219 / 224
    chroma_rows = np.hstack([chroma, (128 - 128 * chroma.sum(axis=1))[:, None]])
    luma_row = np.hstack([luma, [128 - 128 * luma.sum()]])[None, :]
    return chroma_rows.astype(np.float32), luma_row.astype(np.float32)


_CHROMA_709_TO_601, _LUMA_CHANGE_709_TO_601 = _bt709_to_601_transforms()


def bt709_to_601(luma: np.ndarray, u: np.ndarray, v: np.ndarray, upsample: bool) -> None:
    """Video-range BT.709 planes (uint8) moved to BT.601 in place. ``upsample``: ``u`` and
    ``v`` are 4:2:0 planes, each sample shared by a 2 x 2 block of ``luma`` (as OpenCV's
    conversions pair them); else one chroma sample per luma sample (same shapes)."""
    chroma = cv2.merge([u, v])
    change = cv2.transform(chroma, _LUMA_CHANGE_709_TO_601)
    if upsample:
        change = cv2.resize(change, (luma.shape[1], luma.shape[0]),
                            interpolation=cv2.INTER_NEAREST)
    cv2.addWeighted(luma, 1.0, change, 1.0, -128.0, dst=luma)
    new_u, new_v = cv2.split(cv2.transform(chroma, _CHROMA_709_TO_601))
    u[:], v[:] = new_u, new_v


def to_video_range(luma: np.ndarray, u: np.ndarray, v: np.ndarray) -> None:
    """Full-range Y, U and V planes (uint8, contiguous) moved to video range in place."""
    cv2.LUT(luma, _VIDEO_LUMA, dst=luma)
    for chroma in (u, v):
        cv2.LUT(chroma, _VIDEO_CHROMA, dst=chroma)


class I420Frame(Frame):
    """A frame held as its Y, U and V planes (decoded yuv420p video, raw yuv420p input).

    Build it from one packed ``(h * 3 // 2, w)`` I420 array (PyAV's ``to_ndarray()`` layout, raw
    yuv420p input), or with :meth:`from_planes` from three plane arrays, which may be strided
    views of a decoder's own buffers: nothing is copied until a window is asked for.
    ``full_range``: the planes use the full 0..255 range (yuvj420p: MJPEG, many phones and
    cameras) rather than video range; ``bt709``: their colours are BT.709's (most HD video)
    rather than BT.601's. The planes are kept as decoded; only the pixels converted to BGR are
    moved to video range and BT.601 first (what OpenCV's conversions take), and pictures
    written out to video range, so colours are neither stretched nor shifted.
    """

    __slots__ = ("y", "u", "v", "full_range", "bt709")

    def __init__(self, index: int, time_s: float, planes: np.ndarray,
                 full_range: bool = False, bt709: bool = False) -> None:
        check_pixels(index, planes, 2, "(h * 3 // 2)xW I420")
        width, height = planes.shape[1], planes.shape[0] * 2 // 3
        if planes.shape[0] != height * 3 // 2 or width % 2 or height % 2:
            raise TypeError(f"frame {index}: expected an (h * 3 // 2)xW I420 image of even "
                            f"width and height, got shape {planes.shape}")
        super().__init__(index, time_s, width, height)
        self.y, self.u, self.v = i420_planes(planes, width, height)
        self.full_range, self.bt709 = full_range, bt709

    @classmethod
    def from_planes(cls, index: int, time_s: float, y: np.ndarray, u: np.ndarray,
                    v: np.ndarray, full_range: bool = False, bt709: bool = False) -> I420Frame:
        """A frame over existing planes (``y`` is (h, w), ``u`` and ``v`` (h/2, w/2)); no copy."""
        for plane in (y, u, v):
            check_pixels(index, plane, 2, "HxW plane")
        half = (y.shape[0] // 2, y.shape[1] // 2)
        if u.shape != half or v.shape != half or y.shape[0] % 2 or y.shape[1] % 2:
            raise TypeError(f"frame {index}: expected an even-sized Y plane and U, V planes of "
                            f"half its size, got {y.shape}, {u.shape}, {v.shape}")
        frame = cls.__new__(cls)
        Frame.__init__(frame, index, time_s, y.shape[1], y.shape[0])
        frame.y, frame.u, frame.v = y, u, v
        frame.full_range, frame.bt709 = full_range, bt709
        return frame

    def _to_opencv_levels(self, luma: np.ndarray, u: np.ndarray, v: np.ndarray,
                          upsample: bool) -> None:
        """Planes of this frame's pixels (uint8, contiguous, its own copies) moved in place to
        video range and BT.601, what OpenCV's conversions take (``upsample``: 4:2:0 chroma,
        else one chroma sample per luma sample)."""
        if self.full_range:
            to_video_range(luma, u, v)
        if self.bt709:
            bt709_to_601(luma, u, v, upsample)

    def _converted(self, packed: np.ndarray, luma_rows: int) -> np.ndarray:
        """BGR of a packed I420 buffer of this frame's pixels (its own copy)."""
        self._to_opencv_levels(*i420_planes(packed, packed.shape[1], luma_rows), upsample=True)
        return cv2.cvtColor(packed, cv2.COLOR_YUV2BGR_I420)

    def bgr(self, window: Window | None = None) -> np.ndarray:
        if window is None:
            return self._converted(self.i420(), self.height)
        # Convert an even-aligned window on its own, then trim it to the one asked for.
        ex0, ey0 = window.x0 & ~1, window.y0 & ~1
        ex1 = min(window.x1 + (window.x1 & 1), self.width)
        ey1 = min(window.y1 + (window.y1 & 1), self.height)
        ew, eh = ex1 - ex0, ey1 - ey0
        packed = np.empty((eh * 3 // 2, ew), np.uint8)
        py, pu, pv = i420_planes(packed, ew, eh)
        py[:] = self.y[ey0:ey1, ex0:ex1]
        pu[:] = self.u[ey0 // 2 : ey1 // 2, ex0 // 2 : ex1 // 2]
        pv[:] = self.v[ey0 // 2 : ey1 // 2, ex0 // 2 : ex1 // 2]
        bgr = self._converted(packed, eh)
        return bgr[window.y0 - ey0 : window.y1 - ey0, window.x0 - ex0 : window.x1 - ex0]

    def bgr_sampled(self, window: Window, k: int) -> np.ndarray:
        """Only the sampled pixels are converted (1 / k^2 of the window). Each keeps its own
        chroma sample, so they go through 4:2:2 (YUY2: one chroma pair per two pixels, the
        second pixel a copy, dropped after); OpenCV converts 4:2:2 and 4:2:0 with the same
        BT.601 integer arithmetic, so the values equal those of :meth:`bgr` (checked over all
        256^3 Y, U, V triples)."""
        o = (k - 1) // 2
        rows = np.arange(window.y0 + o, window.y1, k)
        cols = np.arange(window.x0 + o, window.x1, k)
        if rows.size == 0 or cols.size == 0:
            return np.empty((rows.size, cols.size, 3), np.uint8)
        luma = np.ascontiguousarray(
            self.y[window.y0 + o : window.y1 : k, window.x0 + o : window.x1 : k])
        # chroma of each sampled pixel, from the window's part of the U and V planes
        r0, c0 = rows[0] // 2, cols[0] // 2
        half_rows, half_cols = rows // 2 - r0, cols // 2 - c0
        u, v = (plane[r0 : half_rows[-1] + r0 + 1, c0 : half_cols[-1] + c0 + 1]
                .take(half_rows, axis=0).take(half_cols, axis=1) for plane in (self.u, self.v))
        if self.full_range or self.bt709:  # (luma may be a view of the decoder's plane)
            luma, u, v = (np.array(p, copy=True) for p in (luma, u, v))
            self._to_opencv_levels(luma, u, v, upsample=False)
        packed = cv2.merge([luma, u, luma, v])  # Y0 U Y1 V: one YUY2 pair per pixel
        pairs = cv2.cvtColor(packed.reshape(rows.size, cols.size * 2, 2),
                             cv2.COLOR_YUV2BGR_YUY2)
        # every other pixel: nearest-neighbour halving takes column 2 j exactly (a NumPy
        # strided copy of 3-byte pixels costs ~4x more)
        return cv2.resize(pairs, (cols.size, rows.size), interpolation=cv2.INTER_NEAREST)

    def bgr_shrunk(self, k: int) -> np.ndarray:
        """As :meth:`Frame.bgr_shrunk`, shrinking the planes (each by ``k``) before converting:
        the full-size frame is never converted (at 1080p that alone costs ~3 ms)."""
        w, h = self.shrunk_size(k)
        packed = np.empty((h * 3 // 2, w), np.uint8)
        for target, plane, side in zip(i420_planes(packed, w, h), (self.y, self.u, self.v),
                                       (1, 2, 2), strict=True):
            tw, th = w // side, h // side
            target[:] = halved(plane[: th * k, : tw * k], k)
        return self._converted(packed, h)

    def gray(self, window: Window | None = None) -> np.ndarray:
        return self.y if window is None else self.y[window.slices]

    def copy_planes_into(self, buffer: np.ndarray) -> None:
        """Copy the picture into a packed I420 ``buffer`` of the same size."""
        for target, plane in zip(i420_planes(buffer, self.width, self.height),
                                 (self.y, self.u, self.v), strict=True):
            np.copyto(target, plane)

    def i420(self) -> np.ndarray:
        packed = np.empty((self.height * 3 // 2, self.width), np.uint8)
        self.copy_planes_into(packed)
        return packed
