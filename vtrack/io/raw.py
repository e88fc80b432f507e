"""Raw frames from stdin (``-``), a FIFO or a file: fixed-size chunks read straight into buffers.

Each frame is read with ``readinto`` into one of a small ring of preallocated buffers (no 6 MB
allocation per frame at 1080p). A pipe is enlarged to 1 MiB first, which lifts 1080p bgr24 from
~145 to ~490 fps (PERFORMANCE.md point 5). A stream whose length is not a whole number of frames
yields its whole frames, then raises :class:`~vtrack.errors.PartialInputError`. An input that
begins as a container or an image does (an MP4 given with ``--raw``) is refused before a frame.

Plain reads are what PyAV's rawvideo demuxer does underneath; measured at 1080p bgr24 through an
enlarged pipe, the demuxer (a new packet per frame) was slower, so plain reads are used.
"""

from __future__ import annotations

import contextlib
import fcntl
import math
import os
import re
import stat
from collections.abc import Iterator
from dataclasses import dataclass
from numbers import Integral
from typing import BinaryIO

import cv2
import numpy as np

from vtrack.errors import (
    ConfigError,
    InputError,
    PartialInputError,
    number_text,
    real_or_nan,
)
from vtrack.frame import BgrFrame, Frame, GrayFrame, I420Frame
from vtrack.geometry import frame_size_problem
from vtrack.io.files import check_input_path, os_reason, piped_stdin
from vtrack.io.signatures import SIGNATURE_BYTES, container_kind
from vtrack.io.source import InputInfo, Source
from vtrack.io.specs import input_name
from vtrack.params import shown

#: The raw frame layouts vtrack reads (``--pix-fmt``) and ``vtrack scene --format raw`` writes
#: (bytes per frame: 3wh, 3wh, 1.5wh, wh).
PIX_FMTS = ("bgr24", "rgb24", "yuv420p", "gray")
_F_SETPIPE_SZ = 1031  # fcntl.F_SETPIPE_SZ (Linux), missing from the fcntl module before 3.10
PIPE_BYTES = 1 << 20
#: Ring buffers beyond the prefetch queue: the frame being filled, the one being tracked and the
#: one before it. A raw frame's pixels stay valid until two more frames have been taken.
_RING_SLACK = 3


#: Frame rates vtrack takes (``--fps``): a frame every 100 s to a high-speed camera's 10,000
#: a second. Beyond them times overflow the video writer's time base (1e12) or become infinite
#: (1e-308).
MIN_FPS, MAX_FPS = 0.01, 10_000.0


def checked_fps(fps: object, name: str = "--fps") -> float:
    """``fps`` if it is a frame rate from :data:`MIN_FPS` to :data:`MAX_FPS`; ConfigError
    naming it (``name``) otherwise."""
    value = real_or_nan(fps)
    if not (math.isfinite(value) and MIN_FPS <= value <= MAX_FPS):
        given = number_text(value) if math.isfinite(value) else shown(fps)  # as given
        raise ConfigError(f"{name} {given}: must be a frame rate from {MIN_FPS:g} to "
                          f"{MAX_FPS:g} frames per second")
    return value


@dataclass(frozen=True)
class RawFormat:
    """Layout of raw input frames: ``width x height`` pixels of ``pix_fmt`` at ``fps``."""

    width: int
    height: int
    pix_fmt: str
    fps: float

    @classmethod
    def parse(cls, size: str, pix_fmt: str, fps: float,
              names: tuple[str, str, str] = ("--raw", "--pix-fmt", "--fps")) -> RawFormat:
        """Check and build a format from ``--raw 1920x1080 --pix-fmt bgr24 --fps 60``.

        Raises ConfigError naming the value and the problem; ``names`` are what the size, the
        pixel format and the rate are called there: the command's options, or the library's
        arguments (``("raw", "pix_fmt", "fps")``, :func:`vtrack.open_source`).
        """
        size_name, pix_name, fps_name = names
        match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", size)
        if not match:
            raise ConfigError(f"{size_name} {shown(size)}: expected WIDTHxHEIGHT, e.g. "
                              "1920x1080")
        return cls(int(match[1]), int(match[2]), pix_fmt, fps).checked(
            f"{size_name} {shown(size)}", pix_name, fps_name)

    def checked(self, size_name: str | None = None, pix_name: str = "raw.pix_fmt",
                fps_name: str = "raw.fps") -> RawFormat:
        """This format, its size as ints and its rate as a float, if vtrack reads it: width and
        height whole numbers above 0 of a frame vtrack takes (even for yuv420p), one of
        :data:`PIX_FMTS`, a frame rate :func:`checked_fps` takes; ConfigError otherwise,
        naming ``size_name`` (default ``raw (width W, height H)``), ``pix_name`` or
        ``fps_name``."""
        width, height = self.width, self.height
        size_name = size_name or f"raw (width {shown(width)}, height {shown(height)})"
        if not all(isinstance(v, Integral) and not isinstance(v, bool) for v in (width, height)):
            raise ConfigError(f"{size_name}: width and height must be whole numbers")
        if width <= 0 or height <= 0:
            raise ConfigError(f"{size_name}: width and height must be positive")
        too_big = frame_size_problem(width, height, named=True)  # (size_name shows it)
        if too_big:
            raise ConfigError(f"{size_name}: {too_big}")
        if self.pix_fmt not in PIX_FMTS:
            raise ConfigError(f"{pix_name} {shown(self.pix_fmt)}: expected one of "
                              f"{', '.join(PIX_FMTS)}")
        if self.pix_fmt == "yuv420p" and (width % 2 or height % 2):
            raise ConfigError(f"{size_name}: yuv420p frames need an even width and height")
        return RawFormat(int(width), int(height), self.pix_fmt, checked_fps(self.fps, fps_name))

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of one frame's array in its stored layout."""
        if self.pix_fmt == "yuv420p":
            return (self.height * 3 // 2, self.width)
        if self.pix_fmt == "gray":
            return (self.height, self.width)
        return (self.height, self.width, 3)

    @property
    def frame_bytes(self) -> int:
        return math.prod(self.shape)

    def describe(self) -> str:
        return f"{self.width}x{self.height} {self.pix_fmt}"


def _enlarge_pipe(fd: int) -> None:
    """Raise a pipe's capacity to 1 MiB (best effort: the limit may forbid it)."""
    with contextlib.suppress(OSError):
        fcntl.fcntl(fd, _F_SETPIPE_SZ, PIPE_BYTES)


def _read_full(stream: BinaryIO | _AfterHead, view: memoryview) -> int:
    """Fill ``view`` from ``stream``; the number of bytes read (short only at end of stream)."""
    got = 0
    size = len(view)
    while got < size:
        n = stream.readinto(view[got:])
        if not n:
            break
        got += n
    return got


class _AfterHead:
    """``stream`` read on from its first bytes ``head``, already read: what it hands over
    starts with those (a read ends at their end)."""

    def __init__(self, head: bytes, stream: BinaryIO) -> None:
        self._head = memoryview(head)
        self._stream = stream

    def readinto(self, view: memoryview) -> int | None:
        if not self._head:
            return self._stream.readinto(view)
        n = min(len(view), len(self._head))
        view[:n] = self._head[:n]
        self._head = self._head[n:]
        return n


def _refuse_a_container(label: str, head: bytes, raw_name: str) -> None:
    """InputError when ``head``, the input's first bytes, begins a container or an image
    (:func:`~vtrack.io.signatures.container_kind`): its bytes would be tracked as pixels.
    ``raw_name``: how the caller gave the raw format (``--raw``, ``raw=``)."""
    kind = container_kind(head)
    if kind:
        raise InputError(f"{label}: {kind}, not raw frames: read it without "
                         f"{raw_name} (its frames carry their own size and pixel "
                         "format)")


class RawSource(Source):
    """Raw frames of a known :class:`RawFormat` from ``-`` (stdin), a FIFO or a regular file."""

    def __init__(self, spec: str, fmt: RawFormat, raw_name: str = "--raw") -> None:
        """``raw_name``: how the caller gave ``fmt``, for a message (``--raw``, ``raw=``)."""
        self._fmt = fmt
        self._raw_name = raw_name
        # messages name the input as it was given (``-``), as a container on stdin's do
        self._label = spec
        self._stream = self._open(spec)
        try:
            fd = self._stream.fileno()
            mode = os.fstat(fd).st_mode
            frame_count = None
            #: A regular file's frame count when it holds whole frames only (None: not known
            #: without reading to its end, a pipe; or stray bytes end it).
            self._whole_frames: int | None = None
            if stat.S_ISFIFO(mode):
                _enlarge_pipe(fd)
            elif stat.S_ISREG(mode):  # stdin may be a file read from past its start
                left = os.fstat(fd).st_size - os.lseek(fd, 0, os.SEEK_CUR)
                frame_count = max(left, 0) // fmt.frame_bytes
                if left % fmt.frame_bytes == 0:
                    self._whole_frames = frame_count
            ring = self.depth + _RING_SLACK
            self._ring = [np.empty(fmt.shape, np.uint8) for _ in range(ring)]
            self._rgb = np.empty(fmt.shape, np.uint8) if fmt.pix_fmt == "rgb24" else None
            info = InputInfo(
                path=spec,
                kind="raw",
                name=input_name(spec),  # the output folder's: ``stdin`` for ``-``
                width=fmt.width,
                height=fmt.height,
                fps=fmt.fps,
                frame_count=frame_count,
                duration_s=None if frame_count is None else frame_count / fmt.fps,
                codec="rawvideo",
                pix_fmt=fmt.pix_fmt,
            )
            super().__init__(info)
            self._reader = self._read_frames()
            self._first = next(self._reader, None)
        except PartialInputError as exc:  # not even one whole frame: the input is unusable
            self._release()
            raise InputError(str(exc)) from None
        except BaseException:
            self._release()
            raise
        if self._first is None:
            self._release()
            raise InputError(f"{self._label}: no raw frames (the input is empty)")

    def ends_after(self, index: int) -> bool:
        """Whether ``index`` is a regular file's last whole frame (it ends there)."""
        return self._whole_frames is not None and index == self._whole_frames - 1

    def _open(self, spec: str) -> BinaryIO:
        if spec == "-":
            stdin = piped_stdin("raw frames")
            return open(stdin.fileno(), "rb", buffering=0, closefd=False)
        check_input_path(spec)
        if os.path.isdir(spec):
            raise InputError(f"{spec}: is a folder, not a file of raw frames")
        try:
            return open(spec, "rb", buffering=0)  # a FIFO blocks here until a writer opens it
        except OSError as exc:
            raise InputError(f"{spec}: cannot be read ({os_reason(exc)})") from None

    def _read_into(self, stream: BinaryIO | _AfterHead, view: memoryview, index: int) -> int:
        """:func:`_read_full` of ``view`` (for frame ``index``): PartialInputError when
        reading fails."""
        try:
            return _read_full(stream, view)
        except OSError as exc:
            raise PartialInputError(
                f"{self._label}: reading stopped at frame {index} ({os_reason(exc)})", index
            ) from None

    def _read_frames(self) -> Iterator[Frame]:
        """The frames, once the input's first :data:`SIGNATURE_BYTES` bytes (across as many
        frames as they take: a container given as tiny frames) were found to be no
        container's or image's (:func:`_refuse_a_container`)."""
        fmt, ring, label = self._fmt, self._ring, self._label
        head = bytearray(SIGNATURE_BYTES)
        got = self._read_into(self._stream, memoryview(head), 0)
        _refuse_a_container(label, bytes(head[:got]), self._raw_name)
        stream = _AfterHead(bytes(head[:got]), self._stream)
        index = 0
        while True:
            slot = ring[index % len(ring)]
            target = self._rgb if self._rgb is not None else slot
            got = self._read_into(stream, memoryview(target).cast("B"), index)
            if got == 0:
                return
            if got < fmt.frame_bytes:
                raise PartialInputError(
                    f"{label}: raw stream ended with {got} stray bytes after {index} whole "
                    f"frames (frame size {fmt.frame_bytes} bytes for {fmt.describe()})",
                    index,
                )
            time_s = index / fmt.fps
            if fmt.pix_fmt == "yuv420p":
                yield I420Frame(index, time_s, slot)
            elif fmt.pix_fmt == "gray":
                yield GrayFrame(index, time_s, slot)
            else:
                if self._rgb is not None:
                    cv2.cvtColor(self._rgb, cv2.COLOR_RGB2BGR, dst=slot)
                yield BgrFrame(index, time_s, slot)
            index += 1

    def _frames(self) -> Iterator[Frame]:
        first, self._first = self._first, None
        if first is not None:
            yield first
        yield from self._reader

    def _release(self) -> None:
        self._stream.close()  # stdin itself stays open (closefd=False)
