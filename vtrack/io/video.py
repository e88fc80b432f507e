"""Video files through PyAV: frames in their decoded layout, timestamps, rotation, truncation.

yuv420p/yuvj420p frames of even size become :class:`~vtrack.frame.I420Frame` (no full-frame
colour conversion; full-range levels and BT.709 colours are marked, ``full_range`` and
``bt709``, and moved to video range and BT.601 only where pixels are converted); anything else
is converted once to BGR, but deep grey or RGB pictures (16-bit: a thermal camera's 12 bits in
FFV1 ``gray16le``, a 16-bit PNG) are scaled by the bits the first frame uses (rising with a
later frame's), as an image folder's are (:mod:`vtrack.io.depth`), with a warning. ``time_s``
is each frame's presentation time relative to the first frame, so variable frame rate input
keeps its timing.
A display-matrix rotation (phone footage) is applied to the pixels and recorded in
``info.rotation``.

A truncated file often decodes "successfully" to fewer frames than its container promises;
that is reported like a decoding error, as a :class:`~vtrack.errors.PartialInputError` after the
good frames.

Damage in the middle of a file is skipped as the ``ffmpeg`` command skips it: a packet the
decoder refuses (``InvalidDataError``) is dropped and decoding goes on with the next one. Damage
also shows without an error: pictures the decoder marks as decoded with errors, and, in a
constant-rate stream, pictures that vanish, leaving a gap in the timestamps. A stream is
constant-rate when its listed frame count is its duration times its rate, or, in a container
that lists no count but carries constant-rate video (MPEG-TS), when its pictures came one frame
apart until the gap. The frames lost are counted (``frames_skipped``), those decoded with
errors too (``frames_corrupt``), each kind with a warning (also when reading stops before the
end), and later frames keep their place in the stream, so ground truth stays aligned: in a
constant-rate stream, once damage was seen, a frame's index comes from its timestamp
(``round(time_s * fps)``, never less than the next index), and a stale picture out of order is
dropped; in a variable-rate one, whose timestamps cannot tell, each refused packet leaves one
place. Only a stream that really ends early is partial. Of several video streams, the one
``ffmpeg`` would take is read (not a cover picture; the default; the largest), with a
warning naming it; a file whose only picture is a cover picture (an audio file's album art)
has no video to read.
"""

from __future__ import annotations

import errno
import itertools
import math
import os
import re
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from typing import Any

import av
import cv2
import numpy as np

from vtrack.errors import (
    COMMAND_NAMES,
    InputError,
    OptionNames,
    PartialInputError,
    cut,
    plural,
)
from vtrack.frame import BgrFrame, Frame, GrayFrame, I420Frame
from vtrack.geometry import frame_size_problem
from vtrack.io.depth import DepthScale, as_kind, deep, stored_pixels
from vtrack.io.ffoptions import input_protocols, unused_options
from vtrack.io.files import ffmpeg_file, os_reason, piped_stdin
from vtrack.io.follow import FollowedFileChanged, GrowingFile
from vtrack.io.planes import quarter_turns, rotate_i420, turned
from vtrack.io.pyfile import HEAD_BYTES, CapturingStream, CountedStream
from vtrack.io.signatures import (
    PHOTO_CODECS,
    header_problem,
    matroska_torn_element,
    mp4_fragmented,
    mp4_head_fragmented,
    mp4_index_problem,
    mp4_torn_box,
    photo_bytes_mirrored,
    photo_mirrored,
)
from vtrack.io.source import ESTIMATE_SLACK_FRAMES, ESTIMATE_SLACK_SHARE, InputInfo, Source
from vtrack.io.specs import ffmpeg_url, input_name, is_live, is_url, url_scheme
from vtrack.io.threads import run_aside
from vtrack.machine import cpu_count
from vtrack.params import MAX_TIMEOUT_S, MAX_WAIT_S, MIN_TIMEOUT_S, checked_seconds

#: Containers whose pictures carry no presentation time of their own: AVI stores one picture
#: per chunk in decoding order, and with B-frames the decoder hands the pictures over (in
#: display order) labelled with their packets' times, out of order. A frame's time there is
#: its place over the frame rate, as FFmpeg's own frame counting does.
FRAME_ORDER_FORMATS = frozenset({"avi"})
#: Containers (FFmpeg's format names) whose duration FFmpeg's muxer writes as the last
#: timestamp rather than the length: a file starting at t > 0 ends at its duration.
END_AS_DURATION_FORMATS = frozenset({"matroska,webm"})
#: Containers that list no frame count but carry constant-rate video (broadcast and streaming
#: transport): a stream whose pictures came at its frame rate until a gap in their timestamps
#: lost pictures there (with a listed count, the count tells; see the module docstring).
STEADY_RATE_FORMATS = frozenset({"mpegts"})
#: ... after at least this many intervals of one frame each (within :data:`STEADY_TOLERANCE`
#: of a frame).
STEADY_INTERVALS = 4
STEADY_TOLERANCE = 0.1
#: FFmpeg's readers that render text as pictures (ANSI art): such an input is a text file.
TEXT_FORMATS = frozenset({"tty"})
#: Decoded layouts handed over as I420 planes without conversion.
I420_FORMATS = frozenset({"yuv420p", "yuvj420p"})
#: FFmpeg's AVCOL_RANGE_JPEG: a picture whose levels use the full 0..255 range.
_FULL_RANGE = 2


#: FFmpeg's AVCOL_SPC_BT709: a picture whose colours are BT.709's (most HD video).
_BT709 = 1


def full_range(decoded: av.VideoFrame) -> bool:
    """Whether a decoded picture's levels are full range (yuvj420p, or flagged so)."""
    return (decoded.format.name == "yuvj420p"
            or getattr(decoded, "color_range", 0) == _FULL_RANGE)


def bt709(decoded: av.VideoFrame) -> bool:
    """Whether a decoded picture is flagged as BT.709 (untagged pictures are taken as BT.601,
    as FFmpeg's own conversions take them)."""
    return getattr(decoded, "colorspace", 0) == _BT709
#: MPEG-TS packet sizes (plain, M2TS with timestamps, DVB with Reed-Solomon bytes).
TS_PACKET_SIZES = (188, 192, 204)
#: Slack when comparing the decoded length with the container's: a few frames or half a second.
_END_SLACK_FRAMES, _END_SLACK_S = 3, 0.5
#: Fewest frame threads the decoder gets on a machine of two cores or more. FFmpeg's own choice
#: is one per core and one more (3 on two cores), which leaves the cores idle while frames wait
#: for their reference pictures; with 8 in flight the decoder keeps the cores busy beside the
#: tracker (benchmarks/RESULTS.md section 1, two cores: a decode-only process 5-10% faster,
#: `run --no-video` ~8% faster).
MIN_DECODER_THREADS = 8
#: ... but no more threads than this many bytes of decoded pictures hold (8K: fewer than 8).
DECODER_PICTURE_BUDGET = 256 << 20
#: FFmpeg's cap on the threads it picks by itself.
_FFMPEG_AUTO_MAX = 16


def plane_views(frame: av.VideoFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Y, U, V planes of a decoded yuv420p frame as numpy views (no copy)."""
    views = []
    for plane in frame.planes:
        rows = np.frombuffer(plane, np.uint8)[: plane.line_size * plane.height]
        views.append(rows.reshape(plane.height, plane.line_size)[:, : plane.width])
    return views[0], views[1], views[2]


def decoder_threads(width: int, height: int, cores: int) -> int:
    """Frame threads to decode ``width`` x ``height`` pictures on ``cores`` cores: FFmpeg's
    own choice (one per core and one more, at most 16; one on a single core, where there is no
    idle core to fill), raised to :data:`MIN_DECODER_THREADS` as far as
    :data:`DECODER_PICTURE_BUDGET` allows one yuv420p picture per thread."""
    if cores <= 1:
        return 1
    auto = min(cores + 1, _FFMPEG_AUTO_MAX)
    affordable = DECODER_PICTURE_BUDGET // max(width * height * 3 // 2, 1)
    return max(auto, min(MIN_DECODER_THREADS, affordable))


def _is_cover(stream: av.stream.Stream) -> bool:
    """Whether ``stream`` is a cover picture (an attached picture: an MP3's or M4A's album
    art), one still image, not a video."""
    return bool(stream.disposition & av.stream.Disposition.attached_pic)


def _main_video_stream(container: av.container.InputContainer) -> av.VideoStream:
    """The video stream ``ffmpeg -i`` would take: not a cover picture (attached picture), then
    the one marked default, then the largest; the first on a tie."""
    def rank(stream: av.VideoStream) -> tuple[bool, bool, int]:
        flags, context = stream.disposition, stream.codec_context
        return (not _is_cover(stream),
                bool(flags & av.stream.Disposition.default),
                0 if context is None else (context.width or 0) * (context.height or 0))

    return max(container.streams.video, key=rank)


def _several_videos(path: str, container: av.container.InputContainer,
                    chosen: av.VideoStream) -> str | None:
    """The warning of a file holding more than one video stream (cover pictures left out),
    naming the one tracked (``chosen``) by its number among the video streams, as ``ffmpeg
    -map 0:v:N`` counts them; None for one."""
    videos = [s for s in container.streams.video if not _is_cover(s)]
    if len(videos) < 2:
        return None
    number = list(container.streams.video).index(chosen)
    which = "the first" if chosen is videos[0] else "the one ffmpeg takes"
    return f"{path}: {len(videos)} video streams; tracking {which} (#{number})"


class _Tail:
    """How a decoded stream ended, to tell a cut-off file from a complete one.

    FFmpeg decodes a truncated file "successfully" to fewer frames; the evidence is that the
    stream falls short of the frame count or duration its container promised, or (for streams
    without an index, like MPEG-TS or raw H.264) that its last frame decoded with errors or
    came after a jump over missing frames (B-frames cut off) in an otherwise regular stream.
    """

    def __init__(self) -> None:
        self.frames = 0
        self.first_time: float | None = None
        self.last_time: float | None = None
        self.last_gap = 0.0
        self.regular_gap = 0.0  # the largest gap between frames before the last one
        self.last_corrupt = False

    def add(self, time: float | None, corrupt: bool) -> None:
        self.frames += 1
        self.last_corrupt = corrupt
        if time is None:
            return
        if self.first_time is None:
            self.first_time = time
        elif self.last_time is not None:
            self.regular_gap = max(self.regular_gap, self.last_gap)
            self.last_gap = time - self.last_time
        self.last_time = time

    def shortfall(self, listed: int, end_s: float | None, fps: float) -> str | None:
        """Why the stream looks cut short (None: it looks complete).

        ``listed``: the container's frame count (0 = none); ``end_s``: where it says the
        stream ends. A listed count is trusted unless the frames still reach ``end_s`` (edit
        lists can hide frames); a promised end must be reached within a few frames.
        """
        reaches_end = None
        if end_s is not None and self.first_time is not None and self.last_time is not None:
            covered = self.last_time + 1.0 / fps
            reaches_end = covered >= end_s - max(_END_SLACK_S, _END_SLACK_FRAMES / fps)
        if listed and self.frames < listed and not reaches_end:
            return f"the container lists {plural(listed, 'frame')}"
        if not listed and reaches_end is False:
            return (f"{covered - self.first_time:.2f} s of the "
                    f"{end_s - self.first_time:.2f} s the container promises")
        if self.last_corrupt and not (listed and self.frames >= listed):
            # (with every listed frame there, it is damage, counted apart: not a cut-off end)
            return "the last frame is incomplete"
        period = 1.0 / fps
        regular = self.frames >= 3 and self.regular_gap <= 1.2 * period
        if regular and self.last_gap > 1.5 * period:
            missing = plural(round(self.last_gap / period) - 1, "frame")
            return f"{missing} missing before the last one"
        return None


#: Seconds a network input may take to open, and to deliver data once open, before the run
#: gives up with one line naming it (FFmpeg's own default is to wait for ever).
NETWORK_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class FFmpegInput:
    """How FFmpeg opens an input, as ``ffmpeg``'s input options would say it.

    ``format``: the demuxer (``ffmpeg -f``; None: probed); ``options``: demuxer/protocol
    options (``ffmpeg -KEY VALUE``), as (key, value) pairs; ``timeout_s``: the most a network
    input may take to open or to send more data; ``follow_s``: read a file that is still being
    written until it has not grown for that many seconds (``tail -f``; None: up to its end).
    """

    format: str | None = None
    options: tuple[tuple[str, str], ...] = ()
    timeout_s: float = NETWORK_TIMEOUT_S
    follow_s: float | None = None
    #: The command's option that sets ``timeout_s``, which a timeout's message names (None: the
    #: command has none, as ``vtrack select`` and ``frame``). Not part of a run's settings.
    timeout_option: str | None = field(default=None, compare=False)

    def waits_longer(self) -> str:
        """``; --timeout SECONDS waits longer`` when the command has the option, else ``""``."""
        return "" if self.timeout_option is None else \
            f"; {self.timeout_option} SECONDS waits longer"

    def checked(self) -> FFmpegInput:
        """This input's settings, its waits as floats, if they are in the command's ranges
        (``--timeout``: ``timeout_s`` from :data:`~vtrack.params.MIN_TIMEOUT_S` to
        :data:`~vtrack.params.MAX_TIMEOUT_S`; ``--follow``: ``follow_s`` None or above 0 to
        :data:`~vtrack.params.MAX_WAIT_S`); ConfigError naming the field otherwise (a wait
        of nan or 10**5000 would never end). TypeError naming the field for a ``format`` that
        is not text or None and for ``options`` that are not (key, value) pairs of text (a
        dict, a ``"KEY=VALUE"`` string, a number for a value), which FFmpeg would be handed
        as Python's own errors; the pairs come back as a tuple of tuples."""
        if self.format is not None and not isinstance(self.format, str):
            raise TypeError(f"ffmpeg.format: expected a format name (text) or None, got "
                            f"{type(self.format).__name__}")
        options = _option_pairs(self.options)
        timeout = checked_seconds("ffmpeg.timeout_s", self.timeout_s, MIN_TIMEOUT_S,
                                  MAX_TIMEOUT_S, False,
                                  " (how long a network input may send nothing)")
        follow = None if self.follow_s is None else checked_seconds(
            "ffmpeg.follow_s", self.follow_s, 0, MAX_WAIT_S, True, " (how long a file being "
            "written may not grow)")
        return replace(self, options=options, timeout_s=timeout, follow_s=follow)


def _option_pairs(options: object) -> tuple[tuple[str, str], ...]:
    """``options`` (:attr:`FFmpegInput.options`) as a tuple of (key, value) text pairs;
    TypeError naming ``ffmpeg.options`` and what was given otherwise."""
    if not isinstance(options, tuple | list):
        hint = " (a dict's: tuple(options.items()))" if isinstance(options, dict) else ""
        raise TypeError(f"ffmpeg.options: expected (key, value) pairs of text, e.g. "
                        f"((\"probesize\", \"32\"),), got {type(options).__name__}{hint}")
    for pair in options:
        if not (isinstance(pair, tuple | list) and len(pair) == 2
                and all(isinstance(part, str) for part in pair)):
            raise TypeError(f"ffmpeg.options: expected (key, value) pairs of text, e.g. "
                            f"((\"probesize\", \"32\"),), got {cut(repr(pair))}")
    return tuple((key, value) for key, value in options)


def checked_ffmpeg(how: object) -> FFmpegInput:
    """``how`` checked (:meth:`FFmpegInput.checked`) if it is an :class:`FFmpegInput` (a
    RunRequest's or ``open_source``'s ``ffmpeg``); TypeError naming ``ffmpeg`` otherwise."""
    if not isinstance(how, FFmpegInput):
        raise TypeError(f"ffmpeg: expected a vtrack.io.video.FFmpegInput, got "
                        f"{type(how).__name__}")
    return how.checked()


def _python_file(container: av.container.InputContainer) -> object:
    """The Python object ``container`` reads from (None for a path or URL FFmpeg opened):
    PyAV 14+ wraps it in a ``PyIOFile`` whose ``file`` it is."""
    given = container.file
    return getattr(given, "file", given)


def text_file_problem(path: str, container: av.container.InputContainer) -> str | None:
    """Why ``container`` (``path`` opened) is no video when FFmpeg read it as a text file
    (:data:`TEXT_FORMATS`); None otherwise."""
    if container.format.name not in TEXT_FORMATS:
        return None
    return (f"{path}: a text file, not a video (FFmpeg's {container.format.name} reader "
            "would draw its characters as pictures)")


#: FFmpeg's read buffer for a container on a pipe: its default probe size (``probesize``).
PIPE_BUFFER_BYTES = 5_000_000


def _open_container(path: str, how: FFmpegInput, names: OptionNames
                    ) -> av.container.InputContainer:
    """``path`` opened by FFmpeg as ``how`` says: ``-`` is stdin, ``scheme://`` a network
    input (with ``how.timeout_s``; ``srt://`` refused: the wheel's FFmpeg has no SRT), a file
    with ``how.follow_s`` read while it grows. Messages call ``how``'s fields by ``names``."""
    if how.format is not None and how.format not in av.formats_available:
        raise InputError(f"{names.format} {how.format}: not a format PyAV's FFmpeg reads "
                         "(ffmpeg -formats lists them; capture devices /dev/videoN need no "
                         f"{names.format})")
    kwargs: dict[str, Any] = {"format": how.format, "options": dict(how.options)}
    if path == "-":
        stdin = piped_stdin("a video")
        if stdin.seekable():
            return av.open(stdin, **kwargs)
        # a pipe: FFmpeg's reads are buffered up to its probe size, as ``ffmpeg -i pipe:`` is,
        # so a container whose index comes last (a plain MP4) that fits opens as it does there
        return _open_stream(CountedStream(stdin), buffer_size=PIPE_BUFFER_BYTES, **kwargs)
    if "://" not in path:
        if how.follow_s is not None:
            return _open_stream(GrowingFile(path, how.follow_s, names.follow), **kwargs)
        return av.open(ffmpeg_file(path), **kwargs)
    scheme = url_scheme(path)
    if scheme == "srt":
        raise InputError(f"{path}: srt:// is not in the FFmpeg that PyAV's wheel ships; relay "
                         "it, e.g. ffmpeg -i srt://... -c copy -f mpegts udp://127.0.0.1:5000")
    options = kwargs["options"]
    if scheme == "rtsp" and "listen" in options.get("rtsp_flags", "") \
            and "listen_timeout" not in options:  # FFmpeg's own default fails (ERANGE)
        options["listen_timeout"] = str(max(1, round(how.timeout_s)))
    # in a thread of its own: FFmpeg holds the thread that opens a URL until something comes
    # or the timeout passes (up to an hour), and Ctrl-C or SIGTERM must not wait that long
    return run_aside(lambda: _open_url(path, how, kwargs), lambda container: container.close())


#: The URLs being opened (by :func:`_open_url`), each with the ``time.monotonic()`` by which
#: each of its opens gives up at the latest: one whose caller was interrupted still opens
#: aside, and holds what it took (a UDP port) meanwhile.
_OPENING: dict[str, list[float]] = {}
_OPENING_LOCK = threading.Lock()
#: Seconds an open may go on past its timeout: FFmpeg notices it at its next check (about
#: every 0.1 s while it waits) and then lets go of what it opened.
OPEN_SLACK_S = 1.0


def _open_url(path: str, how: FFmpegInput, kwargs: dict[str, Any]) -> av.container.InputContainer:
    """The URL ``path`` opened by FFmpeg, with ``how.timeout_s`` for its header and for its
    streams' probe (so twice that at most), listed in :data:`_OPENING` meanwhile."""
    ends = time.monotonic() + 2 * how.timeout_s + OPEN_SLACK_S
    with _OPENING_LOCK:
        _OPENING.setdefault(path, []).append(ends)
    try:
        return av.open(ffmpeg_url(path), timeout=(how.timeout_s, how.timeout_s), **kwargs)
    finally:
        with _OPENING_LOCK:
            _OPENING[path].remove(ends)
            if not _OPENING[path]:
                del _OPENING[path]


def _still_opening(path: str, exc: BaseException) -> str:
    """``; an interrupted open of it still runs ...`` when ``exc`` is FFmpeg's "Address
    already in use" opening the URL ``path`` while an earlier open of it (its caller
    interrupted) still holds the address; else ``""``."""
    with _OPENING_LOCK:
        ends = max(_OPENING.get(path, [0.0]))
    if getattr(exc, "errno", None) != errno.EADDRINUSE or not ends:
        return ""
    left = max(1, math.ceil(ends - time.monotonic()))
    return (f"; an interrupted open of it still runs and may hold the address up to {left} s "
            "more")


def _open_stream(stream: CapturingStream, **kwargs: Any) -> av.container.InputContainer:
    """``stream`` opened by FFmpeg. A signal while FFmpeg probed it ends the probe; what it
    raised is raised here rather than FFmpeg's error about the cut-short data."""
    try:
        container = av.open(stream, **kwargs)
    except av.FFmpegError:
        stream.raise_interruption()
        raise
    if stream.interruption is not None:
        container.close()
        stream.raise_interruption()
    return container


#: Input options that repeat the input (FFmpeg's image demuxers' ``loop``, ``-stream_loop``):
#: a still image so given does not end after its one frame, unless the value is one of
#: :data:`NO_REPEAT` (``loop=0``: the image demuxers' default).
REPEATING_OPTIONS = frozenset({"loop", "stream_loop"})
#: Values of :data:`REPEATING_OPTIONS` that repeat nothing: zero, empty (FFmpeg takes an empty
#: number as 0) and FFmpeg's words for a false flag.
NO_REPEAT = frozenset({"", "0", "false", "n", "no", "disable", "disabled", "off"})
#: Containers FFmpeg cannot read as a stream unless their index comes first (a plain MP4
#: records it at the end, once finished).
INDEX_LAST_SUFFIXES = (".mp4", ".mov", ".m4v", ".3gp")
#: Names of files of raw frames (no header: nothing FFmpeg opens without their size).
RAW_SUFFIXES = (".raw", ".yuv", ".rgb", ".bgr", ".gray")


def _repeats(how: FFmpegInput) -> bool:
    """Whether ``how``'s input options repeat the input: one of :data:`REPEATING_OPTIONS`
    whose value (the last given: FFmpeg takes that one) is not one of :data:`NO_REPEAT`."""
    given = dict(how.options)
    return any(given[key].strip().lower() not in NO_REPEAT
               for key in REPEATING_OPTIONS.intersection(given))


def decoded_frame(decoded: av.VideoFrame, index: int, time_s: float,
                  rotation: int | None = None, mirrored: bool = False,
                  scale: DepthScale | None = None) -> Frame:
    """A decoded picture as the :class:`Frame` every reader hands over: I420 planes as they
    are (4:2:0 of even size; converted by OpenCV only where a stage asks), else BGR from
    FFmpeg's converter; turned by ``rotation`` degrees (the stream's display matrix; None:
    the picture's own, as ``vtrack run`` turns a phone's footage), after a flip top to
    bottom when ``mirrored`` (a photo's mirroring orientation, FFmpeg's turn being the rest of
    it: :func:`~vtrack.io.signatures.photo_mirrored`). With ``scale``, the reading of a deep
    stream (its first frame is :func:`~vtrack.io.depth.deep`), every picture, deep or 8-bit,
    is read by it (:meth:`~vtrack.io.depth.DepthScale.frame`) and is a :class:`GrayFrame` or
    a :class:`BgrFrame` as the first frame is; without, FFmpeg converts a deep picture (its
    top 8 bits)."""
    if rotation is None:
        rotation = quarter_turns(decoded.rotation)
    if scale is not None:
        pixels = as_kind(scale.frame(stored_pixels(decoded), index), scale.colour)
        pixels = turned(cv2.flip(pixels, 0) if mirrored else pixels, rotation)
        return (BgrFrame if scale.colour else GrayFrame)(index, time_s, pixels)
    if mirrored:
        return BgrFrame(index, time_s,
                        turned(cv2.flip(decoded.to_ndarray(format="bgr24"), 0), rotation))
    even = decoded.width % 2 == 0 and decoded.height % 2 == 0
    if even and decoded.format.name in I420_FORMATS and rotation:
        planes = rotate_i420(decoded.to_ndarray(), decoded.width, decoded.height, rotation)
        return I420Frame(index, time_s, planes, full_range(decoded), bt709(decoded))
    if even and decoded.format.name in I420_FORMATS:
        # Views of the decoder's own planes: no 3 MB copy per 1080p frame. Reading them is
        # safe; the buffers live as long as the views (PyAV refcounts them).
        return I420Frame.from_planes(index, time_s, *plane_views(decoded),
                                     full_range=full_range(decoded), bt709=bt709(decoded))
    return BgrFrame(index, time_s, turned(decoded.to_ndarray(format="bgr24"), rotation))


def _cut_file(path: str, follow_s: float | None, names: OptionNames) -> str | None:
    """The line for ``path``, a local file, when it is empty (and stayed so for ``--follow``'s
    ``follow_s``), declares pictures larger than vtrack takes, has a header FFmpeg cannot
    decode from (:func:`~vtrack.io.signatures.header_problem`), or is an MP4 whose index is
    missing or cut short (:func:`~vtrack.io.signatures.mp4_index_problem`: FFmpeg then finds
    no frames, or no streams at all); None otherwise."""
    if path == "-" or not os.path.isfile(path):
        return None
    if os.path.getsize(path) == 0:
        if follow_s is not None:
            return (f"{path}: stayed empty (0 bytes) for {names.follow}'s wait of "
                    f"{follow_s:g} s: nothing was written to it (a writer that starts later, "
                    f"or holds its first bytes longer, needs a longer {names.follow})")
        return f"{path}: an empty file (0 bytes), not a video"
    problem = header_problem(path)
    if problem:
        return f"{path}: {problem}"
    problem = mp4_index_problem(path)
    if problem is None:
        return None
    return (f"{path}: an MP4 with {problem}: the recording was cut off before it was finished "
            "(a camera or phone stopped, a copy not complete), and its frames cannot be found "
            "without it")


def _undecodable(path: str, how: FFmpegInput, exc: av.FFmpegError, live: bool,
                 names: OptionNames) -> str:
    """The one line for an input FFmpeg could not open or decode a first frame from, saying
    what the way it was read (a URL, ``--follow``), its bytes (none; an MP4 without its whole index)
    or its name (raw frames) makes likely. Data that is no video from a URL is said to be a
    stream joined between key frames only when it may be one: read as ``live``, or of a live
    scheme (udp, rtsp, ...); an ``http://`` file serves its bytes from the start, as a file
    holds them."""
    reason = os_reason(exc)
    if "://" in path:  # a network input, as _open_container opens it
        if not isinstance(exc, av.error.InvalidDataError):
            return f"{path}: cannot be opened ({reason}{_still_opening(path, exc)})"
        if not (live or is_live(path)):
            return f"{path}: not a video FFmpeg can decode ({reason})"
        return (f"{path}: nothing FFmpeg could decode came within {how.timeout_s:g} s "
                f"({reason}): a live stream starts at a key frame{how.waits_longer()}")
    if how.follow_s is not None and path.lower().endswith(INDEX_LAST_SUFFIXES):
        return (f"{path}: cannot be read as it grows ({reason}): a plain MP4 holds its index "
                "at its end; follow fragmented MP4, MPEG-TS or Matroska, or read a finished "
                f"MP4 without {names.follow}")
    cut = _cut_file(path, how.follow_s, names)
    if cut:
        return cut
    if path.lower().endswith(RAW_SUFFIXES):
        raw = "vtrack run --raw WxH (with --pix-fmt, --fps)" if names.options else \
            f"{names.raw}'WxH' (with pix_fmt, fps)"
        return (f"{path}: not a video FFmpeg can decode ({reason}); raw frames are read only "
                f"by {raw}")
    return f"{path}: not a video FFmpeg can decode ({reason})"


def _refuse_unused_options(path: str, how: FFmpegInput,
                           container: av.container.InputContainer, names: OptionNames) -> None:
    """InputError naming the first ``--input-option`` FFmpeg had no use for opening ``path``
    (it ignores those without a word; :mod:`vtrack.io.ffoptions`)."""
    demuxer = container.format.name
    protocols = input_protocols(path, _python_file(container) is not None)
    unused = unused_options([key for key, _ in how.options], demuxer, protocols)
    if unused:
        read = f"its {demuxer} demuxer" + "".join(f", the {p} protocol" for p in protocols)
        raise InputError(f"{names.input_option} {unused[0]}: FFmpeg did not use it opening "
                         f"{path} "
                         f"(not an option of {read} or of every input; ffmpeg -h "
                         f"demuxer={demuxer.split(',')[0]} lists the demuxer's)")


def _refuse_nobuffer(path: str, how: FFmpegInput, names: OptionNames) -> None:
    """InputError for ``fflags=nobuffer`` opening ``path``, an input that is not live: FFmpeg
    then drops the packets it reads to probe it (less delay on a live stream), so a file's
    first frames, up to a key frame after them, would be lost without a word (all of them in
    a clip with one key frame), and ground truth would no longer line up."""
    value = _nobuffer(how)
    if value is not None:
        raise InputError(f"{names.input_option} fflags={value}: FFmpeg drops the packets "
                         f"it reads probing {path}, so its first frames would be lost; "
                         "nobuffer is for live streams (rtsp://, udp:// ..., or "
                         f"{names.live if names.options else names.live + '=True'})")


def _nobuffer(how: FFmpegInput) -> str | None:
    """The value of the ``fflags`` option of ``how`` that sets ``nobuffer`` (``nobuffer``,
    ``+nobuffer+genpts`` ...), or None when none does."""
    for key, value in how.options:
        flags = re.findall(r"([+-]?)(\w+)", value)
        if key == "fflags" and any(sign != "-" and name == "nobuffer" for sign, name in flags):
            return value
    return None


def _no_frame(path: str, how: FFmpegInput, names: OptionNames) -> str:
    """The message for an input of which no frame could be decoded; with ``fflags=nobuffer``
    it says that the flag may be why: FFmpeg drops the packets it read probing the input,
    which may have held its only key frame (every frame after needs it)."""
    value = _nobuffer(how)
    if value is None:
        return _cut_file(path, how.follow_s, names) or f"{path}: no frame could be decoded"
    return (f"{path}: no frame could be decoded; {names.input_option} fflags={value} may have "
            "dropped the stream's only key frame (FFmpeg drops the packets it reads probing "
            "the input): try without it")


def _check_estimate(info: InputInfo, index: int, time_s: float, fps: float) -> None:
    """Give up ``info``'s estimated frame count (None) when frame ``index``, ``time_s``
    seconds after the first, is off the timeline of ``fps`` frames a second the estimate
    counted with by more than :data:`ESTIMATE_SLACK_FRAMES` and
    :data:`ESTIMATE_SLACK_SHARE` of ``index``: the timestamps jump or the rate varies."""
    if abs(time_s * fps - index) > ESTIMATE_SLACK_FRAMES + ESTIMATE_SLACK_SHARE * index:
        info.frame_count, info.frame_count_estimated = None, False


class VideoSource(Source):
    """A video file, stream or URL (anything FFmpeg opens, as ``how`` says), decoded with frame
    threads in a reader thread (fewer for a ``live`` source: each holds back a frame). Its
    messages call ``how``'s fields by ``names`` (``--follow``, ``--input-option``; the
    library's ``ffmpeg.follow_s``, ``ffmpeg.options``)."""

    def __init__(self, path: str, how: FFmpegInput | None = None, live: bool = False,
                 names: OptionNames = COMMAND_NAMES) -> None:
        self._how = how = how or FFmpegInput()
        self._names = names
        if not live:
            _refuse_nobuffer(path, how, names)
        try:
            # ``-``: the container on stdin, through Python's file object so that FFmpeg may
            # seek in a redirected file (``< clip.mp4``) and reads a pipe as a stream
            container = _open_container(path, how, names)
        except PermissionError:
            raise InputError(f"{path}: cannot be read (permission denied)") from None
        except FileNotFoundError:
            raise InputError(f"{path}: no such file") from None
        except av.error.ExitError:  # the timeout's interrupt
            raise InputError(f"{path}: cannot be opened (nothing came within "
                             f"{how.timeout_s:g} s{how.waits_longer()})") from None
        except av.FFmpegError as exc:
            raise InputError(_undecodable(path, how, exc, live, names)) from None
        except (OSError, ValueError) as exc:  # ValueError: PyAV found stdin unreadable
            raise InputError(f"{path}: cannot be read ({os_reason(exc)})") from None
        # a regular file can be read again (a photo's orientation tag) and, unless it grows,
        # jump to a key frame (start_near): not stdin, a FIFO or a URL
        self._regular = "://" not in path and path != "-" and os.path.isfile(path)
        self._seekable = not live and how.follow_s is None and self._regular
        try:
            info = self._open(path, container, live)
        except BaseException:
            container.close()
            raise
        super().__init__(info)
        self._note_depth()
        several = _several_videos(path, container, self._stream)
        if several:
            self._warnings.append(several)
        turn = self._first.rotation  # the display matrix's angle, read at a quarter turn
        if abs((turn - self._rotation + 180) % 360 - 180) > 1:
            self._warnings.append(f"{path}: its display matrix turns the picture {turn:g} "
                                 "degrees, not a quarter turn; it is read turned "
                                 f"{self._rotation} degrees (the nearest quarter turn)")

    def _open(self, path: str, container: av.container.InputContainer, live: bool
              ) -> InputInfo:
        """Pick the video stream, decode the first frame, describe the input."""
        _refuse_unused_options(path, self._how, container, self._names)
        if not any(not _is_cover(s) for s in container.streams.video):
            cut = _cut_file(path, self._how.follow_s, self._names)
            if cut:
                raise InputError(cut)
            kinds = ", ".join(sorted({"cover picture" if _is_cover(s) else s.type
                                      for s in container.streams})) or "none"
            raise InputError(f"{path}: no video stream (streams: {kinds})")
        text = text_file_problem(path, container)
        if text:
            raise InputError(text)
        self._container = container
        self._stream = stream = _main_video_stream(container)
        if stream.codec_context is None:  # e.g. a video file read with --format image2
            raise InputError(f"{path}: no decoder for its video stream as FFmpeg reads it "
                             f"(format {container.format.name}; a wrong {self._names.format}?)")
        self._dropped = 0  # packets the decoder refused (damage in the middle of the file)
        self._corrupt = 0  # pictures the decoder marked as decoded with errors
        self._damaged = False  # damage seen: later frames keep their places in the stream
        self._damage_warned = False
        #: A network input that went quiet: the timeout that ended it (``perf_counter`` start
        #: and end), a wait that only found the end (see :attr:`end_wait`).
        self._quiet: tuple[float, float] | None = None
        # Bounded before the decoder allocates a picture (the size is in the stream header).
        too_big = frame_size_problem(stream.codec_context.width, stream.codec_context.height)
        if too_big and stream.codec_context.width and stream.codec_context.height:
            raise InputError(f"{path}: {too_big}")
        stream.thread_type = "AUTO"
        # a live source waits for no frame: one frame thread per core (each holds back a frame)
        stream.codec_context.thread_count = cpu_count() if live else decoder_threads(
            stream.codec_context.width, stream.codec_context.height, cpu_count())
        # a photo's orientation tag is read from the file, or for what cannot be read again
        # from its first packet (the photo's bytes, as the image demuxers hand a photo over),
        # which :meth:`_decode` keeps as ``_photo`` until it is read
        photo = stream.codec_context.name in PHOTO_CODECS
        self._photo: bytes | None = None
        self._keep_photo = photo and not self._regular
        #: A photo file's size until its first packet is read (:meth:`_decode`), and whether
        #: that packet was the whole file: a still image alone, frame 0 its last (not when an
        #: input option repeats it: the image demuxers' ``loop``, ``stream_loop``).
        repeated = _repeats(self._how)
        self._photo_size = (os.path.getsize(path) if photo and self._seekable and not repeated
                            else None)
        self._still = False
        self._decoded = self._decode()
        try:
            self._first = next(self._decoded)
        except StopIteration:
            raise InputError(_no_frame(path, self._how, self._names)) from None
        except av.FFmpegError as exc:
            raise InputError(_undecodable(path, self._how, exc, live, self._names)) from None

        rate = stream.guessed_rate or stream.average_rate
        fps = float(rate) if rate else None
        self._end_s = self._promised_end_s()
        start_s = self._first.time
        duration = None
        if self._end_s is not None and start_s is not None:
            duration = self._end_s - start_s
        frame_count = stream.frames or None
        mp4 = "mp4" in self._container.format.name
        fragmented = mp4 and self._fragmented_mp4(path)
        read = _python_file(self._container)
        if isinstance(read, CountedStream):  # its first MiB was kept for that look only
            read.drop_head()
        if fragmented:
            frame_count = None  # its index lists the first fragment's frames: its duration counts
        # a fragmented MP4 read without seeking (stdin, a followed file, a URL) states the
        # duration of what FFmpeg read before its first frame, the first fragment: no estimate
        estimated = (frame_count is None and duration is not None and bool(fps)
                     and not (mp4 and not self._seekable and (fragmented or not stream.frames)))
        if estimated:
            frame_count = round(duration * fps)
        # a gap in a constant-rate stream's timestamps is pictures lost (a variable-rate one
        # may pause): its listed frame count is its duration times its rate
        self._constant_rate = bool(stream.frames and duration and fps
                                   and abs(stream.frames - duration * fps) <= 1)
        self._frame_order = self._container.format.name in FRAME_ORDER_FORMATS
        self._t0 = self._first.time  # frame 0's timestamp: the others' places count from it
        self._start = 0  # the index of the frame iteration begins at (start_near)
        #: Frame places left empty before the run's first frame (None until it is read).
        self._uncounted: int | None = None

        self._rotation = quarter_turns(self._first.rotation)
        #: How a deep stream (its first frame is deep) is read as 8-bit; None: FFmpeg's
        #: conversion serves.
        self._scale = DepthScale(path, stored_pixels(self._first), "frames") if deep(
            self._first.format) else None
        # a photo whose orientation tag mirrors it (FFmpeg's rotation is the rest of it)
        self._mirrored = photo and (photo_mirrored(path) if self._regular else
                                    photo_bytes_mirrored(self._photo or b""))
        self._photo = None
        width, height = self._first.width, self._first.height
        self._coded_size = (width, height)
        if self._rotation in (90, 270):
            width, height = height, width
        return InputInfo(
            path=path,
            kind="video",
            name=input_name(path),
            width=width,
            height=height,
            fps=fps,
            frame_count=frame_count,
            duration_s=duration,
            codec=stream.codec_context.name,
            pix_fmt=self._first.format.name,
            rotation=self._rotation,
            frame_count_estimated=estimated,
        )

    def _fragmented_mp4(self, path: str) -> bool:
        """Whether ``path``, an MP4 being read, holds fragments, so that its index lists the
        first fragment's frames at most: a file read by seeking by its boxes
        (:func:`~vtrack.io.signatures.mp4_fragmented`), a pipe on stdin, a redirected stdin or
        a followed file by its first bytes
        (:func:`~vtrack.io.signatures.mp4_head_fragmented`). False when it holds none, or for
        what cannot be looked at again (a FIFO, a URL)."""
        if self._seekable:
            return mp4_fragmented(path)
        read = _python_file(self._container)
        if isinstance(read, CountedStream):
            return read.head is not None and mp4_head_fragmented(bytes(read.head))
        try:
            if path == "-" and read is not None:  # stdin redirected from a file
                head = os.pread(read.fileno(), HEAD_BYTES, 0)  # type: ignore[attr-defined]
            elif isinstance(read, GrowingFile):
                with open(path, "rb") as handle:
                    head = handle.read(HEAD_BYTES)
            else:
                return False
        except OSError:
            return False
        return mp4_head_fragmented(head)

    @property
    def frames_skipped(self) -> int:
        """Packets the decoder refused while decoding; once the stream has ended, every frame
        place left empty after the damage (some pictures vanish without an error). Those
        before the run's first frame (:meth:`_run_begins`) do not count."""
        if self._uncounted is None:  # no frame tracked yet
            return 0
        return max(0, self._dropped - self._uncounted)

    @property
    def frames_corrupt(self) -> int:
        """Frames handed over that the decoder marked as decoded with errors (their pictures
        may show damage)."""
        return self._corrupt

    @property
    def end_wait(self) -> tuple[float, float] | None:
        """Also a network input's ``--timeout`` wait after its last packet, once it went
        quiet: the frames the decoder still held come only after it."""
        read = _python_file(self._container)
        return read.end_wait if isinstance(read, GrowingFile) else self._quiet

    def _note_depth(self) -> None:
        """Keep the warnings :attr:`_scale` added (the stream's depth, a frame of another)."""
        if self._scale is not None:
            self._warnings.extend(text for _, text in self._scale.news())

    def ends_after(self, index: int) -> bool:
        """Frame 0 of a still image given alone (a PNG, JPEG, TIFF or WebP file whose first
        picture is the whole file) is its last; for any other input, only reading on tells."""
        return self._still and index == 0

    def stop_at_end(self) -> bool:
        read = _python_file(self._container)
        return isinstance(read, GrowingFile) and read.stop_at_end()

    def _decode(self) -> Iterator[av.VideoFrame]:
        """Decoded frames in order, dropping packets the decoder refuses (damage in the middle
        of the file: ffmpeg skips them the same way). A demuxer error still ends the stream;
        a network input that went quiet (``ExitError``, the timeout) first hands over the
        frames the decoder still holds (one per frame thread)."""
        try:
            for packet in self._container.demux(self._stream):
                if self._keep_photo:  # a photo's first packet: the whole photo, its tags too
                    self._keep_photo, self._photo = False, bytes(packet)
                if self._photo_size is not None:  # the image is the whole file: nothing after
                    self._still = packet.size == self._photo_size
                    self._photo_size = None
                try:
                    frames = packet.decode()
                except av.error.InvalidDataError:
                    self._dropped += 1
                    self._damaged = True
                    continue
                yield from frames
            read = _python_file(self._container)
            if isinstance(read, CapturingStream):  # a signal while a read waited
                read.raise_interruption()
        except av.error.ExitError:
            # the demuxer hands over the packet it held only now: the quiet began a timeout ago
            now = time.perf_counter()
            self._quiet = (now - self._how.timeout_s, now)
            for frame in self._stream.decode(None):
                frame.time_base = self._stream.time_base  # a flushed frame comes without one
                yield frame
            raise

    def start_near(self, index: int) -> int:
        """Jump to the key frame at or before frame ``index`` when the frames' places follow
        from their timestamps, ``round((t - t0) * fps)`` (a local file of constant frame rate:
        its listed count is its duration times its rate; not AVI, whose pictures carry no
        times of their own). The frame found there is checked: a clean picture on that
        timeline, at or before ``index`` (a key frame after it, which FFmpeg finds where
        B-frames put its decoding time before ``index``'s, makes it aim 1, 2, 4... frames
        earlier); else (or when FFmpeg cannot seek) the reader goes back to the first frame,
        and iteration begins there as it would have. Returns the index iteration begins at."""
        super().start_near(index)
        fps = self.info.fps
        if (index <= 0 or self._prefetch is not None or not self._seekable or not fps
                or not self._constant_rate or self._frame_order or self._t0 is None):
            return 0
        dropped = self._dropped
        back = 0  # frames the seek aims before ``index``
        try:
            while back <= index:
                first = self._seek(round((self._t0 + (index - back) / fps)
                                         / self._stream.time_base))
                place = (first.time - self._t0) * fps
                if abs(place - round(place)) > 0.25 or round(place) < 0:
                    break
                if round(place) <= index:
                    self._first, self._start, self._dropped = first, round(place), 0
                    return self._start
                # a key frame shown after ``index`` but decoded before it (B-frames: FFmpeg
                # seeks by decoding times): aim further back
                back = 2 * back or 1
        except (av.FFmpegError, StopIteration, TypeError):  # TypeError: a frame without time
            pass
        try:
            self._first = self._seek(self._stream.start_time or 0)
        except (av.FFmpegError, StopIteration):
            raise InputError(f"{self.info.path}: cannot be read again from its first frame "
                             "after a seek") from None
        self._start, self._dropped = 0, dropped
        return 0

    def _seek(self, pts: int) -> av.VideoFrame:
        """The first clean picture decoded from the key frame at or before ``pts`` (stream
        time base); the decoder then goes on from it."""
        self._container.seek(pts, stream=self._stream, backward=True, any_frame=False)
        self._decoded = self._decode()
        return next(frame for frame in self._decoded if not frame.is_corrupt)

    def _promised_end_s(self) -> float | None:
        """Where the container says the video stream ends (seconds, stream clock), if it says.

        The whole container's duration counts only when the video is its only stream (an audio
        track may run longer than the video).
        """
        stream, container = self._stream, self._container
        if stream.duration and stream.time_base:
            return float((stream.start_time or 0) * stream.time_base + stream.duration *
                         stream.time_base)
        if container.duration and len(container.streams) == 1:
            if container.format.name in END_AS_DURATION_FORMATS:
                # FFmpeg's Matroska muxer records the last timestamp as the duration, which is
                # the end when the timestamps do not start at 0 (`-f segment`'s later parts)
                return max(container.start_time or 0, container.duration) / av.time_base
            return ((container.start_time or 0) + container.duration) / av.time_base
        return None

    def _frames(self) -> Iterator[Frame]:
        info = self.info
        fps = info.fps or 30.0
        first, self._first = self._first, None  # do not keep a decoded picture alive
        t0 = None if self._frame_order else self._t0
        tail = _Tail()
        index = yielded = self._start  # (start_near: the frames before it were not read)
        refused = 0
        last_t: float | None = None
        # a gap in the timestamps of a stream that kept its frame rate so far is pictures lost
        steady = self._constant_rate
        intervals = 0 if self._container.format.name in STEADY_RATE_FORMATS else None
        try:
            for decoded in itertools.chain((first,), self._decoded):
                if (decoded.width, decoded.height) != self._coded_size:
                    raise PartialInputError(
                        f"{info.path}: the frame size changed from {self._coded_size[0]}x"
                        f"{self._coded_size[1]} to {decoded.width}x{decoded.height} at frame "
                        f"{index}; an input must keep one size",
                        index,
                    )
                t = None if self._frame_order else decoded.time
                step = None if t is None or last_t is None else (t - last_t) * fps
                if decoded.is_corrupt:
                    self._damaged = True
                elif steady and step is not None and step > 1.5:
                    self._damaged = True  # pictures vanished without an error
                elif intervals is not None and step is not None and not self._damaged:
                    regular = abs(step - 1) <= STEADY_TOLERANCE
                    intervals = intervals + 1 if regular else None
                    steady = steady or (intervals or 0) >= STEADY_INTERVALS
                if self._damaged and t is not None and last_t is not None and t <= last_t:
                    continue  # a stale picture of the damaged stretch, out of order: its place
                    # has passed, it counts as skipped
                last_t = t
                tail.add(t, decoded.is_corrupt)
                self._corrupt += decoded.is_corrupt
                time_s = index / fps if t is None or t0 is None else t - t0
                # Frames lost to damage keep their places (see the module docstring): in a
                # constant-rate stream its timestamps tell them; in another (a variable rate),
                # one place a packet the decoder refused
                if self._damaged and steady and t is not None and t0 is not None:
                    index = max(index, round(time_s * fps))
                elif self._dropped > refused:
                    index += self._dropped - refused
                refused = self._dropped
                if info.frame_count_estimated and t is not None and t0 is not None:
                    _check_estimate(info, index, time_s, fps)
                if self._uncounted is None and self._tracked(index, time_s):
                    # places passed over before the run's frames (see _run_begins)
                    self._uncounted = self._run_begins(index) - yielded
                frame = decoded_frame(decoded, index, time_s, self._rotation, self._mirrored,
                                      self._scale)
                self._note_depth()
                yield frame
                index += 1
                yielded += 1
        except av.error.ExitError:  # the timeout's interrupt: a network input went quiet
            raise PartialInputError(
                f"{info.path}: the stream stopped at frame {index} (no data for "
                f"{self._how.timeout_s:g} s: the sender stopped or the network dropped it)",
                index) from None
        except av.FFmpegError as exc:
            raise PartialInputError(
                f"{info.path}: decoding stopped at frame {index} ({os_reason(exc)})", index
            ) from None
        except FollowedFileChanged as exc:
            raise PartialInputError(f"{info.path}: reading stopped at frame {index}: {exc}",
                                    index) from None
        finally:
            if self._damaged:  # every place left empty, also by pictures the decoder dropped
                self._dropped = max(self._dropped, index - yielded)
        self._warn_of_damage()
        # skipped frames were in the file, and so were those before a jump: not a shortfall
        tail.frames += self._dropped + self._start
        # a torn last packet is a cut for certain: named before what the frames suggest
        shortfall = (self._torn_packet() or tail.shortfall(self._stream.frames, self._end_s, fps)
                     or self._torn_container())
        if shortfall:
            follow_s = self._how.follow_s
            # (a URL: its sender closed the connection inside its last frames, as a killed
            # one may; no file was cut)
            cause = ("the sender stopped mid-stream?" if is_url(info.path) else
                     "truncated file?" if follow_s is None else
                     f"truncated, or its writer paused longer than {self._names.follow}'s "
                     f"{follow_s:g} s: give a longer {self._names.follow} if it was still "
                     "being written")
            raise PartialInputError(
                f"{info.path}: decoding stopped at frame {index} ({shortfall}; {cause})", index)
        if not self._stream.frames:  # read to its end: the count is known now
            info.frame_count, info.frame_count_estimated = index, False

    def _torn_packet(self) -> str | None:
        """MPEG-TS is a run of fixed-size packets (188 bytes; 192 or 204 in variants): a file
        that ends inside one was cut (FFmpeg drops the torn packet without a word)."""
        if self._container.format.name != "mpegts":
            return None
        size = self._container.size
        if size <= 0:  # a pipe or a followed file: what was read of it
            size = getattr(_python_file(self._container), "bytes_read", 0)
        if size > 0 and all(size % n for n in TS_PACKET_SIZES):
            return f"the file ends inside a {TS_PACKET_SIZES[0]}-byte transport packet"
        return None

    def _torn_container(self) -> str | None:
        """A fragmented MP4 (``moof`` boxes: its index lists the first fragment's frames at
        most) ends with a whole top-level box, a Matroska/WebM file written live (no duration)
        with a whole element: one cut inside (a recording stopped part way: no count or
        duration to fall short of) was cut, though FFmpeg reads the whole fragments or blocks
        before it without a word (a regular file read to its end only). Other files are judged
        by the count or duration they state (:meth:`_Tail.shortfall`): bytes after a file's
        last box (a phone's trailer) are no cut. A followed file (``--follow``) is judged the
        same way once it stopped growing: the file at its path is then what was read."""
        if not self._seekable and not isinstance(_python_file(self._container), GrowingFile):
            return None
        demuxer = self._container.format.name
        if "mp4" in demuxer:
            return mp4_torn_box(self.info.path)
        if "matroska" in demuxer and self._end_s is None:
            return matroska_torn_element(self.info.path)
        return None

    def _warn_of_damage(self) -> None:
        """The warnings of frames skipped and decoded with errors, once: when the stream has
        ended, or when it is closed before its end (``--frames``)."""
        if self._damage_warned:
            return
        self._damage_warned = True
        read = _python_file(self._container)
        if isinstance(read, CapturingStream) and read.interruption is not None:
            return  # the stream was cut short by a signal, not damaged
        if self.frames_skipped:
            damaged = plural(self.frames_skipped, "damaged frame")
            were = "was" if self.frames_skipped == 1 else "were"
            self._warnings.append(f"{self.info.path}: {damaged} could not be decoded and "
                                 f"{were} skipped")
        if self.frames_corrupt:
            self._warnings.append(f"{self.info.path}: {plural(self.frames_corrupt, 'frame')} "
                                 "decoded with errors (damaged file: their pictures may be "
                                 "wrong)")

    def _release(self) -> None:
        self._warn_of_damage()
        self._decoded.close()  # finish the demuxer before its container goes
        self._container.close()
