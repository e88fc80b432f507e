"""Options several commands share, declared once so they read and behave the same."""

from __future__ import annotations

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
