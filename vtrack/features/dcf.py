"""Discriminative correlation filters over multi-channel features, and the confidence of their
responses.

- :class:`CorrelationFilter`: the multi-channel filter of DSST (Danelljan et al., BMVC 2014,
  eqs. 4-6; the same closed form as MOSSE, Bolme et al., CVPR 2010), learnt in the Fourier domain
  with a running average of numerator and denominator (learning rate ``rate``, regulariser
  ``lam``). Translation uses 2-D features (rows, cols, channels); scale uses 1-D ones (DSST's
  scale filter: samples along the scale axis).
- :func:`apce` (Wang et al., LMCF, CVPR 2017, eq. 7) and :func:`psr` (Bolme et al., MOSSE):
  how sharp and unique a response's peak is.
"""

from __future__ import annotations

import cv2
import numpy as np


def hann(n: int) -> np.ndarray:
    """Hann window of ``n`` samples (0 at both ends), float32."""
    if n < 2:
        return np.ones(n, np.float32)
    return (0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / (n - 1))).astype(np.float32)


def hann2d(rows: int, cols: int) -> np.ndarray:
    """Separable 2-D Hann window (rows, cols, 1): the cosine window of KCF/DSST."""
    return (hann(rows)[:, None] * hann(cols)[None, :])[..., None]


def gaussian_label(rows: int, cols: int, sigma: float) -> np.ndarray:
    """Desired response: a Gaussian of ``sigma`` cells with its peak at (0, 0), wrapped around
    (KCF's circularly shifted label), so that a response's argmax is the displacement."""
    dy = np.fft.ifftshift(np.arange(rows) - rows // 2)
    dx = np.fft.ifftshift(np.arange(cols) - cols // 2)
    return np.exp(-0.5 * (dy[:, None] ** 2 + dx[None, :] ** 2) / sigma**2).astype(np.float32)


def gaussian_label_1d(n: int, sigma: float) -> np.ndarray:
    """1-D Gaussian label of DSST's scale filter, peak at index 0 (wrapped)."""
    d = np.fft.ifftshift(np.arange(n) - n // 2)
    return np.exp(-0.5 * d**2 / sigma**2).astype(np.float32)


class CorrelationFilter:
    """A multi-channel correlation filter (DSST eqs. 4-6) along ``axes`` of its samples.

    ``learn(x)`` folds sample ``x`` (features, channels last) into the model; ``respond(z)`` is
    the filter's real response on ``z``, whose argmax (wrapped) is ``z``'s displacement from the
    learnt samples.
    """

    def __init__(self, label: np.ndarray, lam: float, rate: float) -> None:
        self.axes = tuple(range(label.ndim))
        self.shape = label.shape
        # real samples: half the spectrum carries everything (rfftn)
        self.label_f = np.fft.rfftn(label, axes=self.axes).astype(np.complex64)[..., None]
        self._label_conj = np.conj(self.label_f)
        self.lam = lam
        self.rate = rate
        self.numerator: np.ndarray | None = None
        self.denominator: np.ndarray | None = None
        self._filter: np.ndarray | None = None
        #: A wide sample's size and the filter's kernel padded to it, transformed (respond_wide).
        self._wide: tuple[tuple[int, ...], np.ndarray] | None = None

    def spectrum(self, x: np.ndarray) -> np.ndarray:
        """The Fourier transform of sample ``x`` along the filter's axes, half of it as
        ``np.fft.rfftn`` gives (what the ``*_spectrum`` methods take: one transform serves a
        frame's response and its learning)."""
        return real_spectrum(x, len(self.axes))

    def learn(self, x: np.ndarray, rate: float | None = None) -> None:
        """Update with sample ``x``; the first sample replaces the model (rate 1)."""
        self.learn_spectrum(self.spectrum(x), rate)

    def learn_spectrum(self, xf: np.ndarray, rate: float | None = None) -> None:
        """:meth:`learn` from the sample's spectrum."""
        numerator = self._label_conj * xf
        denominator = np.einsum("...k,...k->...", xf.real, xf.real)
        denominator += np.einsum("...k,...k->...", xf.imag, xf.imag)
        if self.numerator is None or self.denominator is None:
            self.numerator, self.denominator = numerator, denominator
        else:
            # (1 - eta) * model + eta * sample, in place: the model's arrays are its own
            eta = self.rate if rate is None else rate
            numerator *= eta
            self.numerator *= 1 - eta
            self.numerator += numerator
            denominator *= eta
            self.denominator *= 1 - eta
            self.denominator += denominator
        # the conjugate filter, as every response takes it (DSST eq. 6). NumPy divides a
        # complex number by a real one as a product with the real's single-precision
        # reciprocal, which is what this computes, without complex division's extra work.
        inverse = np.divide(1, self.denominator + self.lam)
        conjugate = np.multiply(self.numerator, inverse[..., None])
        self._filter = np.conjugate(conjugate, out=conjugate)
        self._wide = None

    def constrain(self, support: np.ndarray) -> None:
        """Replace the learnt filter by the one whose spatial kernel is zero outside
        ``support`` (a (rows, cols) 0/1 mask in sample coordinates) that fits the learnt samples
        best: the spatially constrained filter of CSR-DCF (Lukezic et al., CVPR 2017, eqs. 4-8)
        and BACF (Kiani Galoogahi et al., ICCV 2017) with DSST's model (the sample energy
        summed over channels), solved by ADMM (:func:`constrained_filter`). The model's
        numerator is set so that later learning blends new samples into that filter as into
        any other (the denominator is kept). 2-D filters only."""
        assert self.numerator is not None and self.denominator is not None, "constrain before learn"
        energy = self.denominator[..., None] + self.lam
        solution = constrained_filter(self.numerator, energy, support, self.shape)
        self.numerator = (solution * energy).astype(np.complex64)
        self._filter = np.conj(solution)
        self._wide = None

    def respond(self, z: np.ndarray) -> np.ndarray:
        """Response to sample ``z`` (same shape as the learnt ones), real, peak at (0, ...) for
        no displacement."""
        return self.respond_spectrum(self.spectrum(z))

    def respond_spectrum(self, zf: np.ndarray) -> np.ndarray:
        """:meth:`respond` to the sample whose spectrum is ``zf``."""
        assert self._filter is not None, "respond before learn"
        product = np.einsum("...k,...k->...", self._filter, zf)
        return np.fft.irfftn(product, s=self.shape, axes=self.axes)

    def respond_wide(self, z: np.ndarray, rank: int | None = None) -> np.ndarray:
        """The response over a sample ``z`` larger than the learnt ones (2-D filters): the
        filter's spatial kernel, zero-padded to ``z``'s size, convolved with it (circularly).
        Index ``p`` scores a target centred at ``p`` plus the learnt samples' centre cell.

        ``rank``: the kernel's channels are first reduced to that many (ECO's projection,
        Danelljan et al., CVPR 2017: the kernel's leading right singular vectors as cells x
        channels), and so are ``z``'s, so that only ``rank`` channels are transformed."""
        assert self._filter is not None, "respond before learn"
        size = z.shape[:2]
        if self._wide is None or self._wide[0] != (size, rank):
            kernel = np.fft.irfftn(self._filter, s=self.shape, axes=(0, 1)).astype(np.float32)
            projection = None
            if rank is not None and rank < kernel.shape[2]:
                # the leading right singular vectors: the leading eigenvectors of the channels'
                # Gram matrix (OpenCV's: NumPy's would wake a BLAS thread pool that then spins)
                gram = cv2.mulTransposed(kernel.reshape(-1, kernel.shape[2]), True,
                                         dtype=cv2.CV_64F)
                _, _, vectors = cv2.eigen(gram)  # rows, by decreasing eigenvalue
                projection = np.ascontiguousarray(vectors[:rank].T, np.float32)
                kernel = _project(kernel, projection)
            padded = np.zeros(size + kernel.shape[2:], np.float32)
            # the kernel's wrapped offsets (negative ones at the end) keep their offsets
            ys, xs = (np.rint(np.fft.fftfreq(n, 1 / n)).astype(int) % m
                      for n, m in zip(self.shape, size, strict=True))
            padded[np.ix_(ys, xs)] = kernel
            # kept until the filter learns again (it learns nothing while the target is lost)
            self._wide = ((size, rank), real_spectrum(padded, 2), projection)
        _, kernel_f, projection = self._wide
        if projection is not None:
            z = _project(z, projection)
        product = np.einsum("...k,...k->...", kernel_f, real_spectrum(z, 2))
        return np.fft.irfftn(product, s=size, axes=(0, 1))


#: ADMM's penalty for :func:`constrained_filter`, in units of the samples' mean spectral energy,
#: and its iterations: kept fixed (no growth), 16 iterations bring the objective within ~1% of
#: its optimum on the first frames of ``../shared/data`` (a growing penalty from CSR-DCF's
#: start, or fewer iterations, stop short of it).
ADMM_PENALTY = 10.0
ADMM_ITERATIONS = 16


def constrained_filter(numerator: np.ndarray, energy: np.ndarray, support: np.ndarray,
                       shape: tuple[int, ...]) -> np.ndarray:
    """The filter spectrum ``W`` (half spectra, channels last) that minimises DSST's
    ``sum |W|^2 energy - 2 Re(conj(W) numerator)`` over the frequencies while its spatial
    kernel is zero outside ``support``: ADMM as in CSR-DCF (Lukezic et al., CVPR 2017,
    section 3.2): a free filter in the Fourier domain, one constrained in space, and their
    difference driven to zero. Without the constraint the minimiser is ``numerator / energy``,
    DSST's filter; with it, the filter cannot use the background around the target as
    evidence, yet is still fitted to respond only at the target over the whole sample."""
    mask = support.astype(np.float32)[..., None]
    penalty = ADMM_PENALTY * float(np.mean(energy))

    def cut_to_support(spectrum: np.ndarray) -> np.ndarray:
        kernel = np.fft.irfftn(spectrum, s=shape, axes=(0, 1))
        return real_spectrum((mask * kernel).astype(np.float32), 2)

    constrained = cut_to_support(numerator / energy)
    multiplier = np.zeros_like(constrained)
    for _ in range(ADMM_ITERATIONS):
        free = (numerator + penalty * constrained - multiplier) / (energy + penalty)
        constrained = cut_to_support(free + multiplier / penalty)
        multiplier += penalty * (free - constrained)
    return constrained


def _project(x: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """``x``'s channels (last axis) times ``projection`` (channels x rank), by OpenCV's
    per-element transform (a matrix product would wake a BLAS thread pool that then spins)."""
    return cv2.transform(np.ascontiguousarray(x, np.float32), projection.T)


#: Above this many cells a 2-D sample's channels are transformed one by one with OpenCV: NumPy's
#: transform over the first two axes of a channels-last array is 2.3x faster on a search
#: region's 35x39 cells but 1.4x slower on the frame-wide 144x256 of re-detection.
NUMPY_DFT_MAX_CELLS = 4096


def real_spectrum(x: np.ndarray, axes: int) -> np.ndarray:
    """``np.fft.rfftn(x, axes=range(axes))`` of a real sample with channels last (``axes`` 1:
    along the first axis; 2: over the first two), in single precision. Along one axis every
    channel goes through OpenCV's DFT in one call, as rows (several times faster than NumPy's
    on these short float32 signals); over two, NumPy transforms all channels at once on a
    search region's size, OpenCV one channel at a time on larger samples
    (:data:`NUMPY_DFT_MAX_CELLS`)."""
    flags = cv2.DFT_COMPLEX_OUTPUT
    if axes == 1:
        rows = np.ascontiguousarray(x.reshape(x.shape[0], -1).T, dtype=np.float32)
        full = cv2.dft(rows, flags=flags | cv2.DFT_ROWS)
        half = full[:, : x.shape[0] // 2 + 1].view(np.complex64)[..., 0]
        return half.T.reshape((half.shape[1],) + x.shape[1:])
    rows, cols = x.shape[:2]
    if rows * cols <= NUMPY_DFT_MAX_CELLS:
        return np.fft.rfftn(np.asarray(x, np.float32), axes=(0, 1))
    out = np.empty((x.shape[2], rows, cols // 2 + 1), np.complex64)
    for c in range(x.shape[2]):
        full = cv2.dft(np.ascontiguousarray(x[..., c], dtype=np.float32), flags=flags)
        out[c] = full[:, : cols // 2 + 1].view(np.complex64)[..., 0]
    return out.transpose(1, 2, 0)


def shift_spectrum(xf: np.ndarray, dy: float, dx: float, cols: int) -> np.ndarray:
    """The spectrum (as :func:`real_spectrum` gives it, over the first two axes of a sample
    ``cols`` wide) of that sample moved by (``dy``, ``dx``) cells, fractions too: the sample's
    content at (``dy``, ``dx``) comes to (0, 0), circularly. ECO (Danelljan et al., CVPR 2017)
    learns from the detection sample moved this way instead of cutting and describing the
    region again at the found position."""
    ky = np.fft.fftfreq(xf.shape[0])[:, None]
    kx = (np.arange(xf.shape[1]) / cols)[None, :]
    ramp = np.exp(2j * np.pi * (ky * dy + kx * dx)).astype(np.complex64)
    return xf * ramp[..., None]


def apce(response: np.ndarray) -> float:
    """Average peak-to-correlation energy (LMCF eq. 7): |Fmax - Fmin|^2 / mean((F - Fmin)^2).
    Large for one sharp peak, small for a flat or multi-peaked response."""
    fmin = float(response.min())
    spread = float(np.mean((response - fmin) ** 2))
    if spread <= 0:
        return 0.0
    return (float(response.max()) - fmin) ** 2 / spread


def psr(response: np.ndarray, exclude: int = 5) -> float:
    """Peak-to-sidelobe ratio (MOSSE): (peak - mean) / std of the response outside the
    (2*exclude+1)^2 window around the peak (a centred response)."""
    r, c = np.unravel_index(int(np.argmax(response)), response.shape)
    mask = np.ones(response.shape, bool)
    mask[max(r - exclude, 0): r + exclude + 1, max(c - exclude, 0): c + exclude + 1] = False
    side = response[mask]
    if side.size < 2:
        return 0.0
    std = float(side.std())
    return (float(response[r, c]) - float(side.mean())) / std if std > 0 else 0.0


def subpixel_peak(response: np.ndarray, r: int, c: int) -> tuple[float, float]:
    """Parabolic refinement of the peak at (r, c) along each axis (wrapped neighbours)."""
    rows, cols = response.shape

    def offset(minus: float, centre: float, plus: float) -> float:
        denom = minus - 2 * centre + plus
        return 0.0 if denom >= 0 else float(np.clip(0.5 * (minus - plus) / denom, -0.5, 0.5))

    dr = offset(response[(r - 1) % rows, c], response[r, c], response[(r + 1) % rows, c])
    dc = offset(response[r, (c - 1) % cols], response[r, c], response[r, (c + 1) % cols])
    return r + dr, c + dc
