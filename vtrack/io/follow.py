"""A file that is still being written, read as a stream (``tail -f``): ``--follow``."""

from __future__ import annotations

import os
import time

from vtrack.io.pyfile import CapturingStream

#: How often a reader at the current end looks for more data (seconds).
POLL_S = 0.05


class FollowedFileChanged(OSError):
    """The followed file is no longer the recording that was being read: the stream ends."""


class FollowedFileCut(FollowedFileChanged):
    """The followed file became shorter than what was read of it: rewritten from its start
    (a recorder restarted over the same name) or cut. Reading on where the old data ended
    would hand over the middle of other data."""


class FollowedFileReplaced(FollowedFileChanged):
    """The followed path names another file than the one opened (a new recording renamed
    over it, or the old one rotated away and a new one made). The file opened is read to its
    end first (``tail -f``, not ``tail -F``); what the path names now is another recording."""


class GrowingFile(CapturingStream):
    """``path`` read from its start; at its current end a read waits for more data and reports
    the end only once the file has not grown for ``idle_s`` seconds. Not seekable, so FFmpeg
    reads it as a stream (a container that needs its end first, like a plain MP4, cannot be
    followed: record fragmented MP4, MPEG-TS or Matroska). A file cut shorter than what was
    read of it ends the stream, and :attr:`interruption` holds :class:`FollowedFileCut`; the
    file opened read to its end while ``path`` names another file ends it with
    :class:`FollowedFileReplaced`.
    :meth:`stop_at_end` ends the stream where the file ends now (a signal: the frames already
    in the file still come out of the decoder)."""

    def __init__(self, path: str, idle_s: float, option: str = "--follow") -> None:
        """``option``: what the caller set ``idle_s`` with, for a message (``--follow``,
        ``ffmpeg.follow_s``)."""
        super().__init__()
        self._option = option
        self._file = open(path, "rb", buffering=0)  # noqa: SIM115 (closed by close())
        self._path = path
        opened = os.fstat(self._file.fileno())
        self._identity = (opened.st_dev, opened.st_ino)
        self.idle_s = idle_s
        #: When a read last found new data (``perf_counter``): the idle time counts from
        #: there, across reads (FFmpeg asks again several times at the end; each must not wait
        #: ``idle_s`` anew).
        self._grew_at = time.perf_counter()
        #: When a read first found no more data since the last growth (None: the last read
        #: found some): the reader's wait at the end starts there.
        self._empty_since: float | None = None
        #: The wait that found the end: from the first read that found nothing more to the end
        #: reported (``perf_counter`` times; None before the end). It is no reading.
        self.end_wait: tuple[float, float] | None = None
        #: Set by :meth:`stop_at_end`: where the stream ends (the file's size then); what is
        #: written after the stop is not read, also by a read already under way.
        self._end_at: int | None = None

    def _read_into(self, buffer: bytearray | memoryview) -> int:
        while True:
            end_at = self._end_at
            if end_at is not None and self._file.tell() >= end_at:
                return self._ended(time.perf_counter())
            got = self._file.readinto(buffer)
            now = time.perf_counter()
            end_at = self._end_at  # (a stop may have come while the read was under way)
            if end_at is not None:
                got = max(0, min(got, end_at - (self._file.tell() - got)))
            if got:
                self._grew_at, self._empty_since = now, None
                return got
            size, read = os.fstat(self._file.fileno()).st_size, self._file.tell()
            if size < read:
                raise FollowedFileCut(f"the file was cut to {size} bytes after {read} were read "
                                      "(rewritten from its start?)")
            if self._empty_since is None:
                self._empty_since = now
            if now - self._grew_at >= self.idle_s or self.closed:
                if not self.closed and self._replaced():
                    raise FollowedFileReplaced(
                        f"another file now has its name (renamed over it, or the recording "
                        f"rotated); the {read} bytes of the one opened were read and it stayed "
                        f"{self.idle_s:g} s without growing; {self._option} does not go on to the "
                        "new one (as tail -f, not tail -F)")
                return self._ended(now)
            time.sleep(POLL_S)

    def _ended(self, now: float) -> int:
        """The stream's end (0), its wait at the end recorded once: from the first read that
        found nothing more (or ``now``) to ``now``."""
        if self.end_wait is None:
            self.end_wait = (self._empty_since or now, now)
        return 0

    def _replaced(self) -> bool:
        """Whether the path names another file than the one opened now (a missing name is
        not: the writer may still write the file opened)."""
        try:
            now = os.stat(self._path)
        except OSError:
            return False
        return (now.st_dev, now.st_ino) != self._identity

    def stop_at_end(self) -> bool:
        """If everything the file holds now has been read (what is not out yet is in the
        reader's buffers and the decoder's frame threads), end the stream there instead of
        waiting for more, and return True; else (more is left to read, or the file is closed)
        False and nothing changes. Safe to call from another thread (a signal handler)."""
        try:
            read = self._file.tell()
            done = read >= os.fstat(self._file.fileno()).st_size
        except (OSError, ValueError):  # closed meanwhile
            return False
        if done and self._end_at is None:
            self._end_at = read
        return done

    def close(self) -> None:
        self._file.close()
        super().close()
