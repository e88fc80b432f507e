"""What an input argument names: a URL, a capture device, a path; its short name and whether
it is live. Plain string rules, no I/O beyond resolving a device link."""

from __future__ import annotations

import os
import re
from pathlib import Path

from vtrack.io.files import folder_name

#: URL schemes of live streams: frames come at the sender's pace and are not waited for
#: (``--live``); ``http(s)://`` and files are read as fast as they are tracked.
LIVE_SCHEMES = frozenset({"rtsp", "rtsps", "rtp", "udp", "tcp", "rtmp", "srt"})
_DEVICE = re.compile(r"/dev/video(\d+)$")
#: File suffixes taken as videos (a batch's inputs; a folder holding one is no flat image
#: sequence): what phones, cameras (MXF, DV, HDV .m2t, camcorders' .mod/.tod, GoPro's .lrv),
#: DVDs, IP cameras (ASF, Dahua's .dav) and tools write.
VIDEO_SUFFIXES = frozenset({
    ".mp4", ".m4v", ".mov", ".qt", ".mkv", ".webm", ".avi", ".divx", ".ts", ".mts", ".m2ts",
    ".m2t", ".mpg", ".mpeg", ".m2v", ".vob", ".mod", ".tod", ".mxf", ".dv", ".flv", ".f4v",
    ".wmv", ".asf", ".ogv", ".3gp", ".3g2", ".lrv", ".dav", ".nut", ".ivf", ".y4m", ".h264",
    ".264", ".h265", ".hevc", ".mjpeg", ".mjpg",
})
#: The animations FFmpeg decodes as frames, as ``vtrack run`` tracks them (GIF, APNG; not an
#: animated WebP, which it refuses): a batch's inputs in a folder that is no sequence, but
#: not videos that make a folder no flat image sequence (a sequence's ``thumb.gif`` beside its
#: frames leaves it a sequence).
ANIMATION_SUFFIXES = frozenset({".gif", ".apng"})
#: File suffixes a batch takes as inputs in a folder that is no sequence folder: videos and
#: animations.
BATCH_SUFFIXES = VIDEO_SUFFIXES | ANIMATION_SUFFIXES


def url_scheme(spec: str) -> str | None:
    """The scheme of ``spec`` when it is a URL (``scheme://...``, the scheme letters only),
    lowercased: a scheme is read in any case (RFC 3986), ``UDP://`` as ``udp://``,
    ``FILE://`` as ``file://``; None for a path. The one place vtrack reads a scheme."""
    scheme, sep, _ = spec.partition("://")
    return scheme.lower() if sep and scheme.isalpha() else None


def ffmpeg_url(spec: str) -> str:
    """``spec`` as FFmpeg is given it: a URL with its scheme lowercased (FFmpeg's protocol
    names are case-sensitive: ``UDP://`` is 'Protocol not found' there), anything else as
    it is."""
    scheme = url_scheme(spec)
    return spec if scheme is None else f"{scheme}://{spec.partition('://')[2]}"


def is_url(spec: str) -> bool:
    """True when ``spec`` names a network input (``scheme://...``) rather than a path."""
    return url_scheme(spec) is not None


def device_number(spec: str) -> int | None:
    """N when ``spec`` is a V4L2 capture device ``/dev/videoN`` (or a link to one, such as
    ``/dev/v4l/by-id/...``); None for anything else."""
    if not spec.startswith("/dev/"):
        return None
    found = _DEVICE.match(os.path.realpath(spec))
    return int(found.group(1)) if found else None


def is_live(spec: str) -> bool:
    """Whether ``spec`` is a live source by default: a stream URL (rtsp, rtp, udp, tcp, ...)
    or a capture device. Its frames come at their own pace (see ``--live``)."""
    if is_url(spec):
        return url_scheme(spec) in LIVE_SCHEMES
    return device_number(spec) is not None


def input_name(spec: str) -> str:
    """A short name for ``spec`` (output folders, progress): a file's stem, a folder's name
    (a sequence's images, ``SEQ/img`` or ``SEQ/img1``: ``SEQ``), ``stdin`` for ``-``,
    ``udp-127.0.0.1-5000`` for a URL, ``video0`` for a device."""
    if spec == "-":
        return "stdin"
    scheme = url_scheme(spec)
    if scheme is not None:  # (UDP://... names the folder as udp://... does)
        rest = spec.split("://", 1)[1].split("?", 1)[0].strip("/")
        return folder_name(f"{scheme}-{rest}".replace(":", "-").replace("/", "-"), "stream")
    path = Path(spec.rstrip("/") or "/")
    if path.is_dir():  # SEQ/img, SEQ/img1: the sequence's name, as the images' reader names
        # the input (run.json, the report) and a batch its results folder
        from vtrack.io.sidecar import sequence_of

        path = sequence_of(path.resolve()) or path
    return (path.stem if path.suffix else path.name) or "input"
