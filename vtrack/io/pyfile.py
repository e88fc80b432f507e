"""Python streams FFmpeg reads through PyAV (a pipe on stdin, a file that is still growing)."""

from __future__ import annotations

import io
from typing import IO


class CapturingStream(io.RawIOBase):
    """A readable, unseekable stream that counts the bytes it hands over (``bytes_read``:
    FFmpeg cannot ask a stream for its size) and keeps what a signal raised inside a read.

    FFmpeg calls :meth:`readinto` from C, and PyAV prints and drops an exception raised there
    (a Ctrl-C or SIGTERM while a read waited): the run would go on as if nothing had happened.
    Here the read ends the stream instead, and the reader's owner raises the kept exception
    (:meth:`raise_interruption`) once it sees the end."""

    def __init__(self) -> None:
        super().__init__()
        #: What a signal raised while a read waited, once one did.
        self.interruption: BaseException | None = None
        self.bytes_read = 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: bytearray | memoryview) -> int:  # type: ignore[override]
        if self.interruption is not None:
            return 0
        try:
            got = self._read_into(buffer)
        except BaseException as exc:  # a signal's exception, inside FFmpeg's call: kept
            self.interruption = exc
            return 0
        self.bytes_read += got
        return got

    def _read_into(self, buffer: bytearray | memoryview) -> int:
        """Fill ``buffer`` with what there is; 0 at the stream's end."""
        raise NotImplementedError

    def raise_interruption(self) -> None:
        """Raise what a signal raised while a read waited, if one did."""
        if self.interruption is not None:
            raise self.interruption


#: The first bytes of a stream that cannot seek kept for a look at its layout (an MP4's index:
#: :func:`vtrack.io.signatures.mp4_head_fragmented`).
HEAD_BYTES = 1 << 20


class CountedStream(CapturingStream):
    """A stream that cannot seek (a pipe on stdin), read through as it arrives; its first
    :data:`HEAD_BYTES` bytes are kept in :attr:`head` until :meth:`drop_head` (then None)."""

    def __init__(self, raw: IO[bytes]) -> None:
        super().__init__()
        self._raw = raw
        self.head: bytearray | None = bytearray()

    def _read_into(self, buffer: bytearray | memoryview) -> int:
        got = self._raw.readinto1(buffer) or 0  # type: ignore[attr-defined]  # what has arrived
        if self.head is not None and len(self.head) < HEAD_BYTES:
            self.head += buffer[:min(got, HEAD_BYTES - len(self.head))]
        return got

    def drop_head(self) -> None:
        """Keep no more of the first bytes, and free those kept (the look at them is over)."""
        self.head = None
