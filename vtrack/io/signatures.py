"""What a file's first bytes say it is, where FFmpeg's own message says too little: a container
or an image given as raw frames (``--raw``), an MP4 cut off before its index was written.

Only signatures of four bytes or more are taken, so raw pixels are not mistaken for one
(MPEG-TS's one sync byte and JPEG's three are not).
"""

from __future__ import annotations

import os

#: Boxes an MP4/QuickTime file is read through to find its index; beyond them it is not
#: looked for (the top level of a real file holds a handful).
_MAX_BOXES = 10_000
_NO_INDEX = "no index (moov box)"


def container_kind(head: bytes) -> str | None:
    """What ``head`` (a file's or stream's first 12 bytes or more) begins, ``"an MP4/QuickTime
    file"`` ... ``"a PNG image"``, when it is a container's or an image's signature; None
    otherwise (raw pixels)."""
    if head[4:8] == b"ftyp" and 8 <= int.from_bytes(head[:4], "big") <= 4096:
        return "an MP4/QuickTime file"
    if head[:4] == b"\x1a\x45\xdf\xa3":
        return "a Matroska/WebM file"
    if head[:4] == b"RIFF" and head[8:12] == b"AVI ":
        return "an AVI file"
    if head[:4] == b"FLV\x01":
        return "an FLV file"
    if head[:8] == b"\x89PNG\r\n\x1a\n":
        return "a PNG image"
    if head[:6] in (b"GIF87a", b"GIF89a"):
        return "a GIF image"
    return None


def mp4_index_problem(path: str | os.PathLike[str]) -> str | None:
    """What is wrong with the index (``moov`` box) of ``path``, an MP4/QuickTime file (its
    first box ``ftyp``): ``"no index (moov box)"`` when none of its top-level boxes is one,
    ``"its index (moov box) cut short"`` when the file ends inside it: a recording cut off
    before it was finished (a plain MP4 writes its index last). None when its index is whole,
    when it is no such file or cannot be read."""
    try:
        with open(path, "rb") as handle:
            end = os.fstat(handle.fileno()).st_size
            offset = 0
            for _ in range(_MAX_BOXES):
                handle.seek(offset)
                header = handle.read(16)
                if len(header) < 8:  # the file ends after whole boxes, none an index
                    return _NO_INDEX if offset > 0 else None
                size, kind = int.from_bytes(header[:4], "big"), header[4:8]
                if offset == 0 and kind != b"ftyp":
                    return None
                if size == 1 and len(header) == 16:  # a 64-bit size follows the type
                    size = int.from_bytes(header[8:], "big")
                elif size == 0:  # the box runs to the end of the file
                    size = end - offset
                if size < 8:
                    return None  # not boxes as MP4 lays them out
                if kind == b"moov":
                    return "its index (moov box) cut short" if offset + size > end else None
                offset += size
                if offset >= end:
                    return _NO_INDEX
    except OSError:
        return None
    return None

