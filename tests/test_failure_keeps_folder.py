"""Issue 21 item 4: a run that fails before its first frame is out (the tracker refuses the
target, exit 2) leaves its folder as it was: the earlier run's files stay, byte for byte."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_cli import assert_one_line_error, vtrack

from vtrack.scenes import make_scene, write_groundtruth, write_video


def clip(folder: Path, scenario: str) -> tuple[Path, Path]:
    scene = make_scene(scenario, seed=0, width=96, height=72, frames=60, fps=30.0)
    write_video(scene, folder / f"{scenario}.mp4")
    write_groundtruth(scene, folder / f"{scenario}.gt.txt")
    return folder / f"{scenario}.mp4", folder / f"{scenario}.gt.txt"


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("video", [True, False])
def test_a_run_refused_at_frame_0_leaves_the_folder_as_it_was(tmp_path: Path,
                                                              video: bool) -> None:
    colour, grey = clip(tmp_path, "smooth"), clip(tmp_path, "grey")
    out = tmp_path / "out"
    flags = [] if video else ["--no-video"]
    first = vtrack("run", str(colour[0]), "--gt", str(colour[1]), "-c", "s0", "-o", str(out))
    assert first.returncode == 0, first.stderr.decode()
    before = snapshot(out)
    assert {"annotated.mp4", "track.csv", "run.json"} <= set(before)
    again = vtrack("run", str(grey[0]), "--gt", str(grey[1]), "-c", "s0", *flags, "-y", "-o",
                   str(out))
    assert_one_line_error(again, "no colour")
    assert again.returncode == 2
    assert snapshot(out) == before


def test_a_refused_run_into_a_new_folder_leaves_no_folder(tmp_path: Path) -> None:
    grey = clip(tmp_path, "grey")
    result = vtrack("run", str(grey[0]), "--gt", str(grey[1]), "-c", "s0",
                    "-o", str(tmp_path / "new" / "out"))
    assert result.returncode == 2
    assert not (tmp_path / "new").exists()
