"""Issue 21 item 1: `vtrack batch` resumes a result only while it still stands: its outputs are
there whole and its input and ground truth are the files it was made from (run as a user runs
it, on a small generated clip)."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from test_cli import vtrack

from vtrack.scenes import make_scene, write_groundtruth, write_video

W, H, FRAMES = 64, 48, 20


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A batch folder holding one clip ``occ.mp4`` and its ground truth."""
    folder = tmp_path / "in"
    folder.mkdir()
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    write_video(scene, folder / "occ.mp4")
    write_groundtruth(scene, folder / "occ.gt.txt")
    return folder


def resume(folder: Path, out: Path) -> str:
    """Run the batch (s0, with video) and return its line for occ."""
    result = vtrack("batch", str(folder), "-c", "s0", "-o", str(out), "-j", "1")
    assert result.returncode == 0, result.stderr.decode()
    return result.stdout.decode()


def test_an_untouched_result_is_skipped(folder: Path, tmp_path: Path) -> None:
    out = tmp_path / "r"
    resume(folder, out)
    record = json.loads((out / "occ" / "s0" / "run.json").read_text())
    assert record["identity"]["input"]["size"] == (folder / "occ.mp4").stat().st_size
    assert record["identity"]["gt"]["size"] == (folder / "occ.gt.txt").stat().st_size
    assert set(record["output_bytes"]) == {"track.csv", "annotated.mp4"}
    assert "already complete: not run again" in resume(folder, out)


@pytest.mark.parametrize("change", ["rm_csv", "cut_csv", "rm_video", "edit_gt", "new_input"])
def test_a_result_that_no_longer_stands_is_run_again(folder: Path, tmp_path: Path,
                                                     change: str) -> None:
    out = tmp_path / "r"
    resume(folder, out)
    run_dir = out / "occ" / "s0"
    if change == "rm_csv":
        (run_dir / "track.csv").unlink()
    elif change == "cut_csv":
        data = (run_dir / "track.csv").read_bytes()
        (run_dir / "track.csv").write_bytes(data[: len(data) // 2])
    elif change == "rm_video":
        (run_dir / "annotated.mp4").unlink()
    elif change == "edit_gt":
        gt = folder / "occ.gt.txt"
        lines = gt.read_text().splitlines()
        lines[5] = "1,1,10,10"
        gt.write_text("\n".join(lines) + "\n")
    else:  # another video of the same name (the scene at another quality), its mtime set back
        stat = (folder / "occ.mp4").stat()
        other = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
        write_video(other, tmp_path / "other.mp4", crf=40)
        shutil.copy(tmp_path / "other.mp4", folder / "occ.mp4")
        os.utime(folder / "occ.mp4", ns=(stat.st_atime_ns, stat.st_mtime_ns))
    line = resume(folder, out)
    assert "not run again" not in line, line
    assert (run_dir / "track.csv").is_file() and (run_dir / "annotated.mp4").is_file()
    record = json.loads((run_dir / "run.json").read_text())
    assert record["status"] == "complete"
    assert record["identity"]["gt"]["size"] == (folder / "occ.gt.txt").stat().st_size
    assert "already complete: not run again" in resume(folder, out)


def test_a_moved_batch_folder_resumes_and_a_refusal_names_what_changed(folder: Path,
                                                                      tmp_path: Path) -> None:
    """`mv r r2; vtrack batch in -o r2`: every pair failed 'made with other settings' (the
    record's out_dir was the old folder: nothing the user set), and with -y all ran again. Now
    it resumes, its line naming where the results are now. A pair that other settings did
    make is refused naming them ('made with other settings: --no-video, --frames')."""
    out = tmp_path / "r"
    resume(folder, out)
    moved = tmp_path / "r2"
    shutil.move(out, moved)
    line = resume(folder, moved)
    assert "already complete: not run again" in line, line
    assert f"-> {moved.resolve() / 'occ' / 's0'} " in line, line
    result = vtrack("batch", str(folder), "-c", "s0", "-o", str(moved), "-j", "1",
                    "--no-video", "--frames", "5")
    assert result.returncode == 1
    assert "(made with other settings: --no-video, --frames)" in result.stderr.decode()


@pytest.mark.parametrize("record", [None, "{broken"])
def test_results_without_a_record_are_not_said_made_with_other_settings(
        folder: Path, tmp_path: Path, record: str | None) -> None:
    """A pair's folder holding a track.csv and no run.json (its run killed before it
    recorded itself: a stopped batch's worker killed while its encoder flushed) was refused
    as '(made with other settings)': nothing said which settings made it. Then it said
    '(no run.json says what made them: a run stopped before it recorded itself?)', a
    question, and said so too of a folder whose run.json is there but cannot be read: that
    is now said, and the other is no question."""
    pair = tmp_path / "r" / "occ" / "s0"
    pair.mkdir(parents=True)
    (pair / "track.csv").write_text("frame,time_s\n0,0\n")
    if record is not None:
        (pair / "run.json").write_text(record)
    result = vtrack("batch", str(folder), "-c", "s0", "-o", str(tmp_path / "r"), "-j", "1")
    assert result.returncode == 1
    stderr = result.stderr.decode()
    held = "track.csv" if record is None else "run.json, track.csv"
    why = ("no run.json says what made them: a run stopped before it recorded itself leaves "
           "its files so" if record is None else
           "its run.json cannot be read: what made them is unknown")
    assert f"holds the results of an earlier run ({held})" in stderr, stderr
    assert "other settings" not in stderr and stderr.rstrip().endswith(f"--out ({why})"), stderr


def test_force_replaces_results_of_other_settings_as_its_help_says(folder: Path,
                                                                   tmp_path: Path) -> None:
    """--force replaced the results of a run with other settings without -y, while the help
    (and README) said those are replaced only with --overwrite; the help now says it."""
    out = tmp_path / "r"
    resume(folder, out)
    result = vtrack("batch", str(folder), "-c", "s0", "-o", str(out), "-j", "1", "--force",
                    "--no-video")
    assert result.returncode == 0, result.stderr.decode()
    assert json.loads((out / "occ" / "s0" / "run.json").read_text())["request"]["video"] is False
    help_text = " ".join(vtrack("batch", "--help").stdout.decode().split())
    force = help_text.split("--force ", 1)[1].split(" -y, --overwrite", 1)[0]
    assert "other settings" in force and "--overwrite" in force, force
    assert "without it (or --force) those pairs fail" in help_text


def test_a_config_at_a_long_path_is_recorded_whole_and_resumed(folder: Path,
                                                               tmp_path: Path) -> None:
    """A config at a path of more than 200 characters was recorded cut (``aaaa...aaaa (N
    characters)``) in run.json's request.config.source: a result made before was seen as made
    with other settings, and two long paths differing in the middle compared equal."""
    from vtrack.config import config_file

    deep = tmp_path / ("c" * 120) / ("d" * 120)
    deep.mkdir(parents=True)
    config = deep / "mine.toml"
    config.write_text(config_file("s0").read_text())
    assert len(str(config)) > 200
    out = tmp_path / "r"
    args = ("batch", str(folder), "-c", str(config), "-o", str(out), "-j", "1")
    first = vtrack(*args)
    assert first.returncode == 0, first.stderr.decode()
    record = json.loads((out / "occ" / "s0" / "run.json").read_text())  # (its name)
    assert record["request"]["config"]["source"] == str(config)
    again = vtrack(*args)
    assert again.returncode == 0, again.stderr.decode()
    assert "already complete: not run again" in again.stdout.decode(), again.stdout.decode()
