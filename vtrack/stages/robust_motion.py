"""The ``robust`` tracker's motion model: a Kalman filter that also says how unsure it is.

Last link of the ``robust`` chain. The filter is S0's constant-velocity model per axis (S0 eq.
8-17, :class:`vtrack.filters.ConstantVelocity`) with noises in proportion to the target's size
(a filter tuned in pixels is too stiff for a big target and too loose for a small one): process
noise ``q = (q_rel d)^2``, measurement noise ``r = (r_rel d)^2``, ``P0 = (p0_rel d)^2 I``, ``d``
the first box's diagonal. Each measurement's noise is ``r / score^4`` (standard deviation
``/ score^2``, the score floored at ``min_trust``): the less the found box looks like the target
(``ctx.score``), the less it moves the filter.

The next frame's predicted box (``ctx.prediction``) centres ``robust_model``'s search region.
The filter steps by the frames that elapsed since the frame before (the chain's
:class:`~vtrack.clock.FrameClock`, ``ctx.clock``: the index difference, or
the time difference over the stream's frame period where the timestamps say otherwise, a change
of frame rate), not by one a call: a frame passed over (dropped by a camera, by ``--live``
falling behind, by a reader skipping a damaged stretch) moves the prediction as far as the
target went meanwhile, and the process noise grows with the elapsed frames (``Q`` per frame);
more than ``FrameClock.GAP`` frames elapsed (a stream that stalled or was cut, a clock or
numbering that jumped) is a break, not motion: the prediction stays at the last position, its
velocity unknown, as while lost. The prediction is made when the frame comes
(``ctx.forecast``); ``ctx.prediction`` left after a frame is the one for the frame after it.
While hidden the filter coasts; while lost it stands still at its last position (a lost
target's velocity is not known), so re-detection searches around where it was last seen; a
target taken back after being lost restarts the filter at the re-found box (its jump is not a
velocity).

On a frame where neither of ``robust``'s learners sees the target (``robust_failure``'s
``coast_unseen``: the response says occluded and the colours at its peak are not the
target's), the box reported is the constant-velocity extrapolation from the last frame that saw
it (S0 sec. 3's coasting), while the filter still takes the frame's peak (as weakly as its
score says) and the next search stays there: a target passing behind an occluder is reported
where it goes, not on the occluder's edge, and a wrong velocity never moves the search.

Pipeline contract of stage ``robust_motion``: reads ``ctx.measurement``, ``ctx.box``,
``ctx.state``, ``ctx.score``, ``ctx.robust`` (whether this frame saw the target), ``ctx.clock``;
writes ``ctx.box`` (the prediction while coasting, the extrapolation on an unseen frame),
``ctx.prediction``, ``ctx.forecast`` and ``ctx.robust`` (an unseen frame's peak, for the next
search).
"""

from __future__ import annotations

import math

import numpy as np

from vtrack.clock import FrameClock
from vtrack.filters import ConstantVelocity, GaussianState
from vtrack.frame import Frame
from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, TrackState, register
from vtrack.stages.robust_failure import mostly_outside


@register
class RobustMotion(Stage):
    """Constant-velocity Kalman filter with size-relative noise; predicts box and uncertainty."""

    name = "robust_motion"
    summary = ("robust: constant-velocity Kalman filter (S0 sec. 3, eq. 8-17) with noise "
               "relative to the target size; predicts the next centre and its uncertainty")
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
    requires = frozenset({"measurement", "box", "state", "score", "robust", "clock"})
    provides = frozenset({"box", "prediction", "forecast", "robust"})

    # Set from the parameters by Stage.__init__.
    q_rel: float
    r_rel: float
    p0_rel: float
    min_trust: float

    def start(self, ctx: TrackContext) -> None:
        assert ctx.box is not None
        d = math.hypot(ctx.box.w, ctx.box.h)
        # S0's model (sec. 3) (vtrack.filters), noises in proportion to the first box's diagonal
        self._model = ConstantVelocity(q=(self.q_rel * d) ** 2, r=(self.r_rel * d) ** 2,
                                       p0=(self.p0_rel * d) ** 2)
        self._state = self._model.initiate([(ctx.box.cx, ctx.box.cy)])
        self._was = TrackState.TRACKING
        #: The frames elapsed since the first one (the pipeline's :class:`FrameClock`, moved
        #: on to a frame before its forecast is asked).
        self._clock = ctx.clock
        #: The filter's state on the last frame that saw the target, and that frame's time on
        #: the clock.
        self._seen: tuple[GaussianState, float] | None = None
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
        frame that saw it (S0 sec. 3's coasting; the filter itself still takes this frame's
        peak, as weakly as its score says), unless that box is mostly outside the frame (then
        the peak's box, which ``robust_failure`` found in view), and keep the peak for the next
        search; otherwise remember this frame's position and velocity."""
        target = ctx.robust
        assert target is not None
        target.peak_box = None
        if target.unseen and self._seen is not None and ctx.box is not None:
            target.peak_box = ctx.box
            seen, seen_at = self._seen
            extrapolated = self._model.predict(seen, self._clock.now - seen_at)
            coasted = ctx.box.moved_to(*self._model.position(extrapolated))
            # an extrapolation past the edge of the view is no place a hidden target can be
            # (robust_failure calls a box mostly outside lost): the peak's box is reported
            if not mostly_outside(coasted, ctx.frame, target.least_inside):
                ctx.box = coasted
        elif ctx.state != TrackState.LOST:
            self._seen = (self._state, self._clock.now)

    def _predict(self, ctx: TrackContext) -> None:
        """Keep this frame's posterior and box for :meth:`_forecast`; leave the prediction
        for a frame one frame later (the prior the next frame uses if it comes then)."""
        assert ctx.box is not None
        if ctx.state == TrackState.LOST:
            self._state = self._model.with_velocity(self._state, np.zeros(2))
        self._posterior, self._box = self._state, ctx.box
        self._state = self._model.predict(self._state, 1.0)
        ctx.prediction = ctx.box.moved_to(*self._position())
        ctx.forecast = self._forecast

    def _forecast(self, frame: Frame) -> Box:
        """The prediction for ``frame``: the last posterior moved on by the frames elapsed
        since it (the one left assumed one), with ``Q`` for each elapsed frame. After a
        discontinuity (more than ``FrameClock.GAP`` frames elapsed) the velocity is not known:
        the prediction stays at the last position, as while lost, with ``Q`` for ``GAP`` frames,
        and an unseen frame's extrapolation starts again from the last box reported."""
        before, steps = self._clock.before, self._clock.elapsed  # the clock is at ``frame``
        if steps > FrameClock.GAP:
            still = self._model.with_velocity(self._posterior, np.zeros(2))
            self._state = self._model.predict(still, FrameClock.GAP,
                                              Q=self._model.Q * FrameClock.GAP)
            if self._seen is not None:
                seen, seen_at = self._seen
                reported = self._model.predict(seen, before - seen_at)
                self._seen = (self._model.with_velocity(reported, np.zeros(2)), self._clock.now)
        elif steps != 1.0:
            self._state = self._model.predict(self._posterior, steps,
                                              Q=self._model.Q * steps)
        return self._box.moved_to(*self._position())
