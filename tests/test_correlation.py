"""The parts `robust` is built from (issue 20): fHOG, the correlation filter, its confidence
measures, the colour histograms, DSST's scale filter and the fixed-size patch, each against
what its paper promises, on generated images."""

from __future__ import annotations

import math
import subprocess
import sys

import cv2
import numpy as np
import pytest

from vtrack.features.colour import ColourHistograms, box_mean
from vtrack.features.dcf import (
    CorrelationFilter,
    apce,
    constrained_filter,
    gaussian_label,
    hann2d,
    psr,
    real_spectrum,
    shift_spectrum,
    subpixel_peak,
)
from vtrack.features.fhog import CHANNELS, fhog
from vtrack.features.patch import ConvertedWindow, area_resized, region_patch
from vtrack.features.scale import ScaleFilter
from vtrack.frame import BgrFrame, GrayFrame, I420Frame
from vtrack.geometry import Window
from vtrack.stages.robust_model import support_mask


def texture(height: int, width: int, seed: int = 0) -> np.ndarray:
    """A smooth random texture (uint8 BGR): gradients everywhere, no periodicity."""
    rng = np.random.default_rng(seed)
    noise = rng.integers(0, 256, (height // 4 + 1, width // 4 + 1, 3), dtype=np.uint8)
    return cv2.resize(noise, (width, height), interpolation=cv2.INTER_CUBIC)


def test_fhog_has_31_channels_per_cell_and_is_zero_on_a_flat_patch() -> None:
    features = fhog(texture(64, 48), 4)
    assert features.shape == (16, 12, CHANNELS)
    assert features.dtype == np.float32
    assert features.max() <= 0.5 + 1e-6 and features.min() >= 0
    assert np.all(fhog(np.full((32, 32, 3), 90, np.uint8), 4) == 0)


def test_the_cached_cell_grids_cannot_be_written() -> None:
    """fhog's cell index and the colour model's cell centres are cached (lru_cache): every
    caller gets the same array, so one that wrote into it would change every later call's.
    They are read only."""
    from vtrack.features.colour import _cell_centres
    from vtrack.features.fhog import _cell_index

    for grid in (_cell_index(3, 4, 4), _cell_centres(40, 50, 3, 4, 4)):
        with pytest.raises(ValueError, match="read-only"):
            grid[0, 0] = 1
    fhog(np.zeros((16, 16), np.uint8))  # which still reads it


def test_fhog_follows_the_image_cell_by_cell() -> None:
    """Shifting the image by one cell shifts the features by one cell (away from the borders)."""
    image = texture(80, 80)
    shifted = np.roll(image, 4, axis=1)
    a, b = fhog(image, 4), fhog(shifted, 4)
    assert np.allclose(a[2:-2, 2:-3], b[2:-2, 3:-2], atol=1e-5)


def test_fhog_sees_orientation() -> None:
    """Vertical stripes put their energy in the horizontal-gradient bins, horizontal ones in
    the vertical-gradient bins."""
    stripes = np.tile(((np.arange(64) // 4) % 2 * 255).astype(np.uint8), (64, 1))
    vertical = fhog(stripes, 4)[..., 18:27].sum(axis=(0, 1))
    horizontal = fhog(stripes.T.copy(), 4)[..., 18:27].sum(axis=(0, 1))
    assert int(np.argmax(vertical)) == 0  # gradient along x: orientation bin 0
    assert int(np.argmax(horizontal)) == 4  # gradient along y: 90 degrees of 180 in 9 bins


@pytest.mark.parametrize("shift", [(0, 0), (3, -2), (-5, 4)])
def test_filter_response_peaks_at_the_displacement(shift: tuple[int, int]) -> None:
    """DSST eq. 6: a filter learnt on a sample responds to the sample moved by (dy, dx) with a
    peak at (dy, dx) (wrapped)."""
    rng = np.random.default_rng(1)
    sample = rng.random((24, 30, 8)).astype(np.float32)
    filt = CorrelationFilter(gaussian_label(24, 30, 1.5), lam=1e-3, rate=0.02)
    filt.learn(sample)
    response = filt.respond(np.roll(sample, shift, axis=(0, 1)))
    peak = np.unravel_index(int(np.argmax(response)), response.shape)
    assert (int(peak[0]), int(peak[1])) == (shift[0] % 24, shift[1] % 30)


def test_wide_response_is_the_response_at_the_learnt_size() -> None:
    rng = np.random.default_rng(3)
    sample = rng.random((21, 25, 4)).astype(np.float32) * hann2d(21, 25)
    filt = CorrelationFilter(gaussian_label(21, 25, 1.5), lam=1e-3, rate=0.02)
    filt.learn(sample)
    probe = rng.random((21, 25, 4)).astype(np.float32)
    assert np.allclose(filt.respond_wide(probe), filt.respond(probe), atol=1e-5)


def test_wide_response_through_fewer_channels_is_exact_for_a_kernel_of_that_rank() -> None:
    """``rank``: the kernel's channels reduced to their leading singular vectors, and the
    sample's with them. A filter learnt from a sample whose 12 channels mix 3 is a kernel of
    rank 3: through 3 channels its response is the full one (and through 12, trivially)."""
    rng = np.random.default_rng(5)
    base = rng.random((21, 25, 3)).astype(np.float32)
    mixed = base @ rng.random((3, 12)).astype(np.float32)
    filt = CorrelationFilter(gaussian_label(21, 25, 1.5), lam=1e-3, rate=0.02)
    filt.learn(mixed * hann2d(21, 25))
    probe = rng.random((48, 60, 12)).astype(np.float32)
    full = filt.respond_wide(probe)
    assert np.allclose(filt.respond_wide(probe, rank=3), full, atol=1e-4 * np.abs(full).max())
    assert np.allclose(filt.respond_wide(probe, rank=12), full, atol=1e-5)
    assert not np.allclose(filt.respond_wide(probe, rank=2), full,
                           atol=1e-2 * np.abs(full).max())


@pytest.mark.parametrize("rank", [None, 10])
@pytest.mark.parametrize("where", [(20, 30), (70, 130), (95, 15)])
def test_wide_response_finds_the_target_anywhere_in_a_larger_image(where, rank) -> None:
    """A filter learnt on fHOG of a textured target, windowed as the tracker learns it, scores
    the whole image (through all 31 channels, or 10 as the tracker's frame-wide search): its
    peak plus the sample's centre cell is where the target is."""
    cell, rows, cols = 4, 16, 20
    image = texture(rows * cell * 8, cols * cell * 8, seed=4)  # 128 x 160 cells
    target = texture(8 * cell, 10 * cell, seed=5)
    cy, cx = where  # the target's centre cell
    y0, x0 = (cy - 4) * cell, (cx - 5) * cell
    image[y0:y0 + 8 * cell, x0:x0 + 10 * cell] = target
    features = fhog(image, cell)
    sample = features[cy - rows // 2: cy - rows // 2 + rows, cx - cols // 2: cx - cols // 2 + cols]
    filt = CorrelationFilter(gaussian_label(rows, cols, 1.0), lam=1e-3, rate=0.02)
    filt.learn(sample * hann2d(rows, cols))
    response = filt.respond_wide(features, rank)
    r, c = np.unravel_index(int(np.argmax(response)), response.shape)
    found = ((r + rows // 2) % features.shape[0], (c + cols // 2) % features.shape[1])
    assert found == (cy, cx)


def test_filter_learns_at_its_rate() -> None:
    """The running average moves ``rate`` of the way to a new sample's model."""
    rng = np.random.default_rng(2)
    a, b = rng.random((16, 16, 3)), rng.random((16, 16, 3))
    label = gaussian_label(16, 16, 1.0)
    filt, only_b = CorrelationFilter(label, 1e-3, 0.25), CorrelationFilter(label, 1e-3, 0.25)
    filt.learn(a)
    first = filt.numerator.copy()
    filt.learn(b)
    only_b.learn(b)
    assert np.allclose(filt.numerator, 0.75 * first + 0.25 * only_b.numerator)


def test_confidence_is_high_for_one_sharp_peak_and_low_for_clutter() -> None:
    """APCE (LMCF eq. 7) and PSR (MOSSE) rank a single sharp peak over a noisy, many-peaked
    response."""
    sharp = np.fft.fftshift(gaussian_label(31, 31, 1.5))
    rng = np.random.default_rng(3)
    clutter = rng.random((31, 31)) * 0.6 + 0.4 * sharp
    assert apce(sharp) > 5 * apce(clutter)
    assert psr(sharp) > 7 > psr(clutter)
    assert apce(np.zeros((8, 8))) == 0.0


def test_subpixel_peak_finds_the_vertex_of_a_parabola() -> None:
    rows = np.arange(9)[:, None]
    cols = np.arange(9)[None, :]
    response = -((rows - 4.3) ** 2) - (cols - 3.8) ** 2
    r, c = subpixel_peak(response, 4, 4)
    assert r == pytest.approx(4.3) and c == pytest.approx(3.8)


def test_colour_likelihood_tells_the_target_from_its_surroundings() -> None:
    """Staple eq. 12: a colour only the box has scores ~1, one mostly around it < 0.5."""
    patch = np.zeros((60, 60, 3), np.uint8)
    patch[:] = (0, 200, 0)  # green surroundings
    patch[20:40, 20:40] = (0, 0, 220)  # red target ...
    patch[20:40, 20:24] = (0, 200, 0)  # ... with a green strip
    model = ColourHistograms(bins=32, inner_padding=0.0, rate=0.04)
    model.learn(patch, (20, 20, 20, 20), first=True)
    likelihood = model.likelihood(patch)
    assert likelihood[30, 30] > 0.9
    assert likelihood[50, 50] < 0.5
    assert box_mean(likelihood, 16, 16)[30, 32] > box_mean(likelihood, 16, 16)[10, 10]


def test_grey_patches_use_grey_level_bins() -> None:
    patch = np.full((40, 40), 30, np.uint8)
    patch[10:30, 10:30] = 220
    model = ColourHistograms(bins=16, inner_padding=0.2, rate=0.04)
    model.learn(patch, (10, 10, 20, 20), first=True)
    assert model.object is not None and model.object.size == 16
    likelihood = model.likelihood(patch)
    assert likelihood[20, 20] > 0.9 > 0.1 > likelihood[2, 2]


@pytest.mark.parametrize("ratio", [0.9, 1.0, 1.1])
def test_scale_filter_recovers_a_size_change(ratio: float) -> None:
    """DSST: learnt on a target at one size, the filter names the ratio the target has grown
    by (within one scale step)."""
    image = texture(240, 320, seed=4)
    scale = ScaleFilter(60, 40, scales=17, step=1.02, rate=0.025, model_area=512, cell=4,
                        interp_scales=33)
    frame = BgrFrame(0, 0.0, image)
    scale.learn(scale.samples(frame, 160, 120, 60, 40), first=True)
    # the same scene seen 1/ratio as large around the centre: the target grew by `ratio`
    zoom = cv2.warpAffine(image, cv2.getRotationMatrix2D((160, 120), 0, ratio), (320, 240),
                          flags=cv2.INTER_LINEAR)
    found = scale.ratio(scale.samples(BgrFrame(1, 0.0, zoom), 160, 120, 60, 40))
    assert found == pytest.approx(ratio, abs=0.025)


@pytest.mark.parametrize("area", [64, 512, 2048])
@pytest.mark.parametrize("width, height", [(4, 240), (240, 4), (10, 200), (16, 200), (60, 40),
                                           (3, 3), (1900, 1000)])
def test_a_scale_sample_holds_at_most_the_model_area_whatever_the_targets_shape(
        width: int, height: int, area: int) -> None:
    """fDSST's samples are resampled to at most ``model_area`` pixels, at least two cells a
    side: a thin target's length is cut to fit (it took a 4 x 240 box to 8 x 172 pixels
    at 512, and the scale filter's products past the size where NumPy's BLAS splits them
    over threads)."""
    scale = ScaleFilter(width, height, scales=17, step=1.02, rate=0.025, model_area=area,
                        cell=4, interp_scales=33)
    assert scale.model_w % 4 == 0 and scale.model_h % 4 == 0
    assert scale.model_w >= 8 and scale.model_h >= 8
    assert scale.model_w * scale.model_h <= area
    samples = scale.samples(BgrFrame(0, 0.0, texture(240, 320, seed=5)), 160, 120, width, height)
    assert samples.shape == (scale.model_w // 4 * scale.model_h // 4 * CHANNELS, 17)


def test_patch_inside_the_frame_is_its_pixels_and_edges_are_replicated() -> None:
    image = texture(100, 120)
    frame = BgrFrame(0, 0.0, image)
    inside = region_patch(frame, 60, 50, 40, 20, 40, 20)
    assert np.array_equal(inside, image[40:60, 40:80])
    corner = region_patch(frame, 0, 0, 20, 20, 20, 20)
    assert np.array_equal(corner[:10, :10], np.broadcast_to(image[0, 0], (10, 10, 3)))
    assert np.array_equal(corner[10:, 10:], image[:10, :10])
    grey = GrayFrame(0, 0.0, cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
    assert region_patch(grey, 60, 50, 40, 20, 40, 20).shape == (20, 40)


def test_a_region_far_outside_the_frame_pads_no_more_than_its_own_size() -> None:
    """A region however far past an edge (a prediction carried across a long gap) is its edge
    replicated, the same patch as the region a whole number of pixels nearer, just outside
    the frame: the fill never spans more than the region (before, the edge was replicated
    across the whole distance: 10^12 pixels away, cv2.error "Failed to allocate")."""
    image = texture(100, 120, seed=3)
    for frame in (BgrFrame(0, 0.0, image), GrayFrame(0, 0.0, image[..., 1].copy())):
        for dx, dy in ((1e12, 0.0), (-1e12, 0.0), (0.0, 1e12), (0.0, -1e12), (7e11, -3e11)):
            far = region_patch(frame, 60.3 + dx, 50.6 + dy, 40, 20, 40, 20)
            near_x = 60.3 + (dx and math.copysign(200, dx))
            near_y = 50.6 + (dy and math.copysign(200, dy))
            assert np.array_equal(far, region_patch(frame, near_x, near_y, 40, 20, 40, 20))


def test_patch_of_a_large_region_costs_its_output_size() -> None:
    """A region 10x the patch: the patch is a faithful downsample (close to an area resize)."""
    image = texture(1000, 1000, seed=5)
    frame = BgrFrame(0, 0.0, image)
    patch = region_patch(frame, 500, 500, 1000, 1000, 100, 100)
    reference = cv2.resize(image, (100, 100), interpolation=cv2.INTER_AREA)
    assert patch.shape == (100, 100, 3)
    assert np.abs(patch.astype(int) - reference.astype(int)).mean() < 12
    assert frame.full_window() == Window(0, 0, 1000, 1000)


@pytest.mark.parametrize("seed", range(4))
def test_area_resize_through_single_precision_gives_opencvs_bytes(seed: int) -> None:
    """The patch's area resample reads the pixels as float32 (OpenCV's faster path): its
    bytes are those of ``cv2.resize(..., INTER_AREA)`` on the uint8 pixels, at random sizes
    and reductions, colour and grey, textured and noisy."""
    rng = np.random.default_rng(seed)
    for _ in range(50):
        h, w = (int(v) for v in rng.integers(8, 300, 2))
        pixels = texture(h, w, seed=int(rng.integers(1000))) if rng.random() < 0.5 else \
            rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        if rng.random() < 0.3:
            pixels = np.ascontiguousarray(pixels[..., 1])
        out_w = max(int(w / rng.uniform(1.2, 8)), 1)
        out_h = max(int(h / rng.uniform(1.2, 8)), 1)
        if rng.random() < 0.3:  # whole reductions: OpenCV's integer paths (halving: its own)
            factor = int(rng.integers(2, 5))
            out_w, out_h = max(w // factor, 1), max(h // factor, 1)
            pixels = pixels[: out_h * factor, : out_w * factor]
        expected = cv2.resize(pixels, (out_w, out_h), interpolation=cv2.INTER_AREA)
        assert np.array_equal(area_resized(pixels, out_w, out_h), expected)


def test_cosine_window_is_zero_at_the_border_and_one_in_the_middle() -> None:
    window = hann2d(9, 11)
    assert window.shape == (9, 11, 1)
    assert window[0].max() == 0 and window[:, 0].max() == 0
    assert window[4, 5, 0] == pytest.approx(1.0)


@pytest.mark.parametrize("axes, shape", [(2, (35, 40, 32)), (2, (34, 41, 3)), (1, (33, 744)),
                                         (2, (80, 97, 4))])
def test_real_spectrum_is_numpys_half_spectrum(axes: int, shape: tuple[int, ...]) -> None:
    """Whichever library transforms it (NumPy on a search region's size, OpenCV along one axis
    and on larger samples), the spectrum is what ``np.fft.rfftn`` gives (single precision)."""
    x = np.random.default_rng(0).random(shape).astype(np.float32)
    expected = np.fft.rfftn(x, axes=tuple(range(axes)))
    assert np.allclose(real_spectrum(x, axes), expected, atol=1e-3 * np.abs(expected).max())


@pytest.mark.parametrize("dy, dx", [(2, -3), (-5, 7), (0, 1)])
def test_shifted_spectrum_is_the_spectrum_of_the_moved_sample(dy: int, dx: int) -> None:
    """ECO's shift in the Fourier domain: moving a sample's spectrum by whole cells gives the
    spectrum of the sample rolled by those cells, its content at (dy, dx) now at (0, 0)."""
    x = np.random.default_rng(1).random((12, 15, 3)).astype(np.float32)
    moved = np.roll(x, (-dy, -dx), axis=(0, 1))
    expected = real_spectrum(moved, 2)
    assert np.allclose(shift_spectrum(real_spectrum(x, 2), dy, dx, 15), expected,
                       atol=1e-4 * np.abs(expected).max())


def test_filter_learnt_on_a_shifted_sample_peaks_at_the_target() -> None:
    """A filter learnt from a sample whose target sits off centre, moved by the offset in the
    Fourier domain, responds on the centred target as one learnt on it directly."""
    rng = np.random.default_rng(2)
    centred = rng.random((20, 24, 4)).astype(np.float32)
    off = np.roll(centred, (3, -4), axis=(0, 1))  # the target 3 cells down, 4 left
    direct = CorrelationFilter(gaussian_label(20, 24, 1.5), 1e-3, 0.0)
    direct.learn(centred)
    moved = CorrelationFilter(gaussian_label(20, 24, 1.5), 1e-3, 0.0)
    moved.learn_spectrum(shift_spectrum(real_spectrum(off, 2), 3, -4, 24))
    response = moved.respond(centred)
    assert np.unravel_index(int(np.argmax(response)), response.shape) == (0, 0)
    assert np.allclose(response, direct.respond(centred), atol=1e-3)


@pytest.mark.parametrize("cx, cy, size", [(160, 120, 40), (3, 4, 30), (318, 238, 90),
                                           (160, 120, 200)])
def test_patches_cut_from_one_converted_window_are_the_frames_own(cx, cy, size) -> None:
    """Regions inside a window converted once give the same pixels as converting each (the
    scale filter's 33 samples), at the frame's edges and with every-k-th-pixel sampling too."""
    frame = I420Frame(0, 0.0, cv2.cvtColor(texture(240, 320, seed=5), cv2.COLOR_BGR2YUV_I420))
    converted = ConvertedWindow.around(frame, cx, cy, size * 1.4, size)
    assert converted is not None
    for f in (0.7, 0.85, 1.0):
        alone = region_patch(frame, cx, cy, size * 1.4 * f, size * f, 13, 9)
        cut = region_patch(frame, cx, cy, size * 1.4 * f, size * f, 13, 9, converted)
        assert np.array_equal(alone, cut)


@pytest.mark.parametrize("centres, size", [(((160, 120), (175, 110)), 60),
                                           (((2, 3), (10, 8)), 50), (((316, 237),), 80),
                                           (((160, 120), (161, 121)), 150)])
def test_overlapping_regions_converted_once_are_cut_as_alone(centres, size) -> None:
    """Overlapping search regions (the last box's and the motion model's) converted once for
    both (no more pixels than converting each) give each region the pixels it gets alone, at
    the frame's edges and past them too. Regions far apart, or read at every k-th pixel, are
    not converted together (that would convert more)."""
    frame = I420Frame(0, 0.0, cv2.cvtColor(texture(240, 320, seed=6), cv2.COLOR_BGR2YUV_I420))
    regions = [(cx, cy, size * 1.3, size) for cx, cy in centres]
    converted = ConvertedWindow.spanning(frame, regions, 40, 30)
    assert converted is not None
    for cx, cy, width, height in regions:
        assert converted.covers_region(frame, cx, cy, width, height)
        assert np.array_equal(region_patch(frame, cx, cy, width, height, 40, 30, converted),
                              region_patch(frame, cx, cy, width, height, 40, 30))
    assert ConvertedWindow.spanning(frame, [(40, 40, 60, 40), (280, 200, 60, 40)], 40, 30) \
        is None  # far apart
    sampled = [(160, 120, 200, 150), (165, 125, 200, 150)]  # 7.5 pixels a patch pixel
    assert ConvertedWindow.spanning(frame, sampled, 26, 20) is None
    grey = GrayFrame(0, 0.0, np.zeros((240, 320), np.uint8))
    assert ConvertedWindow.spanning(grey, regions, 40, 30) is None


def test_fhog_is_the_same_on_a_process_first_call() -> None:
    """The same patch gives the same features on the first call of a fresh process as later
    (``cv2.magnitude`` did not: its first call rounded differently, and runs of one clip
    differed)."""
    code = ("import numpy as np, cv2; from vtrack.features.fhog import fhog; "
            "p = cv2.GaussianBlur(np.random.default_rng(0).integers(0, 255, (64, 48, 3), "
            "np.uint8), (5, 5), 2); print(np.array_equal(fhog(p), fhog(p)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "True"


def _over_static_background(rows: int, cols: int, target_at: tuple[int, int],
                            background_gain: float) -> np.ndarray:
    """Features of an 8x8-cell target at ``target_at`` cells from the sample's centre over a
    textured background that stays where it is (a camera panning with the target), under the
    cosine window."""
    background = np.random.default_rng(0).random((rows, cols, 8)).astype(np.float32)
    target = np.random.default_rng(1).random((8, 8, 8)).astype(np.float32)
    x = background * background_gain
    cy, cx = rows // 2 + target_at[0], cols // 2 + target_at[1]
    x[cy - 4:cy + 4, cx - 4:cx + 4] = target
    return x * hann2d(rows, cols)


@pytest.mark.parametrize("gain", [1.0, 2.0])
def test_filter_constrained_to_the_box_follows_the_target_not_the_background(gain) -> None:
    """CSR-DCF/BACF: learnt over a sample whose background carries as much texture as the
    target, the unconstrained filter follows the background, the one constrained to the
    target's box follows the target."""
    rows, cols, moved = 30, 36, (3, -4)
    found = {}
    for constrained in (False, True):
        filt = CorrelationFilter(gaussian_label(rows, cols, 1.0), lam=1e-3, rate=0.0)
        filt.learn(_over_static_background(rows, cols, (0, 0), gain))
        if constrained:
            filt.constrain(support_mask(rows, cols, 8, 8))
        response = filt.respond(_over_static_background(rows, cols, moved, gain))
        r, c = np.unravel_index(int(np.argmax(response)), response.shape)
        found[constrained] = ((int(r) + rows // 2) % rows - rows // 2,
                              (int(c) + cols // 2) % cols - cols // 2)
    assert found == {False: (0, 0), True: moved}


def test_constrained_filter_is_zero_outside_its_support_and_fits_better_than_a_cut_one() -> None:
    """The ADMM solution keeps no weight outside the support, and fits the samples (DSST's
    objective) better than the unconstrained filter cut to the support, less well than the
    unconstrained one."""
    rows, cols = 24, 30
    rng = np.random.default_rng(4)
    xf = real_spectrum(rng.random((rows, cols, 6)).astype(np.float32) * hann2d(rows, cols), 2)
    label_f = np.fft.rfftn(gaussian_label(rows, cols, 1.5))[..., None]
    numerator = np.conj(label_f) * xf
    energy = np.sum(np.abs(xf) ** 2, axis=2, keepdims=True) + 1e-3
    support = support_mask(rows, cols, 9, 7)

    def objective(spectrum: np.ndarray) -> float:
        return float(np.sum(energy * np.abs(spectrum) ** 2
                            - 2 * np.real(np.conj(spectrum) * numerator)))

    def kernel(spectrum: np.ndarray) -> np.ndarray:
        return np.fft.irfftn(spectrum, s=(rows, cols), axes=(0, 1))

    free = numerator / energy
    cut = real_spectrum((kernel(free) * support[..., None]).astype(np.float32), 2)
    solved = constrained_filter(numerator, energy, support, (rows, cols))
    weights = np.abs(kernel(solved))
    assert weights[support == 0].max() < 1e-5 * weights[support == 1].max()
    assert objective(free) < objective(solved) < objective(cut)
    assert objective(solved) - objective(free) < 0.5 * (objective(cut) - objective(free))
