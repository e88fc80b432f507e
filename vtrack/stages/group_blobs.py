"""Blobs grouped into target-sized detections, each with a score: ``group_blobs``.

Background subtraction on real footage does not give one blob per target: a person in clothes
the colour of the ground falls apart into head, torso and legs, and two people walking side by
side are one blob. ``group_blobs`` turns ``blobs``' connected components into one detection per
target, using what a target of the scene looks like - its usual height/width ratio (the
``aspect``, given, then learnt from the tracker's confirmed targets) and, once learnt, its
usual area:

1. **merge**: two detections one above the other (their columns overlap by at least half the
   narrower one's width) whose vertical gap is at most ``merge_gap`` of their joint height are
   one target when the joint box is not taller than ``1.5 aspect`` widths (fragments of one
   person; repeated until nothing merges);
2. **split**: a detection wider than ``split`` targets of its height (``w > split h /
   aspect``) holds ``n = round(w aspect / h)`` targets side by side (up to ``MAX_PARTS``: a
   flatter blob, a shadow or a low wall, is no row of targets); it is cut at the columns
   of least foreground near its ``n``-ths where these are valleys (at most ``VALLEY`` of the
   fullest column: a solid blob is not cut), and each part gets the box of its own foreground;
   with ``heads``, it is cut between the peaks of its top contour instead where two or more
   are found (W4's heads, :func:`head_cuts`: people one behind or beside another, with or
   without a valley between them);
3. **trim**: each detection's left and right sides are moved in to the columns that leave
   ``trim`` of its foreground outside on either side (:func:`trimmed`): a silhouette's
   extreme columns are thin parts - a foot mid-stride, an arm, a shadow's fringe, what the
   closing added - that benchmarks' boxes of the person leave out (MOT_TUD-Campus's boxes are
   1.37 times narrower than its people's full foreground; heights agree);
4. **border**: a detection cut by the frame's border - a target entering or leaving - is
   carried on beyond it to the usual aspect (:func:`completed_at_border`), as benchmarks'
   ground truth boxes the whole target (MOTChallenge's boxes run past the image's edges);
5. **score** (0..1): how target-like each detection is, the product of its fill (foreground
   share of the box's part in view, full at 0.5 and above), its shape (1 at the usual aspect,
   0.5 at a factor of two from it), once an area is learnt its size (full from half the usual
   area), and the share of its box in view (a target less than half in view continues its
   track but starts none). A detection whose shape is more than ``max_shape`` times off, or
   smaller than ``min_share`` of the usual area, is dropped.

A multi-target tracker after this stage (``byte_tracks``) matches high-score detections first
and uses low-score ones only to continue existing tracks (ByteTrack's second pass).

What is learnt comes from ``ctx.target_shape`` (the tracker's median over the boxes its
confirmed tracks were measured with, from the previous frame); the given ``aspect`` counts as
``vtrack.stages.base.PRIOR_SAMPLES`` samples, so it gives way as the scene shows its targets.
But the tracker confirms only tracks of detections that score well, i.e. of about the given
aspect: targets of another shape (vehicles, h/w 0.3-0.8, told 2.5, a person's) are dropped or
cut into "people" before any is confirmed, and the tracker learns the pieces. With ``persist``
(and ``learn``: without it ``persist`` is not used), the blobs themselves teach the shape
(:class:`PersistentBlobs`): each merged blob, trimmed and before any split, that overlaps one
of the previous frame's and keeps its height/width steady for ``persist`` frames (and is no
smaller than ``min_share`` of the usual area) is a sample; once there are as many as the given
aspect counts for (``PRIOR_SAMPLES``) and their median is off the aspect in use by more than a
factor ``UNLIKE``, that median is the aspect for the rest of the run (on footage of people,
where they agree, nothing changes).
Work per frame: at most ``M`` rounds of ``M^2`` NumPy box comparisons for ``M`` blobs
(``blobs.max_blobs`` bounds ``M``), one column profile per blob that is split (with ``heads``
its top contour too), and with ``persist`` one per blob and ``M^2`` box overlaps.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from vtrack.geometry import Box, iou_matrix
from vtrack.params import Param
from vtrack.stages.base import (
    PRIOR_SAMPLES,
    ShapeSamples,
    Stage,
    TargetShape,
    TrackContext,
    register,
)
from vtrack.stages.detect import Detection, foreground_under

#: A detection's fill (foreground share of its box) scores 1 from this value on ...
FULL_FILL = 0.5
#: ... and its size from this share of the usual area on.
FULL_SIZE = 0.5
#: A blob is split into at most this many targets (a wider one is no row of targets).
MAX_PARTS = 4
#: A blob is cut only at a column holding at most this share of its fullest column's foreground.
VALLEY = 0.9
#: With ``heads``, a blob is cut between the peaks of its top contour instead, where two or
#: more are found (W4's heads): the contour is smoothed over a head's width, this share of a
#: target's width (a head ~0.15 m across, a walking person's box ~0.7 m wide) ...
HEAD_WIDTH = 0.25
#: ... two heads are at least this share of a target's width apart (people side by side or
#: one behind the other; less is one head and its shoulder) ...
HEAD_APART = 0.5
#: ... and the contour between them dips by at least this share of the blob's height (a head
#: is ~1/8 of a person's height: half a head).
HEAD_DIP = 1.0 / 16
#: A blob is the same one in the next frame when their boxes overlap by this IoU ...
SAME_BLOB = 0.5
#: ... and its shape is steady while its height/width stays within this factor over the last
#: ``persist`` frames.
STEADY = 1.25
#: Once as many samples of persistent blobs are in as the given aspect counts for
#: (``PRIOR_SAMPLES``), their median height/width off the aspect by more than a factor
#: ``UNLIKE`` (where ``shape_score`` halves) replaces it for the rest of the run.
UNLIKE = 2.0


def usual_shape(aspect: float, learnt: TargetShape | None) -> tuple[float, float | None]:
    """The aspect to group with (the given ``aspect`` mixed with the learnt one, by their
    weights) and the usual area (None before anything was learnt)."""
    if learnt is None or learnt.samples == 0:
        return aspect, None
    mixed = math.exp(learnt.mixed(math.log(aspect), math.log(learnt.aspect)))
    return mixed, learnt.area


def shape_score(box: Box, aspect: float) -> float:
    """1 when ``box``'s height/width is ``aspect``, 0.5 at a factor of two either way."""
    return 2.0 ** -abs(math.log2(box.h / box.w / aspect))


def _merged(a: Detection, b: Detection) -> Detection:
    x0, y0 = min(a.box.x, b.box.x), min(a.box.y, b.box.y)
    x1 = max(a.box.x + a.box.w, b.box.x + b.box.w)
    y1 = max(a.box.y + a.box.h, b.box.y + b.box.h)
    box = Box(x0, y0, x1 - x0, y1 - y0)
    return Detection(box, box.cx, box.cy, a.area + b.area, math.nan)


def stacked_pairs(boxes: list[Box], gap: float, aspect: float) -> np.ndarray:
    """Which pairs of ``boxes`` are fragments of one target one above the other: their columns
    overlap by half the narrower's width, the vertical gap between them is at most ``gap`` of
    their joint height and the joint box is at most ``1.5 aspect`` widths tall. A symmetric
    ``(n, n)`` bool matrix, False on the diagonal."""
    b = np.array(boxes, float).reshape(-1, 4)
    x0, y0, x1, y1 = b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    across = np.minimum.outer(x1, x1) - np.maximum.outer(x0, x0)
    between = np.maximum.outer(y0, y0) - np.minimum.outer(y1, y1)
    tall = np.maximum.outer(y1, y1) - np.minimum.outer(y0, y0)
    wide = np.maximum.outer(x1, x1) - np.minimum.outer(x0, x0)
    pairs = ((across >= 0.5 * np.minimum.outer(b[:, 2], b[:, 2])) & (between <= gap * tall)
             & (tall <= 1.5 * aspect * wide))
    np.fill_diagonal(pairs, False)
    return pairs


def merge_fragments(detections: list[Detection], gap: float, aspect: float) -> list[Detection]:
    """Detections with stacked fragments (:func:`stacked_pairs`) merged, one pair at a time
    until no pair is left (at most ``M`` rounds of ``M^2`` NumPy comparisons)."""
    found = list(detections)
    while len(found) > 1:
        pairs = np.argwhere(np.triu(stacked_pairs([d.box for d in found], gap, aspect)))
        if not len(pairs):
            break
        i, j = (int(k) for k in pairs[0])
        found[i] = _merged(found[i], found[j])
        del found[j]
    return found


def head_cuts(inside: np.ndarray, parts: int, aspect: float) -> list[int]:
    """The columns of ``inside`` (a blob's foreground, rows x columns) between the heads of up
    to ``parts`` people standing side by side or one behind the other (W4, Haritaoglu,
    Harwood and Davis, TPAMI 2000): the heads are the peaks of the silhouette's top contour
    (each column's topmost foreground row), smoothed over a head's width (``HEAD_WIDTH`` of a
    target's ``h / aspect``); of its local maxima, the highest ones at least ``HEAD_APART`` of
    a target's width apart, ``parts`` at most, are heads. Two neighbouring heads are cut at
    the lowest point of the contour between them, where it dips by at least ``HEAD_DIP`` of
    the blob's height below the lower head. Sorted, none when no two heads are found."""
    rows, columns = inside.shape
    width = rows / aspect
    filled = inside.any(axis=0)
    top = np.where(filled, rows - np.argmax(inside, axis=0), 0).astype(float)
    head = max(1, round(HEAD_WIDTH * width))
    contour = np.convolve(np.pad(top, (head // 2, head - 1 - head // 2), mode="edge"),
                          np.ones(head) / head, mode="valid")
    padded = np.pad(contour, 1, constant_values=-1.0)
    peaks = np.flatnonzero((contour >= padded[:-2]) & (contour > padded[2:]) & filled)
    heads: list[int] = []
    for peak in peaks[np.argsort(-contour[peaks], kind="stable")]:
        if all(abs(int(peak) - h) >= HEAD_APART * width for h in heads):
            heads.append(int(peak))
            if len(heads) == parts:
                break
    heads.sort()
    cuts = []
    for left, right in zip(heads[:-1], heads[1:], strict=True):
        cut = left + int(np.argmin(contour[left:right + 1]))
        if min(contour[left], contour[right]) - contour[cut] >= HEAD_DIP * rows:
            cuts.append(cut)
    return cuts


def split_side_by_side(detection: Detection, parts: int, mask: np.ndarray,
                       scale: float, heads: float | None = None) -> list[Detection]:
    """``detection`` cut into up to ``parts`` side by side: when ``heads`` (the targets' usual
    aspect) is given, between the heads of its top contour where two or more are found
    (:func:`head_cuts`); otherwise at the columns of least foreground of ``mask`` (``scale``
    frame pixels per mask pixel) within a quarter part of its equal divisions, where that
    column holds at most ``VALLEY`` of the fullest column's foreground (a solid blob is not
    cut). Each part gets the box and the pixel count of its own foreground."""
    covered, inside = foreground_under(detection.box, mask, scale)
    x0, y0 = covered.x0, covered.y0
    if inside.shape[1] < 2 * parts:
        return [detection]
    cuts = [0] + ([] if heads is None else head_cuts(inside, parts, heads))
    if len(cuts) == 1:  # no heads to cut between: the columns of least foreground
        profile = inside.sum(axis=0)
        width = inside.shape[1] / parts
        for k in range(1, parts):
            lo, hi = round(k * width - width / 4), round(k * width + width / 4) + 1
            cut = lo + int(np.argmin(profile[lo:hi]))
            if profile[cut] <= VALLEY * profile.max():
                cuts.append(cut)
    if len(cuts) == 1:
        return [detection]
    cuts.append(inside.shape[1])
    pieces = []
    for c0, c1 in zip(cuts[:-1], cuts[1:], strict=True):
        rows = np.flatnonzero(inside[:, c0:c1].any(axis=1))
        if c1 <= c0 or rows.size == 0:
            continue
        box = Box((x0 + c0) * scale, (y0 + rows[0]) * scale, (c1 - c0) * scale,
                  (rows[-1] - rows[0] + 1) * scale)
        area = float(inside[rows[0]:rows[-1] + 1, c0:c1].sum()) * scale * scale
        pieces.append(Detection(box, box.cx, box.cy, area, math.nan))
    return pieces


def at_border(low: float, high: float, extent: int, scale: float) -> tuple[bool, bool]:
    """Whether the span ``low..high`` of a frame side ``extent`` pixels long reaches its start
    and its end, within a foreground pixel (``scale`` frame pixels; a reduced foreground
    leaves out the frame's last pixels beyond whole blocks)."""
    return low <= scale, high >= extent - 2 * scale


def trimmed(detection: Detection, share: float, mask: np.ndarray, scale: float,
            width: int) -> Detection:
    """``detection`` with its box's left and right sides moved in to the columns that leave
    ``share`` of its foreground (``mask``, ``scale`` frame pixels per pixel) outside on each
    side: the box of the body's bulk, not of its farthest pixels. A side on the frame's border
    (``width`` pixels wide) stays there, for :func:`completed_at_border`."""
    covered, inside = foreground_under(detection.box, mask, scale)
    profile = inside.sum(axis=0).astype(float)
    total = profile.sum()
    if total <= 0 or profile.size < 3:
        return detection
    cum = np.cumsum(profile) / total
    c0 = int(np.searchsorted(cum, share))
    c1 = int(np.searchsorted(cum, 1.0 - share)) + 1
    b = detection.box
    x0, x1 = b.x, b.x + b.w
    at_left, at_right = at_border(x0, x1, width, scale)
    if not at_left:  # a side on the frame's border stays there (completed_at_border)
        x0 = max(x0, (covered.x0 + c0) * scale)
    if not at_right:
        x1 = min(x1, (covered.x0 + c1) * scale)
    if x1 - x0 < 1:
        return detection
    return replace(detection, box=Box(x0, b.y, x1 - x0, b.h))


def completed_at_border(box: Box, aspect: float, width: int, height: int,
                        scale: float) -> Box:
    """``box`` carried on beyond the frame's border where it touches it (within ``scale``
    pixels, the foreground's pixel) and is shorter there than a target of the usual
    ``aspect``: a target entering or leaving through the left or right border keeps its
    height and is given the width ``h / aspect`` (beyond the border, its inner side kept); one
    through the top or bottom border keeps its width and is given the height ``w aspect``."""
    x0, y0, x1, y1 = box.x, box.y, box.x + box.w, box.y + box.h
    at_left, at_right = at_border(x0, x1, width, scale)
    if box.w < box.h / aspect and at_left != at_right:  # one side cut (both: it fills the view)
        if at_left:
            x0 = x1 - box.h / aspect
        else:
            x1 = x0 + box.h / aspect
    at_top, at_bottom = at_border(y0, y1, height, scale)
    if box.h < box.w * aspect and at_top != at_bottom:
        if at_top:
            y0 = y1 - box.w * aspect
        else:
            y1 = y0 + box.w * aspect
    return Box(x0, y0, x1 - x0, y1 - y0)


@dataclass
class _Blob:
    box: Box
    aspects: deque[float]  # height / width over its last frames


@dataclass
class PersistentBlobs:
    """The shape of the blobs that persist: a blob matched frame to frame (IoU >= ``SAME_BLOB``
    with one of the previous frame's) whose height/width stayed within ``STEADY`` over its last
    ``frames`` frames is a sample of the scene's targets' shape, whatever that shape is - what
    the tracker cannot learn from before its tracks are confirmed, which takes detections of
    the usual shape. Blobs touching the frame's border are cut and give no sample."""

    frames: int
    _blobs: list[_Blob] = field(default_factory=list)
    _samples: ShapeSamples = field(default_factory=ShapeSamples)

    def see(self, boxes: list[Box], width: int, height: int, scale: float,
            least: float = 0.0) -> None:
        """One frame's blobs: each continues the previous frame's blob it overlaps most (if
        by ``SAME_BLOB``), and gives a sample once it has been steady for ``frames`` frames
        and has at least ``least`` square pixels (no target: see ``min_share``)."""
        inside = [box for box in boxes
                  if not any(at_border(box.x, box.x + box.w, width, scale))
                  and not any(at_border(box.y, box.y + box.h, height, scale))]
        overlaps = iou_matrix(inside, [b.box for b in self._blobs])  # (new, previous)
        blobs = []
        for box, row in zip(inside, overlaps, strict=True):
            best = int(np.argmax(row)) if row.size else -1
            aspects: deque[float] = (deque(self._blobs[best].aspects, maxlen=self.frames)
                                     if best >= 0 and row[best] >= SAME_BLOB
                                     else deque(maxlen=self.frames))
            aspects.append(box.h / box.w)
            steady = len(aspects) == self.frames and max(aspects) <= STEADY * min(aspects)
            if steady and box.area >= least:
                self._samples.add(box)
            blobs.append(_Blob(box, aspects))
        self._blobs = blobs

    def shape(self) -> TargetShape | None:
        """Median height/width and area of the samples so far (None: none yet)."""
        return self._samples.shape()


@register
class GroupBlobs(Stage):
    """Blobs -> one scored detection per target: fragments merged, side-by-side targets split,
    shapes unlike the scene's targets dropped (see the module docstring)."""

    name = "group_blobs"
    summary = ("blobs -> target-sized detections: fragments merged, side-by-side targets "
               "split, each scored 0..1")
    params = (
        Param("aspect", float, 2.5,
              "usual height / width of a target before the scene teaches it (a walking person "
              "~2.5; 1 for round or square targets)", min=0.05, max=20.0),
        Param("learn", bool, True,
              "learn the aspect and usual area from the tracker's confirmed targets "
              "(ctx.target_shape); false: only the given aspect"),
        Param("merge_gap", float, 0.3,
              "fragments one above the other are merged when their gap is at most this share "
              "of their joint height (0: touching only)", min=0.0, max=1.0),
        Param("split", float, 1.6,
              "a detection wider than this many targets of its height is split into targets "
              "side by side (0: never split)", min=0.0, max=100.0),
        Param("max_shape", float, 3.0,
              "detections whose height/width is more than this factor from the usual aspect "
              "are dropped", min=1.0, max=100.0),
        Param("min_share", float, 0.15,
              "once an area is learnt, detections smaller than this share of it are dropped",
              min=0.0, max=1.0),
        Param("heads", bool, False,
              "a detection split by its width is cut between the peaks of its top contour "
              "where two or more are found (W4's heads: people one behind or beside another, "
              "with or without a gap), at its columns of least foreground elsewhere; false: "
              "at its columns of least foreground only"),
        Param("trim", float, 0.0,
              "each detection's left and right sides are moved in to the columns that leave "
              "this share of its foreground outside on either side (a stride's foot, an arm, "
              "a shadow's fringe; 0: the foreground's full extent)", min=0.0, max=0.4),
        Param("persist", int, 0,
              "blobs that persist this many frames with a steady height/width are samples of "
              f"the targets' shape; once there are {PRIOR_SAMPLES} and their median is more "
              f"than a factor {UNLIKE:g} off the aspect, it is the aspect (targets of another "
              "shape than the given one, which the tracker cannot learn; 0: off; not used "
              "when learn is false)", min=0, max=1000),
        Param("border", bool, True,
              "a detection cut by the frame's border is carried on beyond it to the usual "
              "aspect (a target entering or leaving; ground truth such as MOTChallenge's "
              "boxes the whole target); false: only its visible part"),
    )
    requires = frozenset({"frame", "detections", "likelihood", "feature_scale"})
    provides = frozenset({"detections"})
    needs_init_box = False

    def __init__(self, **values: Any) -> None:
        super().__init__(**values)
        self._forget()

    def _forget(self) -> None:
        self._persistent = PersistentBlobs(self.persist)
        self._unlike = False  # the persistent blobs are shaped unlike the aspect's targets

    def start(self, ctx: TrackContext) -> None:
        """Forget the blobs of any previous run, then group this frame's."""
        self._forget()
        self.step(ctx)

    def step(self, ctx: TrackContext) -> None:
        learning = self.learn and self.persist > 0
        aspect, area = usual_shape(self.aspect, ctx.target_shape if self.learn else None)
        persistent = self._persistent.shape() if learning else None
        if persistent is not None and persistent.samples >= PRIOR_SAMPLES and not self._unlike:
            self._unlike = abs(math.log(persistent.aspect / aspect)) > math.log(UNLIKE)
        if self._unlike:  # the scene's targets are not of the aspect's shape: theirs, from now
            assert persistent is not None
            aspect = persistent.aspect
        found = merge_fragments(ctx.detections, self.merge_gap, aspect)
        frame = ctx.frame
        whole = [self._trimmed(d, ctx) for d in found] if learning else None
        if whole is not None:  # each blob whole, before it is split by the aspect learnt so far
            self._persistent.see([d.box for d in whole], frame.width, frame.height,
                                 ctx.feature_scale,
                                 0.0 if area is None else self.min_share * area)
        grouped: list[Detection] = []  # each trimmed (an unsplit blob once: ``whole``'s)
        for n, detection in enumerate(found):
            b = detection.box
            parts = round(b.w * aspect / b.h)
            if self.split and b.w * aspect > self.split * b.h and 2 <= parts <= MAX_PARTS:
                assert ctx.likelihood is not None
                grouped.extend(self._trimmed(d, ctx) for d in split_side_by_side(
                    detection, parts, ctx.likelihood, ctx.feature_scale,
                    aspect if self.heads else None))
            else:
                grouped.append(self._trimmed(detection, ctx) if whole is None else whole[n])
        scored = []
        for detection in grouped:
            visible = b = detection.box
            if self.border:
                b = completed_at_border(visible, aspect, frame.width, frame.height,
                                        ctx.feature_scale)
                detection = replace(detection, box=b)
            shape = shape_score(b, aspect)
            size = 1.0 if area is None else min(1.0, b.area / (FULL_SIZE * area))
            small = area is not None and b.area < self.min_share * area
            if shape < 1.0 / self.max_shape or small:
                continue
            fill = min(1.0, detection.area / visible.area / FULL_FILL)
            seen = visible.area / b.area  # a target half out of view is half the evidence
            scored.append(replace(detection, score=fill * shape * size * seen))
        ctx.detections = sorted(scored, key=lambda d: (d.box.y, d.box.x))

    def _trimmed(self, detection: Detection, ctx: TrackContext) -> Detection:
        """``detection`` trimmed by ``trim`` (:func:`trimmed`; as it is when ``trim`` is 0)."""
        if not self.trim:
            return detection
        assert ctx.likelihood is not None
        return trimmed(detection, self.trim, ctx.likelihood, ctx.feature_scale,
                       ctx.frame.width)
