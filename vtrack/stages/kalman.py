"""Kalman filtering of the target centre: places the next search window, rides through occlusion.

The filter math and the three motion models live in :mod:`vtrack.filters`:

- ``cv``: S0 item 6 (Liu et al. 2022, eq. 8-17): per axis ``(x, dx)``, ``F = [[1,1],[0,1]]``,
  ``H = [1,0]``, ``Q = q I`` (S0: I), ``R = r`` (S0: 1), ``P0 = p0 I`` (not given; 100 I);
- ``ca``: S2 item 8 (Di & Zhu 2008, eq. 14-16): per axis ``(x, v, a)``, ``A`` with ``T^2`` as
  printed (``kinematic``: ``T^2/2``), ``W = diag(0, 0, q)``, ``R = r``, started from the first
  three measured positions; until then there is no prediction and the measurement passes
  through;
- ``gravity``: S4 item 3 (Gan 2018, eq. 11-13): ``(x, y, ux, vy)``, constant velocity plus a
  gravity input ``g`` on the vertical velocity, ``P(1) = p0 I`` (S4: 100 I); ``init =
  "document"`` starts from ``(w/2, 0, 0, 0)`` (``w`` the image width) corrected by the first
  measurement, ``"first_measurement"`` starts at the first measurement at rest.

The models' time step ``T`` is ``dt`` frames (``timebase = "frame"``, S0 and S4: velocities in
pixels per frame) or the time between the last two frames' timestamps (``timebase = "seconds"``,
S2's "time interval between frames": velocities in pixels per second). The next frame is
predicted with the last interval; when it arrives after another interval (a change of frame
rate, as in S2's fig. 1 where the sampling drops from 5 to 2 frames per second), the prediction
is made again for its actual time before any stage uses it (``prepare``).

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

import math

import numpy as np

from vtrack.filters import (
    KalmanFilter,
    Point,
    constant_acceleration,
    constant_velocity,
    gravity,
    transition,
)
from vtrack.params import Param
from vtrack.stages.base import Stage, TrackContext, register


@register
class Kalman(Stage):
    """Kalman filter on the box centre: cv (S0), ca (S2) or gravity (S4) motion model."""

    name = "kalman"
    summary = "Kalman filter on the box centre (cv: S0 6, ca: S2 8, gravity: S4 3); predicts"
    params = (
        Param(
            "model", str, "cv",
            "cv = constant velocity per axis (S0); ca = constant acceleration per axis (S2); "
            "gravity = (x, y, ux, vy) with gravity input (S4)",
            choices=("cv", "ca", "gravity"),
        ),
        Param(
            "output", str, "measurement",
            "the frame's box: measurement = the measured box (S0; the filter places the next "
            "window); filtered = the filter's corrected centre",
            choices=("measurement", "filtered"),
        ),
        Param("q", float, 1.0, "process noise: Q = q I (cv, gravity), W = diag(0,0,q) (ca)",
              min=0.0),
        Param("r", float, 1.0, "measurement noise variance R (S0, S2: 1)", min=1e-9),
        Param("p0", float, 100.0, "initial covariance P0 = p0 I (cv, gravity; S4: 100)",
              min=0.0),
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
              min=1e-9),
        Param("kinematic", bool, False,
              "ca: use T^2/2 in A instead of the T^2 printed in S2 eq. 14"),
        Param("g", float, 1.0,
              "gravity: vertical acceleration in pixels per dt^2, downwards positive"),
        Param(
            "init", str, "document",
            "gravity: document = start from (w/2, 0, 0, 0) as in S4; first_measurement = "
            "start at the first measured centre",
            choices=("document", "first_measurement"),
        ),
    )
    requires = frozenset({"measurement", "box", "prediction"})
    provides = frozenset({"box", "prediction"})
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
        self._filter: KalmanFilter | None = None
        self._points: list[Point] = []  # ca: positions until the filter can start
        # T of the models: fixed, or (timebase = seconds) the latest positive interval between
        # two frames' timestamps, None until there is one. The filter's matrices are for
        # _filter_step.
        self._step: float | None = self.dt if self.timebase == "frame" else None
        self._filter_step: float | None = None
        self._last_time: float | None = None
        self._posterior: tuple[np.ndarray, np.ndarray] | None = None  # before the last predict
        self.step(ctx)

    def prepare(self, ctx: TrackContext) -> None:
        """timebase = seconds: if this frame came after another interval than the one its
        prediction assumed, predict again from the last posterior with the actual interval."""
        if self.timebase != "seconds" or self._posterior is None or self._last_time is None:
            return
        interval = ctx.frame.time_s - self._last_time
        if interval <= 0 or _same_step(interval, self._filter_step) or ctx.box is None:
            return
        assert self._filter is not None  # a posterior exists only once the filter does
        self._filter.x, self._filter.P = (a.copy() for a in self._posterior)
        self._predict(interval)
        ctx.prediction = ctx.box.moved_to(*self._filter.position())

    def step(self, ctx: TrackContext) -> None:
        if self.timebase == "seconds":
            self._time(ctx.frame.time_s)
        if ctx.prediction is not None:
            ctx.extras["pred_cx"] = ctx.prediction.cx
            ctx.extras["pred_cy"] = ctx.prediction.cy
        box = ctx.measurement
        if box is not None:
            self._correct((box.cx, box.cy), ctx.frame.width)
            if self.output == "filtered" and self._filter is not None:
                box = box.moved_to(*self._filter.position())
            ctx.box = box
        elif self._filter is not None and ctx.box is not None:
            ctx.box = ctx.box.moved_to(*self._filter.position())  # coast: this frame's prior
        if self._filter is None or ctx.box is None or self._step is None:
            ctx.prediction = None
            return
        if self.timebase == "seconds":
            self._posterior = (self._filter.x.copy(), self._filter.P.copy())
        self._predict(self._step)
        ctx.prediction = ctx.box.moved_to(*self._filter.position())

    def _predict(self, step: float) -> None:
        """Advance the filter by ``step`` (retiming its matrices when the step changed)."""
        assert self._filter is not None
        if not _same_step(step, self._filter_step):  # timebase = seconds: another interval
            self._filter.F, self._filter.B = transition(self.model, step, self.kinematic)
            self._filter_step = step
        self._filter.predict()

    def _time(self, time_s: float) -> None:
        """timebase = seconds: take T from this frame's timestamp and the previous one's (an
        interval that is not positive, from a broken timestamp, keeps the previous T)."""
        if self._last_time is not None and time_s > self._last_time:
            interval = time_s - self._last_time
            if not _same_step(interval, self._step):
                self._step = interval
        self._last_time = time_s

    def _correct(self, point: Point, width: int) -> None:
        """Update the filter with a measured centre, creating it when it does not exist yet."""
        # Until timebase = seconds has seen two frames T is unknown; cv and gravity start at
        # rest, where T does not matter, and get their matrices before their first prediction.
        if self._filter is not None:
            self._filter.update(point)
            return
        if self.model == "ca":
            self._points.append(point)
            if len(self._points) < 3:
                return
        step = self._step or 1.0
        self._filter_step = self._step  # None: the matrices are retimed before the first predict
        if self.model == "cv":
            self._filter = constant_velocity(point, self.q, self.r, self.p0, step)
        elif self.model == "gravity":
            start = (width / 2.0, 0.0) if self.init == "document" else point
            self._filter = gravity(start, self.q, self.r, self.p0, step, self.g)
            if self.init == "document":
                self._filter.update(point)  # S4: X(1) = (w/2, 0, 0, 0), corrected by y(1)
        else:
            # S2: S3 and V3 from the first three positions, with T the latest interval.
            self._filter = constant_acceleration(self._points, self.q, self.r, step,
                                                 self.kinematic)


def _same_step(a: float, b: float | None) -> bool:
    """Whether two frame intervals are the same up to timestamp rounding (constant frame rate
    timestamps i / fps differ in their last bits)."""
    return b is not None and math.isclose(a, b, rel_tol=1e-6)
