"""Run a producer in a background thread, handing its items over through a small bounded queue.

Readers and writers use this to keep decoding and encoding off the tracker thread: PyAV/FFmpeg and
file reads release the GIL, so a second core does the I/O while the first one tracks.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Iterator
from typing import Generic, TypeVar

T = TypeVar("T")

_END = object()
#: How often a producer blocked on a full queue checks whether it was asked to stop (seconds).
_POLL_S = 0.1


class _Failure:
    """The exception that ended the producer, carried to the consumer thread."""

    def __init__(self, error: BaseException) -> None:
        self.error = error


class Prefetcher(Generic[T]):
    """Iterate ``items`` in a daemon thread at most ``depth`` items ahead of the consumer.

    Iterating the prefetcher yields the producer's items in order; if the producer raised, the
    same exception is raised in the consumer after every item produced before it. ``close()``
    stops the producer (it notices at its next item) and waits for its thread to finish.
    """

    def __init__(self, items: Iterator[T], depth: int, name: str) -> None:
        self._items = items
        self._queue: queue.Queue[object] = queue.Queue(maxsize=max(depth, 1))
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._produce, name=name, daemon=True)
        self._started = False

    def _put(self, item: object) -> bool:
        """Queue ``item``; False when asked to stop before there was room."""
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=_POLL_S)
                return True
            except queue.Full:
                continue
        return False

    def _produce(self) -> None:
        try:
            for item in self._items:
                if not self._put(item):
                    return
            self._put(_END)
        except BaseException as exc:  # handed to the consumer, who decides what it means
            self._put(_Failure(exc))
        finally:
            close = getattr(self._items, "close", None)
            if close is not None:
                close()  # a generator's cleanup runs in the thread that ran it

    def __iter__(self) -> Iterator[T]:
        if not self._started:
            self._started = True
            self._thread.start()
        while True:
            item = self._queue.get()
            if item is _END:
                return
            if isinstance(item, _Failure):
                raise item.error
            yield item  # type: ignore[misc]

    def close(self, timeout: float = 2.0) -> bool:
        """Stop the producer; True once its thread has finished (or never started).

        False means the producer is stuck in a blocking call (e.g. a read from an idle pipe) and
        still owns its resources; it is a daemon thread and dies with the process.
        """
        self._stop.set()
        if not self._started:
            return True
        while True:  # free the queued items (and a producer blocked on a full queue)
            try:
                self._queue.get_nowait()
            except queue.Empty:
                break
        self._thread.join(timeout)
        return not self._thread.is_alive()
