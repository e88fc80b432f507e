"""``--stream FILE|-``: one JSON line per tracked frame, flushed as soon as the frame is done.

A reader downstream (``tail -f``, a pipe) follows the target while it moves; ``track.csv`` stays
the file that is whole only once the run has ended. Each line holds ``frame`` (the run's frame
number, from 0 as ``track.csv``'s and ``--start``'s) and ``time_s`` (the frame's timestamp).
A single-target line adds ``x``, ``y``, ``w``, ``h`` (null while lost), ``state``, ``score`` and
``extras`` (the stages' extra columns): its ``track.csv`` row's values. A multi-target line adds
only ``tracks``: the frame's confirmed tracks, each its ``tracks.csv`` row (the rows whose
MOTChallenge ``frame``, numbered from 1, is the line's ``frame`` + 1) as ``id``, ``x``, ``y``,
``w``, ``h``, ``conf``, ``state``. Numbers are the values the CSV files hold (rounded as they
are written, :func:`~vtrack.io.csvfile.as_written`: pixels to 3 decimals, ``time_s``,
``score`` and ``conf`` to 4), so a line and its rows agree; non-finite numbers are written as
null.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import math
import os
import select
import stat
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from vtrack.errors import COMMAND_NAMES, OptionNames, OutputError, StreamReaderGone, plural
from vtrack.geometry import Box
from vtrack.io.csvfile import as_written, box_as_written
from vtrack.io.files import Closing, os_reason, remove_quietly
from vtrack.io.threads import STOP_POLL_S
from vtrack.pipeline import FrameResult
from vtrack.stages.base import TrackStatus

#: ``--stream -``: the lines go to standard output.
STDOUT = "-"


def _number(value: Any, column: str) -> Any:
    """A JSON-ready cell: what ``column``'s CSV cell holds of ``value``: a float rounded as
    written (:func:`~vtrack.io.csvfile.as_written`), NaN and infinities as None (an empty
    cell); NumPy scalars as Python ones; other values as they are."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float):
        return as_written(value, column) if math.isfinite(value) else None
    return value


def _box(box: Box | None) -> dict[str, Any]:
    """``x``, ``y``, ``w``, ``h`` of ``box`` as the CSV files write it (None: all null)."""
    if box is None:
        return dict.fromkeys(("x", "y", "w", "h"))
    written = box_as_written(box)  # rounded as the cells are: only non-finite values to null
    return {key: value if math.isfinite(value) else None
            for key, value in zip(("x", "y", "w", "h"), written, strict=True)}


def frame_record(result: FrameResult, multi_target: bool) -> dict[str, Any]:
    """What one stream line says about ``result`` (see the module docstring): a multi-target
    line holds no single-target fields (no box, state, score or extras of one target)."""
    record: dict[str, Any] = {"frame": result.index,
                              "time_s": _number(result.time_s, "time_s")}
    if multi_target:
        record["tracks"] = [
            {"id": t.id, **_box(t.box), "conf": _number(t.confidence, "conf"),
             "state": str(t.state)}
            for t in result.tracks if t.state == TrackStatus.CONFIRMED]
        return record
    return {**record, **_box(result.box), "state": str(result.state),
            "score": _number(result.score, "score"),
            "extras": {key: _number(value, key) for key, value in result.extras.items()}}


class StreamWriter(Closing):
    """Writes :func:`frame_record` lines to ``target`` (a path, or ``-`` for standard output),
    each written out before :meth:`write` returns. OutputError names the target when a line
    cannot be written (a full disk; :class:`~vtrack.errors.StreamReaderGone` for a reader that
    went away) or when the reader of a pipe takes
    nothing for ``stall_s`` seconds (the run must not wait for ever on a reader that stopped
    reading). A line none of which is out yet gives way to a stop (see :meth:`write`), so
    Ctrl-C or SIGTERM does not wait for ``stall_s``. A regular file whose line could not be
    written whole (a full disk) is cut back to its last whole line. A regular file it opens
    is emptied at the first line (or at :meth:`close`), not as it is opened: a run refused
    before its first frame (:meth:`abort`) leaves an earlier run's lines as they were, as it
    leaves its folder. Its messages call the target and the wait by ``names`` (``--stream
    F``, ``--timeout``; ``stream F``, ``ffmpeg.timeout_s``)."""

    def __init__(self, target: str, multi_target: bool, stall_s: float = 10.0,
                 names: OptionNames = COMMAND_NAMES) -> None:
        self.target = target
        #: How a message begins: the target as the caller gave it (``--stream F``).
        self.given = f"{names.stream} {target}"
        self.multi_target = multi_target
        self.stall_s = stall_s
        self.lines = 0
        try:
            #: The file this writer made (removed by abort(); None: it was there, or stdout):
            #: the target, or the file a link at it names, made as the link is written through.
            self._file: IO[bytes]
            self._created: str | None
            self._file, self._created = (
                (_stdout_bytes(), None) if target == STDOUT
                else _open_for_lines(target, stall_s, self.given, names.timeout))
        except OSError as exc:
            raise OutputError(f"{self.given}: {os_reason(exc)}") from None
        try:
            self._fd: int | None = self._file.fileno()
        except (OSError, ValueError):  # standard output replaced by an object (a test runner)
            self._fd = None
        self._regular = self._fd is not None and _regular_file(self._fd)
        #: A regular file opened here, not emptied yet (at the first line, or close())
        self._to_empty = self._regular and target != STDOUT

    def write(self, result: FrameResult, stop: Callable[[], bool] | None = None) -> bool:
        """Write ``result``'s line; True once it is out. False, with nothing of the line
        written, when ``stop()`` turned true while the line waited for a reader to make room
        (a line already begun is finished). OutputError as the class says."""
        line = json.dumps(frame_record(result, self.multi_target), separators=(",", ":"))
        data = (line + "\n").encode("utf-8")
        try:
            self._empty()
        except OSError as exc:
            raise OutputError(f"{self.given}: {os_reason(exc)}") from None
        start = _line_start(self._fd) if self._regular and self._fd is not None else None
        try:
            if self._fd is None:
                self._file.write(data)
                self._file.flush()
            elif not self._send(memoryview(data), stop):
                return False
        except BrokenPipeError:
            raise StreamReaderGone(f"{self.given}: its reader went away (closed the "
                                   f"pipe) after {plural(self.lines, 'line')}: the run stopped "
                                   "there (SIGPIPE)") from None
        except (OSError, ValueError) as exc:
            if start is not None and self._fd is not None:  # a full disk: no half line left
                with contextlib.suppress(OSError):
                    os.ftruncate(self._fd, start)
                    os.lseek(self._fd, start, os.SEEK_SET)
            raise OutputError(f"{self.given}: {os_reason(exc)}") from None
        self.lines += 1
        return True

    def _send(self, data: memoryview, stop: Callable[[], bool] | None) -> bool:
        """Write ``data`` to the descriptor, at most ``PIPE_BUF`` bytes at a time and each
        only once it can take them (a pipe with room: such a write does not block), waiting
        at most ``stall_s`` for that room; False (nothing written) if ``stop()`` turned true
        while the first bytes waited."""
        first = True
        while data:
            deadline = time.monotonic() + self.stall_s
            while not select.select([], [self._fd], [],
                                    max(0.0, min(STOP_POLL_S, deadline - time.monotonic())))[1]:
                if first and stop is not None and stop():
                    return False
                if time.monotonic() >= deadline:
                    raise OutputError(f"{self.given}: its reader took nothing for "
                                      f"{self.stall_s:g} s")
            data = data[os.write(self._fd, data[:select.PIPE_BUF]):]
            first = False
        return True

    def _empty(self) -> None:
        """Empty the regular file opened here, once (OSError)."""
        if self._to_empty and self._fd is not None:
            os.ftruncate(self._fd, 0)
            os.lseek(self._fd, 0, os.SEEK_SET)
            self._to_empty = False

    def close(self) -> None:
        """Close the target, a file holding this run's lines only (none: emptied)."""
        if self.target == STDOUT:
            with contextlib.suppress(OSError, ValueError):  # the reader went away: write()
                self._file.flush()                           # has said so already
            return
        try:
            if not self._file.closed:
                self._empty()
            self._file.close()
        except (OSError, ValueError) as exc:
            raise OutputError(f"{self.given}: {os_reason(exc)}") from None

    def abort(self) -> None:
        """Close without a line, for a run refused before its first frame: a file that held
        an earlier run's lines keeps them (it was not emptied), one made here is removed. After
        a line, as :meth:`close`."""
        if self.lines or self.target == STDOUT:
            self.close()
            return
        with contextlib.suppress(OSError, ValueError):
            self._file.close()
        if self._created is not None and self._regular:
            remove_quietly(Path(self._created))


def _regular_file(fd: int) -> bool:
    """Whether ``fd`` is a regular file (not a pipe, FIFO, terminal or device)."""
    try:
        return stat.S_ISREG(os.fstat(fd).st_mode)
    except OSError:
        return False


def _line_start(fd: int) -> int | None:
    """Where the next line written to ``fd``, a regular file, begins: its end when it was
    opened to append (``--stream - >> log``), else its offset; None when that cannot be
    told."""
    try:
        if fcntl.fcntl(fd, fcntl.F_GETFL) & os.O_APPEND:
            return os.fstat(fd).st_size
        return os.lseek(fd, 0, os.SEEK_CUR)
    except OSError:
        return None


#: How often the opening of a FIFO looks for its reader (seconds).
READER_POLL_S = 0.05


def _open_for_lines(target: str, wait_s: float, given: str, wait_name: str
                    ) -> tuple[IO[bytes], str | None]:
    """``target`` opened to write, and the path of the file the open made (None: one was
    there). A FIFO is opened once a reader has opened it, waiting at most ``wait_s`` (a plain
    open would wait for ever: OutputError beginning ``given``, the target as the caller named
    it, and naming ``wait_name``, what sets the wait)."""
    try:
        fifo = stat.S_ISFIFO(os.stat(target).st_mode)
    except OSError:
        fifo = False
    if not fifo:  # (not emptied here: StreamWriter empties a regular file at its first line)
        return _open_or_make(target)
    deadline = time.monotonic() + wait_s
    while True:
        try:
            fd = os.open(target, os.O_WRONLY | os.O_NONBLOCK)  # ENXIO: no reader yet
            break
        except OSError as exc:
            if exc.errno != errno.ENXIO:
                raise
            if time.monotonic() >= deadline:
                raise OutputError(f"{given}: a FIFO that no reader opened within "
                                  f"{wait_s:g} s ({wait_name})") from None
            time.sleep(READER_POLL_S)
    os.set_blocking(fd, True)
    return open(fd, "wb"), None  # noqa: SIM115


def _open_or_make(target: str) -> tuple[IO[bytes], str | None]:
    """``target`` opened to write as it is, or made when it is not there, and the path of the
    file made (None: it was there). A link to no file is written through, as a plain open
    does: the file made, and the path returned, is the one the link names."""
    made = os.path.realpath(target)
    try:
        fd = os.open(made, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    except FileExistsError:
        fd, made = os.open(target, os.O_WRONLY), None
    return open(fd, "wb"), made  # noqa: SIM115


def _stdout_bytes() -> IO[bytes]:
    """Standard output for bytes, after what was printed to it as text. EBADF OSError when the
    process has none (``>&-``: Python then sets ``sys.stdout`` to None), as a closed file
    descriptor is."""
    if sys.stdout is None:
        raise OSError(errno.EBADF, "standard output was closed before vtrack started (>&-): "
                                   "nothing can read the lines")
    sys.stdout.flush()
    return sys.stdout.buffer if hasattr(sys.stdout, "buffer") else sys.stdout  # type: ignore[return-value]
