"""Issue 21 item 2: `vtrack report` never scores a `track.csv` cut (or edited) after its run
as if it were whole: the run is left out with one warning naming the file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from test_cli import vtrack

from vtrack.scenes import make_scene, write_groundtruth, write_video

W, H, FRAMES = 64, 48, 40


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("whole")
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    write_video(scene, folder / "clip.mp4")
    write_groundtruth(scene, folder / "clip.gt.txt")
    out = folder / "run"
    result = vtrack("run", str(folder / "clip.mp4"), "--gt", str(folder / "clip.gt.txt"),
                    "-c", "s0", "--no-video", "-o", str(out))
    assert result.returncode == 0, result.stderr.decode()
    return out


def report(run: Path, out: Path) -> tuple[int, str]:
    result = vtrack("report", str(run), "-o", str(out), "-q")
    stderr = result.stderr.decode()
    assert "Traceback" not in stderr, stderr
    return result.returncode, stderr


def test_a_whole_run_is_scored(run_dir: Path, tmp_path: Path) -> None:
    code, stderr = report(run_dir, tmp_path / "rep")
    assert code == 0 and "left out" not in stderr, stderr
    rows = (tmp_path / "rep" / "summary.csv").read_text().splitlines()
    assert len(rows) == 2


@pytest.mark.parametrize("sizes_recorded", [True, False])
def test_a_cut_track_csv_is_left_out_with_a_warning(run_dir: Path, tmp_path: Path,
                                                    sizes_recorded: bool) -> None:
    copy = tmp_path / "run"
    copy.mkdir()
    record = json.loads((run_dir / "run.json").read_text())
    if not sizes_recorded:  # a record from before sizes were recorded: rows against frames
        del record["output_bytes"]
    (copy / "run.json").write_text(json.dumps(record))
    data = (run_dir / "track.csv").read_bytes()
    (copy / "track.csv").write_bytes(data[:1000])
    code, stderr = report(copy, tmp_path / "rep")
    assert code != 0  # the only run is left out: nothing to report
    assert "track.csv" in stderr and "cut or edited" in stderr, stderr
    assert f"{FRAMES} frames" in stderr or "bytes" in stderr, stderr
