"""fDSST's scale filter: the target's size from a 1-D correlation filter over a scale pyramid.

Danelljan, Hager, Khan and Felsberg, "Discriminative scale space tracking", TPAMI 2017 (fDSST),
section 4, which speeds up the scale filter of their BMVC 2014 DSST without losing accuracy:

- ``n`` samples of the target (fDSST: 17) at sizes ``step^(k * n_interp / n)`` times the current
  one (``k`` from ``-(n-1)/2`` to ``(n-1)/2``): the same span as DSST's ``n_interp`` = 33 scales,
  half the samples. Each sample is resampled to a fixed model size of at most ``model_area``
  pixels and described by fHOG.
- fDSST compresses the samples' features to ``n`` dimensions (its 'MAX' setting) before the
  transforms along the scale axis. With every dimension kept, the projection on the template's
  own basis leaves each inner product with the template as it is, so the response is DSST's
  exactly: here it is computed from the ``n`` x ``n`` inner products of the samples with the
  template (a circular cross-correlation along the scale axis), which is that compression's
  saving without its QR decompositions.
- The response, computed at the ``n`` sampled scales, is interpolated to ``n_interp`` scales in
  the Fourier domain (zero padding of its spectrum, fDSST section 4.2); its peak is the size
  ratio to apply.

Defaults are the paper's: 17 samples interpolated to 33 scales, step 1.02, learning rate 0.025,
lambda 0.01, a 512-pixel model, a Gaussian label of ``n_interp / 16`` interpolated scales.
"""

from __future__ import annotations

import math

import numpy as np

from vtrack.features.dcf import hann
from vtrack.features.fhog import fhog
from vtrack.features.patch import ConvertedWindow, region_patch
from vtrack.frame import Frame

#: fDSST's label width: n_interp / 16 interpolated scales.
SCALE_SIGMA_FACTOR = 1 / 16
#: DSST's regulariser of the scale filter.
SCALE_LAMBDA = 1e-2


class ScaleFilter:
    """An fDSST scale filter for a target first seen at ``width`` x ``height`` frame pixels:
    ``scales`` samples, the response interpolated to ``interp_scales`` sizes."""

    def __init__(self, width: float, height: float, scales: int, step: float, rate: float,
                 model_area: int, cell: int, interp_scales: int | None = None) -> None:
        interp = interp_scales or scales
        exponents = (np.arange(scales) - (scales - 1) / 2) * interp / scales
        self.factors = step ** exponents
        #: the sizes the interpolated response stands for, centred (index interp // 2: 1)
        self.interp_factors = step ** (np.arange(interp) - interp // 2)
        self.interp_scales = interp
        self.window = hann(scales)[None, :]
        shrink = min(1.0, math.sqrt(model_area / (width * height)))
        self.model_w = max(int(width * shrink) // cell, 2) * cell
        self.model_h = max(int(height * shrink) // cell, 2) * cell
        # a thin target's two cells across would take its length past the model's area: the
        # length is cut to fit (the samples' features, and so their cost, stay bounded)
        if self.model_w * self.model_h > model_area:
            if self.model_w < self.model_h:
                self.model_h = max(model_area // self.model_w // cell, 2) * cell
            else:
                self.model_w = max(model_area // self.model_h // cell, 2) * cell
        self.cell = cell
        self.rate = rate
        # the label over the samples' exponents, peak at index 0 (wrapped)
        wrapped = np.roll(exponents, -((scales - 1) // 2))
        label = np.exp(-0.5 * wrapped**2 / (interp * SCALE_SIGMA_FACTOR) ** 2)
        self.label_f = np.fft.fft(label)
        #: the running average of the windowed samples (DSST's numerator is the label's
        #: spectrum times its transform's conjugate) and of their energy spectrum (denominator)
        self.template: np.ndarray | None = None  # (features, scales)
        self.denominator: np.ndarray | None = None

    def samples(self, frame: Frame, cx: float, cy: float, width: float, height: float,
                converted: ConvertedWindow | None = None) -> np.ndarray:
        """(features, scales) samples of the target centred on (cx, cy) at ``width`` x
        ``height`` times each scale factor, under the Hann window along the scales. The
        samples are laid side by side and described by one fHOG call (each is a whole number
        of cells wide, so no cell straddles two). They are cut from ``converted`` (this
        frame's pixels already converted) where it holds them all."""
        # the largest sample's pixels are converted once; every sample is cut from them
        largest = float(self.factors.max())
        if converted is None or not converted.covers_region(frame, cx, cy, width * largest,
                                                             height * largest):
            converted = ConvertedWindow.around(frame, cx, cy, width * largest, height * largest)
        strip = np.concatenate(
            [region_patch(frame, cx, cy, width * f, height * f, self.model_w, self.model_h,
                          converted) for f in self.factors], axis=1)
        hog = fhog(strip, self.cell)
        rows, cols = self.model_h // self.cell, self.model_w // self.cell
        n = len(self.factors)
        per_scale = hog.reshape(rows, n, cols, hog.shape[2]).transpose(0, 2, 3, 1)
        return per_scale.reshape(-1, n).astype(np.float64) * self.window

    def learn(self, samples: np.ndarray, first: bool = False) -> None:
        """Fold ``samples`` into the template and the denominator (DSST eqs. 4-5, learning
        rate ``rate``); the first replaces them."""
        energy = np.fft.fft(_correlation(samples, samples)).real  # sum of |F(x_l)|^2
        if first or self.template is None or self.denominator is None:
            self.template, self.denominator = samples, energy
            return
        self.template = (1 - self.rate) * self.template + self.rate * samples
        self.denominator = (1 - self.rate) * self.denominator + self.rate * energy

    def ratio(self, samples: np.ndarray) -> float:
        """The size ratio whose (interpolated) scale the filter matches best (1: unchanged, also
        when no scale matches better than another)."""
        assert self.template is not None and self.denominator is not None, "ratio before learn"
        # DSST eq. 6: sum over features of conj(F(template)) F(sample), times the label
        response_f = self.label_f * np.fft.fft(_correlation(self.template, samples)) / (
            self.denominator + SCALE_LAMBDA)
        response = np.fft.fftshift(np.fft.ifft(_resized_spectrum(
            response_f, self.interp_scales)).real)
        peak = float(np.abs(response).max())
        if peak == 0.0 or float(np.ptp(response)) <= 1e-6 * peak:
            return 1.0  # a flat response (a featureless patch) is no evidence of a new size
        return float(self.interp_factors[int(np.argmax(response))])


def _correlation(template: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """Circular cross-correlation along the scale axis, summed over features: ``c[t] = sum_s
    <template[:, s], samples[:, s + t]>`` (whose transform is ``sum_l conj(F(template_l))
    F(samples_l)``), from the scales' inner products."""
    n = template.shape[1]
    inner = template.T @ samples
    shifted = (np.arange(n)[:, None] + np.arange(n)[None, :]) % n
    return inner[np.arange(n)[:, None], shifted].sum(axis=0)


def _resized_spectrum(spectrum: np.ndarray, length: int) -> np.ndarray:
    """A 1-D spectrum zero-padded (or cut) to ``length`` frequencies, scaled so the signal keeps
    its values: its inverse transform is the signal interpolated to ``length`` samples (fDSST
    section 4.2)."""
    n = len(spectrum)
    if n == length:
        return spectrum
    shortest = min(n, length)
    out = np.zeros(length, spectrum.dtype)
    low, high = math.ceil(shortest / 2), (shortest - 1) // 2
    out[:low] = spectrum[:low]
    if high:
        out[-high:] = spectrum[-high:]
    return out * (length / n)
