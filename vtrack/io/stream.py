"""``--stream FILE|-``: one JSON line per tracked frame, flushed as soon as the frame is done.

A reader downstream (``tail -f``, a pipe) follows the target while it moves; ``track.csv`` stays
the file that is whole only once the run has ended. Each line holds ``frame`` (the source's own
number), ``time_s`` (the frame's timestamp), ``x``, ``y``, ``w``, ``h`` (null while lost),
``state``, ``score`` and ``extras`` (the stages' extra columns); the multi-target configs add
``tracks``: the confirmed tracks as ``tracks.csv`` lists them (``id``, ``x``, ``y``, ``w``,
``h``, ``conf``, ``state``). Non-finite numbers are written as null.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys
from typing import IO, Any

from vtrack.errors import OutputError
from vtrack.io.files import Closing, os_reason
from vtrack.pipeline import FrameResult
from vtrack.stages.base import TrackStatus

#: ``--stream -``: the lines go to standard output.
STDOUT = "-"


def _number(value: Any) -> Any:
    """A JSON-ready cell: NumPy scalars as Python ones, NaN and infinities as None."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def frame_record(result: FrameResult, multi_target: bool) -> dict[str, Any]:
    """What one stream line says about ``result`` (see the module docstring)."""
    box = result.box
    record: dict[str, Any] = {
        "frame": result.index,
        "time_s": _number(result.time_s),
        "x": None if box is None else _number(box.x),
        "y": None if box is None else _number(box.y),
        "w": None if box is None else _number(box.w),
        "h": None if box is None else _number(box.h),
        "state": str(result.state),
        "score": _number(result.score),
        "extras": {key: _number(value) for key, value in result.extras.items()},
    }
    if multi_target:
        record["tracks"] = [
            {"id": t.id, "x": _number(t.box.x), "y": _number(t.box.y), "w": _number(t.box.w),
             "h": _number(t.box.h), "conf": _number(t.confidence), "state": str(t.state)}
            for t in result.tracks if t.state == TrackStatus.CONFIRMED]
    return record


class StreamWriter(Closing):
    """Writes :func:`frame_record` lines to ``target`` (a path, or ``-`` for standard output),
    each flushed before :meth:`write` returns. OutputError names the target when a line cannot
    be written (a full disk, a reader that went away)."""

    def __init__(self, target: str, multi_target: bool) -> None:
        self.target = target
        self.multi_target = multi_target
        self.lines = 0
        try:
            self._file: IO[str] = sys.stdout if target == STDOUT else open(  # noqa: SIM115
                target, "w", encoding="utf-8")
        except OSError as exc:
            raise OutputError(f"--stream {target}: {os_reason(exc)}") from None

    def write(self, result: FrameResult) -> None:
        line = json.dumps(frame_record(result, self.multi_target), separators=(",", ":"))
        try:
            self._file.write(line + "\n")
            self._file.flush()
        except (OSError, ValueError) as exc:
            raise OutputError(f"--stream {self.target}: {os_reason(exc)}") from None
        self.lines += 1

    def close(self) -> None:
        if self.target == STDOUT:
            with contextlib.suppress(OSError, ValueError):  # the reader went away: write()
                self._file.flush()                           # has said so already
            return
        try:
            self._file.close()  # flushes what a failed write left in the buffer: fails again
        except (OSError, ValueError) as exc:
            raise OutputError(f"--stream {self.target}: {os_reason(exc)}") from None
