"""S4 per track: one Kalman filter per target, nearest-neighbour gated association.

S4 (Gan 2018) tracks one ball: background subtraction gives the measurement, a Kalman filter
with state ``(x, y, ux, vy)`` (S4 eq. 11-13) smooths and predicts it. The ``kalman_tracks``
stage runs that filter (``model = "gravity"``, :class:`vtrack.filters.Gravity`; ``g = 0``
leaves S4's constant-velocity matrices without the gravity input), or any other motion model
of :data:`vtrack.filters.MOTION_MODELS` (``cv``, S0's; ``ca``, S2's, started from one position
at rest: three equal positions), for every target the detector reports (``ctx.detections``),
which is what S4's method becomes with several targets:

1. every track's filter predicts this frame (S4 eq. 5-6);
2. association by global nearest neighbour: the (track, measurement) pairs whose distance
   between predicted and measured centre is within ``gate`` pixels are taken shortest first,
   each track and each measurement at most once, tracks that missed fewer frames in a row
   first (the matching cascade of DeepSORT, Wojke et al. 2017): when two targets merge into
   one blob, the track that had it keeps it and the other coasts on its filter, instead of the
   two taking turns and both filters learning the blob's motion;
3. matched tracks are updated with the measured centre (S4 eq. 7-10); a measurement left over
   starts a tentative track (its filter starts at the measurement, at rest: S4's start at
   ``(w/2, 0)`` suits one ball falling from the top, not targets anywhere);
4. a track is confirmed after ``confirm`` updates; a tentative track is deleted on its first
   miss, a confirmed one after more than ``max_coast`` misses in a row; any track once its
   box has left the frame, and a detection wholly outside the frame starts none (as
   ``byte_tracks``: a track wholly outside the frame is never reported).

Output (``ctx.tracks``): one :class:`~vtrack.stages.base.Track` per track, the filtered centre
with the last measured size, confidence = the share of its frames with a measurement, state
``confirmed`` (confirmed and updated this frame: written to ``tracks.csv``), ``coasting``
(confirmed, predicted only) or ``tentative``. Ids start at the run's first track id (1 unless
it gives another: ``--first-id``), one per track created, never reused. Work per frame:
``O(T M)`` distances (NumPy) for ``T`` tracks and ``M`` measurements, one 4x4 filter step per
track.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vtrack.filters import MOTION_MODELS, GaussianState, MotionModel, motion_model
from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.stages.base import Stage, Track, TrackContext, register
from vtrack.stages.detect import (
    Detection,
    TrackIds,
    centroids,
    fewest_misses,
    pairwise_distances,
    track_state,
)


@dataclass(eq=False)
class _KalmanTrack:
    id: int
    state: GaussianState
    size: tuple[float, float]  # last measured width, height
    age: int = 1  # frames since creation, this one included
    hits: int = 1  # frames with a measurement
    misses: int = 0  # frames in a row without one
    confirmed: bool = False


@register
class KalmanTracks(Stage):
    """S4 per track: S4's Kalman filter per target, nearest-neighbour gated association,
    confirmation and deletion counts."""

    name = "kalman_tracks"
    summary = "S4 per track: a Kalman filter per detected target, nearest-neighbour association"
    params = (
        Param(
            "model", str, "gravity",
            "motion model of every track: gravity = S4's (x, y, ux, vy) with gravity input g; "
            "cv = constant velocity per axis (S0); ca = constant acceleration per axis (S2)",
            choices=tuple(MOTION_MODELS),
        ),
        Param("q", float, 1.0, "process noise Q = q I (not given by S4: 1)",
              min=0.0, max=1e6),
        Param("r", float, 1.0, "measurement noise R = r I (not given by S4: 1)",
              min=1e-9, max=1e6),
        Param("p0", float, 100.0, "initial covariance P(1) = p0 I (S4 eq. 13: 100)",
              min=0.0, max=1e6),
        Param("dt", float, 1.0, "time step between frames (S4's dt; 1 = a frame)",
              min=1e-9, max=100.0),
        Param(
            "g",
            float,
            0.0,
            "S4's gravity input: vertical acceleration in pixels per dt^2, downwards positive "
            "(0: constant velocity, for targets that do not fall; the generated bounce scene "
            "at 30 fps falls at 1 px/frame^2)",
            min=-1e4, max=1e4,
        ),
        Param(
            "gate",
            float,
            20.0,
            "largest distance in pixels between a track's predicted centre and a measurement "
            "it may take",
            min=1.0, max=1e5,
        ),
        Param("confirm", int, 3, "updates after which a track is confirmed",
              min=1, max=1000),
        Param(
            "max_coast",
            int,
            15,
            "a confirmed track missing more frames in a row than this is deleted",
            min=0, max=100000,
        ),
        Param(
            "max_tracks",
            int,
            1000,
            "at most this many tracks are kept, those coasting longest dropped first (bounds "
            "each frame's work and memory whatever max_coast lets live; not in S4)",
            min=1, max=1000,
        ),
    )
    requires = frozenset({"detections", "first_track_id"})
    provides = frozenset({"tracks"})
    multi_target = True
    needs_init_box = False

    def start(self, ctx: TrackContext) -> None:
        """Forget any previous run (no track), then track this frame."""
        self._model: MotionModel = motion_model(self.model, self.q, self.r, self.p0, g=self.g)
        self._tracks: list[_KalmanTrack] = []
        self._ids = TrackIds(ctx)
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        detections: list[Detection] = ctx.detections
        model = self._model
        for track in self._tracks:
            track.state = model.predict(track.state, self.dt)  # S4 eq. 5-6
            track.age += 1
        matches = self._associate(detections)
        updated = set()
        for row, column in matches:
            track, detection = self._tracks[row], detections[column]
            track.state = model.update(track.state, (detection.cx, detection.cy))  # S4 eq. 7-10
            track.size = (detection.box.w, detection.box.h)
            track.hits += 1
            track.misses = 0
            track.confirmed = track.confirmed or track.hits >= self.confirm
            updated.add(id(track))
        for track in self._tracks:
            if id(track) not in updated:
                track.misses += 1
        width, height = ctx.frame.width, ctx.frame.height
        self._tracks = [
            t for t in self._tracks
            if (id(t) in updated or (t.confirmed and t.misses <= self.max_coast))
            and not self._box(t).outside(width, height)
        ]
        taken = {column for _, column in matches}
        for column, detection in enumerate(detections):
            if column not in taken and not detection.box.outside(width, height):
                self._tracks.append(self._start(detection))
                updated.add(id(self._tracks[-1]))
        self._tracks = fewest_misses(self._tracks, self.max_tracks)
        ctx.tracks = [
            Track(
                t.id,
                self._box(t),
                t.hits / t.age,
                track_state(t.confirmed, id(t) in updated),
            )
            for t in self._tracks
        ]

    def _box(self, track: _KalmanTrack) -> Box:
        return Box.from_center(*self._model.position(track.state), *track.size)

    def _start(self, detection: Detection) -> _KalmanTrack:
        point = (detection.cx, detection.cy)
        state = self._model.initiate([point] * self._model.points, self.dt)
        return _KalmanTrack(
            next(self._ids), state, (detection.box.w, detection.box.h),
            confirmed=self.confirm <= 1,
        )

    def _associate(self, detections: list[Detection]) -> list[tuple[int, int]]:
        """Global nearest neighbour: gated (track, measurement) pairs, by the track's misses in
        a row, then shortest first."""
        predicted = np.array([self._model.position(t.state) for t in self._tracks],
                             float).reshape(-1, 2)
        distances = pairwise_distances(predicted, centroids(detections))
        rows, columns = np.nonzero(distances <= self.gate)
        misses = np.array([t.misses for t in self._tracks], int)
        order = np.lexsort((distances[rows, columns], misses[rows]))
        matches: list[tuple[int, int]] = []
        used_rows: set[int] = set()
        used_columns: set[int] = set()
        for row, column in zip(rows[order].tolist(), columns[order].tolist(), strict=True):
            if row not in used_rows and column not in used_columns:
                matches.append((row, column))
                used_rows.add(row)
                used_columns.add(column)
        return matches
