"""Frames of an input by index, for pages that step back and forth through it.

An input can be read only forward; :class:`FrameStore` decodes as far as the frame asked for and
keeps the most recently used frames encoded (JPEG by default, ~20x smaller than the pixels) up
to a byte budget, so stepping back and forth near a frame costs nothing, while memory stays
bounded whatever the input's length and size: a frame that was dropped from the cache is
decoded again, reopening the input. Frames are numbered as the input numbers them (as ``vtrack
run --start`` and ``vtrack frame --at`` count): an image missing from a folder's numbering, or a
frame that does not decode, leaves its number out (:class:`AbsentFrame`), it does not shift the
frames after it.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Iterator

import numpy as np

from vtrack.errors import InputError
from vtrack.frame import Frame
from vtrack.io import open_source
from vtrack.io.images import encode_image
from vtrack.io.sidecar import has_sidecar
from vtrack.io.source import (
    InputInfo,
    Source,
    no_frame_after_text,
    no_frame_text,
    past_end,
    past_end_text,
    seek_time,
    start_toward,
)

#: Encoded frames kept for stepping back and forth (bytes; a 1080p JPEG is ~0.5-1 MB).
CACHE_BYTES = 64 << 20
#: Frames ahead of the last one read from which :class:`FrameStore` reopens the input at a key
#: frame before the one asked for (where it can jump) rather than decoding its way there.
JUMP_FRAMES = 100


class AbsentFrame(InputError):
    """A frame number within the input that has no picture: missing from an image folder's
    numbering, or not decodable. ``previous`` and ``following`` are the nearest frames before
    and after it that have one (``previous`` None when there is none before)."""

    def __init__(self, message: str, previous: int | None, following: int) -> None:
        super().__init__(message)
        self.previous = previous
        self.following = following


class FrameStore:
    """Encoded frames of one input, decoded on demand up to the highest index asked for, by the
    input's own frame numbers (:class:`AbsentFrame` for one it passes over).

    At most ``cache_bytes`` of encoded frames are kept (least recently used dropped first;
    the frame asked for is always returned). Safe to use from several threads (a page's
    requests). ``close()`` releases the input.
    """

    def __init__(self, input_spec: str, ext: str = ".jpg",
                 cache_bytes: int = CACHE_BYTES) -> None:
        self._spec = input_spec
        self._source: Source = open_source(input_spec)
        self.info: InputInfo = self._source.info
        self._frames: Iterator[Frame] = iter(self._source)
        self._next = 0  # index after the last frame the input yielded
        #: Runs of frame numbers the input passed over (first, last), in order.
        self._gaps: list[tuple[int, int]] = []
        self._end: int | None = None  # the frame count, once the end was reached
        self._cache: OrderedDict[int, bytes] = OrderedDict()
        self._budget = cache_bytes
        self.cached_bytes = 0
        self._ext = ext
        self._lock = threading.Lock()

    @property
    def count(self) -> int | None:
        """The number of frames: exact once the end was reached, else the input's estimate."""
        return self._end if self._end is not None else self.info.frame_count

    def get(self, index: int) -> bytes | None:
        """Frame ``index`` (0-based, the input's numbering) encoded, or None when the input has
        no such frame (past its end: at once when its frame count says so, :func:`past_end`).
        AbsentFrame when the input passes over that number."""
        if index < 0 or (self._end is not None and index >= self._end) \
                or past_end(self.info, index):
            return None
        with self._lock:
            if index in self._cache:
                self._cache.move_to_end(index)
                return self._cache[index]
            self._check_present(index)
            if index < self._next:  # dropped from the cache: read the input again
                self._rewind(index)
            elif index >= self._next + JUMP_FRAMES and has_sidecar(self._spec):
                self._jump(index)  # (not a stream: it can be opened again)
            data = None
            while self._next <= index:
                frame = next(self._frames, None)
                if frame is None:
                    self._end = self._next
                    return None
                gap = (self._next, frame.index - 1)
                if frame.index > self._next and gap not in self._gaps:
                    # wherever it lies: after a jump or a rewind, gaps are met out of order
                    self._gaps.append(gap)
                self._next = frame.index + 1
                data = encode_image(frame.bgr(), self._ext)
                self._keep(frame.index, data)
            self._check_present(index)
            return data

    def _check_present(self, index: int) -> None:
        """AbsentFrame when ``index`` lies in a run of numbers the input passed over."""
        for first, last in self._gaps:
            if first <= index <= last:
                raise AbsentFrame(absent_text(self._spec, index, self._source, last + 1),
                                  first - 1 if first else None, last + 1)

    def _keep(self, index: int, data: bytes) -> None:
        self._cache[index] = data
        self.cached_bytes += len(data)
        while self.cached_bytes > self._budget and len(self._cache) > 1:
            _, dropped = self._cache.popitem(last=False)
            self.cached_bytes -= len(dropped)

    def no_frame_text(self, index: int) -> str:
        """What is said of frame ``index`` when :meth:`get` found none there: ``no frame N
        (frames 0..M)`` by :attr:`count` (exact once the end was reached)."""
        estimated = self._end is None and self.info.frame_count_estimated
        return no_frame_text(index, self.count, estimated)

    def _rewind(self, index: int) -> None:
        """Read the input again, from its first frame or a key frame at or before ``index``."""
        if not has_sidecar(self._spec):  # not a file or folder (stdin, URL, device): read once
            raise InputError(f"{self._spec}: its earlier frames are no longer held and it "
                             "cannot be read again (a stream); pick a later frame, or give "
                             "the input as a file")
        self._use(*self._reopen(index))

    def _jump(self, index: int) -> None:
        """Go on from a key frame at or before ``index`` when the input can jump there past
        the frames already read; else go on reading from where the store is."""
        source, begin = self._reopen(index)
        if begin <= self._next:
            source.close()
            return
        self._use(source, begin)

    def _reopen(self, index: int) -> tuple[Source, int]:
        """The input opened again and made to begin at a key frame at or before ``index``
        (:func:`start_toward`; else its first frame): the source and that frame's index."""
        source = open_source(self._spec)
        try:
            return source, start_toward(source, index) or 0
        except BaseException:
            source.close()
            raise

    def _use(self, source: Source, begin: int) -> None:
        """Read on from ``source``, whose iteration begins at frame ``begin``."""
        self._source.close()
        self._source = source
        self._frames = iter(source)
        self._next = begin  # (the frames before it were passed by a jump, not missing)

    def close(self) -> None:
        self._source.close()

    def __enter__(self) -> FrameStore:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def read_frame(input_spec: str, index: int) -> np.ndarray:
    """Frame ``index`` (0-based) of an input as a BGR image; InputError naming the input and
    its length when it has no such frame (at once when its frame count says so), or the next
    frame when that one does not decode. A far frame of a seekable video is reached from the
    key frame before it (:func:`start_toward`), the frame checked by its index."""
    last = -1
    with open_source(input_spec) as source:
        if start_toward(source, index) is None:
            raise InputError(past_end_text(input_spec, index, source.info))
        for frame in source:
            if frame.index == index:
                return frame.bgr().copy()
            if frame.index > index:
                raise InputError(absent_text(input_spec, index, source, frame.index))
            last = frame.index
    raise InputError(f"{input_spec}: has {no_frame_text(index, last + 1)}")


def read_frame_at(input_spec: str, seconds: float) -> tuple[int, np.ndarray]:
    """The first frame of an input whose timestamp is at or after ``seconds`` (as ``vtrack run
    --start Ts`` finds it, :func:`~vtrack.io.source.seek_time`): its index and BGR image;
    InputError naming the input when it ends before."""
    with open_source(input_spec) as source:
        found, _ = seek_time(source, seconds)
        if found is None:
            raise InputError(no_frame_after_text(input_spec, seconds, source))
        return found, next(iter(source)).bgr().copy()


def absent_text(input_spec: str, index: int, source: Source, following: int) -> str:
    """What is said of frame ``index``, which ``source`` passed over (``following`` is the next
    frame it has): why it has no picture, and where the frames go on."""
    return (f"{input_spec}: frame {index} {source.absent(index)}; the next frame it has is "
            f"frame {following}")
