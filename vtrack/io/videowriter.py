"""Annotated H.264 MP4 output, encoded in a background thread from reused frames.

``write()`` copies the frame's I420 pixels into a reused output buffer (never into the decoded
frame: the decoder keeps it as a reference, PERFORMANCE.md point 4), lets the caller draw on that
copy, and queues it. The encoder thread copies it into a reused ``av.VideoFrame`` (honouring
FFmpeg's padded line sizes) and encodes it with frame threads. Timestamps follow the input's
(a 90 kHz clock, coarser only for an input whose span it cannot hold:
:mod:`vtrack.io.videoclock`), so variable frame rate input keeps its timing.

The file is written under a temporary name and renamed by ``close()``, which also flushes the
encoder; call it in a ``finally`` so an error or Ctrl-C mid-run still leaves a playable video.
``abort()`` throws the video away instead.
"""

from __future__ import annotations

import os
import queue
import threading
import time
from collections import deque
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from urllib.parse import urlsplit

import av
import cv2
import numpy as np

from vtrack.errors import ConfigError, OutputError, cut
from vtrack.frame import Frame, I420Frame, to_video_range
from vtrack.geometry import Window
from vtrack.io.files import Closing, ffmpeg_file, os_reason, remove_quietly, temp_path
from vtrack.io.planes import i420_planes
from vtrack.io.specs import ffmpeg_url, url_scheme
from vtrack.io.threads import STOP_POLL_S
from vtrack.io.videoclock import RATES, VideoClock, longest_span_s, video_clock

#: Clock of a live output's timestamps (and of a file's, unless its span needs a coarser one):
#: exact for 24, 25, 30, 60 and the 1001-based NTSC rates.
TIME_BASE = Fraction(1, RATES[0])

Draw = Callable[[np.ndarray], None]


class _Slot:
    """One output picture: the packed I420 buffer the caller draws on, and the frame encoded."""

    def __init__(self, width: int, height: int) -> None:
        self.buffer = np.empty((height * 3 // 2, width), np.uint8)
        self.frame = av.VideoFrame(width, height, "yuv420p")
        self.pts = 0

    def fill_frame(self, width: int, height: int) -> av.VideoFrame:
        """Copy the buffer into the frame's planes (each row of a plane may be padded)."""
        frame = self.frame
        frame.make_writable()  # a no-op unless the encoder still holds the previous picture
        for plane, src in zip(frame.planes, i420_planes(self.buffer, width, height), strict=True):
            rows, cols = src.shape
            dst = np.frombuffer(plane, np.uint8).reshape(rows, plane.line_size)
            dst[:, :cols] = src
        frame.pts = self.pts
        return frame


class VideoRefusedError(OutputError):
    """The annotated video cannot be written for this input; the input can be tracked
    without it (``vtrack run --no-video``, ``RunRequest(video=False)``)."""


class VideoTooLongError(VideoRefusedError):
    """An input spanning more than the video's clock holds, refused as the writer opens (a
    frame too long after those before it, its span unknown or understated, ends the video
    instead: :attr:`VideoWriter.ended`)."""


class VideoTooSmallError(VideoRefusedError):
    """Pictures too small for the annotated video (under 2x2 pixels), refused as the writer
    opens, before a frame is tracked: the input can be tracked without the video (``vtrack run
    --no-video``, ``RunRequest(video=False)``)."""


class VideoWriter(Closing):
    """Encode I420 pictures to an H.264 MP4 at ``path`` (yuv420p, ``preset``, ``crf``).

    ``width`` and ``height`` are the input's; yuv420p needs even sizes, so an odd last row or
    column is left out of the video (``self.width``/``self.height`` are the encoded size).

    With ``url`` the pictures go to that live output instead (``--video-out``: MPEG-TS over
    ``udp://``/``tcp://``, RTSP to ``rtsp://``, FLV to ``rtmp://``), encoded for low latency
    (x264 ``zerolatency``, slice threads); nothing is written to ``path``. A receiver that
    takes nothing for ``stall_s`` seconds (FFmpeg's write to it blocks) is an OutputError,
    from :meth:`write` or :meth:`close`: the run never waits on it for ever; a stop gives way
    sooner (see :meth:`write`).

    ``span_s`` is how long the input lasts (None when not known): a file's clock is the finest
    that holds it (:func:`~vtrack.io.videoclock.video_clock`, 90 kHz for any ordinary clip); a
    longer span than any clock holds is refused (VideoTooLongError) before anything is written.
    A frame the clock cannot hold after those before it (the span unknown or understated) ends
    the video at the frame before it (:attr:`ended`): the file is finished as usual on
    :meth:`close`, whole and playable up to there.
    """

    #: Output pictures in flight between the caller and the encoder thread.
    depth = 3

    def __init__(
        self,
        path: Path | str,
        width: int,
        height: int,
        fps: float,
        preset: str = "ultrafast",
        crf: int = 23,
        codec: str = "libx264",
        url: str | None = None,
        stall_s: float = 10.0,
        span_s: float | None = None,
    ) -> None:
        self.path = Path(path)
        self.url = url
        #: How long a live output's receiver may take nothing (None for a file: no bound).
        self._stall_s = stall_s if url is not None else None
        self._stalled = False
        #: A picture gave way to a stop while a live output's receiver took nothing.
        self._gave_way = False
        self.width, self.height = width & ~1, height & ~1
        if self.width <= 0 or self.height <= 0:  # before anything is written
            raise VideoTooSmallError(f"{url or self.path}: cannot encode a {width}x{height} "
                                     "video (H.264 in yuv420p needs at least 2x2 pixels)")
        #: None for a live output (MPEG-TS, RTSP, FLV: no 32-bit steps to guard).
        self._clock: VideoClock | None = None
        if url is None:
            self._clock = video_clock(preset, span_s)
            if self._clock is None:
                raise VideoTooLongError(
                    f"{self.path}: the input spans {span_s:g} s, more than the video's "
                    f"timestamps hold ({longest_span_s(preset):g} s with preset {preset})")
        self._preset = preset
        self._recent: deque[int] = deque(maxlen=self._clock.window if self._clock else 1)
        self._temp = temp_path(self.path) if url is None else None
        self._rate = Fraction(fps).limit_denominator(1001) if fps and fps > 0 else Fraction(30)
        self._container = self._open(preset, crf, codec)
        self._stream = self._container.streams.video[0]
        self._free: queue.Queue[_Slot] = queue.Queue()
        for _ in range(self.depth):
            self._free.put(_Slot(self.width, self.height))
        self._todo: queue.Queue[_Slot | bool] = queue.Queue()
        self._error: BaseException | None = None
        self._error_reported = False
        #: Why the video ended before the picture :meth:`write` refused first (``it comes ... s
        #: after the frame before it, more than ...``); None while it takes pictures.
        self.ended: str | None = None
        self._frames = 0
        self._last_pts = -1
        self._closed = False
        self._thread = threading.Thread(target=self._encode_loop, name="vtrack-encode",
                                        daemon=True)
        self._thread.start()

    def _open(self, preset: str, crf: int, codec: str) -> av.container.OutputContainer:
        """Open the encoder and create the temporary file: bad settings and unwritable places
        fail here (ConfigError / OutputError), not in the encoder thread."""
        live = self.url is not None
        where = self.url if self.url is not None else str(self._temp)
        try:  # a file: nothing touches the disk yet
            container = av.open(ffmpeg_url(where) if live else ffmpeg_file(where), "w",
                                format=live_format(where) if live else None,
                                options=self._muxer_options())
        except (av.FFmpegError, OSError) as exc:  # a live output that cannot be reached
            raise OutputError(f"--video-out {where}: cannot be opened ({os_reason(exc)})"
                              ) from None
        try:
            stream = container.add_stream(codec, rate=self._rate)
            stream.width, stream.height, stream.pix_fmt = self.width, self.height, "yuv420p"
            stream.codec_context.time_base = stream.time_base = self.time_base
            # frame threads: +28% over slices (PERFORMANCE.md 2), but each holds a picture back
            stream.codec_context.thread_type = "SLICE" if live else "FRAME"
            stream.options = {"preset": preset, "crf": str(crf),
                              **({"tune": "zerolatency"} if live else {})}
            stream.codec_context.open()
        except (av.FFmpegError, ValueError) as exc:
            container.close()
            raise ConfigError(
                f"video encoder {codec} (preset {preset!r}, crf {crf}): {os_reason(exc)}"
            ) from None
        try:
            container.start_encoding()  # creates the file and writes the header
        except (av.FFmpegError, OSError) as exc:
            container.close()
            if self._temp is not None:
                remove_quietly(self._temp)
            raise OutputError(f"{self.url or self.path}: cannot write ({os_reason(exc)})"
                              ) from None
        return container

    def _muxer_options(self) -> dict[str, str]:
        """A file's track keeps the clock's ticks: left to itself, the MP4 muxer doubles a
        clock under 10 kHz until it is not (1 kHz would become 16 kHz, 16 times shorter)."""
        if self._clock is None:
            return {}
        return {"video_track_timescale": str(self._clock.rate)}

    def _encode_loop(self) -> None:
        """Encoder thread: encode queued slots in order; ``True`` flushes and ends, ``False``
        ends without flushing. After a failure it only recycles slots."""
        stream, container = self._stream, self._container
        while True:
            item = self._todo.get()
            if isinstance(item, bool):
                flush = item
                break
            if self._error is None:
                try:
                    for packet in stream.encode(item.fill_frame(self.width, self.height)):
                        container.mux(packet)
                except BaseException as exc:  # reported to the caller by write()/close()
                    self._error = exc
            self._free.put(item)
        if flush and self._error is None:
            try:
                for packet in stream.encode(None):
                    container.mux(packet)
            except BaseException as exc:
                self._error = exc

    def _raise_error(self) -> None:
        """Raise the encoder thread's failure as an OutputError, once."""
        if self._error is not None and not self._error_reported:
            self._error_reported = True
            if isinstance(self._error, OutputError):  # already says what and where
                raise self._error
            raise OutputError(f"{self.url or self.path}: cannot write video "
                              f"({os_reason(self._error)})")

    def _fill(self, buffer: np.ndarray, image: Frame | np.ndarray) -> None:
        """Copy (or convert) ``image`` into the I420 output ``buffer``."""
        if isinstance(image, np.ndarray):
            np.copyto(buffer, image)
        elif isinstance(image, I420Frame) and (image.width, image.height) == (
                self.width, self.height):
            image.copy_planes_into(buffer)
            if image.full_range:  # written as yuv420p: video range
                to_video_range(*i420_planes(buffer, self.width, self.height))
        else:  # BGR/grey pictures convert straight into the buffer; odd sizes lose a row/column
            window = Window(0, 0, self.width, self.height)
            cv2.cvtColor(image.bgr(window), cv2.COLOR_BGR2YUV_I420, dst=buffer)

    def write(
        self, image: Frame | np.ndarray, draw: Draw | None = None, time_s: float | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> bool:
        """Queue one picture: ``image`` is an I420 buffer of the encoded size or a Frame.

        The pixels are copied into a reused output buffer first, ``draw(buffer)`` may then
        annotate that copy in place (an I420 buffer, see :mod:`vtrack.io.planes`); ``image``
        itself is never modified and may be reused as soon as this returns. ``time_s`` is the
        picture's time (a Frame's own by default; else ``frame number / fps``).
        Blocks while the encoder is ``depth`` pictures behind; True once the picture is
        queued. For a live output, False (the picture not written, and :meth:`close` then
        waits no more for the receiver) when ``stop()`` turned true while it waited. False
        (nothing written) for this picture and every later one once the clock cannot hold
        this one (:attr:`ended` says why): the video ends at the picture before.
        """
        if self._closed:
            raise RuntimeError(f"{self.path}: the video writer is closed")
        self._raise_error()
        if time_s is None and isinstance(image, Frame):
            time_s = image.time_s
        if time_s is None:
            time_s = self._frames / self._rate
        pts = self._pts(time_s)
        if pts is None:
            return False
        slot = self._free_slot(stop if self.url is not None else None)
        if slot is None:
            self._gave_way = True
            return False
        try:
            self._fill(slot.buffer, image)
            if draw is not None:
                draw(slot.buffer)
        except BaseException:
            self._free.put(slot)
            raise
        slot.pts = self._last_pts = pts
        self._recent.append(pts)
        self._frames += 1
        self._todo.put(slot)
        return True

    @property
    def time_base(self) -> Fraction:
        """The clock of the video's timestamps."""
        return TIME_BASE if self._clock is None else self._clock.time_base

    def _pts(self, time_s: float) -> int | None:
        """The timestamp of a picture at ``time_s``: strictly increasing. None, and the video
        :attr:`ended` (with why), when the clock cannot hold it, or could not an earlier one."""
        if self.ended is not None:
            return None
        pts = max(round(time_s / self.time_base), self._last_pts + 1)
        clock = self._clock
        if clock is not None and self._recent and pts - self._recent[0] > clock.bound_ticks:
            back = ("the frame before it" if clock.window == 1
                    else f"the frame {clock.window} before it")
            self.ended = (
                f"it comes {clock.seconds(pts - self._recent[0]):.9g} s after {back}, more than "
                f"the video's timestamps hold ({clock.seconds(clock.bound_ticks):.9g} s with "
                f"preset {self._preset})")
            return None
        return pts

    def _free_slot(self, stop: Callable[[], bool] | None) -> _Slot | None:
        """An output buffer the encoder is done with, waiting for one at most ``stall_s``
        (OutputError, a live output) and, with ``stop``, None once ``stop()`` is true."""
        if stop is None and self._stall_s is None:  # a file: the encoder frees one in time
            return self._free.get()
        deadline = None if self._stall_s is None else time.monotonic() + self._stall_s
        while True:
            waits = [STOP_POLL_S] if stop is not None else []
            if deadline is not None:
                waits.append(max(0.0, deadline - time.monotonic()))
            try:
                return self._free.get(timeout=min(waits) if waits else None)
            except queue.Empty:
                if stop is not None and stop():
                    return None
                if deadline is not None and time.monotonic() >= deadline:
                    self._stalled, self._error_reported = True, True  # said here, not on close
                    self._error = OutputError(self._stall_message())
                    raise self._error from None

    def _stall_message(self) -> str:
        return f"--video-out {self.url}: the receiver took nothing for {self._stall_s:g} s"

    def _finish(self, flush: bool) -> None:
        self._closed = True
        self._todo.put(flush)
        self._thread.join(0 if self._stalled or self._gave_way else self._stall_s)
        if self._thread.is_alive():  # blocked in a write to the receiver: left to exit with us
            if not self._gave_way:  # after a stop the last pictures are not awaited
                self._stalled = True
                self._error = self._error or OutputError(self._stall_message())
            return
        try:
            self._container.close()
        except (av.FFmpegError, OSError) as exc:
            self._error = self._error or exc

    def close(self) -> None:
        """Encode what is queued, finish the file and give it its final name.

        Safe to call twice. Raises OutputError if encoding or writing failed (the partial
        file is removed then).
        """
        if self._closed:
            return
        self._finish(flush=True)
        if self._error is not None:
            if self._temp is not None:
                remove_quietly(self._temp)
            self._raise_error()
            return
        if self._temp is None:  # a live output: nothing to rename
            return
        try:
            os.replace(self._temp, self.path)
        except OSError as exc:
            raise OutputError(f"{self.path}: cannot write ({os_reason(exc)})") from None

    def abort(self) -> None:
        """Stop without a video: nothing is renamed and the temporary file is removed."""
        if not self._closed:
            self._finish(flush=False)
        if self._temp is not None:
            remove_quietly(self._temp)

    @property
    def frames_written(self) -> int:
        return self._frames



#: The live outputs ``--video-out`` sends to, by scheme, and the container each is sent as.
LIVE_OUTPUT_FORMATS = {"udp": "mpegts", "tcp": "mpegts", "rtsp": "rtsp", "rtmp": "flv",
                       "rtmps": "flv"}


#: The live outputs that have no default port: FFmpeg refuses to send to one without a port.
_PORT_NEEDED = ("udp", "tcp")


def live_format(url: str) -> str:
    """The container a live output ``url`` is sent as: RTSP to ``rtsp://``, FLV to
    ``rtmp://``, MPEG-TS to ``udp://`` and ``tcp://`` (:data:`LIVE_OUTPUT_FORMATS`)."""
    return LIVE_OUTPUT_FORMATS.get(url_scheme(url) or "", "mpegts")


def video_out_problem(url: str, out: str = "--out") -> str | None:
    """Why ``url`` cannot be ``--video-out``'s live output, if so: not a URL, or one of a
    scheme not in :data:`LIVE_OUTPUT_FORMATS` (``file://`` would write a file past the checks
    that keep a run off its own input and an earlier run's results, ``http://`` is no live
    output), a port outside 1 to 65535 (FFmpeg would send to another one), or no port for
    ``udp://`` and ``tcp://`` (``rtsp://`` and ``rtmp://`` have default ones). ``out``: what
    names the run's folder (``--out``, ``out_dir``)."""
    scheme, sep, _ = url.partition("://")
    where = f"udp://HOST:PORT, tcp://, rtsp://, rtmp://); a file is annotated.mp4 in {out}"
    if not sep:
        return f"expected a URL ({where}"
    lowered = url_scheme(url)  # (UDP:// is udp://, as for an input)
    if lowered not in LIVE_OUTPUT_FORMATS:
        return f"{cut(scheme)}:// is not a live output vtrack sends to ({where}"
    try:
        port = urlsplit(url).port
    except ValueError:  # Port out of range 0-65535, or not a number
        port = 0
    if port == 0:
        return "its port must be a number from 1 to 65535"
    if port is None and lowered in _PORT_NEEDED:  # (FFmpeg fails only once it sends)
        return f"needs a port: {lowered}://HOST:PORT"
    return None


def verify_video(path: Path | str, frames: int) -> str | None:
    """None if ``path`` is a video that opens and holds ``frames`` pictures, else the reason.

    Reads the container's index (the moov atom of an MP4), not the pictures; an index without
    a frame count falls back to counting the packets.
    """
    try:
        with av.open(ffmpeg_file(path)) as container:
            stream = container.streams.video[0]
            found = stream.frames or sum(1 for p in container.demux(stream) if p.size)
    except (av.FFmpegError, OSError, IndexError) as exc:
        return f"does not open ({os_reason(exc)})"
    if found != frames:
        return f"holds {found} frames, {frames} were written"
    return None
