"""The ``robust`` tracker's motion model: a Kalman filter that also says how unsure it is.

Last link of the ``robust`` chain. The filter is S0's constant-velocity model per axis (S0 eq.
8-17, :class:`vtrack.filters.ConstantVelocity`) with noises in proportion to the target's size
(a filter tuned in pixels is too stiff for a big target and too loose for a small one): process
noise ``q = (q_rel d)^2``, measurement noise ``r = (r_rel d)^2``, ``P0 = (p0_rel d)^2 I``, ``d``
the first box's diagonal. Each measurement's noise is ``r / score^4`` (standard deviation
``/ score^2``, the score floored at ``min_trust``): the less the found box looks like the target
(``ctx.score``), the less it moves the filter.

The next frame's predicted box (``ctx.prediction``) centres ``robust_model``'s search region.
While hidden the filter coasts; while lost it stands still at its last position (a lost
target's velocity is not known), so re-detection searches around where it was last seen; a
target taken back after being lost restarts the filter at the re-found box (its jump is not a
velocity).

Where a hidden target coasts from: a target covered slowly from one side is measured further
and further back (its visible part) on the frames before it is hidden, and the filter learns
that it slows down, so it would coast at the wrong speed. The filter keeps its state on the last
confident frame (``rewind_above``), with the velocity replaced by the mean displacement of the
measured centre over the last ``velocity_frames`` confident frames (the filter's own velocity
follows the measurement noise, and starts at rest); on the frame the target becomes hidden it
coasts from that state, predicted to this frame, if it is at most ``rewind_frames`` back: the
recent past re-estimated once later evidence says its measurements were bad, in the spirit of
fixed-lag smoothing (our choice; measured in benchmarks/RESULTS.md section 8).

Pipeline contract of stage ``robust_motion``: reads ``ctx.measurement``, ``ctx.box``,
``ctx.state``, ``ctx.score``; writes ``ctx.box`` (the prediction while coasting) and
``ctx.prediction``.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from vtrack.filters import ConstantVelocity, GaussianState
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, TrackState, register


@register
class RobustMotion(Stage):
    """Constant-velocity Kalman filter with size-relative noise; predicts box and uncertainty."""

    name = "robust_motion"
    summary = ("robust: constant-velocity Kalman filter (S0 6) with noise relative to the "
               "target size; predicts the next centre and its uncertainty")
    params = (
        Param("q_rel", float, 0.05, "process noise std per frame, in target diagonals",
              min=0.0, max=10.0),
        Param("r_rel", float, 0.05, "measurement noise std, in target diagonals",
              min=1e-6, max=10.0),
        Param("p0_rel", float, 0.5, "initial uncertainty std, in target diagonals",
              min=0.0, max=10.0),
        Param("min_trust", float, 0.1,
              "floor of the score that scales a measurement's noise (R / score^4; 0.1: at "
              "most 10^4 R): the lower, the less a held frame's low-scoring measurement moves "
              "the filter, and the more its uncertainty (and the search window) grows while "
              "the hold lasts", min=0.01, max=1.0),
        Param("rewind_frames", int, 30,
              "when a tracked target becomes hidden, coast from the last confident frame if "
              "it is at most this many frames back (0: coast from the current state)",
              min=0, max=10000),
        Param("rewind_above", float, 0.9,
              "a tracking frame is confident at this score or above", min=0.0, max=1.0),
        Param("velocity_frames", int, 10,
              "the coasting velocity is the mean displacement of the measured centre over the "
              "last this many confident frames (1: the filter's own)", min=1, max=1000),
    )
    requires = frozenset({"measurement", "box", "state", "score"})
    provides = frozenset({"box", "prediction"})

    # Set from the parameters by Stage.__init__.
    q_rel: float
    r_rel: float
    p0_rel: float
    min_trust: float
    rewind_frames: int
    rewind_above: float
    velocity_frames: int

    def start(self, ctx: TrackContext) -> None:
        assert ctx.box is not None
        d = math.hypot(ctx.box.w, ctx.box.h)
        # S0 item 6's model (vtrack.filters), noises in proportion to the first box's diagonal
        self._model = ConstantVelocity(q=(self.q_rel * d) ** 2, r=(self.r_rel * d) ** 2,
                                       p0=(self.p0_rel * d) ** 2)
        self._state = self._model.initiate([(ctx.box.cx, ctx.box.cy)])
        self._was = TrackState.TRACKING
        # the state on the last confident frame (its velocity the running mean over confident
        # frames) and that frame's index: where a target that becomes hidden coasts from
        self._confident: tuple[GaussianState, int] | None = None
        self._centres: deque[tuple[int, float, float]] = deque(maxlen=self.velocity_frames)
        self._predict(ctx)

    def _position(self) -> tuple[float, float]:
        return self._model.position(self._state)

    def step(self, ctx: TrackContext) -> None:
        box = ctx.measurement
        if box is not None:
            z = np.array([box.cx, box.cy])
            if self._was == TrackState.LOST:
                # re-found: a jump, not a velocity
                self._state = self._model.initiate([(box.cx, box.cy)])
                self._centres.clear()
                self._confident = None
            else:
                # a measurement is as trustworthy as the match it came from: its standard
                # deviation grows as 1 / score^2 (R / score^4), so a partly covered target's
                # biased centre does not become a velocity before it is hidden
                confidence = min(max(ctx.score, self.min_trust), 1.0)
                self._state = self._model.update(self._state, z,
                                                 R=self._model.R / confidence**4)
            if ctx.state == TrackState.TRACKING and ctx.score >= self.rewind_above:
                self._remember(ctx.frame.index, box.cx, box.cy)
        elif ctx.box is not None:
            if self._was == TrackState.TRACKING and self._confident is not None:
                state, index = self._confident
                age = ctx.frame.index - index
                if 0 < age <= self.rewind_frames:
                    # just hidden: the frames since the last confident one measured a target
                    # being covered (its visible part, further and further back); coast from
                    # before them
                    self._state = self._model.predict(state, float(age))
            ctx.box = ctx.box.moved_to(*self._position())  # coast: this frame's prior
        self._was = ctx.state
        self._predict(ctx)

    def _remember(self, index: int, cx: float, cy: float) -> None:
        """Keep the state of confident frame ``index`` (measured centre ``cx, cy``), its
        velocity replaced by the mean displacement over the last ``velocity_frames`` confident
        frames: the filter's own velocity follows the measurement noise, and starts at rest
        (so nothing is kept before two confident frames give a displacement; ``velocity_frames =
        1``: the filter's state as it is)."""
        if self.velocity_frames == 1:
            self._confident = (self._state, index)
            return
        self._centres.append((index, cx, cy))
        first, last = self._centres[0], self._centres[-1]
        if last[0] > first[0]:
            velocity = np.array([last[1] - first[1], last[2] - first[2]]) / (last[0] - first[0])
            self._confident = (self._model.with_velocity(self._state, velocity), index)

    def _predict(self, ctx: TrackContext) -> None:
        assert ctx.box is not None
        if ctx.state == TrackState.LOST:
            self._state = self._model.with_velocity(self._state, np.zeros(2))
        self._state = self._model.predict(self._state, 1.0)
        ctx.prediction = ctx.box.moved_to(*self._position())
