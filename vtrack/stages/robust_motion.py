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

On a frame where neither of ``robust``'s learners sees the target (``robust_failure``'s
``coast_unseen``: the response says occluded and the colours at its peak are not the
target's), the box reported is the constant-velocity extrapolation from the last frame that saw
it (S0 item 7's coasting), while the filter still takes the frame's peak (as weakly as its
score says) and the next search stays there: a target passing behind an occluder is reported
where it goes, not on the occluder's edge, and a wrong velocity never moves the search.

Pipeline contract of stage ``robust_motion``: reads ``ctx.measurement``, ``ctx.box``,
``ctx.state``, ``ctx.score``, ``ctx.robust`` (whether this frame saw the target); writes
``ctx.box`` (the prediction while coasting, the extrapolation on an unseen frame),
``ctx.prediction`` and ``ctx.robust`` (an unseen frame's peak, for the next search).
"""

from __future__ import annotations

import math

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
        Param("min_trust", float, 0.5,
              "floor of the score that scales a measurement's noise (R / score^4; 0.5: at "
              "most 16 R, 0.1: 10^4 R): the lower, the less a held frame's low-scoring "
              "measurement moves the filter (a partly covered target's biased centre), and "
              "the longer the filter lags a target that changes as it speeds up", min=0.01,
              max=1.0),
    )
    requires = frozenset({"measurement", "box", "state", "score", "robust"})
    provides = frozenset({"box", "prediction", "robust"})

    # Set from the parameters by Stage.__init__.
    q_rel: float
    r_rel: float
    p0_rel: float
    min_trust: float

    def start(self, ctx: TrackContext) -> None:
        assert ctx.box is not None
        d = math.hypot(ctx.box.w, ctx.box.h)
        # S0 item 6's model (vtrack.filters), noises in proportion to the first box's diagonal
        self._model = ConstantVelocity(q=(self.q_rel * d) ** 2, r=(self.r_rel * d) ** 2,
                                       p0=(self.p0_rel * d) ** 2)
        self._state = self._model.initiate([(ctx.box.cx, ctx.box.cy)])
        self._was = TrackState.TRACKING
        #: The filter's state on the last frame that saw the target, and that frame's index.
        self._seen: tuple[GaussianState, int] | None = None
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
            else:
                # a measurement is as trustworthy as the match it came from: its standard
                # deviation grows as 1 / score^2 (R / score^4), so a partly covered target's
                # biased centre does not become a velocity before it is hidden
                confidence = min(max(ctx.score, self.min_trust), 1.0)
                self._state = self._model.update(self._state, z,
                                                 R=self._model.R / confidence**4)
        elif ctx.box is not None:
            ctx.box = ctx.box.moved_to(*self._position())  # coast: this frame's prior
        self._report_unseen(ctx)
        self._was = ctx.state
        self._predict(ctx)

    def _report_unseen(self, ctx: TrackContext) -> None:
        """On a frame where neither of ``robust``'s learners sees the target
        (``ctx.robust.unseen``), report the box extrapolated at constant velocity from the last
        frame that saw it (S0 item 7's coasting; the filter itself still takes this frame's
        peak, as weakly as its score says) and keep the peak for the next search; otherwise
        remember this frame's position and velocity."""
        target = ctx.robust
        assert target is not None
        target.peak_box = None
        if target.unseen and self._seen is not None and ctx.box is not None:
            target.peak_box = ctx.box
            seen, seen_at = self._seen
            extrapolated = self._model.predict(seen, ctx.frame.index - seen_at)
            ctx.box = ctx.box.moved_to(*self._model.position(extrapolated))
        elif ctx.state != TrackState.LOST:
            self._seen = (self._state, ctx.frame.index)

    def _predict(self, ctx: TrackContext) -> None:
        assert ctx.box is not None
        if ctx.state == TrackState.LOST:
            self._state = self._model.with_velocity(self._state, np.zeros(2))
        self._state = self._model.predict(self._state, 1.0)
        ctx.prediction = ctx.box.moved_to(*self._position())
