"""``vtrack.track`` and ``vtrack.open_source``: the library in one call, taking plain Python
values.

Kept out of ``vtrack/__init__.py`` so that ``import vtrack`` (and every ``vtrack`` command) pays
only for what it uses: this module pulls in the config, the stages and the readers.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from vtrack.config import Config
from vtrack.errors import LIBRARY_NAMES, ConfigError, InputWarning
from vtrack.frame import Frame
from vtrack.geometry import Box, as_box
from vtrack.io import inputs
from vtrack.io.files import path_text
from vtrack.io.images import DEFAULT_FPS
from vtrack.io.raw import RawFormat
from vtrack.io.source import Source
from vtrack.io.video import FFmpegInput, checked_ffmpeg
from vtrack.params import check_flag
from vtrack.pipeline import FrameResult, first_box_refused
from vtrack.request import RunRequest
from vtrack.tracker import Tracker, shape_text

FrameInput = str | os.PathLike[str] | RunRequest | Iterable[Frame] | Iterable[np.ndarray]
BoxInput = Box | Sequence[float]


def track(frames: FrameInput,
          config: str | os.PathLike[str] | Config | None = None,
          init_box: BoxInput | None = None, seed: int | None = None, fps: float | None = None,
          keep_frames: bool = False, first_track_id: int | None = None
          ) -> Iterator[FrameResult]:
    """Yield one :class:`FrameResult` per frame of ``frames``, from a :class:`vtrack.Tracker`.

    ``frames`` is an input (``str`` or ``pathlib.Path``: a video file, an image folder, a URL
    or a capture device, opened with :func:`open_source`; a live one hands over the
    frames the tracker keeps up with), a :class:`RunRequest` (its input, raw format,
    frame rate, config, initial box, seed, first track id and frame limit; nothing is
    written), or any iterable of :class:`Frame`, of NumPy BGR (``HxWx3``) / grey (``HxW``,
    ``HxWx1``) uint8 images (timed at ``fps``, default 30, as an image folder is; 4 channels
    are a TypeError saying what to give) or of ``av.VideoFrame``; ``fps`` given for a
    video file, URL or device (whose frames carry their own timestamps) is a ConfigError, as
    ``vtrack run --fps`` is; ``config`` a shipped config name, a TOML path or a
    :class:`Config` (None: ``DEFAULT_CONFIG``); ``seed`` seeds the stochastic stages (None:
    0); ``init_box`` the target's first box as a :class:`Box` or ``(x, y, w, h)`` (not
    needed by the detecting trackers s3/s4); ``first_track_id`` the id a multi-target config
    gives its first track (None: 1; as :class:`vtrack.Tracker`'s). A RunRequest carries its own
    ``config``, ``init_box``, ``seed``, ``fps`` and ``first_track_id``: giving any of them
    beside it is a ConfigError (the default config's name too: which of two configs was meant
    cannot be told). Results hold their decoded frame only with ``keep_frames=True``. One
    image or frame on its own (not in a sequence) is a TypeError.

    Checked when ``track`` is called, before it returns: the arguments, the config and the
    first box (a request's too, from its sidecar or ground truth, unless it starts later:
    ``start``, ``start_s``, or a local file or folder is checked for a single-target
    ``gt_first``'s frame) and, for a path or a request's input, what needs no opening:
    ``fps`` and ``raw`` for it, and a local path that exists and can be read (a folder: that
    it holds an image). Nothing is opened then: the input is opened and its first frame
    decoded at the first ``next()`` (a file that is no video, a URL that does not answer, a
    FIFO waiting for its writer show there), the others as the results are taken. A generator
    never started holds nothing open; a started one closes its input when the results end,
    however they end (``break`` then ``close()``, or its being discarded).

    Damage read past in the input is an :class:`~vtrack.errors.InputWarning` given as the
    results end; made an error (``warnings.simplefilter("error", InputWarning)``) it is raised
    there, or, when they end by an error (PartialInputError), added to that error's notes.
    After a ``break`` they end when closed: call ``close()`` (or iterate them in
    ``contextlib.closing(track(...))``) to have it raised; a generator the garbage collector
    closes can only print it ("Exception ignored in").
    """
    _refuse_one_frame(frames)
    if isinstance(frames, RunRequest):
        given = [name for name, value in (("config", config), ("init_box", init_box),
                                          ("seed", seed), ("fps", fps),
                                          ("first_track_id", first_track_id))
                 if value is not None]
        if given:  # it would be ignored
            raise ConfigError(f"{', '.join(given)}: the RunRequest carries its own; set "
                              f"{'it' if len(given) == 1 else 'them'} in the request "
                              "(dataclasses.replace(request, ...))")
        request = frames
        tracker = Tracker(request.config, seed=request.seed, keep_frames=keep_frames,
                          first_track_id=request.first_track_id)
        opener = _source_opener(request.input, request.raw, fps=request.fps,
                                ffmpeg=request.ffmpeg, live=request.live)
        from vtrack.run import requested_frames  # the run machinery only for a request

        # (its box now, unless it starts later or a local input is checked for gt_first's
        # frame: then once the input opens)
        requested = requested_frames(request)

        def results(source: Source) -> Iterator[FrameResult]:
            box, taken = requested(source)
            return _run(tracker, taken, box)

        return _closing(opener, results)
    box = None if init_box is None else as_box(init_box)
    tracker = Tracker(config, seed=0 if seed is None else seed,
                      fps=DEFAULT_FPS if fps is None else fps,
                      keep_frames=keep_frames,
                      first_track_id=1 if first_track_id is None else first_track_id)
    if box is None and tracker.needs_init_box:  # said before the input is opened
        raise ConfigError(f"init_box: {tracker.config.name} starts from the target's first "
                          "box: give init_box=(x, y, w, h)")
    if box is not None and tracker.multi_target:  # (Tracker.init's words name init())
        raise first_box_refused(f"init_box: {tracker.config.name}", "leave init_box out")
    if isinstance(frames, str | bytes | os.PathLike):  # bytes: a path, not 1-byte frames
        # an image folder is timed at fps; a video keeps its own timestamps (fps refused)
        opener = _source_opener(path_text(frames, "frames"), fps=fps)
        return _closing(opener, lambda source: _run(tracker, source, box))
    return _run(tracker, frames, box)


def open_source(spec: str | os.PathLike[str], raw: RawFormat | str | None = None, *,
                pix_fmt: str | None = None, fps: float | None = None,
                ffmpeg: FFmpegInput | None = None, live: bool | None = None) -> Source:
    """:func:`vtrack.io.open_source` taking what a user writes: ``spec`` a ``str`` or
    ``pathlib.Path``; ``raw`` a :class:`RawFormat` or, as ``vtrack run --raw`` takes it,
    ``"WIDTHxHEIGHT"`` of ``pix_fmt`` frames (default bgr24) at ``fps`` (default 30);
    ``ffmpeg`` and ``live`` as there (``live`` True, False or 1, 0, as RunRequest's; None:
    live for stream URLs and devices). ConfigError, with ``vtrack run``'s message,
    for a raw format vtrack cannot read, naming this function's arguments: ``raw``,
    ``pix_fmt`` and ``fps`` (a RawFormat's fields ``raw.pix_fmt``, ``raw.fps``), for a
    ``live`` of another kind (``"no"`` is true to Python, not the answer given), or an
    ``ffmpeg`` wait out of its range (:meth:`~vtrack.io.video.FFmpegInput.checked`; TypeError
    for its ``format`` or ``options`` of another kind)."""
    return _source_opener(spec, raw, pix_fmt=pix_fmt, fps=fps, ffmpeg=ffmpeg, live=live)()


def _source_opener(spec: str | os.PathLike[str], raw: RawFormat | str | None = None, *,
                   pix_fmt: str | None = None, fps: float | None = None,
                   ffmpeg: FFmpegInput | None = None,
                   live: bool | None = None) -> Callable[[], Source]:
    """:func:`open_source`'s arguments checked as it checks them, with the cheap checks of
    :func:`vtrack.io.inputs.source_opener` (a local path exists and can be read, a folder has
    an image); returns the function that opens the input."""
    if isinstance(raw, str):
        raw = RawFormat.parse(raw, pix_fmt or "bgr24", DEFAULT_FPS if fps is None else fps,
                              ("raw", "pix_fmt", "fps"))
    elif raw is not None and not isinstance(raw, RawFormat):
        raise ConfigError(f"raw: expected a vtrack.io.RawFormat or 'WIDTHxHEIGHT', got "
                          f"{type(raw).__name__}")
    elif pix_fmt is not None:
        raise ConfigError("pix_fmt is the pixel format of raw input: give raw='WIDTHxHEIGHT' "
                          "with it")
    elif raw is not None:  # (one made in Python is not checked as it is made)
        raw = raw.checked()
    if not isinstance(spec, str | bytes | os.PathLike):
        raise TypeError(f"spec: expected a path (str or pathlib.Path), a URL or a device, got "
                        f"{type(spec).__name__}")
    if ffmpeg is not None:  # (one made in Python: its waits as RunRequest checks them)
        ffmpeg = checked_ffmpeg(ffmpeg)
    if live is not None:  # (a RunRequest's is checked as it is made)
        live = check_flag(live, "live")
    return inputs.source_opener(path_text(spec, "spec"), raw, fps=fps, names=LIBRARY_NAMES,
                                ffmpeg=ffmpeg, live=live)


#: The last axis of an ``HxWxC`` NumPy image: BGR, BGRA (a PNG with alpha) or one channel.
#: An array ending in 1 or 4 is one such image, not a sequence of grey frames 1 or 4 pixels
#: wide.
IMAGE_CHANNELS = (1, 3, 4)


def _refuse_one_frame(frames: object) -> None:
    """TypeError for one picture given where a sequence of frames is expected: a NumPy image
    would be iterated row by row (a 240x320x3 image as 240 grey 3x320 frames, a 240x320x4 BGRA
    one as 240 grey 4x320 frames); for a NumPy array of no or one dimension (numbers, not
    pictures); and for what is neither a path nor iterable (None, a number), named as
    ``frames``."""
    if isinstance(frames, np.ndarray) and (frames.ndim == 2 or frames.ndim == 3
                                           and frames.shape[2] in IMAGE_CHANNELS):
        raise TypeError(f"frames: expected an iterable of frames, got one image of "
                        f"{shape_text(frames)} (give [image] for a single frame)")
    if isinstance(frames, np.ndarray) and frames.ndim < 2:
        raise TypeError(f"frames: expected an iterable of frames, got a NumPy array of shape "
                        f"{frames.shape}, no picture")
    if isinstance(frames, Frame) or type(frames).__module__.split(".")[0] == "av":
        raise TypeError(f"frames: expected an iterable of frames, got one "
                        f"{type(frames).__name__} (give [frame] for a single frame)")
    if not isinstance(frames, str | bytes | os.PathLike | RunRequest | Iterable):
        raise TypeError(f"frames: expected a path (str or pathlib.Path), a RunRequest or an "
                        f"iterable of frames, got {type(frames).__name__}")


def _closing(opener: Callable[[], Source],
             results: Callable[[Source], Iterator[FrameResult]]) -> Iterator[FrameResult]:
    """``results`` of the input ``opener`` opens at the first ``next()`` (a generator not
    started holds nothing open), then the input closed and its warnings given
    (:func:`_warn_of_damage`), however they end: the frames' end, the input broken part way
    (PartialInputError) or the caller stopping (``break``, ``close()``), as ``vtrack run``
    warns of them however it ends. A warning made an error does not hide an error already on
    its way out: it is a note of that error's (``close()`` is no error: the warning is raised
    from it)."""
    source = opener()
    failed = None
    try:
        with source:  # a video's damage is counted up as it closes
            yield from results(source)
    except GeneratorExit:
        raise
    except BaseException as error:
        failed = error
        raise
    finally:
        _warn_of_damage(source, failed)


def _warn_of_damage(source: Source, failed: BaseException | None = None) -> None:
    """Each of ``source``'s warnings (what ``vtrack run`` prints as ``vtrack: warning:``) as an
    :class:`~vtrack.errors.InputWarning`, shown at the caller's line that took the results.
    One made an error (``warnings.simplefilter("error", InputWarning)``) is raised, unless the
    results ended by the error ``failed``: it is added to that error's notes, which goes on
    (``except PartialInputError`` still catches a file cut short)."""
    for line in source.warnings:
        try:
            # 1: here, 2: _closing (the generator the caller iterates), 3: the caller
            warnings.warn(line, InputWarning, stacklevel=3)
        except InputWarning as made_error:
            if failed is None:
                raise
            failed.add_note(f"{made_error.__class__.__name__}: {made_error}")


def _run(tracker: Tracker, frames: Iterable[Any], box: Box | None) -> Iterator[FrameResult]:
    """``tracker.init`` on the first frame, ``update`` on the rest."""
    for n, frame in enumerate(frames):
        yield tracker.init(frame, box) if n == 0 else tracker.update(frame)
