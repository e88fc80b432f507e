"""Things a stage asks the annotator to draw besides the tracked box (``ctx.overlays``).

Each kind is a small frozen dataclass; :meth:`vtrack.annotate.Annotator.draw` draws each by one
dispatch and refuses a kind it does not know (``TypeError``), so a new kind is added here and
there together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vtrack.geometry import Box


@dataclass(frozen=True)
class SearchWindow:
    """This frame's search window, drawn as a thin rectangle."""

    box: Box


@dataclass(frozen=True, eq=False)
class Particles:
    """Particle centres, an (N, 2) float array of x, y, drawn as small dots."""

    centres: np.ndarray


#: Every overlay kind.
Overlay = SearchWindow | Particles
