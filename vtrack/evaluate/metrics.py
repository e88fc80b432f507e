"""Single-target metrics with the OTB conventions (Wu, Lim, Yang, "Online Object Tracking: A
Benchmark", CVPR 2013).

Per frame: the overlap (IoU) and the centre error (pixels) between the tracker's box and the
ground truth. Over a sequence:

- success curve: share of frames with IoU **>** t for t = 0, 0.05, ..., 1 (strictly greater, as
  the OTB toolkit's ``errCoverage > threshold``); its mean over the 21 thresholds is the AUC;
- precision curve: share of frames with centre error **<=** t for t = 0, 1, ..., 50 px; the
  value at 20 px is the usual precision score.

Frames whose ground truth is absent (target out of view, or the ground truth ends before the
tracker's output) are not evaluated: they count neither for nor against the tracker (the OTB
toolkit counts them in the denominator; we do not). A frame where the tracker claims no box
(``lost``) while the target is present has IoU 0 and an infinite centre error, so it fails
every threshold.

Honesty of the state (issue 14): a frame *misses* when the target is present and the tracker's
box does not touch it (IoU 0, or no box). :func:`tracking_miss_rate` is the share of the frames
the tracker calls ``tracking`` that miss; :func:`flagged_miss_rate` the share of missed frames
it calls ``occluded`` or ``lost``. An honest tracker has the first low and the second high.
A frame the input skipped (damaged, or missing from an image sequence's numbering; its state
:data:`SKIPPED`) is scored as a miss but is left out of both: the tracker never saw it, so it
says nothing about the tracker's states.

Functions over a sequence take the per-frame lists of :func:`frame_scores`,
``None`` entries included, and return NaN when no frame is evaluated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NotRequired, TypedDict

import numpy as np

from vtrack.geometry import Box, center_error, iou

#: Success-plot overlap thresholds, OTB ``0:0.05:1`` (i/20 so 0.15, 0.3, ... are exact floats).
OVERLAP_THRESHOLDS = np.arange(21) / 20
OVERLAP_THRESHOLDS.setflags(write=False)

#: Precision-plot centre-error thresholds in pixels, OTB ``0:50``.
ERROR_THRESHOLDS = np.arange(51, dtype=float)
ERROR_THRESHOLDS.setflags(write=False)

#: The centre-error threshold of the precision score (OTB: 20 px).
PRECISION_THRESHOLD_PX = 20.0

#: Normalised precision thresholds (TrackingNet, Müller et al. ECCV 2018): centre error in
#: units of the ground truth's size, 0 to 0.5.
NORMALIZED_THRESHOLDS = np.arange(51) / 100
NORMALIZED_THRESHOLDS.setflags(write=False)


class Summary(TypedDict):
    """One sequence's scores; metric values are None when no frame is evaluated."""

    frames_evaluated: int
    mean_overlap: float | None
    auc: float | None
    precision20: float | None
    mean_center_error: float | None
    tracking_miss: NotRequired[float | None]
    miss_flagged: NotRequired[float | None]


#: States that say "my box may not be on the target" (the pipeline's ``occluded`` / ``lost``).
FLAGGED_STATES = frozenset({"occluded", "lost"})
#: The state of a frame the input skipped (no row in ``track.csv``): no state of the tracker's.
SKIPPED = "skipped"


def score_frame(pred: Box | None, gt: Box | None) -> tuple[float | None, float | None]:
    """One frame's ``(overlap, centre_error)`` by the rules of :func:`frame_scores`."""
    if gt is None or not gt.is_valid():
        return None, None
    if pred is None or not pred.is_valid():
        return 0.0, math.inf
    return iou(pred, gt), center_error(pred, gt)


def frame_scores(
    pred: Sequence[Box | None], gt: Sequence[Box | None]
) -> tuple[list[float | None], list[float | None]]:
    """Per-frame ``(overlaps, centre_errors)``, one entry per predicted frame.

    An entry is None where the ground truth is absent (None, non-finite or ``w/h <= 0``) or
    missing (``gt`` shorter than ``pred``); ground truth beyond ``pred`` is not scored. A
    predicted box that is None or invalid (the tracker claims nothing, e.g. ``lost``) while the
    target is present scores IoU 0 and centre error ``inf``.
    """
    padded = list(gt[: len(pred)]) + [None] * (len(pred) - len(gt))
    scores = [score_frame(p, g) for p, g in zip(pred, padded, strict=True)]
    return [s[0] for s in scores], [s[1] for s in scores]


def _evaluated(values: Sequence[float | None]) -> np.ndarray:
    """The values of evaluated frames (None dropped) as a float array."""
    array = np.asarray(values, dtype=float)  # None -> NaN
    return array[~np.isnan(array)]


def _rate(passed: np.ndarray) -> np.ndarray:
    """Share of frames (rows) passing each threshold (columns); NaN when there are no frames."""
    if len(passed) == 0:
        return np.full(passed.shape[1], np.nan)
    return passed.mean(axis=0)


def success_curve(overlaps: Sequence[float | None]) -> np.ndarray:
    """Share of evaluated frames with IoU > t for each t in :data:`OVERLAP_THRESHOLDS` (21)."""
    return _rate(_evaluated(overlaps)[:, None] > OVERLAP_THRESHOLDS)


def auc(overlaps: Sequence[float | None]) -> float:
    """Area under the success curve, OTB style: the mean of its 21 values."""
    return float(success_curve(overlaps).mean())


def success_rate(overlaps: Sequence[float | None], threshold: float) -> float:
    """Share of evaluated frames with IoU > ``threshold`` (GOT-10k's SR at 0.5 and 0.75)."""
    values = _evaluated(overlaps)
    return float((values > threshold).mean()) if values.size else math.nan


def normalized_center_errors(
    pred: Sequence[Box | None], gt: Sequence[Box | None]
) -> list[float | None]:
    """Per predicted frame, the centre error with x divided by the ground truth's width and y by
    its height (TrackingNet); None where the ground truth is absent, ``inf`` where the tracker
    claims no box, as :func:`frame_scores`."""
    padded = list(gt[: len(pred)]) + [None] * (len(pred) - len(gt))
    errors: list[float | None] = []
    for p, g in zip(pred, padded, strict=True):
        if g is None or not g.is_valid():
            errors.append(None)
        elif p is None or not p.is_valid():
            errors.append(math.inf)
        else:
            errors.append(math.hypot((p.cx - g.cx) / g.w, (p.cy - g.cy) / g.h))
    return errors


def normalized_precision(errors: Sequence[float | None]) -> float:
    """Area under the normalised precision curve: the mean over
    :data:`NORMALIZED_THRESHOLDS` of the share of evaluated frames whose normalised centre
    error is <= the threshold (NaN when no frame is evaluated)."""
    return float(_rate(_evaluated(errors)[:, None] <= NORMALIZED_THRESHOLDS).mean())


def mean_overlap(overlaps: Sequence[float | None]) -> float:
    """Mean IoU over evaluated frames (lost frames count as 0)."""
    values = _evaluated(overlaps)
    return float(values.mean()) if values.size else math.nan


def precision_curve(errors: Sequence[float | None], max_px: int = 50) -> np.ndarray:
    """Share of evaluated frames with centre error <= t for t = 0, 1, ..., ``max_px`` pixels.

    With the default ``max_px`` the thresholds are :data:`ERROR_THRESHOLDS`.
    """
    thresholds = np.arange(max_px + 1, dtype=float)
    return _rate(_evaluated(errors)[:, None] <= thresholds)


def precision_at(
    errors: Sequence[float | None], threshold_px: float = PRECISION_THRESHOLD_PX
) -> float:
    """Share of evaluated frames with centre error <= ``threshold_px`` (an error equal counts)."""
    return float(_rate(_evaluated(errors)[:, None] <= threshold_px)[0])


def mean_center_error(errors: Sequence[float | None]) -> float:
    """Mean centre error in pixels over evaluated frames where the tracker claimed a box.

    Lost frames (infinite error) are left out so the mean stays finite; NaN if there are none.
    """
    values = _evaluated(errors)
    values = values[np.isfinite(values)]
    return float(values.mean()) if values.size else math.nan


def _misses(states: Sequence[str], overlaps: Sequence[float | None]) -> tuple[np.ndarray, ...]:
    """(evaluated, missed, tracking, flagged) boolean arrays over the frames of ``overlaps``;
    ``missed`` holds only frames the tracker saw (not :data:`SKIPPED`)."""
    if len(states) != len(overlaps):
        raise ValueError(f"{len(states)} states for {len(overlaps)} scored frames")
    values = np.asarray(overlaps, dtype=float)  # None -> NaN
    evaluated = ~np.isnan(values)
    state = np.asarray([str(s) for s in states])  # str: TrackState values are strings
    missed = evaluated & (np.nan_to_num(values, nan=1.0) <= 0.0) & (state != SKIPPED)
    tracking = state == "tracking"
    flagged = np.isin(state, list(FLAGGED_STATES))
    return evaluated, missed, tracking, flagged


def tracking_miss_rate(states: Sequence[str], overlaps: Sequence[float | None]) -> float:
    """Share of evaluated frames called ``tracking`` whose box misses the target (IoU 0);
    NaN when no evaluated frame is called ``tracking``."""
    evaluated, missed, tracking, _ = _misses(states, overlaps)
    called = evaluated & tracking
    return float((missed & called).sum() / called.sum()) if called.any() else math.nan


def flagged_miss_rate(states: Sequence[str], overlaps: Sequence[float | None]) -> float:
    """Share of missed frames (target present, IoU 0 or no box) called ``occluded`` or
    ``lost``; NaN when no frame misses. Frames the input skipped (:data:`SKIPPED`) are left
    out."""
    _, missed, _, flagged = _misses(states, overlaps)
    return float((missed & flagged).sum() / missed.sum()) if missed.any() else math.nan


def _or_none(value: float) -> float | None:
    return None if math.isnan(value) else value


def summarize(
    pred: Sequence[Box | None], gt: Sequence[Box | None], states: Sequence[str] | None = None
) -> Summary:
    """One sequence's scores for ``vtrack run``'s summary, ``run.json`` and reports.

    Keys: ``frames_evaluated`` (frames with ground truth present), ``mean_overlap``, ``auc``,
    ``precision20`` (share of frames within 20 px) and ``mean_center_error`` (pixels, over frames
    where the tracker claimed a box); with the per-frame ``states`` also ``tracking_miss``
    (:func:`tracking_miss_rate`) and ``miss_flagged`` (:func:`flagged_miss_rate`). A value that
    cannot be computed (no frame evaluated, or no box claimed for the centre error) is None, so
    the dict is valid JSON as it is.
    """
    overlaps, errors = frame_scores(pred, gt)
    return summarize_scores(overlaps, errors, states)


def summarize_scores(
    overlaps: Sequence[float | None], errors: Sequence[float | None],
    states: Sequence[str] | None = None,
) -> Summary:
    """:func:`summarize` of per-frame ``overlaps`` and centre ``errors`` already computed (as
    :func:`frame_scores` gives them: None where unscored, ``inf`` where no box was claimed)."""
    summary = Summary(
        frames_evaluated=sum(o is not None for o in overlaps),
        mean_overlap=_or_none(mean_overlap(overlaps)),
        auc=_or_none(auc(overlaps)),
        precision20=_or_none(precision_at(errors)),
        mean_center_error=_or_none(mean_center_error(errors)),
    )
    if states is not None:
        summary["tracking_miss"] = _or_none(tracking_miss_rate(states, overlaps))
        summary["miss_flagged"] = _or_none(flagged_miss_rate(states, overlaps))
    return summary
