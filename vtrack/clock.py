"""The frames elapsed between the frames a tracker is given: the pipeline's frame clock.

A tracker is given frames, not time: a camera drops some, ``vtrack run --live`` passes over
those it cannot keep up with, a reader skips a damaged stretch, a stream's rate changes. What
measures time counts on :class:`FrameClock` instead of the calls: the pipeline's rule that a box
entirely outside the frame for ``OFF_FRAME_FRAMES`` frames is lost (:mod:`vtrack.pipeline`),
and in the ``robust`` chain the motion model's steps (``robust_motion``), the hidden time before
a target is lost and the lost target's growing search (``robust_failure``). The pipeline makes
one per track on its first frame (``ctx.clock``, a field of
:class:`~vtrack.stages.base.TrackContext`) and moves it on to each later frame before anything
else is asked about that frame (the predictors' ``ctx.forecast``, the stages).
"""

from __future__ import annotations

import statistics

from vtrack.frame import Frame


class FrameClock:
    """Frames elapsed between the frames a tracker is given, counted in the stream's frame
    period.

    Between two frames, the elapsed frames are the index difference; where the timestamps say
    otherwise by more than ``JITTER`` of a frame (a change of frame rate, a reader that skipped
    frames without numbering the gap, numbers that start again), the time difference over the
    frame period. The period starts at the time per index step of the first two intervals in a
    row that agree on it within ``JITTER`` (a first interval stretched by a device starting up,
    or a gap the numbers do not show, is not taken for it), then is the median of the
    ``PERIOD_INTERVALS`` intervals from those two on (a camera's buffered first frames,
    delivered at once, do not set it for good); until then, and where neither tells (indices
    that do not increase and no usable timestamps), the index difference, or one frame. A
    timestamp that did not increase is not the base of the next interval (that one counts by
    the numbers)."""

    #: Timestamps that differ from the index difference by at most this many frames agree with
    #: it (a capture clock's jitter, timestamp rounding).
    JITTER = 0.25
    #: More frames than this elapsed between two frames is a discontinuity (a stream that
    #: stalled or was cut, a clock or numbering that jumped), not a gap the target crossed at
    #: its velocity: about a second at common rates, and as many frames as ``robust_failure``
    #: lets a hidden target go before it is lost (``lost_after``'s default), after which its
    #: velocity is not trusted either. Motion extrapolated further moves a prediction (and the
    #: region cut there) arbitrarily far from the target.
    GAP = 30.0
    #: Timed steps are rounded to this many decimals of a frame: a container's time base
    #: (1/90000 s, milliseconds) tells no finer, and two frames' worth of timestamps divided by
    #: the period should count 2, not 1.9999999999999996 (whose whole rings are one fewer).
    DECIMALS = 6
    #: The period is the median time per index step of this many intervals from the first two
    #: that agree (of those so far until then): a few frames at the start timed otherwise (a
    #: camera's buffered first frames delivered at once) are outvoted rather than taken for the
    #: period for good, while a rate that changes later does not change it (the timestamps
    #: then count the frames elapsed: a rate that halves after the first five intervals still
    #: counts two frames an interval).
    PERIOD_INTERVALS = 9

    def __init__(self, frame: Frame) -> None:
        #: The last frame's index and time (None: its timestamp did not increase, so the
        #: next interval is not timed).
        self._index: int = frame.index
        self._time: float | None = frame.time_s
        #: The frame period (None until two intervals in a row agree), and the times per index
        #: step it is the median of (until then: the last interval's).
        self._period: float | None = None
        self._first: list[float] = []
        #: Frames elapsed since the first frame, and from the frame before to the last frame
        #: given (1 on the first).
        self.now = 0.0
        self.elapsed = 1.0
        #: :attr:`now` at the frame before the last one given (exactly: ``now - elapsed`` may
        #: differ in the last bit; 0 on the first).
        self.before = 0.0

    def advance(self, frame: Frame) -> float:
        """The frames elapsed from the last frame given to ``frame`` (more than 0, also kept as
        :attr:`elapsed`); ``frame`` becomes the last one."""
        indexed, interval = self._since(frame)
        steps = float(indexed) if indexed > 0 else 1.0
        if interval > 0 and self._period is not None:
            timed = round(interval / self._period, self.DECIMALS)
            if abs(timed - steps) > self.JITTER:
                steps = timed
        # a timestamp that did not increase is no base for the next interval either (one frame
        # stamped 0 in a long stream would make the next interval the whole stream)
        self._index = frame.index
        self._time = frame.time_s if interval > 0 or self._time is None else None
        if interval > 0 and indexed > 0:
            self._learn(interval / indexed)
        self.before = self.now
        self.now += steps
        self.elapsed = steps
        return steps

    @property
    def frame(self) -> int:
        """Whole frames elapsed since the first frame (:attr:`now` to the nearest): what the
        counts of frames take differences of (frames hidden, frames outside the picture), so
        that a timestamp a fraction of a frame late or early (a live camera's clock) makes no
        frame more or fewer, and such offsets do not add up over the frames."""
        return round(self.now)

    @property
    def whole_elapsed(self) -> int:
        """Whole frames from the frame before the last one given to the last one:
        :attr:`frame`'s step (1 on an input without gaps; 0 after a frame stamped late)."""
        return round(self.now) - round(self.before)

    def _since(self, frame: Frame) -> tuple[int, float]:
        """``frame``'s index difference and time difference from the last frame (0 s when the
        last frame's time is no base)."""
        interval = frame.time_s - self._time if self._time is not None else 0.0
        return frame.index - self._index, interval

    def _learn(self, per: float) -> None:
        """Take an interval's time per index step into the period: the first that agrees with
        the one before it within ``JITTER`` starts it (a first interval stretched by a device
        starting up is not taken for it); from then on it is the median of the intervals since
        those two, up to ``PERIOD_INTERVALS``."""
        if self._period is None:
            last = self._first[-1] if self._first else None
            self._first = [per]
            if last is not None and abs(per - last) <= self.JITTER * last:
                self._period, self._first = last, [last, per]
        elif len(self._first) < self.PERIOD_INTERVALS:
            self._first.append(per)
            self._period = statistics.median(self._first)
