"""Progress bars of the commands (tqdm on stderr, only in a terminal).

A bar appears only once there is progress to show: for ``vtrack run`` after the first frame is
tracked (so an error opening the input or starting the tracker is never preceded by an empty
bar), sized by the input's frame count (exact, or the container's duration x frame rate) and
capped by ``--frames``. It shows done / total, percent,
rate and ETA; without any count (a pipe) it shows frames done and the rate.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from tqdm import tqdm

    from vtrack.io import InputInfo


def terminal(quiet: bool) -> bool:
    """Whether to draw a bar: not ``--quiet`` and stderr is a terminal."""
    return not quiet and sys.stderr.isatty()


class FrameProgress:
    """``on_open`` / ``on_frame`` callbacks of :func:`vtrack.run.run` drawing a frame bar."""

    def __init__(self, enabled: bool, max_frames: int | None) -> None:
        self.enabled = enabled
        self.max_frames = max_frames
        self.bar: tqdm | None = None
        self.info: InputInfo | None = None

    def on_open(self, info: InputInfo) -> None:
        self.info = info

    def on_frame(self, done: int) -> None:
        if self.bar is None:
            if not self.enabled or self.info is None:
                return
            from tqdm import tqdm

            total = self.info.frame_count
            if self.max_frames is not None:
                total = min(total, self.max_frames) if total else self.max_frames
            self.bar = tqdm(total=total, unit="frame", desc=self.info.name, dynamic_ncols=True,
                            file=sys.stderr)
        if self.bar.total is not None and done > self.bar.total:  # the estimate was short
            self.bar.total = done
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
