"""Reading a small file whole, with a ceiling: ``--gt /dev/zero`` or a 40 GB file given as
ground truth must be one line, not a memory error.

Every text file vtrack reads whole (ground truth, sidecar boxes, configs, ``run.json``) goes
through :func:`read_bounded` with its own ceiling; the ceilings are far above any real file of
that kind.
"""

from __future__ import annotations

import codecs
import os
import stat
from pathlib import Path

from vtrack.errors import InputError
from vtrack.io.files import os_reason

#: Ground truth: MOT20's largest ``gt.txt`` is ~40 MB; OTB/LaSOT files are under 1 MB.
GROUND_TRUTH_BYTES = 256 << 20
#: A sidecar ``NAME.init.txt`` holds one line.
SIDECAR_BYTES = 64 << 10
#: A config TOML (the shipped ones are ~2 KB).
CONFIG_BYTES = 1 << 20
#: A ``run.json`` record (a few KB; its config and warnings bound it).
RECORD_BYTES = 64 << 20


#: Bytes read at a time (one read of ``limit + 1`` would allocate that much at once).
_PIECE = 1 << 20


def _mb(limit: int) -> str:
    return f"{limit / (1 << 20):g} MB" if limit >= 1 << 20 else f"{limit >> 10} KB"


#: What :func:`special_kind` calls each kind of file that is neither a file nor a folder.
_SPECIAL_KINDS = (
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def special_kind(path: str | os.PathLike[str]) -> str | None:
    """What ``path`` is when it exists but is neither a regular file nor a folder: ``"a
    FIFO"`` (a named pipe, a shell's ``<(...)``), ``"a character device"`` (``/dev/null``),
    ``"a block device"`` or ``"a socket"``; None otherwise (also when it cannot be looked at)."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    return next((kind for test, kind in _SPECIAL_KINDS if test(mode)), None)


def not_a_file(path: str | os.PathLike[str], kind: str, what: str) -> str:
    """The message refusing ``path``, of ``kind`` (:func:`special_kind`), given as the ``what``
    file: ``x: a FIFO, not a file: give the config as a file``."""
    return f"{path}: {kind}, not a file: give the {what} as a file"


def read_bounded(path: str | os.PathLike[str], limit: int, what: str = "file") -> bytes:
    """The bytes of ``path`` if it holds at most ``limit`` of them. Raises InputError naming
    the file when it cannot be read or is larger (a device or pipe that never ends included:
    at most ``limit + 1`` bytes are read, in pieces: memory grows with what the file holds,
    not with ``limit``)."""
    pieces: list[bytes] = []
    size = 0
    try:
        if stat.S_ISFIFO(os.stat(path).st_mode):  # opening one waits for a writer, maybe for ever
            raise InputError(not_a_file(path, "a FIFO", what))
        with open(path, "rb") as handle:
            while size <= limit:
                piece = handle.read(min(_PIECE, limit + 1 - size))
                if not piece:
                    break
                pieces.append(piece)
                size += len(piece)
    except OSError as exc:
        raise InputError(f"{path}: cannot read {what} ({os_reason(exc)})") from None
    if size > limit:
        raise InputError(f"{path}: larger than {_mb(limit)}, too large for a {what}")
    return b"".join(pieces)


def read_text_bounded(path: str | os.PathLike[str], limit: int, what: str = "file") -> str:
    """:func:`read_bounded` as UTF-8 text, a leading byte-order mark dropped (Windows editors
    write one). InputError when the bytes are not UTF-8 (saying so of UTF-16 with its
    byte-order mark, which Windows editors also write)."""
    data = read_bounded(path, limit, what)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        if _utf16_text(data):  # Notepad's "Unicode"
            raise InputError(f"{Path(path)}: {what} is UTF-16 text; vtrack reads UTF-8 (save "
                             "it as UTF-8)") from None
        raise InputError(f"{Path(path)}: {what} is not text (not UTF-8)") from None


def _utf16_text(data: bytes) -> bool:
    """Whether ``data`` reads as UTF-16 text of the kind vtrack's files hold: a byte-order mark,
    then characters that are mostly ASCII (binary bytes after FF FE decode as UTF-16 too)."""
    if not data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return False
    try:
        text = data.decode("utf-16")
    except UnicodeDecodeError:
        return False
    return sum(char.isascii() for char in text) >= 0.9 * len(text) > 0
