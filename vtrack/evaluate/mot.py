"""Multi-target metrics: CLEAR MOT and the identity measures, as the MOTChallenge devkit does them.

- **CLEAR MOT** (Bernardin & Stiefelhagen, "Evaluating Multiple Object Tracking Performance:
  The CLEAR MOT Metrics", EURASIP JIVP 2008). A ground-truth box and a track box may be matched
  when their IoU is >= 0.5. Frame by frame: a pair matched before (the object's last matched
  track) stays matched if it still may be; the other objects and tracks are matched by a
  minimum-cost assignment (Hungarian) on ``1 - IoU``; a matched object whose last track was a
  different one is an **id switch** (counted once, on the frame it happens). Unmatched objects
  are **misses**, unmatched track boxes **false positives**.
  ``MOTA = 1 - (misses + false positives + id switches) / ground-truth boxes``.
  **MOTP is the mean IoU of the matched pairs** (0..1, higher is better: the MOTChallenge
  devkit's convention; py-motmetrics reports ``1 - IoU`` instead).
  An object is **mostly tracked** when matched in >= 80% of the frames it is present,
  **mostly lost** below 20%, partially tracked otherwise.
- **IDF1 / IDP / IDR** (Ristani et al., "Performance Measures and a Data Set for Multi-Target,
  Multi-Camera Tracking", ECCV 2016 workshops). Each ground-truth identity is paired with at most
  one track identity (and vice versa) by a global assignment that maximises the number of frames
  in which the paired boxes overlap with IoU >= 0.5 (the identity true positives, IDTP).
  ``IDF1 = 2 IDTP / (ground-truth boxes + track boxes)``, ``IDP = IDTP / track boxes``,
  ``IDR = IDTP / ground-truth boxes``.

Before a frame is scored, track boxes on a **distractor** (a ground-truth row of class 2, 7, 8 or
12: a person on a vehicle, a static person, a distractor, a reflection) are taken out, as
TrackEval's MOT16/17 preprocessing does: the frame's track boxes are assigned to all its
ground-truth rows (any class or consider flag; maximum total IoU, pairs of IoU >= 0.5) and those
assigned to a distractor are neither matches nor false positives.

These are the definitions py-motmetrics implements; the assignments are SciPy's
``linear_sum_assignment`` (the solver py-motmetrics uses), so py-motmetrics itself (which calls
``np.asfarray``, gone in NumPy 2) is not needed.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from os import PathLike
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from vtrack.evaluate.groundtruth import read_mot_counting
from vtrack.geometry import Box, iou_matrix

#: A ground-truth box and a track box may be matched when their IoU is at least this.
MATCH_IOU = 0.5
#: An object matched in at least this share of its frames is mostly tracked ...
MOSTLY_TRACKED = 0.8
#: ... and below this share mostly lost.
MOSTLY_LOST = 0.2

#: Boxes per frame: ``{0-based frame: [(id, box), ...]}`` (ground truth or tracker output).
FrameBoxes = Mapping[int, Sequence[tuple[int, Box]]]
#: A frame's ground-truth rows of every class, ``[(box, is a distractor), ...]``
#: (:attr:`~vtrack.evaluate.groundtruth.MotTruth.distractors` holds them by frame).
TruthRows = Sequence[tuple[Box, bool]]


def _forbidding(cost: np.ndarray, allowed: np.ndarray) -> np.ndarray:
    """``cost`` with forbidden pairs priced so no minimum assignment prefers one to an allowed
    pair (py-motmetrics' ``add_expensive_edges``: more than ``(2r - 1)`` times the largest
    allowed cost, ``r`` the number of pairs an assignment makes)."""
    if not allowed.any():
        return np.zeros_like(cost)
    bound = float(np.abs(cost[allowed]).max()) + 1.0
    return np.where(allowed, cost, 2.0 * min(cost.shape) * bound + 1.0)


def _ratio(numerator: float, denominator: float) -> float | None:
    return numerator / denominator if denominator > 0 else None


def _off_distractors(hyps: Sequence[tuple[int, Box]],
                     rows: TruthRows) -> Sequence[tuple[int, Box]]:
    """``hyps`` without the boxes TrackEval takes out: those a maximum-IoU assignment to the
    frame's ground-truth ``rows`` (pairs of IoU >= 0.5) gives to a distractor."""
    if not hyps or not any(d for _, d in rows):
        return hyps
    overlap = iou_matrix([b for b, _ in rows], [b for _, b in hyps])
    overlap[overlap < MATCH_IOU] = 0.0
    out = {int(c) for r, c in zip(*linear_sum_assignment(-overlap), strict=True)
           if overlap[r, c] > 0 and rows[r][1]}
    return [h for j, h in enumerate(hyps) if j not in out]


def evaluate_mot(gt: FrameBoxes, tracks: FrameBoxes, frames: int,
                 distractors: Mapping[int, TruthRows] | None = None) -> dict[str, Any]:
    """CLEAR MOT and identity measures of ``tracks`` against ``gt`` over frames ``0..frames-1``.

    Boxes of other frames are ignored. ``distractors`` (by frame, as
    :attr:`~vtrack.evaluate.groundtruth.MotTruth.distractors`) takes the track boxes on
    distractors out of the score (see the module docstring). Returns ``mota``, ``motp`` (mean
    IoU of matches), ``idf1``, ``idp``, ``idr`` (floats; None when undefined: no ground-truth
    box, no match, no box at all), ``id_switches``, ``false_positives``, ``misses``, ``matches``,
    ``mostly_tracked``, ``partially_tracked``, ``mostly_lost``, ``gt_ids``, ``gt_boxes``,
    ``track_ids``, ``track_boxes`` and ``frames`` (ints). See the module docstring.
    """
    score = MotScore()
    for frame in range(frames):
        score.add(gt.get(frame, ()), tracks.get(frame, ()), (distractors or {}).get(frame, ()))
    return score.result(frames)


class MotScore:
    """:func:`evaluate_mot` one frame at a time: :meth:`add` each frame in order, then
    :meth:`result`. It keeps counts per object, per track and per (object, track) pair that
    overlapped, never per frame: a run scored while it tracks holds no boxes of past frames."""

    def __init__(self) -> None:
        self.last_match: dict[int, int] = {}  # object id -> track id it was last matched to
        self.switches = self.false_positives = self.misses = self.matches = 0
        self.overlap_sum = 0.0  # IoU summed over the matches (MOTP)
        self.present: Counter[int] = Counter()  # frames each object is present
        self.matched: Counter[int] = Counter()  # frames each object is matched
        self.track_boxes: Counter[int] = Counter()
        self.pair_frames: Counter[tuple[int, int]] = Counter()  # frames a pair overlaps (IDF1)

    def add(self, objects: Sequence[tuple[int, Box]], hyps: Sequence[tuple[int, Box]],
            rows: TruthRows = ()) -> None:
        """Score the next frame: its ground truth ``objects`` and tracks ``hyps``, (id, box);
        ``rows``, the frame's ground-truth rows of every class when one is a distractor, takes
        the track boxes on distractors out first."""
        hyps = _off_distractors(hyps, rows)
        oids = [o for o, _ in objects]
        hids = [h for h, _ in hyps]
        self.present.update(oids)
        self.track_boxes.update(hids)
        overlap = iou_matrix([b for _, b in objects], [b for _, b in hyps])
        allowed = overlap >= MATCH_IOU
        for i, j in zip(*np.nonzero(allowed), strict=True):
            self.pair_frames[oids[i], hids[j]] += 1
        pairs: list[tuple[int, int]] = []
        free_o = np.ones(len(oids), bool)
        free_h = np.ones(len(hids), bool)
        last_match = self.last_match
        # 1. Keep the correspondences made before while they still may be matched.
        for i, o in enumerate(oids):
            if o in last_match and last_match[o] in hids:
                j = hids.index(last_match[o])
                if free_h[j] and allowed[i, j]:
                    pairs.append((i, j))
                    free_o[i] = free_h[j] = False
        # 2. Minimum total 1 - IoU for the rest; a new partner of a matched object is a switch.
        rest_o, rest_h = np.flatnonzero(free_o), np.flatnonzero(free_h)
        sub_allowed = allowed[np.ix_(rest_o, rest_h)]
        if sub_allowed.any():
            cost = _forbidding(1.0 - overlap[np.ix_(rest_o, rest_h)], sub_allowed)
            for r, c in zip(*linear_sum_assignment(cost), strict=True):
                if not sub_allowed[r, c]:
                    continue
                i, j = int(rest_o[r]), int(rest_h[c])
                o, h = oids[i], hids[j]
                if o in last_match and last_match[o] != h:
                    self.switches += 1
                last_match[o] = h
                pairs.append((i, j))
                free_o[i] = free_h[j] = False
        self.matched.update(oids[i] for i, _ in pairs)
        self.overlap_sum += sum(float(overlap[i, j]) for i, j in pairs)
        self.matches += len(pairs)
        self.misses += int(free_o.sum())
        self.false_positives += int(free_h.sum())

    def result(self, frames: int) -> dict[str, Any]:
        """The measures of the frames added so far (``frames``: how many, for the record)."""
        present, track_boxes = self.present, self.track_boxes
        gt_boxes = sum(present.values())
        hyp_boxes = sum(track_boxes.values())
        ratios = [self.matched[o] / present[o] for o in present]
        return {
            "mota": _ratio(gt_boxes - self.misses - self.false_positives - self.switches,
                           gt_boxes),
            "motp": self.overlap_sum / self.matches if self.matches else None,
            **_identity_scores(self.pair_frames, list(present), list(track_boxes), gt_boxes,
                               hyp_boxes),
            "id_switches": self.switches,
            "false_positives": self.false_positives,
            "misses": self.misses,
            "matches": self.matches,
            "mostly_tracked": sum(r >= MOSTLY_TRACKED for r in ratios),
            "partially_tracked": sum(MOSTLY_LOST <= r < MOSTLY_TRACKED for r in ratios),
            "mostly_lost": sum(r < MOSTLY_LOST for r in ratios),
            "gt_ids": len(present),
            "gt_boxes": gt_boxes,
            "track_ids": len(track_boxes),
            "track_boxes": hyp_boxes,
            "frames": frames,
        }


def _identity_scores(
    pair_frames: Mapping[tuple[int, int], int],
    oids: list[int],
    hids: list[int],
    gt_boxes: int,
    hyp_boxes: int,
) -> dict[str, float | None]:
    """IDF1, IDP, IDR from the frames each (object, track) pair overlaps (Ristani et al. 2016)."""
    idtp = 0
    if oids and hids:
        counts = np.zeros((len(oids), len(hids)))
        row = {o: i for i, o in enumerate(oids)}
        col = {h: j for j, h in enumerate(hids)}
        for (o, h), n in pair_frames.items():
            counts[row[o], col[h]] = n
        rows, cols = linear_sum_assignment(-counts)  # maximise the identity true positives
        idtp = int(counts[rows, cols].sum())
    return {
        "idf1": _ratio(2 * idtp, gt_boxes + hyp_boxes),
        "idp": _ratio(idtp, hyp_boxes),
        "idr": _ratio(idtp, gt_boxes),
    }


def mot_summary(
    tracks: dict[int, list[tuple[int, Box]]], gt_path: str | PathLike[str], frames: int
) -> dict[str, Any]:
    """Score a run's confirmed tracks against a MOTChallenge ``gt.txt`` (see :func:`evaluate_mot`).

    ``tracks`` is ``{0-based frame: [(track id, box), ...]}``, ``frames`` the number of frames
    the run processed: ground truth beyond them is not scored. The ground truth is read with
    :func:`~vtrack.evaluate.groundtruth.read_mot_counting` (ignored rows and non-pedestrian
    classes dropped, track boxes on distractors taken out); an unreadable file raises
    :class:`~vtrack.errors.InputError`.
    """
    truth = read_mot_counting(gt_path)
    return evaluate_mot(truth.boxes, tracks, frames, truth.distractors)
