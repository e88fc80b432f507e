"""Frames of an input by index, for pages that step back and forth through it.

An input can be read only forward, once; :class:`FrameStore` decodes as far as the highest
frame asked for and keeps every decoded frame encoded (JPEG by default, ~20x smaller than the
pixels), so stepping back costs nothing and nothing is decoded twice.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator

import cv2
import numpy as np

from vtrack.errors import InputError
from vtrack.frame import Frame
from vtrack.io import open_source
from vtrack.io.source import InputInfo, Source


def encode_image(bgr: np.ndarray, ext: str = ".jpg", quality: int = 92) -> bytes:
    """``bgr`` encoded as JPEG (``.jpg``) or PNG (``.png``) bytes by OpenCV."""
    params = [cv2.IMWRITE_JPEG_QUALITY, quality] if ext == ".jpg" else []
    ok, data = cv2.imencode(ext, bgr, params)
    if not ok:
        raise InputError(f"cannot encode a {bgr.shape[1]}x{bgr.shape[0]} frame as {ext}")
    return data.tobytes()


class FrameStore:
    """Encoded frames of one input, decoded on demand up to the highest index asked for.

    Safe to use from several threads (a page's requests). ``close()`` releases the input.
    """

    def __init__(self, input_spec: str, ext: str = ".jpg") -> None:
        self._source: Source = open_source(input_spec)
        self.info: InputInfo = self._source.info
        self._frames: Iterator[Frame] = iter(self._source)
        self._encoded: list[bytes] = []
        self._ended = False
        self._ext = ext
        self._lock = threading.Lock()

    @property
    def decoded(self) -> int:
        """Frames decoded so far."""
        return len(self._encoded)

    @property
    def count(self) -> int | None:
        """The number of frames: exact once the end was reached, else the input's estimate."""
        return len(self._encoded) if self._ended else self.info.frame_count

    def get(self, index: int) -> bytes | None:
        """Frame ``index`` (0-based) encoded, or None when the input has no such frame."""
        if index < 0:
            return None
        with self._lock:
            while len(self._encoded) <= index and not self._ended:
                frame = next(self._frames, None)
                if frame is None:
                    self._ended = True
                    break
                self._encoded.append(encode_image(frame.bgr(), self._ext))
            return self._encoded[index] if index < len(self._encoded) else None

    def close(self) -> None:
        self._source.close()

    def __enter__(self) -> FrameStore:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def read_frame(input_spec: str, index: int) -> np.ndarray:
    """Frame ``index`` (0-based) of an input as a BGR image; InputError naming the input and
    its length when it has no such frame."""
    last = -1
    with open_source(input_spec) as source:
        for frame in source:
            if frame.index == index:
                return frame.bgr().copy()
            last = frame.index
    raise InputError(f"{input_spec}: has no frame {index} (frames 0..{last})")
