"""Work in background threads: producers handing their items over through a small bounded
queue (:class:`Prefetcher`, :class:`KeepingUp`), and one call run aside while the caller waits
for it and stays open to signals (:func:`run_aside`).

Readers and writers use the producers to keep decoding and encoding off the tracker thread:
PyAV/FFmpeg and file reads release the GIL, so a second core does the I/O while the first one
tracks. A network input is opened by :func:`run_aside`: FFmpeg holds the thread that opens it
until data comes or its timeout passes.
"""

from __future__ import annotations

import queue
import signal
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any, Generic, TypeVar

from vtrack.errors import STOP_SIGNALS

T = TypeVar("T")

_END = object()
#: How often a thread waiting on another (a producer blocked on a full queue, a writer waiting
#: for a stalled receiver) checks whether it was asked to stop (seconds).
STOP_POLL_S = 0.1
#: A live consumer may fall this far behind the newest item before older items are passed
#: over: a decoder hands frames over in bursts, and a consumer faster than the source on
#: average works through a short burst in time (issue 23's latency aim: p99 under 50 ms).
LATENCY_BUDGET_S = 0.05


class _Failure:
    """The exception that ended the producer, carried to the consumer thread."""

    def __init__(self, error: BaseException) -> None:
        self.error = error


class _Producer(threading.Thread):
    """A producer's daemon thread whose ``start()`` a stop signal does not cut in two.

    Started from the main thread, it holds SIGINT and SIGTERM off (``pthread_sigmask``)
    until the thread is launched and running: a signal meanwhile is handled as ``start()``
    returns (its ``Interrupted`` raised there), so the thread is either never launched (the
    signal was handled before) or can be joined. A signal another thread took may still raise
    inside ``start()``: then :meth:`finish` waits for the launched thread to run before
    joining it (``Thread.join`` would raise ``RuntimeError``)."""

    def __init__(self, target: Callable[[], None], name: str) -> None:
        super().__init__(target=target, name=name, daemon=True)
        self._producing = threading.Event()
        self._launching = False

    def start(self) -> None:
        """Launch the thread (see the class), a signal held off meanwhile."""
        if threading.current_thread() is not threading.main_thread():
            self._launch()
            return
        held = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)  # (handles one due)
        try:
            self._launch()
        finally:  # a signal that came meanwhile is handled here, the thread started
            signal.pthread_sigmask(signal.SIG_SETMASK, held)

    def _launch(self) -> None:
        self._launching = True
        super().start()

    def run(self) -> None:
        self._producing.set()
        super().run()

    def finish(self, timeout: float) -> bool:
        """Wait up to ``timeout`` seconds for the thread (its ``start()`` called) to end; True
        once it has, or when a signal came before it was launched."""
        if not self._launching:
            return True
        deadline = time.monotonic() + timeout
        if not self._producing.wait(timeout):
            return False
        self.join(max(0.0, deadline - time.monotonic()))
        return not self.is_alive()


class Prefetcher(Generic[T]):
    """Iterate ``items`` in a daemon thread at most ``depth`` items ahead of the consumer.

    Iterating the prefetcher yields the producer's items in order; if the producer raised, the
    same exception is raised in the consumer after every item produced before it. ``close()``
    stops the producer (it notices at its next item) and waits for its thread to finish; an
    iteration under way then ends (as :class:`KeepingUp`'s does), where it waited for ever for
    an item the stopped producer would never queue; :attr:`reached_end` tells whether that end
    was the items' own.
    """

    def __init__(self, items: Iterator[T], depth: int, name: str) -> None:
        self._items = items
        self._queue: queue.Queue[object] = queue.Queue(maxsize=max(depth, 1))
        self._stop = threading.Event()
        self._thread = _Producer(self._produce, name)
        self._started = False
        self._closing = threading.RLock()  # close()'s stop and discarding as one step (a
        # signal handler in the consumer thread may close it while reached_end reads)
        self._exhausted = False  # the producer went through all its items
        self._dropped = False  # close() discarded an item the consumer had not taken

    @property
    def reached_end(self) -> bool:
        """Whether the producer went through all its items and the consumer was handed every
        one (a :meth:`close` after the last item, its end marker still queued, leaves it
        True); False when the producer raised or was stopped before its end (an end it
        reached once ``close()`` had begun is not counted), or ``close()`` discarded an item
        not taken. Final once the iteration has ended on its own, or ``close()`` has returned
        (whatever the producer does later)."""
        with self._closing:
            return self._exhausted and not self._dropped

    def _put(self, item: object) -> bool:
        """Queue ``item``; False when asked to stop before there was room."""
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=STOP_POLL_S)
                return True
            except queue.Full:
                continue
        return False

    def _produce(self) -> None:
        try:
            for item in self._items:
                if not self._put(item):
                    return
            # (before the marker: a close() may leave it unqueued). Not once close() has
            # begun: the last item may have been queued after close() emptied the queue, and
            # the consumer left without it; and reached_end is final once close() returned.
            self._exhausted = not self._stop.is_set()
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
        while not self._stop.is_set():
            try:
                item = self._queue.get(timeout=STOP_POLL_S)
            except queue.Empty:
                continue
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
        with self._closing:
            self._stop.set()
            while True:  # free the queued items (and a producer blocked on a full queue)
                try:
                    item = self._queue.get_nowait()
                except queue.Empty:
                    break
                self._dropped = self._dropped or item is not _END
        if not self._started:
            return True
        return self._thread.finish(timeout)


class KeepingUp(Generic[T]):
    """Iterate ``items`` (a live source) in a daemon thread that never waits for the consumer,
    handing over what the consumer can still keep up with and passing over the rest.

    Items wait in a queue of at most ``depth``. When the consumer asks for the next one, it
    gets the oldest waiting item if it can work through everything waiting within the budget
    (``LATENCY_BUDGET_S``, or the next item's period if longer; at its measured time per item);
    otherwise the older items are passed over until it can (the newest always stays). When the
    queue is full, the producer waits for room until the oldest waiting item has waited the
    budget, and only then passes it over: the rest of a burst stays in the source (the
    decoder, the socket) meanwhile. So a burst of items that arrived together (several frames
    from a frame-threaded decoder, from one network packet, or the backlog FFmpeg buffered
    while a stream was opened), however long, is worked through by a consumer that keeps up
    with it within the budget, while a consumer slower than the source always gets the newest
    and never falls further behind than the budget.

    ``passed`` counts the items passed over; ``received`` is when the item last handed over
    was produced (``time.perf_counter()``). Memory stays flat whatever the consumer's pace. If
    the producer raised, the consumer gets the items still waiting, then the exception.
    """

    def __init__(self, items: Iterator[T], name: str, period_s: float, depth: int = 8) -> None:
        self._items = items
        self._period_s = period_s
        self._waiting: deque[tuple[object, float]] = deque()
        self._depth = max(depth, 1)
        self._ready = threading.Condition()
        self._end: object | None = None  # _END or a _Failure once the producer has finished
        self._exhausted = False  # the producer went through all its items
        self._dropped = False  # close() discarded items the consumer had not been handed
        self._stop = threading.Event()
        self._thread = _Producer(self._produce, name)
        self._started = False
        self._busy_s = 0.0  # the consumer's time per item, a running mean
        self.passed = 0
        self.received = 0.0

    @property
    def reached_end(self) -> bool:
        """Whether the producer went through all its items and the consumer was handed every
        one not passed over; False when the producer raised or was stopped before its end, or
        :meth:`close` discarded items waiting. Final once the iteration has ended."""
        with self._ready:
            return self._exhausted and not self._dropped

    def _produce(self) -> None:
        end: object = _END
        exhausted = False
        try:
            for item in self._items:
                if self._stop.is_set():
                    return
                produced = time.perf_counter()  # before any wait for room: latency counts it
                with self._ready:
                    self._make_room()
                    if self._stop.is_set():
                        return
                    self._waiting.append((item, produced))
                    self._ready.notify_all()
            exhausted = True
        except BaseException as exc:  # handed to the consumer, who decides what it means
            end = _Failure(exc)
        finally:
            with self._ready:
                self._end = end
                self._exhausted = exhausted
                self._ready.notify_all()
            close = getattr(self._items, "close", None)
            if close is not None:
                close()

    def _budget_s(self) -> float:
        return max(self._period_s, LATENCY_BUDGET_S)

    def _make_room(self) -> None:
        """Wait until the queue has room, or passing over its oldest item is due: that item
        has waited the budget (the consumer is not keeping up), or a stop was asked for.
        Called by the producer holding ``_ready``."""
        while len(self._waiting) >= self._depth and not self._stop.is_set():
            waited = time.perf_counter() - self._waiting[0][1]
            if waited >= self._budget_s():
                self._waiting.popleft()
                self.passed += 1
                return
            self._ready.wait(min(STOP_POLL_S, self._budget_s() - waited))

    def _take(self) -> tuple[object, float] | None:
        """The next item to hand over (None: the producer has ended), passing over the ones
        the consumer could not work through in time. Called holding ``_ready``."""
        while not self._waiting and self._end is None:
            self._ready.wait(STOP_POLL_S)
        if not self._waiting:
            return None
        keep = max(1, int(self._budget_s() / self._busy_s)) if self._busy_s > 0 else self._depth
        while len(self._waiting) > keep:
            self._waiting.popleft()
            self.passed += 1
        self._ready.notify_all()  # a producer waiting for room has it now
        return self._waiting.popleft()

    def __iter__(self) -> Iterator[T]:
        if not self._started:
            self._started = True
            self._thread.start()
        first = True
        while True:
            with self._ready:
                taken = self._take()
                end = self._end
            if taken is None:
                if isinstance(end, _Failure):
                    raise end.error
                return
            item, self.received = taken
            started = time.perf_counter()
            yield item  # type: ignore[misc]
            busy = time.perf_counter() - started
            if first:  # the first item also pays for starting up: not a measure of the pace
                first = False
            else:
                self._busy_s = busy if self._busy_s == 0 else 0.8 * self._busy_s + 0.2 * busy

    def close(self, timeout: float = 2.0) -> bool:
        """Stop the producer; True once its thread has finished (or never started)."""
        with self._ready:
            self._stop.set()
            self._dropped = self._dropped or bool(self._waiting)
            self._waiting.clear()
            self._ready.notify_all()
        if not self._started:
            return True
        return self._thread.finish(timeout)


#: One item for each work :func:`run_aside` started that has not finished (an abandoned one
#: too); not ``Thread.is_alive()``, which a ``join()`` cut short by a signal's exception may
#: leave False for a thread still running (Python 3.11's ``_wait_for_tstate_lock``).
_ASIDE: set[object] = set()


def aside_running() -> bool:
    """Whether work :func:`run_aside` started is still running: after a signal ended the
    caller's wait, FFmpeg still opening a URL aside. PyAV's open timeout calls into Python
    from that thread while it waits, and doing so as the interpreter is torn down at the
    process's exit may crash the process (a segmentation fault): a program then ends with
    ``os._exit``."""
    return bool(_ASIDE)


def run_aside(work: Callable[[], T], discard: Callable[[T], None]) -> T:
    """``work()``'s result, computed in a daemon thread (SIGINT and SIGTERM blocked in it, as
    in a producer's) while this one waits in steps of :data:`STOP_POLL_S`, so that a signal's
    Python handler runs (and may raise: Ctrl-C, ``vtrack run``'s Interrupted) at once: a C call
    that holds its thread until its own timeout (FFmpeg opening a network input that sends
    nothing) delays the handlers of the thread it runs in until it returns. ``work``'s
    exception is raised here. When this thread leaves by an exception of its own (a
    handler's, also one that came as the thread was started), ``work`` finishes aside
    (:func:`aside_running` says so meanwhile) and what it gives, if anything, is handed to
    ``discard`` (e.g. closed).

    The wait is in steps rather than one ``join()`` (which a signal does cut short on POSIX):
    a signal sent to the process may be delivered to another of its threads, one that does
    not block it, and then this thread's ``join()`` would go on waiting; a step ends anyway,
    and the handler runs then."""
    lock = threading.Lock()
    outcome: list[tuple[bool, Any]] = []  # [(succeeded, result or exception)]
    left = False
    running = object()

    def aside() -> None:
        try:
            try:
                result: tuple[bool, Any] = (True, work())
            except BaseException as exc:  # noqa: BLE001 - carried to the waiting thread
                result = (False, exc)
            with lock:
                outcome.append(result)
                abandoned = left
            if abandoned and result[0]:
                discard(result[1])
        finally:
            _ASIDE.discard(running)

    thread = _Producer(aside, "vtrack-aside")
    _ASIDE.add(running)
    try:
        thread.start()
        while thread.is_alive():
            thread.join(STOP_POLL_S)
    except BaseException:
        if thread.ident is None:  # never launched (no thread could be, or a signal came first)
            _ASIDE.discard(running)
        with lock:
            left = True
            done = list(outcome)
        if done and done[0][0]:
            discard(done[0][1])
        raise
    succeeded, value = outcome[0]
    if not succeeded:
        raise value
    return value
