"""Progress of the commands on stderr: a tqdm bar in a terminal, plain lines in a log.

``vtrack batch`` counts the frames of all its runs (:class:`BatchProgress`), as ``vtrack run``
counts its input's (:class:`FrameProgress`).

A bar appears only once there is progress to show: for ``vtrack run`` after the first frame is
tracked (so an error opening the input or starting the tracker is never preceded by an empty
bar), sized by the input's frame count (exact, or the container's duration x frame rate until
the frames' timestamps depart from it: then none) less ``--start``, and capped by
``--frames``. It shows done / total, percent, rate and ETA; without any count (a pipe) it
shows frames done and the rate.

When stderr is not a terminal (a log file, a pipe, a job scheduler) there is no bar: a plain
line (:func:`progress_line`) is written every ``--stats-period`` seconds instead, as ``ffmpeg``
does (``-stats_period``); ``--quiet`` silences both.
"""

from __future__ import annotations

import errno
import sys
import time
from collections.abc import Callable
from datetime import timedelta
from typing import TYPE_CHECKING

from vtrack.cli._messages import stdout_to_null
from vtrack.errors import printable

if TYPE_CHECKING:
    from tqdm import tqdm

    from vtrack.batch.jobs import Progress
    from vtrack.io import InputInfo

#: Seconds between two progress lines when stderr is not a terminal.
STATS_PERIOD = 10.0


def terminal(quiet: bool) -> bool:
    """Whether to draw a bar: not ``--quiet`` and stderr is a terminal (none at all: ``2>&-``,
    no bar)."""
    return not quiet and sys.stderr is not None and sys.stderr.isatty()


def progress_line(name: str, done: int, total: int | None, seconds: float,
                  unit: str = "frames") -> str:
    """``name: 120/600 frames (20%), 240.0 fps, 0:00:02 left`` (without a total: done and
    rate only; a rate per second for other units: ``inputs/s``): one line of progress for a
    log."""
    rate = done / seconds if seconds > 0 else 0.0
    per = "fps" if unit == "frames" else f"{unit}/s"
    if not total:
        return f"{name}: {done} {unit}, {rate:.1f} {per}"
    left = timedelta(seconds=round((total - done) / rate)) if rate > 0 else "?"
    return (f"{name}: {done}/{total} {unit} ({100 * done / total:.0f}%), {rate:.1f} {per}, "
            f"{left} left")


class ProgressLines:
    """A line of progress at most every ``period`` seconds (the first after ``period``)."""

    def __init__(self, name: str, total: int | None, period: float,
                 unit: str = "frames", started: float | None = None) -> None:
        self.name, self.total, self.period, self.unit = name, total, period, unit
        self.started = self.last = time.monotonic() if started is None else started

    def update(self, done: int, note: str = "", seconds: float | None = None) -> None:
        """A line on stderr if ``period`` has passed since the last one: ``done`` over
        ``seconds`` (by default, the time since ``started``); none without stderr (``2>&-``)."""
        now = time.monotonic()
        if sys.stderr is None:  # (2>&-: print would write the line on stdout)
            return
        if now - self.last >= self.period:
            self.last = now
            total = max(self.total, done) if self.total else None
            if seconds is None:
                seconds = now - self.started
            try:
                print(progress_line(self.name, done, total, seconds, self.unit)
                      + note, file=sys.stderr, flush=True)
            except (OSError, ValueError):  # the log's reader went away: the run goes on
                self.period = float("inf")


class _Shown:
    """What shows progress: a tqdm bar, :class:`ProgressLines`, or nothing yet (``bar``)."""

    bar: tqdm | ProgressLines | None = None
    quiet: bool
    period: float

    def _open(self, name: str, total: int | None, unit: str = "frames",
              started: float | None = None) -> tqdm | ProgressLines:
        """The bar of ``total`` ``unit`` in a terminal, else progress lines every ``period``
        (their rate counted from ``started``, default now)."""
        if terminal(self.quiet):
            from tqdm import tqdm

            return tqdm(total=total, unit=unit.rstrip("s"), desc=name, dynamic_ncols=True,
                        file=sys.stderr)
        return ProgressLines(name, total, self.period, unit, started)

    def close(self) -> None:
        """End the bar (a log's lines need no ending)."""
        if self.bar is not None and not isinstance(self.bar, ProgressLines):
            self.bar.close()
        self.bar = None


class BatchProgress(_Shown):
    """Frames tracked over a batch's runs (``vtrack batch``): a bar in a terminal, lines every
    ``period`` seconds in a log, each with the runs finished. The total is the frame counts
    the running and finished runs reported, plus their mean for each run not started yet.

    ``on_progress`` takes a worker's :class:`~vtrack.batch.jobs.Progress`; ``finished`` a run's
    frames when its outcome arrives (the only report of a run on a Dask cluster)."""

    def __init__(self, quiet: bool, period: float = STATS_PERIOD) -> None:
        self.quiet, self.period = quiet, period
        self.runs = 0  # runs to do (set once the batch is planned)
        self.done_runs = 0
        self.frames: dict[tuple[str, str], tuple[int, int | None]] = {}
        #: What stopped the batch's lines on standard output (BrokenPipeError when its reader
        #: went away, ENOSPC for ``> /dev/full``); None while they are written.
        self.stdout_failure: OSError | ValueError | None = None

    def write(self, line: str, err: bool = False) -> None:
        """A line on stdout (``err``: stderr) that does not break the bar, and never stops the
        batch: once a line fails on stdout (:attr:`stdout_failure`) the later ones are dropped
        (standard output goes to the null device), as are stderr's when its reader went away
        or there is no stderr (``2>&-``)."""
        if not err and self.stdout_failure is not None:
            return
        stream = sys.stderr if err else sys.stdout
        if stream is None:  # (>&- or 2>&-: closed from the start; print would use stdout)
            if not err:
                self.stdout_failure = OSError(errno.EBADF, "closed before vtrack started")
            return
        try:
            if self.bar is not None and not isinstance(self.bar, ProgressLines):
                self.bar.write(line, file=stream)
                stream.flush()  # (tqdm.write does not: into a pipe, lines came 8 KB at once)
            else:
                print(line, file=stream, flush=True)
        except (OSError, ValueError) as exc:
            if not err:
                self.stdout_failure = exc
                stdout_to_null()

    def on_progress(self, progress: Progress) -> None:
        self.frames[(progress.input, progress.config)] = (progress.frames, progress.total)
        self._show()

    def finished(self, input_name: str, config: str, frames: int) -> None:
        self.frames[(input_name, config)] = (frames, frames)
        self.done_runs += 1
        self._show()

    def _total(self) -> int | None:
        known = [total for _, total in self.frames.values() if total]
        if not known:
            return None
        waiting = max(self.runs - len(self.frames), 0)
        return round(sum(known) + waiting * sum(known) / len(known))

    def _show(self) -> None:
        if self.quiet:
            return
        total, done = self._total(), sum(done for done, _ in self.frames.values())
        note = f", {self.done_runs}/{self.runs} runs"
        if self.bar is None:
            self.bar = self._open("batch", total)
        if isinstance(self.bar, ProgressLines):
            self.bar.total = total
            self.bar.update(done, note)
            return
        self.bar.total = max(total or 0, done) or None
        self.bar.n = done
        self.bar.set_postfix_str(note.lstrip(", "), refresh=False)
        self.bar.refresh()


class FrameProgress(_Shown):
    """``on_open`` / ``on_frame`` callbacks of :func:`vtrack.run.run`: a frame bar in a
    terminal, progress lines every ``period`` seconds otherwise, nothing when ``quiet``."""

    def __init__(self, quiet: bool,
                 expected: Callable[[int | None, float | None], int | None] = (
                     lambda count, fps: count),
                 period: float = STATS_PERIOD) -> None:
        self.quiet = quiet
        #: the frames to track from the input's count and frame rate
        #: (:meth:`vtrack.request.RunRequest.frames_expected`)
        self.expected = expected
        self.period = period
        self.info: InputInfo | None = None
        self._started: float | None = None

    def on_open(self, info: InputInfo) -> None:
        """The input opened: the first progress line comes a period after (its rate is the
        run's own, see :meth:`on_frame`)."""
        self.info = info
        self._started = time.monotonic()

    def on_frame(self, done: int, seconds: float) -> None:
        """``done`` frames tracked in the run's ``seconds`` (a line's rate is the summary
        line's: :func:`vtrack.run.run` counts them as ``timing.seconds``)."""
        if self.quiet or self.info is None:
            return
        # the input's count is read again each time: the reader replaces an estimate as it
        # reads (None once the timestamps depart from it, the exact count at the end)
        total = self.expected(self.info.frame_count, self.info.fps)
        if self.bar is None:
            # the input as given, as the summary line names it (long.mp4, not long)
            self.bar = self._open(printable(self.info.path), total, started=self._started)
        if isinstance(self.bar, ProgressLines):
            self.bar.total = total
            self.bar.update(done, seconds=seconds)
            return
        if total is not None and done > total:  # the estimate was short
            total = done
        self.bar.total = total
        self.bar.update(done - self.bar.n)


class StepProgress(_Shown):
    """Progress through a known number of steps (``vtrack report``'s inputs), called with
    (done, total) after each: a bar in a terminal, lines every ``period`` seconds otherwise,
    nothing when ``quiet``."""

    def __init__(self, quiet: bool, name: str, unit: str, period: float = STATS_PERIOD) -> None:
        self.quiet, self.name, self.unit, self.period = quiet, name, unit, period
        self._started = time.monotonic()  # the first step's time counts in the rate

    def __call__(self, done: int, total: int) -> None:
        if self.quiet:
            return
        if self.bar is None:
            self.bar = self._open(self.name, total, self.unit, self._started)
        if isinstance(self.bar, ProgressLines):
            self.bar.update(done)
        else:
            self.bar.update(done - self.bar.n)
