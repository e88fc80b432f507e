"""The clock of ``annotated.mp4``'s timestamps: as fine as the run's span lets it be.

An MP4 (FFmpeg's muxer) keeps each step between two pictures' decoding times, and each
picture's reordering offset (presentation minus decoding time), in 32 bits. A step of 2^31-1
ticks or more loses the picture's time (the muxer logs an error, sets it one tick after the
one before and goes on: a video that plays every frame at one instant), a larger offset makes
the write fail. At 90 kHz that is a step of ~6.6 hours. Total time is no limit: the durations
are 64-bit.

x264 reorders B-frames: a picture's decoding time is the presentation time of one up to
``bframes + 2`` pictures before it in display order (2: the pyramid's delay), and the first
pictures' decoding times start that delay before 0. So a picture keeps its time when it comes
at most half the limit after the picture ``bframes + 2`` before it (one before, and the whole
limit, without B-frames); a video whose times all stay under that holds any steps.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

#: The largest step (and reordering offset) the MP4 muxer keeps, in ticks.
LIMIT_TICKS = 2**31 - 2

#: Ticks per second, finest first: 90 kHz is exact for 24, 25, 30, 60 and the 1001-based NTSC
#: rates (today's clock of every ordinary clip); the coarser ones only for a span it cannot hold.
RATES = (90000, 1000, 100, 10, 1)

#: B-frames of each x264 preset (``--preset``): how many steps a reordering offset spans.
X264_BFRAMES = {"ultrafast": 0, "superfast": 3, "veryfast": 3, "faster": 3, "fast": 3,
                "medium": 3, "slow": 3, "slower": 3, "veryslow": 8, "placebo": 16}


@dataclass(frozen=True)
class VideoClock:
    """A clock of ``rate`` ticks per second for an encoder that reorders ``bframes``."""

    rate: int
    bframes: int

    @property
    def time_base(self) -> Fraction:
        return Fraction(1, self.rate)

    @property
    def window(self) -> int:
        """How many pictures back a reordering offset reaches."""
        return self.bframes + 2 if self.bframes else 1

    @property
    def bound_ticks(self) -> int:
        """The most ticks a picture may come after the one :attr:`window` pictures before."""
        return LIMIT_TICKS // 2 if self.bframes else LIMIT_TICKS

    def seconds(self, ticks: int) -> float:
        return ticks / self.rate


def video_clock(preset: str, span_s: float | None) -> VideoClock | None:
    """The finest clock of :data:`RATES` that holds any steps over ``span_s`` seconds (the
    input's duration) for x264's ``preset``; 90 kHz when the span is not known (a live input,
    a followed file). :attr:`VideoClock.bound_ticks` is checked picture by picture in any
    case (a duration may understate the span). None when even a clock of 1 tick per second
    cannot hold the span."""
    if span_s is None or span_s != span_s:  # unknown (or NaN)
        return VideoClock(RATES[0], _bframes(preset))
    for rate in RATES:
        clock = VideoClock(rate, _bframes(preset))
        if span_s * rate <= clock.bound_ticks:
            return clock
    return None


def longest_span_s(preset: str) -> float:
    """The longest span any clock holds for ``preset`` (that of 1 tick per second)."""
    clock = VideoClock(RATES[-1], _bframes(preset))
    return clock.seconds(clock.bound_ticks)


def _bframes(preset: str) -> int:
    """x264's B-frames for ``preset`` (the most of any preset for a name it does not know:
    the encoder refuses that as it opens)."""
    return X264_BFRAMES.get(preset, max(X264_BFRAMES.values()))
