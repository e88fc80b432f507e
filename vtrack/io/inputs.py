"""``open_source``: one entry point for every kind of input."""

from __future__ import annotations

import os

from vtrack.errors import ConfigError
from vtrack.io.files import check_input_path
from vtrack.io.images import ImageFolderSource
from vtrack.io.raw import RawFormat, RawSource, checked_fps
from vtrack.io.source import Source
from vtrack.io.video import VideoSource


def is_url(spec: str) -> bool:
    """True when ``spec`` names a network input (``scheme://...``) rather than a path."""
    return "://" in spec and spec.split("://", 1)[0].lower().isalpha()


def check_input(spec: str) -> None:
    """Raise InputError when ``spec`` is a local path that does not exist or cannot be read
    (``-`` and URLs are checked when they are opened). Cheap: callers check it first, so a
    mistyped name is reported as that, not as whatever else is missing."""
    if spec != "-" and not is_url(spec):
        check_input_path(spec)


def open_source(spec: str, raw: RawFormat | None = None, *, fps: float | None = None) -> Source:
    """Open an input and decode its first frame; raise InputError if that is impossible.

    - ``raw`` given: raw frames of that format from ``spec`` (``-`` = stdin, a FIFO or a file);
    - ``spec`` a folder: an image sequence (``folder/img/*`` or ``folder/*``) at ``fps``
      (default 30) frames per second;
    - ``-`` without ``raw``: a container on stdin (``vtrack run - < clip.mp4``, or piped);
    - anything else: a video file FFmpeg can open; its frames carry their own timestamps, so
      ``fps`` is refused for it (ConfigError). A given ``fps`` must be a frame rate (> 0).
    """
    if fps is not None:
        checked_fps(fps)
    if raw is not None:
        return RawSource(spec, raw)
    if spec == "-":  # a container on stdin (a pipe or a redirected file), probed as ffmpeg does
        if fps is not None:
            raise ConfigError("--fps: a container on stdin carries its own timestamps; --fps "
                              "applies to raw input (--raw WxH) and image folders only")
        return VideoSource(spec)
    if is_url(spec):
        if fps is not None:
            raise ConfigError(f"--fps: {spec} carries its own timestamps; --fps applies to raw "
                              "input and image folders only")
        return VideoSource(spec)
    check_input_path(spec)
    if os.path.isdir(spec):
        return ImageFolderSource(spec, fps=fps)
    if fps is not None:
        raise ConfigError(
            f"--fps: {spec} is a video file, whose frames carry their own timestamps; --fps "
            "applies to raw input and image folders only"
        )
    return VideoSource(spec)
