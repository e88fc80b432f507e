"""A file that is still being written, read as a stream (``tail -f``): ``--follow``."""

from __future__ import annotations

import io
import time

#: How often a reader at the current end looks for more data (seconds).
POLL_S = 0.05


class GrowingFile(io.RawIOBase):
    """``path`` read from its start; at its current end a read waits for more data and reports
    the end only once the file has not grown for ``idle_s`` seconds. Not seekable, so FFmpeg
    reads it as a stream (a container that needs its end first, like a plain MP4, cannot be
    followed: record fragmented MP4, MPEG-TS or Matroska)."""

    def __init__(self, path: str, idle_s: float) -> None:
        super().__init__()
        self._file = open(path, "rb", buffering=0)  # noqa: SIM115 (closed by close())
        self.idle_s = idle_s
        #: What a signal raised while a read waited (Ctrl-C, SIGTERM): FFmpeg calls the read,
        #: and PyAV would print and drop an exception raised there, so the read ends the
        #: stream instead and the decoder's owner raises this once it sees the end.
        self.interruption: BaseException | None = None
        #: Bytes handed to FFmpeg so far (a stream's size: FFmpeg cannot ask for it).
        self.bytes_read = 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: bytearray | memoryview) -> int:  # type: ignore[override]
        if self.interruption is not None:
            return 0
        quiet_since: float | None = None
        try:
            while True:
                got = self._file.readinto(buffer)
                if got:
                    self.bytes_read += got
                    return got
                now = time.monotonic()
                quiet_since = now if quiet_since is None else quiet_since
                if now - quiet_since >= self.idle_s or self.closed:
                    return 0
                time.sleep(POLL_S)
        except BaseException as exc:  # a signal's exception, inside FFmpeg's call: kept
            self.interruption = exc
            return 0

    def raise_interruption(self) -> None:
        """Raise what a signal raised while a read waited, if one did."""
        if self.interruption is not None:
            raise self.interruption

    def close(self) -> None:
        self._file.close()
        super().close()
