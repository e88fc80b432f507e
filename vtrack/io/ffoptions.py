"""Which ``--input-option`` keys FFmpeg had a use for when it opened an input.

FFmpeg's ``avformat_open_input`` takes the options it knows out of the dictionary it is given
and leaves the others there; the ``ffmpeg`` command refuses those (``Option framerat not
found``). PyAV 18 frees that dictionary without a word, so a mistyped key would be ignored.
FFmpeg uses a key when it is an option of one of the objects that opened the input: every
input's (``AVFormatContext``: probesize, fflags, ...), its demuxer's (``framerate`` for image2,
``rtsp_transport`` for rtsp), and the protocol's that read its bytes (``file`` for a path; for a
URL its scheme's and the transports under it, tcp, udp, tls). :func:`unused_options` asks the
FFmpeg libraries PyAV loaded about each (``av_opt_find``, through ctypes).
"""

from __future__ import annotations

import ctypes
import functools
import glob
import os
from collections.abc import Iterable

import av

#: av_opt_find's AV_OPT_SEARCH_FAKE_OBJ: the object is a pointer to an AVClass.
_SEARCH_FAKE_OBJ = 2
#: Protocols a network protocol may open below itself, handing them the options it left.
TRANSPORTS = ("tcp", "udp", "tls")


class _InputFormat(ctypes.Structure):
    """The leading public fields of FFmpeg's AVInputFormat (the same since FFmpeg 4)."""

    _fields_ = [("name", ctypes.c_char_p), ("long_name", ctypes.c_char_p),
                ("flags", ctypes.c_int), ("extensions", ctypes.c_char_p),
                ("codec_tag", ctypes.c_void_p), ("priv_class", ctypes.c_void_p)]


def _library_path(stem: str) -> str | None:
    """The file of FFmpeg's library ``stem`` (``libavformat``) that PyAV loaded: from the
    process's memory map (Linux), else next to PyAV's package (its wheel's copies)."""
    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as maps:
            for line in maps:
                path = line.rstrip("\n").split(" ")[-1]
                if os.path.basename(path).startswith((stem + ".", stem + "-")):
                    return path
    except OSError:
        pass
    package = os.path.dirname(av.__file__)
    for folder in (package + ".libs", os.path.join(package, ".dylibs")):
        found = sorted(glob.glob(os.path.join(folder, stem + "*")))
        if found:
            return found[0]
    return None


@functools.cache
def _libraries() -> tuple[ctypes.CDLL, ctypes.CDLL] | None:
    """PyAV's libavformat and libavutil with the functions used here typed (None: not found,
    so nothing can be asked)."""
    paths = _library_path("libavformat"), _library_path("libavutil")
    if paths[0] is None or paths[1] is None:
        return None
    try:
        avformat, avutil = ctypes.CDLL(paths[0]), ctypes.CDLL(paths[1])
    except OSError:
        return None
    avformat.avformat_get_class.restype = ctypes.c_void_p
    avformat.avio_protocol_get_class.restype = ctypes.c_void_p
    avformat.avio_protocol_get_class.argtypes = [ctypes.c_char_p]
    avformat.av_find_input_format.restype = ctypes.c_void_p
    avformat.av_find_input_format.argtypes = [ctypes.c_char_p]
    avutil.av_opt_find.restype = ctypes.c_void_p
    avutil.av_opt_find.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p,
                                   ctypes.c_int, ctypes.c_int]
    return avformat, avutil


def _classes(avformat: ctypes.CDLL, demuxer: str, protocols: Iterable[str]) -> list[int]:
    """The AVClasses whose options FFmpeg took when it opened an input with ``demuxer`` read
    through ``protocols``."""
    classes = [avformat.avformat_get_class()]
    found = avformat.av_find_input_format(demuxer.encode())
    if found:
        classes.append(_InputFormat.from_address(found).priv_class)
    classes += [avformat.avio_protocol_get_class(name.encode()) for name in protocols]
    return [c for c in classes if c]


def input_protocols(path: str, python_io: bool) -> tuple[str, ...]:
    """The protocols FFmpeg reads ``path`` through: none when PyAV hands it a Python file
    (``python_io``: stdin, a followed file), ``file`` for a path, a URL's scheme and the
    :data:`TRANSPORTS` a network protocol may open below it."""
    if python_io:
        return ()
    if "://" not in path:
        return ("file",)
    return (path.split("://", 1)[0].lower(), *TRANSPORTS)


def unused_options(keys: Iterable[str], demuxer: str, protocols: Iterable[str]) -> list[str]:
    """The ``keys`` FFmpeg left unused when it opened an input with ``demuxer`` (its name, as
    ``container.format.name``) read through ``protocols``: those no option of every input,
    of the demuxer or of a protocol is named. Empty when PyAV's FFmpeg libraries cannot be
    found to ask (nothing is refused then)."""
    libraries = _libraries()
    if libraries is None:
        return []
    avformat, avutil = libraries
    classes = _classes(avformat, demuxer, protocols)

    def known(key: str) -> bool:
        for cls in classes:
            fake_object = ctypes.c_void_p(cls)
            if avutil.av_opt_find(ctypes.byref(fake_object), key.encode(), None, 0,
                                  _SEARCH_FAKE_OBJ):
                return True
        return False

    return [key for key in keys if not known(key)]
