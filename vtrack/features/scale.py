"""DSST's scale filter: the target's size from a 1-D correlation filter over a scale pyramid.

Danelljan, Hager, Khan and Felsberg, "Accurate scale estimation for robust visual tracking",
BMVC 2014, section 3: ``n`` samples of the target at sizes ``step^k`` times the current one
(``k`` from ``-(n-1)/2`` to ``(n-1)/2``), each resampled to a fixed model size of at most
``model_area`` pixels and described by fHOG; the samples, stacked along the scale axis under a
Hann window, train a 1-D filter whose Gaussian label (``sigma = sqrt(n) / 4`` samples) peaks at
the current size. The response's peak is the size ratio to apply. Defaults are the paper's
(33 scales, step 1.02, learning rate 0.025, lambda 0.01, 512-pixel model).
"""

from __future__ import annotations

import math

import numpy as np

from vtrack.features.dcf import CorrelationFilter, gaussian_label_1d, hann
from vtrack.features.fhog import fhog
from vtrack.features.patch import ConvertedWindow, region_patch
from vtrack.frame import Frame

#: DSST's label width: sqrt(n) / 4 samples.
SCALE_SIGMA_FACTOR = 0.25
#: DSST's regulariser of the scale filter.
SCALE_LAMBDA = 1e-2


class ScaleFilter:
    """A DSST scale filter for a target first seen at ``width`` x ``height`` frame pixels."""

    def __init__(self, width: float, height: float, scales: int, step: float, rate: float,
                 model_area: int, cell: int) -> None:
        self.factors = step ** (np.arange(scales) - (scales - 1) / 2)
        self.window = hann(scales)[:, None]
        shrink = min(1.0, math.sqrt(model_area / (width * height)))
        self.model_w = max(int(width * shrink) // cell, 2) * cell
        self.model_h = max(int(height * shrink) // cell, 2) * cell
        self.cell = cell
        label = gaussian_label_1d(scales, math.sqrt(scales) * SCALE_SIGMA_FACTOR)
        self.filter = CorrelationFilter(label, SCALE_LAMBDA, rate)

    def samples(self, frame: Frame, cx: float, cy: float, width: float,
                height: float) -> np.ndarray:
        """(scales, features) samples of the target centred on (cx, cy) at ``width`` x
        ``height`` times each scale factor. The samples are laid side by side and described by
        one fHOG call (each is a whole number of cells wide, so no cell straddles two)."""
        # the largest sample's pixels are converted once; every sample is cut from them
        largest = float(self.factors.max())
        converted = ConvertedWindow.around(frame, cx, cy, width * largest, height * largest)
        strip = np.concatenate(
            [region_patch(frame, cx, cy, width * f, height * f, self.model_w, self.model_h,
                          converted) for f in self.factors], axis=1)
        hog = fhog(strip, self.cell)
        rows, cols = self.model_h // self.cell, self.model_w // self.cell
        n = len(self.factors)
        per_scale = hog.reshape(rows, n, cols, hog.shape[2]).transpose(1, 0, 2, 3)
        return per_scale.reshape(n, -1) * self.window

    def learn(self, samples: np.ndarray, first: bool = False) -> None:
        self.filter.learn(samples, 1.0 if first else None)

    def ratio(self, samples: np.ndarray) -> float:
        """The size ratio whose sample the filter matches best (1: unchanged)."""
        response = np.fft.fftshift(self.filter.respond(samples))
        return float(self.factors[int(np.argmax(response))])
