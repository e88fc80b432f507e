"""What every reader hands over: :class:`InputInfo` about the input and a :class:`Source` of frames.

A source is opened by :func:`vtrack.io.open_source`, which checks the input and decodes its first
frame before returning (so a bad input fails at once with an :class:`~vtrack.errors.InputError`).
Iterating it decodes in a background thread a few frames ahead of the consumer; closing it (or
leaving its ``with`` block) stops that thread and releases the file, also mid-stream.
"""

from __future__ import annotations

import itertools
import math
from abc import ABC, abstractmethod
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from typing import Any, ClassVar, Literal

from vtrack.errors import plural
from vtrack.frame import Frame
from vtrack.io.files import Closing
from vtrack.io.threads import KeepingUp, Prefetcher

InputKind = Literal["video", "images", "raw"]

#: Seconds a frame's ``time_s`` may fall short of a time and still count as at it (rounding:
#: frame 15 of a 30 fps stream is at 0.5 s, whatever its float says).
TIME_SLACK_S = 1e-6


@dataclass
class InputInfo:
    """What is known about an input when it is opened (``run.json`` records it)."""

    #: The input as the user gave it (path, folder, ``-``).
    path: str
    kind: InputKind
    #: Short name for output folders: file stem, folder name or ``stdin``.
    name: str
    #: Size of the frames the source yields (after any rotation was applied).
    width: int
    height: int
    #: Nominal frame rate (None when the container does not say).
    fps: float | None
    #: Number of frames (None when unknown, e.g. a pipe): exact, or an estimate when
    #: ``frame_count_estimated`` says so.
    frame_count: int | None
    duration_s: float | None
    codec: str | None
    pix_fmt: str | None
    #: Degrees (0, 90, 180, 270) the stored pictures were turned counter-clockwise to display
    #: them upright, from the stream's display matrix. Frames come out already turned.
    rotation: int = 0
    #: ``frame_count`` is no count the container lists but its duration times the nominal
    #: frame rate (Matroska, WebM, MPEG-TS). A gap in the timestamps or a variable frame rate
    #: makes that wrong, so the reader replaces it as it reads: with None once the frames'
    #: timestamps depart from it, with the exact count (and False here) once it read the
    #: input to its end.
    frame_count_estimated: bool = False

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def turned_note(self) -> str:
        """What a refusal of a box against the frame size adds when the stream's display
        matrix turned the pictures a quarter turn (the size is not the stored one, which a box
        drawn on a frame from another reader fits): `` (the input's rotation metadata turned it
        90 degrees, from 320x240)``; ``""`` for no quarter turn."""
        if self.rotation not in (90, 270):
            return ""
        return (f" (the input's rotation metadata turned it {self.rotation} degrees, from "
                f"{self.height}x{self.width})")


class Source(Closing, ABC):
    """An opened input: ``info``, one pass over its frames in order, ``close()``.

    Frames are decoded ``depth`` frames ahead in a background thread. A source can be iterated
    once. If the input breaks part way, iteration yields every good frame and then raises
    :class:`~vtrack.errors.PartialInputError` saying where it stopped.

    A frame's pixels are valid while it and the next frame are being processed: raw input
    reuses a small ring of buffers, so whoever keeps pixels longer must copy them.
    """

    #: Frames decoded ahead of the consumer.
    depth: ClassVar[int] = 4
    #: A live source (:func:`~vtrack.io.open_source` ``live``): the reader never waits for the
    #: consumer, who gets the frames it can keep up with; the others are passed over
    #: (:class:`~vtrack.io.threads.KeepingUp`).
    live: bool = False

    def __init__(self, info: InputInfo) -> None:
        self.info = info
        #: :attr:`warnings`, filled by the reader thread.
        self._warnings: list[str] = []
        self._prefetch: Prefetcher[Frame] | KeepingUp[Frame] | None = None
        self._closed = False
        #: After :meth:`skip_to`: the frame it stopped at and the frames after it.
        self._resumed: Iterator[Frame] | None = None
        #: The first frame tracked is the first at or after this index and (when not None)
        #: this time (:meth:`start_near`, :meth:`skip_to`); frames passed over before it are
        #: not counted as skipped (:meth:`_tracked`).
        self._from_index = 0
        self._from_s: float | None = None
        #: The last frame :meth:`skip_to` decoded and dropped, ``(index, time_s)``: where an
        #: input that ends before its time ends (None: it dropped none).
        self.passed_last: tuple[int, float] | None = None

    @property
    def warnings(self) -> list[str]:
        """One line per problem the reader went past (e.g. an unreadable image it skipped);
        complete once iteration has ended."""
        return self._warnings

    def not_taken(self, frame: Frame) -> None:
        """``frame``, handed on, was not taken after all (it ended a ``--frames`` duration):
        the counts and warnings of what the run read (:attr:`frames_skipped`,
        :attr:`warnings`) stop at the frame before it. Nothing to undo here."""

    def ends_after(self, index: int) -> bool:
        """Whether frame ``index`` is the input's last, known without reading on (an image
        folder's last numbered image, a regular raw file's last whole frame); False when only
        reading on could tell (a video, a pipe, a stream)."""
        return False

    def image_identity(self) -> str | None:
        """An image sequence's: a fingerprint of its images
        (:func:`~vtrack.io.identity.images_identity`), taken when asked (``run.json`` records
        it once, at the run's end; opening does not look at every image); what tells two
        sequences of one name, frame count and frame size apart. None for other inputs, or
        when an image cannot be read (gone)."""
        return None

    @property
    def frames_skipped(self) -> int:
        """Frames of the input that could not be decoded and were skipped (damage in the middle
        of a file, an unreadable image); later frames keep their indices. Counted from the
        run's first frame (:meth:`_run_begins`: after :meth:`start_near` or :meth:`skip_to`,
        the frames passed over before it are not). Final once iteration has ended."""
        return 0

    @property
    def frames_missing(self) -> int:
        """Of :attr:`frames_skipped`, the frames that have no picture in the input at all
        (images missing from a folder's numbering); the others could not be decoded."""
        return 0

    def absent(self, index: int) -> str:
        """Why frame ``index``, passed over by the frames yielded, has no picture: a phrase
        that follows ``frame N`` in a message (``could not be decoded (damaged)``)."""
        return "could not be decoded (damaged)"

    @abstractmethod
    def _frames(self) -> Iterator[Frame]:
        """Produce the frames (runs in the reader thread)."""

    @abstractmethod
    def _release(self) -> None:
        """Close files and containers; called once, after the reader thread has stopped."""

    def __iter__(self) -> Iterator[Frame]:
        if self._closed:
            raise RuntimeError(f"{self.info.path}: the source is closed")
        if self._resumed is not None:  # the pass skip_to began
            resumed, self._resumed = self._resumed, None
            return resumed
        if self._prefetch is not None:
            raise RuntimeError(f"{self.info.path}: a source can be iterated only once")
        name = f"vtrack-read:{self.info.name}"
        self._prefetch = (KeepingUp(self._frames(), name, 1.0 / (self.info.fps or 30.0))
                          if self.live
                          else Prefetcher(self._frames(), self.depth, name))
        return self._while_open(self._prefetch)

    def _while_open(self, frames: Prefetcher[Frame] | KeepingUp[Frame]) -> Iterator[Frame]:
        """``frames``, then RuntimeError if they ended because the source was closed before
        the input's end was reached (:meth:`close` from another thread, or between two
        ``next()``), a live source's too; a close after the reader reached the end, every
        frame handed over, ends them as the end does."""
        yield from frames
        if self._closed and not frames.reached_end:
            raise RuntimeError(f"{self.info.path}: the source was closed while it was read")

    def skip_to(self, seconds: float) -> int | None:
        """Decode and drop the frames before ``seconds`` (their ``time_s``, the input's own
        timestamps, so a variable frame rate is followed; :data:`TIME_SLACK_S` of rounding
        allowed): the index of the first frame at or after it, which iterating the source then
        hands over first; None when the input ends before. Called instead of a first
        ``iter()``; a broken input raises as iterating does."""
        if self._prefetch is None and self._resumed is None:
            self._from_index, self._from_s = 0, seconds
        frames = iter(self)
        for frame in frames:
            if frame.time_s >= seconds - TIME_SLACK_S:
                self._resumed = itertools.chain((frame,), frames)
                return frame.index
            self.passed_last = (frame.index, frame.time_s)
        return None

    def start_near(self, index: int) -> int:
        """Called instead of a first ``iter()``, to reach frame ``index`` without decoding all
        the frames before it: where the input can jump (a seekable video whose timestamps
        number its frames, :meth:`VideoSource.start_near`; an image folder), iterating then
        begins at a frame at or before ``index``, the frames keeping their numbers; elsewhere
        it begins at the first frame, as without this call. Returns the index iteration
        begins at. Either way the frames passed over before ``index`` are not counted as
        skipped (:attr:`frames_skipped`): they are not the run's."""
        if self._prefetch is None and self._resumed is None:
            self._from_index, self._from_s = max(0, index), None
        return 0

    def _run_begins(self, index: int) -> int:
        """The place the run's frames begin at, given ``index``, the first frame tracked: a
        start given as a frame number (:meth:`start_near`) is that frame, decoded or not (one
        lost at or after it is the run's, skipped as in a whole run); a start by time
        (:meth:`skip_to`) the first frame decoded at or after it, ``index``."""
        return self._from_index if self._from_s is None else index

    def _tracked(self, index: int, time_s: float) -> bool:
        """Whether frame ``index`` at ``time_s`` is at or after the first frame tracked
        (:meth:`start_near`'s index, :meth:`skip_to`'s time): the places passed over before
        the first such frame are not counted as skipped."""
        return index >= self._from_index and (self._from_s is None
                                              or time_s >= self._from_s - TIME_SLACK_S)

    @property
    def frames_passed(self) -> int:
        """Live sources: frames decoded but passed over because the consumer could not have
        kept up with them (their numbers are left out of the output). Always 0 otherwise."""
        return self._prefetch.passed if isinstance(self._prefetch, KeepingUp) else 0

    @property
    def received(self) -> float | None:
        """Live sources: when the frame last handed over was decoded (``perf_counter``), for
        its latency; None otherwise."""
        return self._prefetch.received if isinstance(self._prefetch, KeepingUp) else None

    @property
    def end_wait(self) -> tuple[float, float] | None:
        """When the input waited at its end for data that never came (``--follow``'s idle
        time; a network input's ``--timeout`` after its last packet: ``perf_counter`` start
        and end), which is no reading; None if it did not."""
        return None

    def stop_at_end(self) -> bool:
        """A followed file (``--follow``) read to its current end: stop waiting for more, so
        that the frames the decoder still holds (in the file already) come out and iteration
        ends; True. False for any other input, or one with more left to read (nothing
        changes). Safe to call from a signal handler."""
        return False

    def close(self) -> None:
        """Stop decoding and release the input. Safe to call twice and mid-stream, from
        another thread too: an iteration under way then ends with RuntimeError (the source
        was closed while it was read) unless the reader had reached the input's end and
        handed every frame over, when it ends as the end does (:meth:`_while_open`)."""
        if self._closed:
            return
        self._closed = True
        finished = self._prefetch.close() if self._prefetch is not None else True
        if finished:  # else the reader is stuck in a blocking read and still owns the file
            self._release()


def frame_at_time(seconds: float, fps: float | None) -> int:
    """The first frame at or after ``seconds`` at a constant ``fps`` frames a second
    (:data:`TIME_SLACK_S` of rounding; 0 without a frame rate): exact for a constant rate,
    an estimate for another (the frames' own timestamps tell, :func:`seek_time`)."""
    if fps is None or not math.isfinite(fps) or fps <= 0:
        return 0
    return max(0, math.ceil(seconds * fps - TIME_SLACK_S))


def start_toward(source: Source, index: int) -> int | None:
    """Make ``source`` (opened, not yet iterated) reach frame ``index`` without reading all
    the frames before it: None, reading nothing, when its frame count says it has no such
    frame (:func:`past_end`); else the index its iteration begins at, at or before ``index``
    (a key frame near it where the input can jump there, :meth:`Source.start_near`; else 0)."""
    if past_end(source.info, index):
        return None
    return source.start_near(index)


def seek_time(source: Source, seconds: float) -> tuple[int | None, int]:
    """Make ``source`` (opened, not yet iterated) begin at its first frame whose timestamp is
    at or after ``seconds`` (:meth:`Source.skip_to`, a variable frame rate followed), a
    video that can jump (:meth:`VideoSource.start_near`: a local file of constant frame rate
    that lists its frame count, MP4 or MOV) read from the key frame at or before the frame
    ``seconds`` x fps names (an image folder from that frame's image), other inputs from
    their first frame. Returns that frame's
    index (None when the input ends before) and the index reading began at."""
    read_from = source.start_near(frame_at_time(seconds, source.info.fps))
    return source.skip_to(seconds), read_from


def no_frame_after_text(input_spec: str, seconds: float, source: Source) -> str:
    """What is said when :func:`seek_time` found no frame of ``source`` at or after
    ``seconds``: where the input ends (the last frame it decoded, its index and time; else
    the frames its count states)."""
    if source.passed_last is not None:
        index, time_s = source.passed_last
        end = f"its last frame is frame {index}, at {time_s:.6g} s"
    elif source.info.frame_count is not None and not source.info.frame_count_estimated:
        end = f"it has {plural(source.info.frame_count, 'frame')}"
    else:
        end = "it ends before"
    return f"{input_spec}: has no frame at or after {seconds:g} s ({end})"


#: Frames a frame's place may be off the nominal rate's timeline (frame n at n / fps from the
#: first), plus this share of its number, before a frame count estimated from the duration at
#: that rate is given up (a gap in the timestamps, a variable frame rate).
ESTIMATE_SLACK_FRAMES = 2
ESTIMATE_SLACK_SHARE = 0.1


def past_end(info: InputInfo, index: int) -> bool:
    """Whether the input's frame count says it has no frame ``index``: the count its container
    lists (or an image folder's numbering, a raw file's size), or, estimated from its duration
    and frame rate, that count with the slack the video reader allows such an estimate. False
    when the count is unknown (a pipe, a URL)."""

    count = info.frame_count
    if count is None:
        return False
    if info.frame_count_estimated:
        return index >= count + ESTIMATE_SLACK_FRAMES + ESTIMATE_SLACK_SHARE * count
    return index >= count


def no_frame_text(index: int, count: int | None, estimated: bool = False) -> str:
    """``no frame N (frames 0..M)``: what is said of a frame past the input's end, with the
    input's frame ``count`` (``estimated``: from its duration and frame rate; no range when
    it is unknown)."""
    if count is None:
        return f"no frame {index}"
    about = " by its duration and frame rate, about" if estimated else ""
    return f"no frame {index} (frames{about} 0..{count - 1})"


def past_end_text(input_spec: str, index: int, info: InputInfo) -> str:
    """What is said of frame ``index`` when :func:`past_end` holds: the frames there are."""
    return (f"{input_spec}: has "
            f"{no_frame_text(index, info.frame_count, info.frame_count_estimated)}")
