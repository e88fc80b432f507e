"""Kalman filtering of the target centre: places the next search window, rides through occlusion.

The filter math and the three motion models live in :mod:`vtrack.filters` (``model`` names one
of :data:`vtrack.filters.MOTION_MODELS`):

- ``cv``: S0 (Liu et al. 2022, sec. 3, eq. 8-17): per axis ``(x, dx)``, ``F = [[1,1],[0,1]]``,
  ``H = [1,0]``, ``Q = q I`` (S0: I), ``R = r`` (S0: 1), ``P0 = p0 I`` (not given; 100 I);
- ``ca``: S2 (Di & Zhu 2008, sec. 5, eq. 14-16): per axis ``(x, v, a)``, ``A`` with ``T^2`` as
  printed (``kinematic``: ``T^2/2``), ``W = diag(0, 0, q)``, ``R = r``, started from the first
  three measured positions; until then there is no prediction and the measurement passes
  through;
- ``gravity``: S4 (Gan 2018, sec. 3, eq. 11-13): ``(x, y, ux, vy)``, constant velocity plus a
  gravity input ``g`` on the vertical velocity, ``P(1) = p0 I`` (S4: 100 I); ``init =
  "document"`` starts from ``(w/2, 0, 0, 0)`` (``w`` the image width) corrected by the first
  measurement, ``"first_measurement"`` starts at the first measurement at rest.

The models' time step ``T`` is ``dt`` frames (``timebase = "frame"``, S0 and S4: velocities in
pixels per frame) or the time between the last two frames' timestamps (``timebase = "seconds"``,
S2's "time interval between frames": velocities in pixels per second). The next frame is
predicted with the last interval; with ``timebase = "seconds"`` the stage also leaves
``ctx.forecast``, so that a frame that arrives after another interval (a change of frame rate,
as in S2's fig. 1 where the sampling drops from 5 to 2 frames per second) is predicted for its
actual time before any stage uses the prediction.

Each frame: if ``ctx.measurement`` is a box, the filter is updated with its centre; otherwise it
coasts. The frame's box is the measurement (``output = "measurement"``: the mean-shift result is
the position, the filter only places the next window) or the filtered centre (``"filtered"``);
while there is no measurement it is this frame's prediction. Then the filter predicts the next
frame: ``ctx.prediction`` is a box of the frame's box size centred there.

Pipeline contract of stage ``kalman``: reads ``ctx.measurement``, ``ctx.box``,
``ctx.prediction`` (the one used for this frame) and ``ctx.frame.width``; writes ``ctx.box``,
``ctx.prediction`` and the extras ``pred_cx``, ``pred_cy`` (the centre of the prediction this
frame's search started from; empty when there was none).
"""

from __future__ import annotations

from vtrack.filters import MOTION_MODELS, GaussianState, MotionModel, Point, motion_model, same_step
from vtrack.frame import Frame
from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register


@register
class Kalman(Stage):
    """Kalman filter on the box centre: cv (S0), ca (S2) or gravity (S4) motion model."""

    name = "kalman"
    summary = ("Kalman filter on the box centre (cv: S0 eq. 8-17, ca: S2 eq. 14-16, gravity: "
               "S4 eq. 11-13); predicts")
    params = (
        Param(
            "model", str, "cv",
            "cv = constant velocity per axis (S0); ca = constant acceleration per axis (S2); "
            "gravity = (x, y, ux, vy) with gravity input (S4)",
            choices=tuple(MOTION_MODELS),
        ),
        Param(
            "output", str, "measurement",
            "the frame's box: measurement = the measured box (S0; the filter places the next "
            "window); filtered = the filter's corrected centre",
            choices=("measurement", "filtered"),
        ),
        Param("q", float, 1.0, "process noise: Q = q I (cv, gravity), W = diag(0,0,q) (ca)",
              min=0.0, max=1e6),
        Param("r", float, 1.0, "measurement noise variance R (S0, S2: 1)",
              min=1e-9, max=1e6),
        Param("p0", float, 100.0, "initial covariance P0 = p0 I (cv, gravity; S4: 100)",
              min=0.0, max=1e6),
        Param(
            "timebase", str, "frame",
            "unit of the models' time step T: frame = dt frames per frame (S0, S4); seconds = "
            "the time between the last two frames from their timestamps, so velocities are in "
            "pixels per second and T follows a changing frame rate (S2: 'T is the time interval "
            "between frames')",
            choices=("frame", "seconds"),
        ),
        Param("dt", float, 1.0,
              "timebase = frame: time step between frames in the models' unit (1 = a frame)",
              min=1e-9, max=100.0),
        Param("kinematic", bool, False,
              "ca: use T^2/2 in A instead of the T^2 printed in S2 eq. 14"),
        Param("g", float, 1.0,
              "gravity: vertical acceleration in pixels per dt^2, downwards positive",
              min=-1e4, max=1e4),
        Param(
            "init", str, "document",
            "gravity: document = start from (w/2, 0, 0, 0) as in S4; first_measurement = "
            "start at the first measured centre",
            choices=("document", "first_measurement"),
        ),
    )
    requires = frozenset({"measurement", "box", "prediction"})
    provides = frozenset({"box", "prediction", "forecast"})
    columns = ("pred_cx", "pred_cy")
    needs_init_box = False  # reads ctx.box only when it is set (S4: no box until a detection)

    # Set from the parameters by Stage.__init__.
    model: str
    output: str
    q: float
    r: float
    p0: float
    timebase: str
    dt: float
    kinematic: bool
    g: float
    init: str

    def start(self, ctx: TrackContext) -> None:
        """Forget any previous run, then take the first frame's box as the first measurement."""
        self._model: MotionModel = motion_model(self.model, self.q, self.r, self.p0,
                                                self.kinematic, self.g)
        self._state: GaussianState | None = None  # the last frame's posterior (None: no filter)
        self._prior: GaussianState | None = None  # this frame's prior, if one was predicted
        self._points: list[Point] = []  # positions until the model can start (ca: three)
        # T: fixed, or (timebase = seconds) the latest interval between two frames' timestamps
        # (None until there is one); and the time of the last frame.
        self._step: float | None = self.dt if self.timebase == "frame" else None
        self._time: float | None = None
        self._box: Box | None = None  # the box the last prediction was centred for
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        if self.timebase == "seconds":
            self._retime(ctx.frame.time_s)
        if ctx.prediction is not None:
            ctx.extras["pred_cx"] = ctx.prediction.cx
            ctx.extras["pred_cy"] = ctx.prediction.cy
        state = self._prior if self._prior is not None else self._state
        box = ctx.measurement
        if box is not None:
            state = self._correct(state, (box.cx, box.cy), ctx.frame.width)
            if self.output == "filtered" and state is not None:
                box = box.moved_to(*self._model.position(state))
            ctx.box = box
        elif state is not None and ctx.box is not None:
            ctx.box = ctx.box.moved_to(*self._model.position(state))  # coast: this frame's prior
        self._state, self._prior, self._box = state, None, ctx.box
        ctx.forecast = None
        if state is None or ctx.box is None or self._step is None:
            ctx.prediction = None
            return
        self._prior = self._model.predict(state, self._step)
        ctx.prediction = ctx.box.moved_to(*self._model.position(self._prior))
        if self.timebase == "seconds":
            ctx.forecast = self._forecast

    def _forecast(self, frame: Frame) -> Box | None:
        """timebase = seconds: the prediction for ``frame``, from the last posterior and the
        actual interval (the one published assumed the last interval again)."""
        assert self._state is not None and self._box is not None and self._time is not None
        interval = frame.time_s - self._time
        if interval > 0:  # a broken timestamp keeps the prediction made with the last T
            self._prior = self._model.predict(self._state, interval)
        assert self._prior is not None
        return self._box.moved_to(*self._model.position(self._prior))

    def _retime(self, time_s: float) -> None:
        """timebase = seconds: take T from this frame's timestamp and the previous one's (an
        interval that is not positive, from a broken timestamp, keeps the previous T)."""
        if self._time is not None and time_s > self._time:
            interval = time_s - self._time
            if not same_step(interval, self._step):
                self._step = interval
        self._time = time_s

    def _correct(self, state: GaussianState | None, point: Point,
                 width: int) -> GaussianState | None:
        """``state`` updated with a measured centre; the first state once the model can start
        (None until then)."""
        if state is not None:
            return self._model.update(state, point)
        self._points.append(point)
        if len(self._points) < self._model.points:
            return None
        # S2: S3 and V3 from the first three positions, with T the latest interval (until
        # timebase = seconds has seen two frames T is unknown; cv and gravity start at rest,
        # where T does not matter).
        if self.model == "gravity" and self.init == "document":
            # S4: X(1) = (w/2, 0, 0, 0), corrected by y(1)
            start = self._model.initiate([(width / 2.0, 0.0)])
            return self._model.update(start, point)
        return self._model.initiate(self._points[-self._model.points:], self._step or 1.0)
