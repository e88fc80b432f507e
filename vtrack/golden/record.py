"""What the fixed-point stages share: one typed record in ``TrackContext.fixed``.

The first stage of a fixed chain creates it (``provides = {"fixed"}``), the later ones read and
fill it (``requires = {"fixed"}``). ``trace`` is this frame's row of ``trace.csv`` (``vtrack
vectors``), rebuilt every frame; ``iterations`` is S2's per-iteration trace of the frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class FixedRecord:
    """Model and per-frame values of a fixed-point chain (S0 or S2)."""

    #: S0: the 256 integer counters of eq. 2-3 and their largest value; S2: q_u (undivided).
    hist: np.ndarray | None = None
    hist_max: int = 0
    #: S0: eq. 4 as a table hue -> BP.
    bp_lut: np.ndarray | None = None
    #: S0: the integer S/V mask thresholds in force for BP (0, 0: no mask).
    sat_min: int = 0
    val_min: int = 0
    hue_divider_bits: int = 0
    #: S0: this frame's window ``(x, y, w, h)`` (integer, before clipping to the frame), its
    #: reference pixel and the hue / BP of its in-frame part.
    window: tuple[int, int, int, int] = (0, 0, 0, 0)
    ref: tuple[int, int] = (0, 0)
    #: S0: the target box size ``(w, h)`` in pixels, and the search window's size over it in
    #: permille (1000 while tracking; grows while the target is hidden).
    size: tuple[int, int] = (1, 1)
    growth: int = 1000
    bp: np.ndarray | None = None
    #: S0: this frame's measured centre in units of 2^-bits pixel: (x, y, bits).
    measured_fixed: tuple[int, int, int] = (0, 0, 0)
    #: S0: sum_bp over the initial box on the first frame (the occlusion reference).
    initial_sum: int = 0
    #: This frame's trace.csv row (column -> value), filled by the stages in chain order.
    trace: dict[str, Any] = field(default_factory=dict)
    #: S2: one dict per mean-shift iteration of this frame.
    iterations: list[dict[str, Any]] = field(default_factory=list)
    #: Which golden model wrote it: "s0" or "s2".
    model: str = "s0"
