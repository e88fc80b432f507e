"""S3: simplified multiple-hypothesis tracking (Zhao, Wu, Li).

The ``mht`` stage takes the measurements of a detecting stage (``ctx.detections``: the blobs of
``threshold -> blobs`` in S3's chain) and keeps, frame after frame:

- **tracks and their branches** (S3 section 2.3). Each branch predicts its next position with
  the quadratic predictor ``f(k+1) = 3 f(k) - 3 f(k-1) + f(k-2)`` (S3 eq. 6) when its last three
  positions are uncontested measurements, and with constant velocity otherwise (see
  :func:`predict_position`). Association is the distance between prediction and measurement,
  inside a circular gate of ``gate`` pixels. A branch with several measurements in its gate
  branches, one child per measurement (the ``max_branches`` nearest); a branch without one
  coasts on its prediction, and so may a branch whose measurements another track also gates
  (*contested* measurements: the other track may take them). A measurement that no track of a
  hypothesis uses starts a new track in that hypothesis (S3: "new tracks from unassociated
  measurements").
- **track confidence** ``P_R`` (S3 section 2.3): ``initial`` for a new track, ``+ hit`` on each
  update, ``- miss`` on each frame without one. A track is confirmed once ``P_R >= confirm``;
  a branch is deleted when ``P_R < delete``, or after ``max_coast`` frames in a row without a
  measurement (not in S3: ``P_R`` grows while a track is updated, so the threshold alone would
  keep a long-lived track that left for as long as it had lived).
- **hypotheses** (S3 section 2.4): sets of compatible branches, at most one branch per track
  (branches of one track share their past measurements) and no two sharing a measurement; no
  clustering. ``P_H`` = sum of the ``P_R`` of its branches. Each hypothesis of the last frame is
  extended by choosing one child per branch; the ``max_hypotheses`` best extensions are kept,
  and of those only the ones with ``P_H >= best P_H - prune_margin`` (deletion of low-``P_H``
  hypotheses). Hypotheses of equal ``P_H`` are ranked, in this order, by the sum of the squares
  of their ``P_R`` (when a measurement can go to one of two tracks, it goes to the more
  confident one: a duplicate track on a target, or the weaker of two targets merged into one
  blob, keeps coasting instead of the two taking turns) and by the association cost of their
  branches, accumulated over their lives: ``(distance / gate)^2`` per update, 1 per frame
  without measurement; lower is better (S3 makes the distance the association measure but does
  not say how to break ties).
- **global confidence** (S3 eq. 7): ``P_G(T) = P_R(T) * sum_{H contains T} P_H / sum_H P_H``
  over the kept hypotheses; branches with ``P_G < global_delete`` are deleted (a branch in no
  kept hypothesis has ``P_G = 0``). ``P_G`` is used for nothing else and not carried over.

The output (``ctx.tracks``) is the best hypothesis: one :class:`~vtrack.stages.base.Track` per
track with its ``P_R`` as confidence and state ``confirmed`` (confirmed and updated this frame:
written to ``tracks.csv``), ``coasting`` (confirmed, no measurement this frame) or
``tentative``. Track ids start at the run's first track id (1 unless it gives another:
``--first-id``), are given when a track survives its first frame, and are never reused. A
branch coasting on its prediction wholly outside the frame lives on (it may meet its target
again) but is not reported (as ``kalman_tracks`` and ``byte_tracks``: a track wholly outside
the frame is never reported).

Bounded work per frame: at most ``max_branches`` + 1 children per branch, ``max_hypotheses``
hypotheses of at most ``max_tracks`` tracks each (however long ``miss``, ``delete`` and
``max_coast`` let a coasting track live), and the search for the best extensions of one
hypothesis stops after ``4 * max_hypotheses * (tracks with a choice + 1)`` steps (it always
finds the greedy best extension first; the search is exact unless the budget runs out). With
``B`` branches and ``M`` measurements a frame costs ``O(B M)`` for gating (NumPy) plus the
bounded search.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from vtrack.geometry import Box
from vtrack.params import Param
from vtrack.stages.base import Stage, Track, TrackContext, register
from vtrack.stages.detect import (
    Detection,
    TrackIds,
    centroids,
    pairwise_distances,
    track_state,
)

#: Association cost of a frame without measurement: as if the measurement sat on the gate's edge.
_COAST_COST = 1.0
#: Search steps per kept hypothesis and per track when extending one hypothesis (see module doc).
_SEARCH_EFFORT = 4
#: Positions a branch keeps: 3 for the quadratic predictor, more for a steadier coasting velocity.
HISTORY = 5

Point = tuple[float, float]


def predict_position(positions: Sequence[Point], measured: int) -> Point:
    """Next position of a track from its last positions (oldest first, at most
    :data:`HISTORY`); ``measured`` counts the uncontested measurements at their end.

    S3 eq. 6, the 3-point least-squares parabola ``3 f(k) - 3 f(k-1) + f(k-2)``, when the last
    three positions are uncontested measurements (``measured >= 3``). Otherwise constant
    velocity: the last position plus the least-squares velocity of the kept positions
    (``f(k) - f(k-1)`` with two of them), or the last position when there is only one. This
    covers tracks younger than three frames, frames after a miss (a parabola through three
    noisy points must not be extrapolated for many frames) and measurements another track also
    gates (two targets merging into one blob: the merged centroid jumps, and the parabola would
    triple the jump).
    """
    if len(positions) >= 3 and measured >= 3:
        (x0, y0), (x1, y1), (x2, y2) = positions[-3:]
        return 3 * x2 - 3 * x1 + x0, 3 * y2 - 3 * y1 + y0  # S3 eq. 6
    x, y = positions[-1]
    if len(positions) == 1:
        return x, y
    points = np.asarray(positions, float)
    t = np.arange(len(points), dtype=float)
    t -= t.mean()
    vx, vy = t @ (points - points.mean(axis=0)) / (t @ t)
    return x + float(vx), y + float(vy)


@dataclass(eq=False)
class _Branch:
    """One association history of a track (compared by identity)."""

    family: int  # the track's id (0 until the track survives its first frame)
    positions: tuple[Point, ...]  # last <= HISTORY positions, oldest first
    measured: int  # how many of the last positions in a row are uncontested measurements (<= 3)
    box: Box
    confidence: float  # P_R
    cost: float  # accumulated association cost (tie-break between hypotheses of equal P_H)
    confirmed: bool
    coasting: int  # frames in a row without measurement
    detection: int | None  # index of this frame's measurement, None when coasting


_Key = tuple[float, float, float]


@dataclass(frozen=True)
class _Option:
    """One way a branch can continue: a child branch (None: the track ends) and what it adds
    to the ranking key of a hypothesis that takes it.

    ``key`` is ``(P_R, P_R^2, -cost)`` of the child, with ``initial`` (``initial^2``) taken off
    when it uses a measurement, which then starts no new track: a hypothesis' key is the sum of
    its options' keys plus the same ``(initial, initial^2, 0)`` per measurement for every
    extension, so extensions compare by their options alone.
    """

    key: _Key
    child: _Branch | None
    bit: int  # measurement bit, 0 when coasting or ending


_Hypothesis = tuple[_Branch, ...]


class _Choices(NamedTuple):
    """A branch's options this frame, best first, and the best key any of them adds, part by
    part (a valid bound for a lexicographic comparison)."""

    options: list[_Option]
    bound: _Key


def _score(hypothesis: _Hypothesis) -> _Key:
    """Ranking key ``(P_H, sum of P_R^2, -cost)``, compared in that order, higher is better."""
    return (
        sum(b.confidence for b in hypothesis),
        sum(b.confidence**2 for b in hypothesis),
        -sum(b.cost for b in hypothesis),
    )


def _add(a: _Key, b: _Key) -> _Key:
    return a[0] + b[0], a[1] + b[1], a[2] + b[2]


@register
class MultipleHypothesis(Stage):
    """S3 multiple-hypothesis tracker: quadratic prediction, gated association with branching,
    track confidence, hypotheses ranked by summed confidence, global-confidence pruning."""

    name = "mht"
    summary = "S3 multiple-hypothesis tracking of detections (quadratic predictor, P_R/P_H/P_G)"
    params = (
        Param(
            "gate",
            float,
            20.0,
            "association gate: largest distance in pixels between a track's prediction and a "
            "measurement (S3 sec. 2.3: the distance itself is the association measure; size not "
            "given: 20)",
            min=1.0, max=1e5,
        ),
        Param(
            "max_branches",
            int,
            3,
            "a branch continues with at most this many measurements of its gate, the nearest "
            "(bounds the branching; not in S3)",
            min=1, max=16,
        ),
        Param("initial", float, 1.0, "P_R of a new track (S3 sec. 2.3, value not given: 1)",
              min=0.0, max=1e6),
        Param("hit", float, 1.0, "P_R increment on an update (S3 sec. 2.3, value not given: 1)",
              min=0.0, max=1e6),
        Param("miss", float, 1.0,
              "P_R decrement on a frame without update (S3 sec. 2.3, not given: 1)",
              min=0.0, max=1e6),
        Param(
            "confirm",
            float,
            3.0,
            "a track is confirmed once its P_R reaches this (S3 sec. 2.3 confirmation threshold, "
            "value not given: 3 = a new track updated twice)",
            min=-1e6, max=1e6,
        ),
        Param(
            "delete",
            float,
            0.5,
            "a branch whose P_R falls below this is deleted (S3 sec. 2.3 deletion threshold, value "
            "not given: 0.5 = a new track missed once)",
            min=-1e6, max=1e6,
        ),
        Param(
            "max_coast",
            int,
            15,
            "a branch without measurement for more frames in a row than this is deleted (not "
            "in S3; must outlast targets merging into one blob when they cross)",
            min=0, max=100000,
        ),
        Param(
            "max_hypotheses",
            int,
            8,
            "hypotheses kept per frame, the best (bounds the work; S3 sec. 2.4 deletes low-P_H "
            "hypotheses without saying how many remain)",
            min=1, max=64,
        ),
        Param(
            "prune_margin",
            float,
            4.0,
            "hypotheses whose P_H is more than this below the best are deleted (S3 sec. 2.4, value "
            "not given: 4)",
            min=0.0, max=1e6,
        ),
        Param(
            "global_delete",
            float,
            0.5,
            "branches whose global confidence P_G (S3 eq. 7) is below this are deleted (value "
            "not given: 0.5)",
            min=0.0, max=1e6,
        ),
        Param(
            "max_tracks",
            int,
            1000,
            "at most this many tracks per hypothesis, those coasting longest dropped first "
            "(bounds each frame's work and memory whatever miss, delete and max_coast let live; "
            "not in S3)",
            min=1, max=1000,
        ),
    )
    requires = frozenset({"detections", "first_track_id"})
    provides = frozenset({"tracks"})
    multi_target = True
    needs_init_box = False

    def start(self, ctx: TrackContext) -> None:
        """Forget any previous run: no track, one empty hypothesis; then track this frame."""
        self._hypotheses: list[_Hypothesis] = [()]
        self._ids = TrackIds(ctx)
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        detections: list[Detection] = ctx.detections
        branches = list({id(b): b for h in self._hypotheses for b in h}.values())
        options = self._branch_out(branches, detections)
        newcomers: dict[int, _Branch] = {}
        extended = {}
        for hypothesis in self._extend(options):
            used = {b.detection for b in hypothesis}
            for m in range(len(detections)):
                if m not in used and m not in newcomers:
                    newcomers[m] = self._new_track(detections[m], m)
            full = hypothesis + tuple(newcomers[m] for m in range(len(detections))
                                      if m not in used)
            extended[frozenset(map(id, full))] = full
        hypotheses = self._prune(list(extended.values()))
        hypotheses = self._delete_by_global_confidence(hypotheses)
        for m in sorted(newcomers):  # ids in measurement order, only for tracks that survive
            if any(newcomers[m] in h for h in hypotheses):
                newcomers[m].family = next(self._ids)
        self._hypotheses = hypotheses or [()]
        best = self._hypotheses[0]
        width, height = ctx.frame.width, ctx.frame.height
        ctx.tracks = [  # a branch coasting wholly outside the frame is kept, not reported
            Track(b.family, b.box, b.confidence, track_state(b.confirmed, b.detection is not None))
            for b in sorted(best, key=lambda b: b.family) if not b.box.outside(width, height)
        ]

    # --- branches ------------------------------------------------------------------------

    def _new_track(self, detection: Detection, index: int) -> _Branch:
        return _Branch(
            family=0,
            positions=((detection.cx, detection.cy),),
            measured=1,
            box=detection.box,
            confidence=self.initial,
            cost=0.0,
            confirmed=self.initial >= self.confirm,
            coasting=0,
            detection=index,
        )

    def _branch_out(
        self, branches: list[_Branch], detections: list[Detection]
    ) -> dict[int, _Choices]:
        """Each branch's options for this frame, by ``id(branch)``."""
        predictions = np.array(
            [predict_position(b.positions, b.measured) for b in branches], float
        ).reshape(-1, 2)
        distances = pairwise_distances(predictions, centroids(detections))
        gated = distances <= self.gate
        # A measurement is contested when branches of two or more tracks gate it.
        families = np.array([b.family for b in branches], float)[:, None]
        lowest = np.where(gated, families, np.inf).min(axis=0, initial=np.inf)
        highest = np.where(gated, families, -np.inf).max(axis=0, initial=-np.inf)
        contested = lowest < highest
        options: dict[int, _Choices] = {}
        for row, branch in enumerate(branches):
            inside = np.flatnonzero(gated[row])
            inside = inside[np.argsort(distances[row, inside], kind="stable")][: self.max_branches]
            choices = [
                self._update(branch, detections[m], int(m), float(distances[row, m]),
                             bool(contested[m]))
                for m in inside
            ]
            if inside.size == 0 or contested[inside].any():
                choices.append(self._coast(branch, predictions[row]))
            choices.sort(key=lambda o: o.key, reverse=True)
            keys = [o.key for o in choices]
            bound = (max(k[0] for k in keys), max(k[1] for k in keys), max(k[2] for k in keys))
            options[id(branch)] = _Choices(choices, bound)
        return options

    def _update(self, branch: _Branch, detection: Detection, index: int, distance: float,
                contested: bool) -> _Option:
        confidence = branch.confidence + self.hit
        child = replace(
            branch,
            positions=(*branch.positions[1 - HISTORY :], (detection.cx, detection.cy)),
            measured=0 if contested else min(branch.measured + 1, 3),
            box=detection.box,
            confidence=confidence,
            cost=branch.cost + (distance / self.gate) ** 2,
            confirmed=branch.confirmed or confidence >= self.confirm,
            coasting=0,
            detection=index,
        )
        key = (confidence - self.initial, confidence**2 - self.initial**2, -child.cost)
        return _Option(key, child, 1 << index)

    def _coast(self, branch: _Branch, prediction: np.ndarray) -> _Option:
        confidence = branch.confidence - self.miss
        if confidence < self.delete or branch.coasting >= self.max_coast:
            return _Option((0.0, 0.0, 0.0), None, 0)  # the track ends here (S3 sec. 2.3 deletion)
        x, y = float(prediction[0]), float(prediction[1])
        child = replace(
            branch,
            positions=(*branch.positions[1 - HISTORY :], (x, y)),
            measured=0,
            box=branch.box.moved_to(x, y),
            confidence=confidence,
            cost=branch.cost + _COAST_COST,
            coasting=branch.coasting + 1,
            detection=None,
        )
        return _Option((confidence, confidence**2, -child.cost), child, 0)

    # --- hypotheses -----------------------------------------------------------------------

    def _extend(self, options: dict[int, _Choices]) -> list[_Hypothesis]:
        """The ``max_hypotheses`` best extensions of the current hypotheses (without the new
        tracks), best first: branch-and-bound over one option per branch, no measurement used
        twice (S3 sec. 2.4), ranked by :func:`_score`. Branches with a single option (a measurement
        no other track gates, or none at all) take it without search."""
        limit = self.max_hypotheses
        found: list[tuple[_Key, int, tuple]] = []  # min-heap of (key, order, path), worst first
        order = itertools.count()
        for parent in self._hypotheses:
            key: _Key = (0.0, 0.0, 0.0)
            used = 0
            path: tuple = ()
            free = []
            for choices in (options[id(b)] for b in parent):
                if len(choices.options) == 1:
                    (only,) = choices.options
                    key, used, path = _add(key, only.key), used | only.bit, (only, path)
                else:
                    free.append(choices)
            n = len(free)
            rest: list[_Key] = [(0.0, 0.0, 0.0)] * (n + 1)  # best the remaining ones can add
            for i in range(n - 1, -1, -1):
                rest[i] = _add(rest[i + 1], free[i].bound)
            budget = _SEARCH_EFFORT * limit * (n + 1)
            stack: list[tuple[int, _Key, int, tuple]] = [(0, key, used, path)]
            while stack and budget > 0:
                budget -= 1
                depth, key, used, path = stack.pop()
                if len(found) == limit and _add(key, rest[depth]) <= found[0][0]:
                    continue
                if depth == n:
                    heapq.heappush(found, (key, next(order), path))
                    if len(found) > limit:
                        heapq.heappop(found)
                    continue
                for option in reversed(free[depth].options):  # best popped first
                    if not option.bit & used:
                        stack.append((depth + 1, _add(key, option.key), used | option.bit,
                                      (option, path)))
        return [_unwind(path) for *_, path in sorted(found, reverse=True)]

    def _prune(self, hypotheses: list[_Hypothesis]) -> list[_Hypothesis]:
        """Best first; delete those more than ``prune_margin`` below the best P_H (S3 sec. 2.4)."""
        ranked = sorted(hypotheses, key=_score, reverse=True)[: self.max_hypotheses]
        if not ranked:
            return ranked
        floor = _score(ranked[0])[0] - self.prune_margin
        return [h for h in ranked if _score(h)[0] >= floor]

    def _capped(self, hypothesis: _Hypothesis) -> _Hypothesis:
        """``hypothesis`` with at most ``max_tracks`` branches, those coasting longest dropped
        first (the others in their order)."""
        if len(hypothesis) <= self.max_tracks:
            return hypothesis
        keep = sorted(range(len(hypothesis)), key=lambda i: hypothesis[i].coasting)
        return tuple(hypothesis[i] for i in sorted(keep[: self.max_tracks]))

    def _delete_by_global_confidence(self, hypotheses: list[_Hypothesis]) -> list[_Hypothesis]:
        """Delete branches whose P_G (S3 eq. 7) is below ``global_delete``, then cap each
        hypothesis at ``max_tracks`` (:meth:`_capped`); distinct hypotheses, best first."""
        weights = [_score(h)[0] for h in hypotheses]
        total = sum(weights)
        support: dict[int, float] = {}
        for hypothesis, weight in zip(hypotheses, weights, strict=True):
            for branch in hypothesis:
                support[id(branch)] = support.get(id(branch), 0.0) + weight
        doomed = set()
        for hypothesis in hypotheses:
            for branch in hypothesis:
                share = support[id(branch)] / total if total > 0 else 1.0
                if branch.confidence * share < self.global_delete:  # S3 eq. 7: P_G
                    doomed.add(id(branch))
        kept: dict[frozenset[int], _Hypothesis] = {}
        for hypothesis in hypotheses:
            survivors = self._capped(tuple(b for b in hypothesis if id(b) not in doomed))
            kept.setdefault(frozenset(map(id, survivors)), survivors)
        return sorted(kept.values(), key=_score, reverse=True)


def _unwind(path: tuple) -> _Hypothesis:
    """The branches of a search path ``(option, (option, (... ())))``, in choice order."""
    branches = []
    while path:
        option, path = path
        if option.child is not None:
            branches.append(option.child)
    return tuple(reversed(branches))
