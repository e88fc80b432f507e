"""``open_source``: one entry point for every kind of input."""

from __future__ import annotations

import os
import stat
from collections.abc import Callable
from functools import partial
from urllib.parse import urlsplit

from vtrack.errors import COMMAND_NAMES, ConfigError, InputError, OptionNames
from vtrack.io.files import check_input_path
from vtrack.io.images import ImageFolderSource, images_of
from vtrack.io.raw import RawFormat, RawSource, checked_fps
from vtrack.io.source import Source
from vtrack.io.specs import device_number, is_live, is_url, url_scheme
from vtrack.io.video import FFmpegInput, VideoSource


def check_input(spec: str) -> None:
    """Raise InputError when ``spec`` is a local path that does not exist or cannot be read
    (``-`` and URLs are checked when they are opened), or a ``file://`` URL
    (:func:`_refuse_file_url`). Cheap: callers check it first, so a mistyped name is reported
    as that, not as whatever else is missing."""
    _refuse_file_url(spec)
    if spec != "-" and not is_url(spec):
        check_input_path(spec)


def _refuse_file_url(spec: str) -> None:
    """InputError for a ``file://`` URL: FFmpeg reads it as the file it names, but as a URL
    it is none of what keeps a run off the file it reads (``--stream``, ``--out`` and
    ``--video-out`` written over it, ``--overwrite`` or not), nor read as a file is (its
    sidecar box, a late start's seek): the file's path is asked for, the URL's path when it
    names this host (no host, ``localhost``): all the text after the host, ``#`` and ``?``
    included (file names hold them; FFmpeg's file protocol reads them as such); a file: URL
    of another host cannot be read."""
    if url_scheme(spec) == "file":
        host, slash, tail = spec.partition("://")[2].partition("/")
        try:
            here = urlsplit("//" + host).hostname in (None, "localhost")
        except ValueError:  # (a host with an unclosed [: no host of this machine)
            here = False
        if not here:
            raise InputError(f"{spec}: a file: URL of another host ({host}) cannot be read; "
                             "give a local file's path")
        raise InputError(f"{spec}: a file: URL; give the file's path ({slash + tail or '/'})")


def open_source(spec: str, raw: RawFormat | None = None, *, fps: float | None = None,
                ffmpeg: FFmpegInput | None = None, live: bool | None = None,
                names: OptionNames = COMMAND_NAMES) -> Source:
    """Open an input and decode its first frame; raise InputError if that is impossible.

    - ``raw`` given: raw frames of that format from ``spec`` (``-`` = stdin, a FIFO or a file);
    - ``spec`` a folder: an image sequence (``folder/img/*`` or ``folder/*``) at ``fps``
      (default 30) frames per second;
    - ``/dev/videoN``: a V4L2 capture device, through OpenCV (the PyAV wheel has no V4L2);
    - ``-`` without ``raw``: a container on stdin (``vtrack run - < clip.mp4``, or piped);
    - anything else: a file, FIFO or URL FFmpeg can open (``ffmpeg`` says how); its frames
      carry their own timestamps, so ``fps`` is refused for it (ConfigError). A given ``fps``
      must be a frame rate (> 0). ``ffmpeg``'s ``format`` and ``options`` are refused
      (ConfigError) for the inputs FFmpeg does not open: raw frames, an image folder, a
      capture device.

    ``live`` (None: :func:`is_live`) makes the source hand over the frames its consumer keeps
    up with and pass over the others, counted (:attr:`Source.frames_passed`,
    :class:`~vtrack.io.threads.KeepingUp`). Messages name what the caller gave by ``names``
    (the command's ``--fps``, ``--raw``, ``--follow`` ...; the library's ``fps``, ``raw=``,
    ``ffmpeg.follow_s`` ...: :data:`~vtrack.errors.LIBRARY_NAMES`).
    """
    return source_opener(spec, raw, fps=fps, ffmpeg=ffmpeg, live=live, names=names)()


def source_opener(spec: str, raw: RawFormat | None = None, *, fps: float | None = None,
                  ffmpeg: FFmpegInput | None = None, live: bool | None = None,
                  names: OptionNames = COMMAND_NAMES) -> Callable[[], Source]:
    """What :func:`open_source` opens, checked without opening it: the arguments (ConfigError,
    as open_source gives it) and, for a local path, that it exists and can be read, and that
    a folder holds an image (InputError); nothing is opened (a FIFO, stdin, a URL, a device)
    or decoded. Returns the function that opens it and decodes its first frame (InputError
    when that is impossible)."""
    _refuse_file_url(spec)
    ffmpeg = ffmpeg or FFmpegInput()
    live = is_live(spec) if live is None else live
    if fps is not None:
        fps = checked_fps(fps, names.fps)  # a float from here (a Decimal, a NumPy number)
    unfollowable = _not_followed(spec, raw, names) if ffmpeg.follow_s is not None else None
    if unfollowable:
        raise ConfigError(f"{names.follow} reads a video file that is still being written; "
                          f"{unfollowable}")
    given = names.format if ffmpeg.format is not None else names.input_option \
        if ffmpeg.options else None
    elsewhere = _not_through_ffmpeg(spec, raw, names) if given else None
    if elsewhere:
        raise ConfigError(f"{given} is for inputs FFmpeg reads; {elsewhere}")
    if raw is not None:
        if live:
            raise ConfigError(f"{names.live}: raw frames are read as they come (a pipe holds "
                              "the sender back); give a container (e.g. -f mpegts) to skip "
                              "frames")
        return partial(RawSource, spec, raw, raw_name=names.raw)
    device = device_number(spec)
    if not (spec == "-" or is_url(spec)):
        check_input_path(spec)
        if os.path.isdir(spec):
            images_of(spec, first_only=True)
            return partial(ImageFolderSource, spec, fps=fps)
    if fps is not None:
        what = ("a container on stdin carries its own timestamps" if spec == "-" else
                f"{spec} is a video file, whose frames carry their own timestamps"
                if device is None and not is_url(spec) else
                f"{spec} carries its own timestamps")
        raise ConfigError(f"{names.fps}: {what}; {names.fps} applies to raw input "
                          f"({names.give_raw}) and image folders only")

    def opened() -> Source:
        if device is not None:
            from vtrack.io.capture import CaptureSource

            source: Source = CaptureSource(spec, device)
        else:
            source = VideoSource(spec, ffmpeg, live, names)
        source.live = live
        return source

    return opened


def _not_followed(spec: str, raw: RawFormat | None, names: OptionNames) -> str | None:
    """Why ``--follow`` (a video file still being written) cannot apply to ``spec``, if so
    (what the caller gave called by ``names``)."""
    if raw is not None:
        return ("raw frames are read to the end of what is there (pipe a growing raw file in "
                "with tail -c +1 -f FILE | vtrack run - --raw WxH)")
    if spec == "-":
        return "stdin is read until its writer closes it"
    if is_url(spec):
        return f"{spec} is a stream, read until it ends ({names.timeout})"
    if os.path.isdir(spec):
        return f"{spec} is an image folder, read as it is when it opens"
    try:
        mode = os.stat(spec).st_mode
    except OSError:  # (not there: said as the path is checked)
        return None
    if stat.S_ISFIFO(mode):  # (no size to follow, no place to read from: as stdin)
        return f"{spec} is a FIFO, read until its writer closes it"
    if stat.S_ISSOCK(mode):
        return f"{spec} is a socket, not a file being written"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):  # (a capture device too: through OpenCV)
        return f"{spec} is a device, not a file being written"
    if not stat.S_ISREG(mode):
        return f"{spec} is not a regular file"
    return None


def _not_through_ffmpeg(spec: str, raw: RawFormat | None, names: OptionNames) -> str | None:
    """Why FFmpeg's input options (``--format``, ``--input-option``) cannot apply to ``spec``,
    if so: it is not an input FFmpeg opens (raw input called by ``names``)."""
    if raw is not None:
        return f"raw input ({names.raw}) is read as bare frames without it"
    if device_number(spec) is not None:
        return f"{spec} is a capture device, read through OpenCV's V4L2 backend"
    if spec != "-" and not is_url(spec) and os.path.isdir(spec):
        return f"{spec} is an image folder, whose images are read one by one"
    return None
