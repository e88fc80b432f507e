"""Which ``--input-option`` keys FFmpeg had a use for when it opened an input.

FFmpeg's ``avformat_open_input`` takes the options it knows out of the dictionary it is given
and leaves the others there; the ``ffmpeg`` command refuses those (``Option framerat not
found``). PyAV 18 frees that dictionary without a word, so a mistyped key would be ignored.
FFmpeg uses a key when it is an option of one of the objects that opened the input: every
input's (``AVFormatContext``: probesize, fflags, ...), its demuxer's (``framerate`` for image2,
``rtsp_transport`` for rtsp), and the protocol's that read its bytes (``file`` for a path; for a
URL its scheme's and the transports under it, tcp, udp, tls). :func:`unused_options` asks
PyAV's own FFmpeg about each (``av_opt_find``, through ctypes).
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Iterable

import av.format

from vtrack.io.specs import url_scheme

#: av_opt_find's AV_OPT_SEARCH_FAKE_OBJ: the object is a pointer to an AVClass.
_SEARCH_FAKE_OBJ = 2
#: Protocols a network protocol may open below itself, handing them the options it left.
TRANSPORTS = ("tcp", "udp", "tls")
#: Options of every URL FFmpeg opens through a protocol (its URLContext's class, which
#: libavformat does not export): taken for any input read through a protocol.
URL_OPTIONS = ("rw_timeout", "protocol_whitelist", "protocol_blacklist")
#: libavformat major versions whose AVInputFormat starts with :class:`_InputFormat`'s fields
#: (FFmpeg 4 to 8); with another, the demuxer's own options are not looked up.
KNOWN_LAYOUTS = range(58, 63)


class _InputFormat(ctypes.Structure):
    """The leading public fields of FFmpeg's AVInputFormat (the same in FFmpeg 4 to 8)."""

    _fields_ = [("name", ctypes.c_char_p), ("long_name", ctypes.c_char_p),
                ("flags", ctypes.c_int), ("extensions", ctypes.c_char_p),
                ("codec_tag", ctypes.c_void_p), ("priv_class", ctypes.c_void_p)]


@functools.cache
def _libraries() -> ctypes.CDLL | None:
    """PyAV's own FFmpeg, with the functions used here typed; None where it cannot be asked
    (nothing is refused then). The symbols are looked up through PyAV's extension module, so
    the loader finds the libavformat and libavutil PyAV links with, not another copy in the
    process (OpenCV's wheel carries its own FFmpeg). On Windows a module exports only its own
    symbols: None."""
    try:
        ffmpeg = ctypes.CDLL(av.format.__file__)
        ffmpeg.avformat_version.restype = ctypes.c_uint
        ffmpeg.avformat_get_class.restype = ctypes.c_void_p
        ffmpeg.avio_protocol_get_class.restype = ctypes.c_void_p
        ffmpeg.avio_protocol_get_class.argtypes = [ctypes.c_char_p]
        ffmpeg.av_find_input_format.restype = ctypes.c_void_p
        ffmpeg.av_find_input_format.argtypes = [ctypes.c_char_p]
        ffmpeg.av_opt_find.restype = ctypes.c_void_p
        ffmpeg.av_opt_find.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p,
                                       ctypes.c_int, ctypes.c_int]
    except (OSError, AttributeError):  # not loadable, or a symbol missing
        return None
    return ffmpeg


def _classes(ffmpeg: ctypes.CDLL, demuxer: str, protocols: Iterable[str]) -> list[int]:
    """The AVClasses whose options FFmpeg took when it opened an input with ``demuxer`` read
    through ``protocols``."""
    classes = [ffmpeg.avformat_get_class()]
    found = ffmpeg.av_find_input_format(demuxer.encode())
    if found and ffmpeg.avformat_version() >> 16 in KNOWN_LAYOUTS:
        classes.append(_InputFormat.from_address(found).priv_class)
    classes += [ffmpeg.avio_protocol_get_class(name.encode()) for name in protocols]
    return [c for c in classes if c]


def input_protocols(path: str, python_io: bool) -> tuple[str, ...]:
    """The protocols FFmpeg reads ``path`` through: none when PyAV hands it a Python file
    (``python_io``: stdin, a followed file), ``file`` for a path, a URL's scheme and the
    :data:`TRANSPORTS` a network protocol may open below it."""
    if python_io:
        return ()
    scheme = url_scheme(path)
    return ("file",) if scheme is None else (scheme, *TRANSPORTS)


def unused_options(keys: Iterable[str], demuxer: str, protocols: Iterable[str]) -> list[str]:
    """The ``keys`` FFmpeg left unused when it opened an input with ``demuxer`` (its name, as
    ``container.format.name``) read through ``protocols``: those no option of every input,
    of the demuxer or of a protocol (nor, through a protocol, of every URL) is named. Empty
    when there is no key, or PyAV's FFmpeg cannot be asked (nothing is refused then)."""
    keys, protocols = list(keys), list(protocols)
    ffmpeg = _libraries() if keys else None
    if ffmpeg is None:
        return []
    classes = _classes(ffmpeg, demuxer, protocols)

    def known(key: str) -> bool:
        if protocols and key in URL_OPTIONS:
            return True
        for cls in classes:
            fake_object = ctypes.c_void_p(cls)
            if ffmpeg.av_opt_find(ctypes.byref(fake_object), key.encode(), None, 0,
                                  _SEARCH_FAKE_OBJ):
                return True
        return False

    return [key for key in keys if not known(key)]
