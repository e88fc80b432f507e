"""Capture devices (``/dev/videoN``) through OpenCV's V4L2 backend.

The FFmpeg in PyAV's wheel has no V4L2 input; OpenCV's does. Frames come as BGR pictures;
``time_s`` is the time each was captured (the device's timestamp, in seconds from the first
frame; the wall clock when the driver gives none).
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import cv2

from vtrack.errors import InputError, PartialInputError
from vtrack.frame import BgrFrame, Frame
from vtrack.io.source import InputInfo, Source
from vtrack.io.specs import input_name


class CaptureSource(Source):
    """The V4L2 device ``/dev/video<number>`` (``path`` as the user named it)."""

    def __init__(self, path: str, number: int) -> None:
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)  # our own message
        capture = cv2.VideoCapture(number, cv2.CAP_V4L2)
        if not capture.isOpened():
            capture.release()
            raise InputError(f"{path}: cannot be opened as a V4L2 capture device (busy, "
                             "unplugged or not a camera?)")
        ok, first = capture.read()
        if not ok or first is None:
            capture.release()
            raise InputError(f"{path}: the device opened but sent no picture")
        self._capture = capture
        self._first: BgrFrame | None = None
        self._t0 = self._clock()
        self._first = BgrFrame(0, 0.0, first)
        fps = capture.get(cv2.CAP_PROP_FPS) or None
        super().__init__(InputInfo(
            path=path, kind="video", name=input_name(path), width=first.shape[1],
            height=first.shape[0], fps=fps, frame_count=None, duration_s=None,
            codec="v4l2", pix_fmt="bgr24"))

    def _clock(self) -> float:
        """When the last picture was captured, in seconds (the driver's clock, else ours)."""
        msec = self._capture.get(cv2.CAP_PROP_POS_MSEC)
        return msec / 1000.0 if msec and msec > 0 else time.monotonic()

    def _frames(self) -> Iterator[Frame]:
        first, self._first = self._first, None
        assert first is not None
        yield first
        index = 1
        while True:
            ok, picture = self._capture.read()
            if not ok or picture is None:
                raise PartialInputError(f"{self.info.path}: the device stopped sending at "
                                        f"frame {index}", index)
            yield BgrFrame(index, self._clock() - self._t0, picture)
            index += 1

    def _release(self) -> None:
        self._capture.release()
