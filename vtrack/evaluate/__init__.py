"""Evaluation: ground-truth readers and single-target metrics (OTB conventions).

``groundtruth`` reads OTB/VOT/UAV123/LaSOT single-target files and MOTChallenge files into
:class:`~vtrack.geometry.Box` lists; ``metrics`` scores a tracker's boxes against them.
"""

from vtrack.evaluate.groundtruth import (
    SingleTruth,
    negative_note,
    parse_box,
    read_boxes,
    read_mot,
    read_mot_detections,
    read_truth,
)
from vtrack.evaluate.metrics import (
    ERROR_THRESHOLDS,
    FLAGGED_STATES,
    OVERLAP_THRESHOLDS,
    Summary,
    auc,
    flagged_miss_rate,
    frame_scores,
    mean_center_error,
    mean_overlap,
    precision_at,
    precision_curve,
    score_frame,
    success_curve,
    summarize,
    tracking_miss_rate,
)

__all__ = [
    "ERROR_THRESHOLDS",
    "FLAGGED_STATES",
    "OVERLAP_THRESHOLDS",
    "SingleTruth",
    "Summary",
    "auc",
    "flagged_miss_rate",
    "frame_scores",
    "mean_center_error",
    "mean_overlap",
    "negative_note",
    "parse_box",
    "precision_at",
    "precision_curve",
    "read_boxes",
    "read_mot",
    "read_mot_detections",
    "read_truth",
    "score_frame",
    "success_curve",
    "summarize",
    "tracking_miss_rate",
]
