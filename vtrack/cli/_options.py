"""Options several commands share, declared once so they read and behave the same."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import click


def _origin(ctx: click.Context, param: click.Parameter, value: str) -> int | None:
    return None if value == "auto" else int(value)


def gt_origin_option() -> Callable[[Any], Any]:
    """``--gt-origin auto|0|1`` of ``run``, ``batch`` and ``report``: the command receives
    None for auto (:func:`vtrack.evaluate.groundtruth.gt_origin_of` decides per file), else 0
    or 1."""
    return click.option(
        "--gt-origin", type=click.Choice(["auto", "0", "1"]), default="auto",
        show_default=True, callback=_origin,
        help="Origin of ground-truth boxes: 1 for MATLAB-style 1-based boxes (OTB), 0 for "
             "0-based. auto: 1 for groundtruth_rect.txt or groundtruth.txt inside a sequence "
             "folder (one holding img/), else 0 (name.gt.txt beside a video).")


class StartPoint(click.ParamType):
    """``--start``: a 0-based frame number (``75``) or a time in seconds (``2.5s``, as
    ``ffmpeg -ss``). Converts to ``(frame, seconds)``: ``(75, None)`` or ``(0, 2.5)``."""

    name = "start"

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> tuple[int, float | None]:
        if isinstance(value, tuple):
            return value
        text = str(value).strip()
        try:
            if text.lower().endswith("s"):
                seconds = float(text[:-1])
                if math.isfinite(seconds) and 0 <= seconds <= MAX_START_S:
                    return 0, seconds
            elif text.isdigit():
                return int(text), None
        except ValueError:
            pass
        self.fail(f"{value!r}: expected a frame number (75) or a time in seconds (2.5s, at "
                  f"most {MAX_START_S:g}s)", param, ctx)


#: The latest start time ``--start Ts`` accepts (a year), so a frame number fits any rate.
MAX_START_S = 366 * 24 * 3600.0
