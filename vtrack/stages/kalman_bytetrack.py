"""Many targets through missed and false detections: ``byte_tracks``.

The association of ByteTrack (Zhang et al., "ByteTrack: Multi-Object Tracking by Associating
Every Detection Box", ECCV 2022) over a Kalman filter per track with the project's motion
models (:data:`vtrack.filters.MOTION_MODELS`, on the box centre; the size is smoothed apart):

1. every track's filter predicts this frame; its predicted box is the predicted centre with
   its smoothed size;
2. **first pass**: detections scoring at least ``high`` against the confirmed tracks (measured
   or coasting), by an optimal assignment (``scipy.optimize.linear_sum_assignment``) on
   ``1 - IoU`` of predicted and detected boxes. A pair may match only inside the motion gate
   (squared Mahalanobis distance of the detected centre from the predicted one, under the
   filter's innovation covariance, at most ``gate``) and with IoU >= ``iou``; a gated pair
   without that overlap (small or fast targets) may still match at a cost above every
   overlapping pair's, ``1 + d^2 / gate``;
3. **second pass** (ByteTrack's): detections scoring between ``low`` and ``high`` (a person
   half hidden, a blob cut by the background model) against the confirmed tracks left, with
   IoU >= ``low_iou``: they continue tracks, never start one;
4. tentative tracks against the high-score detections left, as in 2;
5. every high-score detection still left starts a tentative track, unless it lies wholly
   outside the frame.

With ``colour_gate`` < 1, passes 2 and 4 also gate on colours, as DeepSORT (Wojke et al.,
ICIP 2017, eq. 6) admits a pair only inside both its motion gate and its appearance gate, with
a colour histogram for the network's embedding: a pair may match only when the Hellinger
distance ``sqrt(1 - BC)`` between the detection's histogram (``detection_colours``) and the
track's is at most ``colour_gate``. A track's histogram follows its high-score detections' as
JDE/FairMOT follow embeddings (a moving average, momentum ``COLOUR_MOMENTUM``). So a track
whose person is hidden does not take over a differently dressed person passing by, and two
people who cross keep their identities when they come apart. The second pass stays on IoU only,
as ByteTrack's: a low-score detection is a partly hidden target, whose colours mislead.

Life of a track: tentative -> confirmed after ``confirm`` measured frames (a tentative track
missing a frame is deleted) -> coasting while unmeasured (it keeps its identity through short
occlusions and is matched again as in 2, its gate widening with its uncertainty) -> deleted
after more than ``max_coast`` frames in a row without a measurement, or once its box has left
the frame: a track wholly outside the frame is never reported. At most ``max_tracks`` tracks are
kept, those coasting longest dropped first.

The measurement noise of a detection grows with its size (``noise`` x the square root of its
box area, in pixels, as DeepSORT scales it by height): a person's centre from background
subtraction is off by several pixels, a small hot spot's by one.

Output (``ctx.tracks``): every track; ``confirmed`` (confirmed and measured this frame: written
to ``tracks.csv`` and drawn), ``coasting`` or ``tentative``; the box is the filtered centre
with the smoothed size, the confidence the score of its last detection. Ids start at the run's
first track id (1 unless it gives another: ``--first-id``), one per track created, never
reused. ``ctx.target_shape``: the median aspect and area of the boxes confirmed tracks were
measured with (the last ``base.SHAPE_SAMPLES``), for ``group_blobs``.
Work per frame: ``O(T M)`` for ``T <= max_tracks`` tracks and ``M`` detections, and an assignment.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from vtrack.filters import MOTION_MODELS, GaussianState, MotionModel, motion_model
from vtrack.geometry import Box, iou_matrix
from vtrack.histograms import bhattacharyya_rows
from vtrack.params import Param
from vtrack.stages.base import ShapeSamples, Stage, Track, TrackContext, register
from vtrack.stages.detect import Detection, TrackIds, fewest_misses, track_state

#: The cost of a pair that may not match (above any allowed pair's: at most 1 + 1).
_FORBIDDEN = 1e6
#: Weight of a track's colours against a new detection's (JDE/FairMOT's embedding momentum).
COLOUR_MOMENTUM = 0.9


@dataclass(eq=False)
class _Track:
    id: int
    state: GaussianState
    size: tuple[float, float]  # smoothed width, height
    score: float  # of the last detection it was measured with
    colours: np.ndarray | None = None  # colour histogram, moving average (appearance)
    hits: int = 1  # frames with a measurement
    misses: int = 0  # frames in a row without one
    confirmed: bool = False


def colour_distances(tracks: list[np.ndarray | None],
                     detections: list[np.ndarray | None]) -> np.ndarray:
    """Hellinger distance ``sqrt(1 - BC)`` (BC: the Bhattacharyya coefficient) of every
    track's colour histogram with every detection's, ``(T, M)`` in 0..1; 0 where either has
    none (nothing to tell them apart by)."""
    out = np.zeros((len(tracks), len(detections)))
    rows = [i for i, h in enumerate(tracks) if h is not None]
    if not rows:
        return out
    known = np.array([tracks[i] for i in rows])
    for j, histogram in enumerate(detections):
        if histogram is not None:
            coefficient = np.clip(bhattacharyya_rows(known, histogram), 0.0, 1.0)
            out[rows, j] = np.sqrt(1.0 - coefficient)
    return out


def assign(cost: np.ndarray) -> list[tuple[int, int]]:
    """The minimum-cost assignment of rows to columns without forbidden pairs (cost >=
    ``_FORBIDDEN``)."""
    if cost.size == 0:
        return []
    # imported here: SciPy's optimize costs ~0.2 s, which every other command (`vtrack stages`
    # registers this stage) would pay at start-up
    from scipy.optimize import linear_sum_assignment

    rows, cols = linear_sum_assignment(cost)
    return [(int(r), int(c)) for r, c in zip(rows, cols, strict=True) if cost[r, c] < _FORBIDDEN]


@register
class ByteTracks(Stage):
    """ByteTrack's two-pass association over a Kalman filter per track (see the module
    docstring)."""

    name = "byte_tracks"
    summary = ("many targets: a Kalman filter per track, IoU + motion-gated optimal matching, "
               "ByteTrack's second pass over low-score detections")
    params = (
        Param("model", str, "cv",
              "motion model of every track's centre: cv = constant velocity (S0), ca = "
              "constant acceleration (S2), gravity = S4's (with g = 0)",
              choices=tuple(MOTION_MODELS)),
        Param("q", float, 1.0, "process noise Q = q I, pixels^2 per frame", min=0.0, max=1e6),
        Param("noise", float, 0.1,
              "measurement noise: a detected centre's standard deviation as a share of the "
              "square root of its box area", min=1e-4, max=10.0),
        Param("p0", float, 100.0, "initial covariance of a new track's state, P0 = p0 I",
              min=0.0, max=1e6),
        Param("high", float, 0.5,
              "detections scoring at least this are matched first and may start tracks "
              "(group_blobs scores 0..1; a det.txt's detector has its own scale)",
              min=-1e6, max=1e6),
        Param("low", float, 0.1,
              "detections scoring from this up to `high` only continue confirmed tracks "
              "(ByteTrack's second pass); lower ones are ignored", min=-1e6, max=1e6),
        Param("iou", float, 0.2,
              "least IoU of a predicted and a detected box for a match of the first pass",
              min=0.0, max=1.0),
        Param("low_iou", float, 0.5,
              "least IoU for a match of the second pass (low-score detections)",
              min=0.0, max=1.0),
        Param("gate", float, 9.21,
              "largest squared Mahalanobis distance of a detected centre from a predicted one "
              "(9.21: 99% of chi-square with 2 degrees of freedom)", min=0.1, max=1e6),
        Param("confirm", int, 3, "measured frames after which a track is confirmed",
              min=1, max=1000),
        Param("max_coast", int, 30,
              "a confirmed track unmeasured for more frames in a row than this is deleted",
              min=0, max=100000),
        Param("max_tracks", int, 1000,
              "at most this many tracks are kept, those coasting longest dropped first (bounds "
              "each frame's work and memory whatever max_coast lets live)", min=1, max=1000),
        Param("colour_gate", float, 1.0,
              "largest colour distance (Hellinger, 0..1) of a track and a high-score detection "
              "that may match (DeepSORT's appearance gate; refused without detection_colours "
              "before this stage; 1: no gate)", min=0.0, max=1.0),
        Param("size_smoothing", float, 0.3,
              "weight of a new measurement in a track's smoothed width and height "
              "(1: the last detection's)", min=0.0, max=1.0),
    )
    requires = frozenset({"detections", "first_track_id"})
    provides = frozenset({"tracks", "target_shape"})
    multi_target = True
    needs_init_box = False
    rules = ("low <= high", "colour_gate below 1 needs detection_colours before this stage")

    @classmethod
    def values_problem(cls, values: dict[str, Any]) -> str | None:
        """A low score above the high one: no detection would reach the second pass."""
        if values["low"] > values["high"]:
            return (f"low ({values['low']:g}) is above high ({values['high']:g}): no detection "
                    "would score from low up to high (ByteTrack's second pass); give low <= high")
        return None

    @classmethod
    def chain_problem(cls, values: dict[str, Any], before: list[str]) -> str | None:
        default = next(p.default for p in cls.params if p.name == "colour_gate")
        if values.get("colour_gate", default) < 1.0 and "detection_colours" not in before:
            return ("colour_gate below 1 needs the detection_colours stage before it (it gives "
                    "each detection its colours; without it nothing would be gated)")
        return None

    def start(self, ctx: TrackContext) -> None:
        """Forget any previous run (no track, nothing learnt), then track this frame."""
        self._model: MotionModel = motion_model(self.model, self.q, 1.0, self.p0, g=0.0)
        self._tracks: list[_Track] = []
        self._ids = TrackIds(ctx)
        self._shapes = ShapeSamples()
        ctx.target_shape = None
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        model = self._model
        for track in self._tracks:
            track.state = model.predict(track.state, 1.0)
        detections: list[Detection] = ctx.detections
        high = [i for i, d in enumerate(detections) if d.score >= self.high]
        low = [i for i, d in enumerate(detections) if self.low <= d.score < self.high]
        confirmed = [t for t in self._tracks if t.confirmed]
        tentative = [t for t in self._tracks if not t.confirmed]
        matched: dict[int, int] = {}  # id(track) -> detection index
        for tracks, candidates, least, gated in (
            (confirmed, high, self.iou, True),
            (confirmed, low, self.low_iou, False),
            (tentative, high, self.iou, True),
        ):
            tracks = [t for t in tracks if id(t) not in matched]
            candidates = [i for i in candidates if i not in matched.values()]
            cost = self._cost(tracks, [detections[i] for i in candidates], least, gated)
            for row, col in assign(cost):
                matched[id(tracks[row])] = candidates[col]
        kept = []
        for track in self._tracks:
            index = matched.get(id(track))
            if index is not None:
                self._update(track, detections[index])
            else:
                track.misses += 1
            coasting_on = track.confirmed and track.misses <= self.max_coast
            box = self._box(track)
            if (index is not None or coasting_on) and not box.outside(ctx.frame.width,
                                                                      ctx.frame.height):
                kept.append(track)
        used = set(matched.values())
        updated = {id(t) for t in kept if id(t) in matched}
        for index in high:
            if index not in used and not detections[index].box.outside(ctx.frame.width,
                                                                       ctx.frame.height):
                track = self._start(detections[index])
                kept.append(track)
                updated.add(id(track))
        self._tracks = fewest_misses(kept, self.max_tracks)
        if (shape := self._shapes.shape()) is not None:
            ctx.target_shape = shape
        ctx.tracks = [Track(t.id, self._box(t), t.score, track_state(t.confirmed,
                                                                     id(t) in updated))
                      for t in self._tracks]

    def _box(self, track: _Track) -> Box:
        return Box.from_center(*self._model.position(track.state), *track.size)

    def _cost(self, tracks: list[_Track], detections: list[Detection], least: float,
              gated: bool) -> np.ndarray:
        """Cost of each (track, detection) pair: ``1 - IoU`` when the pair is inside the motion
        gate with IoU >= ``least``; with ``gated``, ``1 + d^2 / gate`` for a pair inside the
        gate with less overlap, and only pairs inside the colour gate; ``_FORBIDDEN``
        otherwise."""
        if not tracks or not detections:
            return np.zeros((len(tracks), len(detections)))
        H = self._model.H
        x = np.array([t.state.x for t in tracks])  # (T, n)
        P = np.array([t.state.P for t in tracks])  # (T, n, n)
        sizes = np.array([t.size for t in tracks])  # (T, 2)
        predicted = x @ H.T  # (T, 2) centres
        boxes = np.concatenate([predicted - sizes / 2, sizes], axis=1)
        overlap = iou_matrix(boxes, np.array([d.box for d in detections], float))
        # innovation covariance S = H P H^T + R per track, R from the predicted box's size
        S = np.einsum("ij,tjk,lk->til", H, P, H)
        S[:, 0, 0] += self._variance(sizes)
        S[:, 1, 1] += self._variance(sizes)
        a, b, c, d = S[:, 0, 0], S[:, 0, 1], S[:, 1, 0], S[:, 1, 1]
        det = a * d - b * c
        offset = (np.array([(q.box.cx, q.box.cy) for q in detections])[None, :, :]
                  - predicted[:, None, :])  # (T, M, 2)
        ox, oy = offset[..., 0], offset[..., 1]
        distance = ((d[:, None] * ox - (b + c)[:, None] * oy) * ox
                    + a[:, None] * oy * oy) / det[:, None]  # offset^T S^-1 offset
        inside = distance <= self.gate
        cost = np.full(overlap.shape, _FORBIDDEN)
        if gated:
            cost = np.where(inside, 1.0 + distance / self.gate, cost)
            if self.colour_gate < 1.0:  # DeepSORT eq. 6: both gates must admit the pair
                inside &= colour_distances([t.colours for t in tracks],
                                           [q.colours for q in detections]) <= self.colour_gate
                cost = np.where(inside, cost, _FORBIDDEN)
        return np.where(inside & (overlap >= least) & (overlap > 0), 1.0 - overlap, cost)

    def _variance(self, sizes: np.ndarray) -> np.ndarray:
        """Measurement variance of a detected centre for boxes of ``sizes`` ((N, 2) widths and
        heights): ``(noise sqrt(w h))^2``, at least 1 pixel^2."""
        return np.maximum(1.0, self.noise * np.sqrt(sizes[:, 0] * sizes[:, 1])) ** 2

    def _update(self, track: _Track, detection: Detection) -> None:
        box = detection.box
        variance = float(self._variance(np.array([[box.w, box.h]]))[0])
        track.state = self._model.update(track.state, (box.cx, box.cy), np.eye(2) * variance)
        a = self.size_smoothing
        track.size = (track.size[0] + a * (box.w - track.size[0]),
                      track.size[1] + a * (box.h - track.size[1]))
        track.score = detection.score
        if detection.colours is not None and detection.score >= self.high:
            track.colours = (detection.colours if track.colours is None else COLOUR_MOMENTUM
                             * track.colours + (1 - COLOUR_MOMENTUM) * detection.colours)
        track.hits += 1
        track.misses = 0
        track.confirmed = track.confirmed or track.hits >= self.confirm
        if track.confirmed and detection.score >= self.high:
            self._shapes.add(box)

    def _start(self, detection: Detection) -> _Track:
        box = detection.box
        state = self._model.initiate([(box.cx, box.cy)] * self._model.points, 1.0)
        return _Track(next(self._ids), state, (box.w, box.h), detection.score,
                      colours=detection.colours, confirmed=self.confirm <= 1)
