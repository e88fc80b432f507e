"""The ``robust`` tracker's search: the correlation peak, merged with colour, then the size.

Second link of the ``robust`` chain. On each region ``robust_model`` cut:

1. the correlation filter's response to the region's fHOG features (DSST eq. 6: the filter
   learnt on earlier frames, correlated in the Fourier domain);
2. the colour response: the mean colour likelihood over a target-sized box at each cell
   (Staple section 4, its integral image);
3. the merge ``(1 - merge) * filter + merge * colour`` (Staple eq. 21, merge factor 0.3), whose
   peak (refined to a fraction of a cell by a parabola) is the target's new centre;
4. the target's size from fDSST's scale filter at that centre (:mod:`vtrack.features.scale`).

The confidence of the filter's own response, LMCF's average peak-to-correlation energy and its
peak value (Wang et al., CVPR 2017, eq. 7), and the colour response at the chosen peak go to
``ctx.robust`` for ``robust_failure``;
``ctx.score`` is the smaller of the two relative to their usual values (1: as sure as usual;
on the first frame after the given box, which has no usual values yet, the colour response
against the given box's).
The region whose merged peak is highest wins; a frame-wide candidate searched while the
target is not lost (``robust_failure.redetect_on_colour``) competes only when its filter peak
is at least the usual one (a far jump needs the target's usual strength).

Pipeline contract of stage ``robust_search``: reads ``ctx.robust``, ``ctx.likelihood``; writes
``ctx.measurement`` and ``ctx.box`` (the found box), ``ctx.score``, ``ctx.robust`` (chosen
region, confidence, scale filter).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from vtrack.features.colour import cell_response
from vtrack.features.dcf import apce, psr, subpixel_peak
from vtrack.features.scale import ScaleFilter
from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register
from vtrack.stages.robust_model import Region, RobustTarget


@register
class RobustSearch(Stage):
    """Correlation peak merged with the colour response (Staple); fDSST scale."""

    name = "robust_search"
    summary = ("robust: peak of the fHOG correlation filter's response merged with the colour "
               "response (Staple), then the size from fDSST's scale filter")
    params = (
        Param("merge", float, 0.3, "weight of the colour response against the filter's "
              "(Staple: 0.3; 0: filter only)", min=0.0, max=1.0),
        Param("scale", bool, True, "estimate the size (fDSST's scale filter)"),
        Param("scales", int, 17, "fDSST scale samples (17; DSST: 33)", min=3, max=33),
        Param("interp_scales", int, 33, "scales the response is interpolated to (fDSST: 33; "
              "equal to scales: no interpolation, DSST)", min=3, max=99),
        Param("scale_step", float, 1.02, "ratio between neighbouring (interpolated) scales "
              "(DSST/fDSST: 1.02; the samples are interp_scales / scales steps apart)",
              min=1.001, max=1.5),
        Param("scale_rate", float, 0.025, "scale filter's learning rate (DSST: 0.025)",
              min=0.0, max=1.0),
        Param("scale_area", int, 512, "pixels of a scale sample at most (DSST: 512)",
              min=64, max=2048),
        Param("min_side", float, 5.0, "the box never gets smaller than this many pixels a side "
              "(a first box with a shorter side never shrinks below its first size), unless the "
              "frame is too small for that: the box never grows so large that its "
              "search region (the box and its padding) outgrows the frame (or its first size), "
              "and that limit wins", min=1.0, max=1000.0),
    )
    requires = frozenset({"robust", "likelihood"})
    provides = frozenset({"measurement", "box", "score", "robust"})

    merge: float
    scale: bool
    scales: int
    interp_scales: int
    scale_step: float
    scale_rate: float
    scale_area: int
    min_side: float
    rules = ("interp_scales >= scales when scale is on",)

    @classmethod
    def values_problem(cls, values: dict[str, Any]) -> str | None:
        """Fewer interpolated scales than samples with the scale filter on (``scale``; off,
        neither is used): fDSST interpolates the response of ``scales`` samples up to
        ``interp_scales`` (equal: DSST, no interpolation), never down."""
        samples, interpolated = values["scales"], values["interp_scales"]
        if values["scale"] and interpolated < samples:
            return (f"interp_scales ({interpolated}) is smaller than scales ({samples}): the "
                    f"response of {samples} scale samples is interpolated up to interp_scales, "
                    "never down; give interp_scales >= scales (equal: no interpolation, DSST)")
        return None

    def start(self, ctx: TrackContext) -> None:
        target = ctx.robust
        assert target is not None and ctx.box is not None
        ctx.score = 1.0  # the first frame's box is the target
        target.merge = self.merge if target.colour is not None else 0.0
        if self.scale:
            target.scale_filter = ScaleFilter(ctx.box.w, ctx.box.h, self.scales, self.scale_step,
                                              self.scale_rate, self.scale_area, target.cell,
                                              self.interp_scales)
            target.scale_filter.learn(target.scale_filter.samples(
                ctx.frame, ctx.box.cx, ctx.box.cy, ctx.box.w, ctx.box.h), first=True)
        if target.colour is not None and target.merge > 0:
            # the colour response at the given box starts its mean (robust_failure's colour
            # check and the first frame's confidence need a reference before any frame is seen)
            region = target.region(ctx.frame, ctx.box.cx, ctx.box.cy)
            _, colour = self._responses(target, region, target.colour.likelihood(region.patch))
            assert colour is not None
            target.usual_colour = float(colour[target.rows // 2, target.cols // 2])
            target.colour_frames = 1
        # a first box thinner than min_side is never stretched to it (a uniform scale would
        # widen its long side too, and the filter would search at a size it never learnt)
        self._min_scale = min(self.min_side / min(ctx.box.w, ctx.box.h), 1.0)
        self._max_scale = max(min(ctx.frame.width / target.region_w,
                                  ctx.frame.height / target.region_h), 1.0)

    def step(self, ctx: TrackContext) -> None:
        target = ctx.robust
        assert target is not None
        best: tuple[float, Region, np.ndarray, float, tuple[float, float]] | None = None
        for i, region in enumerate(target.regions):
            likelihood = ctx.likelihood if i == 0 else (
                target.colour.likelihood(region.patch) if target.colour is not None else None)
            response, colour = self._responses(target, region, likelihood)
            if region.far and float(response.max()) < target.usual_peak:
                continue  # a far candidate must look as much like the target as usual
            merged = response if colour is None else target.merged(response, colour)
            r, c = np.unravel_index(int(np.argmax(merged)), merged.shape)
            if best is None or merged[r, c] > best[0]:
                best = (float(merged[r, c]), region, response,
                        1.0 if colour is None else float(colour[r, c]),
                        subpixel_peak(merged, int(r), int(c)))
        assert best is not None
        _, region, response, target.colour_peak, (row, col) = best
        target.chosen = region
        target.apce, target.peak = apce(response), float(response.max())
        target.psr = psr(response)
        # the peak's offset from the region's centre, working -> frame pixels
        step = target.cell / region.factor
        cx = region.cx + (col - target.cols // 2) * step
        cy = region.cy + (row - target.rows // 2) * step
        target.scale_samples = None
        target.previous_scale = target.scale
        if self.scale and target.scale_filter is not None:
            w, h = target.size
            samples = target.scale_filter.samples(ctx.frame, cx, cy, w, h,
                                                  target.converted_pixels(ctx.frame))
            ratio = target.scale_filter.ratio(samples)
            target.scale = float(np.clip(target.scale * ratio, self._min_scale, self._max_scale))
            if target.size == (w, h):
                target.scale_samples = (Box.from_center(cx, cy, w, h), samples)
        w, h = target.size
        ctx.measurement = ctx.box = Box.from_center(cx, cy, w, h)
        ctx.score = confidence(target)

    def _responses(self, target: RobustTarget, region: Region, likelihood: np.ndarray | None
                   ) -> tuple[np.ndarray, np.ndarray | None]:
        """The filter's response on the region (centred: no displacement at the middle cell)
        and the colour response on the same cells (None without colour)."""
        response = np.fft.fftshift(target.translation.respond_spectrum(region.spectrum))
        if likelihood is None or self.merge == 0.0:
            return response, None
        w, h = target.size
        return response, cell_response(likelihood, w * region.factor, h * region.factor,
                                       target.rows, target.cols, target.cell)


def confidence(target: RobustTarget) -> float:
    """This frame's response against the usual ones: min(APCE / usual, peak / usual), at most
    1. On the first frame after the given box there are no usual APCE and peak yet: the colour
    response against the given box's (1 without colour)."""
    if target.response_frames == 0:
        if target.colour_frames == 0:
            return 1.0
        return float(min(target.colour_peak / max(target.usual_colour, 1e-9), 1.0))
    return float(min(target.apce / max(target.usual_apce, 1e-9),
                     target.peak / max(target.usual_peak, 1e-9), 1.0))
