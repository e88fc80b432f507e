"""S1: centroid-corrected particle filter with a tracked/lost state (patent CN105869186A).

One stage runs the document's whole per-frame loop (patent steps 1-9, paragraphs
[0041]-[0048]):

1. the target model is the hue histogram of the first frame's box;
2. ``particles`` boxes of the target's size are scattered: while tracked, ``near_share`` of them
   around the last position and the rest over the whole frame; while lost, all of them over the
   whole frame (``lost_particles`` of them, when set, instead of ``particles``: not the
   document's, it shortens the wait for re-acquisition);
3. each particle's hue pixels give its hue histogram and its centroid weighted by the target
   histogram (CamShift's centroid, ``c = sum (x, y) q[H] / sum q[H]``); only the best
   particle's centroid is ever output, so only that one is computed (the FPGA computes all of
   them in the same pixel pass because it costs it nothing);
4. its weight is the Bhattacharyya coefficient of the normalised histograms;
5. the output is the centroid of the best particle (its centre with ``centroid_correction``
   off), with a box of the initial size centred on it;
6. the best weight is compared with the one ``history`` tracked frames ago to decide between
   tracked and lost, and the history is frozen while lost.

Hue is the 8-bit full-range hue of OpenCV's ``COLOR_BGR2HSV_FULL`` (0..255 for 0..360 degrees),
converted only inside the particle boxes (or once for the bounding region of a cluster of
particles when that is smaller than converting each). Particle boxes always lie inside the frame
(patent [0045]: "particles never leave the visible screen").
"""

from __future__ import annotations

import math
from collections import deque

import cv2
import numpy as np

from vtrack.errors import FirstFrameError
from vtrack.frame import Frame
from vtrack.geometry import Box, Window
from vtrack.histograms import bhattacharyya_rows, hue_histogram, refuse_colourless
from vtrack.overlays import Particles
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, TrackState, register

#: Levels of the 8-bit hue of ``COLOR_BGR2HSV_FULL`` (0..255 spans 0..360 degrees).
HUE_LEVELS = 256


#: Window pixels histogrammed per frame, in frames: 8 particles over a whole-frame box (S1's
#: default count) stay exact; beyond, windows are sampled (bounded cost per frame).
PIXEL_BUDGET = 8


def hue_windows(frame: Frame, windows: list[Window]) -> list[np.ndarray]:
    """The hue plane (channel 0 of ``COLOR_BGR2HSV_FULL``) of each window, converting only what
    is needed.

    The bounding region of all windows is converted once when its area is at most the windows'
    total area (a cluster of overlapping particles); otherwise each window is converted alone.
    """
    if not windows:
        return []
    union = Window.union(windows)
    if len(windows) > 1 and union.width * union.height <= sum(w.width * w.height for w in windows):
        hue = cv2.extractChannel(cv2.cvtColor(frame.bgr(union), cv2.COLOR_BGR2HSV_FULL), 0)
        return [
            hue[w.y0 - union.y0 : w.y1 - union.y0, w.x0 - union.x0 : w.x1 - union.x0]
            for w in windows
        ]
    return [cv2.extractChannel(cv2.cvtColor(frame.bgr(w), cv2.COLOR_BGR2HSV_FULL), 0)
            for w in windows]


def sampled_rows(windows: list[np.ndarray], budget: int) -> list[np.ndarray]:
    """The windows themselves while their pixels total at most ``budget``; beyond, every n-th
    row of each (whole rows: a row step keeps a view OpenCV reads without a copy), n the
    smallest that brings the total within the budget."""
    area = sum(w.size for w in windows)
    step = max(1, math.ceil(area / budget))
    return windows if step == 1 else [w[::step] for w in windows]


@register
class ParticleFilter(Stage):
    """S1: particle filter whose particles are corrected to their target-weighted centroid,
    with the patent's tracked/lost decision on the best weight's 10-frame ratio."""

    name = "particle"
    summary = "S1 particle filter: hue histograms, centroid correction, tracked/lost state"
    params = (
        Param("particles", int, 8, "number of particles per frame (S1 embodiment: 8)",
              min=1, max=1024),
        Param(
            "lost_particles",
            int,
            0,
            "particles scattered over the whole frame while lost; 0: as many as `particles` "
            "(S1). Not the document's: a frame finds the returned target with probability "
            "1 - (1 - p)^N for N particles, p the share of positions that pass the threshold "
            "(~1% for a target 1/60 of the frame: 8 particles wait ~11 frames, 64 about 2)",
            min=0, max=1024,
        ),
        Param(
            "near_share",
            float,
            0.75,
            "share of particles scattered near the last position while tracked, the rest over "
            "the whole frame (S1 step 3, [0011]/[0042]: 'more' near, 'fewer' elsewhere, no "
            "count given; 0.75: 6 of S1's 8 particles)",
            min=0.0,
            max=1.0,
        ),
        Param(
            "spread",
            float,
            0.25,
            "near particles are offset uniformly by up to spread x the box width/height from "
            "the last position (in box sizes; not given by S1: 0.25 keeps the best of 6 near "
            "particles' weight >= 0.9 in 90% of frames on a still target)",
            min=0.0, max=10.0,
        ),
        Param(
            "bins",
            int,
            256,
            "hue bins over 0..360 degrees (S1 step 2, [0041]: one per H value, 0..360; 256 is the "
            "full resolution of 8-bit hue)",
            min=2,
            max=HUE_LEVELS,
        ),
        Param(
            "centroid_correction",
            bool,
            True,
            "output the best particle's target-weighted centroid (S1 step 5, [0013]); false: its "
            "centre (the plain particle filter)",
        ),
        Param(
            "threshold",
            float,
            0.9,
            "tracked while best weight / weight `history` frames ago >= threshold "
            "(S1 step 8, [0047]: 86% to 92%)",
            min=0.0,
            max=1.0,
        ),
        Param(
            "history",
            int,
            10,
            "tracked frames between the compared weights (S1 step 8, [0018]: ten)",
            min=1, max=1000,
        ),
        Param("draw_particles", bool, False,
              "draw the particles (their centres, as dots) in annotated.mp4 (S1 [0048]: the "
              "display shows centroid, box and caption only)"),
    )
    requires = frozenset({"frame", "box", "rng"})  # (rng: the run's --seed)
    provides = frozenset({"box", "state", "score"})
    columns = ("weight_ratio", "reference_weight", "particle_cx", "particle_cy")

    particles: int
    lost_particles: int
    near_share: float
    spread: float
    bins: int
    centroid_correction: bool
    threshold: float
    history: int
    draw_particles: bool

    def start(self, ctx: TrackContext) -> None:
        """Build the target model from the initial box (S1 step 2) and clear the history."""
        frame = ctx.frame
        box = ctx.box
        assert box is not None  # needs_init_box: the pipeline refuses to start without one
        window = box.window(frame.width, frame.height)
        if window is None:
            raise FirstFrameError(
                f"{self.name}: the initial box {box.text()} is outside the "
                f"{frame.width}x{frame.height} frame"
            )
        refuse_colourless(frame.bgr(window), self.name, box.text())
        # S1 step 2: target feature = hue histogram of the first frame's box.
        first = hue_windows(frame, [window])[0]
        self._target = hue_histogram(first, None, self.bins, HUE_LEVELS).astype(np.float64)
        # S1 step 5: q[H] per 8-bit hue value, for the centroid weights (cv2.LUT table).
        bin_of_hue = np.arange(HUE_LEVELS) * self.bins // HUE_LEVELS
        self._q_of_hue = (self._target / self._target.sum())[bin_of_hue].astype(np.float32)
        self._size = (box.w, box.h)
        self._pixels = (
            min(max(round(box.w), 1), frame.width),
            min(max(round(box.h), 1), frame.height),
        )
        # S1 step 8: best weights of the last `history` tracked frames, oldest first. Empty at
        # the start: the first tracked frame is compared with itself and, until `history`
        # weights are stored, later frames with the oldest one. This is the patent's own start
        # ([0047]: the first tracked frame's weight fills the whole shift register).
        self._weights: deque[float] = deque(maxlen=self.history)
        ctx.state = TrackState.TRACKING
        ctx.score = 1.0  # the target box against its own histogram

    def step(self, ctx: TrackContext) -> None:
        """Scatter, score and correct the particles, output the best one, update the state."""
        frame = ctx.frame
        assert ctx.box is not None  # set by start and never cleared
        windows, near, corners = self._scatter(ctx)
        hues = hue_windows(frame, windows[:near]) + hue_windows(frame, windows[near:])
        # S1 steps 4 and 6: each particle's hue histogram and its Bhattacharyya weight.
        # Bounded work: past PIXEL_BUDGET frames' worth of window pixels (many particles over a
        # large box), every window is counted on every n-th row.
        counted = sampled_rows(hues, PIXEL_BUDGET * frame.width * frame.height)
        histograms = np.array([hue_histogram(hue, None, self.bins, HUE_LEVELS)
                               for hue in counted], np.float64)
        weights = bhattacharyya_rows(histograms, self._target)
        best = int(np.argmax(weights))
        weight = float(weights[best])
        window = windows[best]
        centre = (window.x0 + window.width / 2.0, window.y0 + window.height / 2.0)
        # S1 steps 5 and 7: output the best particle's centroid (its centre for the plain filter).
        point = self._centroid(hues[best], window) if self.centroid_correction else centre

        # S1 step 8: tracked/lost ratio against the best weight `history` tracked frames ago
        # (while lost every stored weight is the frozen reference, so it is the oldest one too).
        reference = self._weights[0] if self._weights else weight
        tracked = weight >= self.threshold * reference
        if tracked:
            self._weights.append(weight)  # tracking (or re-acquired): the history resumes
            ctx.box = Box.from_center(point[0], point[1], *self._size)
            ctx.state = TrackState.TRACKING
        elif ctx.state != TrackState.LOST:
            # S1 step 8 ([0018]): entering lost freezes the history at the weight `history`
            # frames before the loss ([0047]: it replaces the other nine entries; this frame is
            # not stored).
            self._weights.extend([reference] * self.history)
            # ctx.box keeps the last tracked box; the pipeline outputs none
            ctx.state = TrackState.LOST
        ctx.score = weight
        ctx.extras.update(
            weight_ratio=weight / reference if reference > 0 else float("nan"),
            reference_weight=reference,
            particle_cx=centre[0],
            particle_cy=centre[1],
        )
        if self.draw_particles:
            ctx.overlays.append(Particles(corners + np.array(self._pixels) / 2.0))

    def _scatter(self, ctx: TrackContext) -> tuple[list[Window], int, np.ndarray]:
        """Particle windows of the target's pixel size, inside the frame (S1 step 3).

        While tracked there are ``particles`` windows and the first ``near_share * particles``
        (rounded to the nearest integer) are scattered near the last position; while lost there
        are ``lost_particles`` (or ``particles`` when 0), none near. Returns the windows, how
        many are near, and their top-left corners as an (N, 2) array. The box size is rounded
        to whole pixels.
        """
        frame, rng = ctx.frame, ctx.rng
        assert ctx.box is not None
        pw, ph = self._pixels
        size = np.array([pw, ph], dtype=np.float64)
        lost = ctx.state == TrackState.LOST
        count = (self.lost_particles or self.particles) if lost else self.particles
        near = 0 if lost else round(self.near_share * self.particles)
        offsets = rng.uniform(-self.spread, self.spread, (near, 2)) * self._size
        near_corners = np.array([ctx.box.cx, ctx.box.cy]) + offsets - size / 2.0
        # S1 step 3: a few particles (all of them while lost) uniformly over the whole frame.
        room = np.array([frame.width - pw, frame.height - ph], dtype=np.float64)
        far_corners = rng.uniform(0.0, 1.0, (count - near, 2)) * room
        corners = np.clip(np.rint(np.vstack([near_corners, far_corners])), 0, room).astype(int)
        windows = [Window(x, y, x + pw, y + ph) for x, y in corners.tolist()]
        return windows, near, corners

    def _centroid(self, hue: np.ndarray, window: Window) -> tuple[float, float]:
        """``sum (x, y) q[H] / sum q[H]`` over the window's pixel centres (S1 step 5, [0033]),
        ``hue`` the window's hue plane; the window's centre when no pixel has a target hue."""
        mass = cv2.LUT(hue, self._q_of_hue.reshape(1, HUE_LEVELS))
        moments = cv2.moments(mass)
        if moments["m00"] <= 0:
            return window.x0 + window.width / 2.0, window.y0 + window.height / 2.0
        return (
            window.x0 + 0.5 + moments["m10"] / moments["m00"],
            window.y0 + 0.5 + moments["m01"] / moments["m00"],
        )
