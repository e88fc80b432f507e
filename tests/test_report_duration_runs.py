"""``vtrack report --gt`` on a run stopped by ``--frames Ts`` (a duration): the run covers part
of its input, so a ground truth longer than the run scores its frames."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from vtrack.report.runs import GroundTruth, load_run
from vtrack.scenes import make_scene, write_groundtruth, write_video

FRAMES = 20


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("duration")
    scene = make_scene("smooth", seed=2, width=160, height=120, frames=FRAMES, fps=30)
    write_groundtruth(scene, folder / "walk.gt.txt")
    return write_video(scene, folder / "walk.mp4")


def _run(clip: Path, out: Path, span: str) -> dict:
    """``vtrack run`` from the first ground-truth box (no ground truth recorded) for ``span``."""
    first = clip.with_suffix(".gt.txt").read_text().splitlines()[0]
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "--init", first,
                           "-c", "s2", "--frames", span, "-q", "--no-video", "-o", str(out)],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads((out / "run.json").read_text())


def test_a_run_a_duration_stopped_is_scored_on_its_frames(clip: Path, tmp_path: Path) -> None:
    """It was 'not scored: walk.gt.txt has 20 boxes for its 9 frames': the report decided
    whether --frames stopped the run from ``max_frames`` alone."""
    truth = GroundTruth.read(clip.with_suffix(".gt.txt"))
    record = _run(clip, tmp_path / "short", "0.3s")
    assert (record["frames"], record["stopped_by_frames"]) == (9, True)
    result = load_run(tmp_path / "short", truth)
    assert result.note is None and len(result.overlaps) == 9
    # a duration past the input's end: the run covers it all, and a longer truth is refused
    record = _run(clip, tmp_path / "long", "5s")
    assert (record["frames"], record["stopped_by_frames"]) == (FRAMES, False)
    assert len(load_run(tmp_path / "long", truth).overlaps) == FRAMES
    longer = GroundTruth(truth.path, [*truth.boxes, truth.boxes[-1]])
    assert "has 21 boxes for its 20 frames" in load_run(tmp_path / "long", longer).note


def test_a_duration_run_recorded_before_stopped_by_frames_is_scored(
        clip: Path, tmp_path: Path) -> None:
    """A run.json written before ``stopped_by_frames`` was recorded: a duration may have
    stopped the run, so its frames are scored."""
    _run(clip, tmp_path / "old", "0.3s")
    path = tmp_path / "old" / "run.json"
    record = json.loads(path.read_text())
    del record["stopped_by_frames"]
    path.write_text(json.dumps(record))
    result = load_run(tmp_path / "old", GroundTruth.read(clip.with_suffix(".gt.txt")))
    assert result.note is None and len(result.overlaps) == 9
