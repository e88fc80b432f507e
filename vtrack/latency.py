"""Per-frame latency of a live run (frame received -> its result written), in flat memory."""

from __future__ import annotations

import math

import numpy as np

#: Bins are this ratio wide (1%): percentiles within 0.5% of the exact value.
_RATIO = 1.01
#: Latencies below this (10 us) share the first bin; 2000 bins reach past an hour.
_FLOOR_S = 1e-5
_BINS = 2000


class Latencies:
    """A histogram of latencies with bins 1% wide: any number of frames in 16 kB."""

    def __init__(self) -> None:
        self._counts = np.zeros(_BINS, np.int64)
        self.count = 0
        self.max_s = 0.0

    def add(self, seconds: float) -> None:
        """Record one frame's latency."""
        k = 0 if seconds <= _FLOOR_S else int(math.log(seconds / _FLOOR_S, _RATIO))
        self._counts[min(k, _BINS - 1)] += 1
        self.count += 1
        self.max_s = max(self.max_s, seconds)

    def percentile(self, q: float) -> float | None:
        """The ``q``-th percentile (0..100) in seconds (the middle of its 1% bin; never above
        the largest latency seen); None before any frame."""
        if not self.count:
            return None
        rank = max(1, math.ceil(q / 100.0 * self.count))
        k = int(np.searchsorted(np.cumsum(self._counts), rank))
        return min(_FLOOR_S * _RATIO ** (k + 0.5), self.max_s)

    def to_dict(self) -> dict[str, float | int | None]:
        """``run.json``'s ``latency``: frames measured, p50, p99 and max in milliseconds."""
        def ms(value: float | None) -> float | None:
            return None if value is None else round(value * 1e3, 3)

        return {"frames": self.count, "p50_ms": ms(self.percentile(50)),
                "p99_ms": ms(self.percentile(99)), "max_ms": ms(self.max_s if self.count else None)}
