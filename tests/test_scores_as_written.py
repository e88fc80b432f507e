"""run.json's single-target metrics are what a reader recomputes from ``track.csv``."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from vtrack.cli import main


def _otb(path: Path) -> tuple[float, float, float]:
    """Mean overlap, AUC (OTB's 21 thresholds 0, 0.05, ..., 1, strict >) and precision@20 from
    track.csv's ``overlap`` and ``center_error`` columns (an empty error next to an overlap: no
    box, infinite error)."""
    with path.open(newline="") as handle:
        rows = [r for r in csv.DictReader(handle) if r["overlap"] != ""]
    overlaps = np.array([float(r["overlap"]) for r in rows])
    errors = np.array([float(r["center_error"] or math.inf) for r in rows])
    thresholds = np.arange(21) / 20
    auc = np.mean([np.mean(overlaps > t) for t in thresholds])
    return float(overlaps.mean()), float(auc), float(np.mean(errors <= 20))


def test_run_json_metrics_are_those_of_track_csv_columns(clip_factory, tmp_path: Path) -> None:
    """run.json's metrics were computed from unrounded scores: the mean overlap of track.csv's
    column differed, and an overlap rounded onto a success threshold (0.95) changed OTB's AUC
    (0.925198 vs 0.925317 on a 1200-frame run). Now they are computed from the scores as
    written and agree to the last bits a float sum allows."""
    clip = clip_factory("smooth", seed=3, width=160, height=120, frames=600)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "-c", "s0", "--gt",
                                       str(clip.gt), "--no-video", "-o", str(out), "-q"])
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "run.json").read_text())["metrics"]
    mean, auc, precision = _otb(out / "track.csv")
    assert metrics["frames_evaluated"] == 600
    assert math.isclose(metrics["mean_overlap"], mean, rel_tol=0, abs_tol=1e-12)
    assert math.isclose(metrics["auc"], auc, rel_tol=0, abs_tol=1e-12)
    assert math.isclose(metrics["precision20"], precision, rel_tol=0, abs_tol=1e-12)


def test_the_report_scores_the_run_as_its_run_json_does(clip_factory, tmp_path: Path) -> None:
    """`vtrack report` rescored the run's boxes at full precision, so its mean overlap (and an
    AUC whose overlap sits on a threshold) could differ from run.json's in the last digits."""
    clip = clip_factory("smooth", seed=3, width=160, height=120, frames=600)
    out = tmp_path / "out"
    runner = CliRunner()
    result = runner.invoke(main, ["run", str(clip.path), "-c", "s0", "--gt", str(clip.gt),
                                  "--no-video", "-o", str(out), "-q"])
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "run.json").read_text())["metrics"]
    report = tmp_path / "report"
    result = runner.invoke(main, ["report", str(out), "-o", str(report), "-q"])
    assert result.exit_code == 0, result.output
    with (report / "summary.csv").open(newline="") as handle:
        (row,) = list(csv.DictReader(handle))
    for column in ("auc", "mean_overlap", "precision20"):
        assert float(row[column]) == round(metrics[column], 6), column


def test_a_score_written_onto_a_threshold_is_scored_as_written() -> None:
    """A box whose overlap (0.9500005) is written as 0.95 is not a success at OTB's 0.95 in
    run.json; the report, rescoring at full precision, counted it as one."""
    from vtrack.evaluate import metrics
    from vtrack.geometry import Box
    from vtrack.report.runs import _scored_as_written

    truth = [Box(0, 0, 100, 100)]
    box = [Box(0, 0, 99.999, 95.001)]
    assert metrics.frame_scores(box, truth)[0][0] > 0.95
    overlaps, errors = _scored_as_written(box, truth)
    assert overlaps == [0.95] and errors[0] is not None
    assert metrics.auc(overlaps) < metrics.auc(metrics.frame_scores(box, truth)[0])
