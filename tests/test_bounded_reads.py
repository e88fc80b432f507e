"""Issue 21 items 13 and 16: ground truth, sidecar boxes and configs are read with a ceiling
(`--gt /dev/zero` is one line, not a memory error), a byte-order mark is accepted wherever
text is read, and MOTChallenge ground truth that cannot be right is not taken silently."""

from __future__ import annotations

import codecs
import json
from pathlib import Path

import pytest
from test_cli import assert_one_line_error, vtrack

from vtrack.scenes import make_scene, write_clip, write_groundtruth, write_video

W, H, FRAMES = 64, 48, 20


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("bounded")
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    write_video(scene, folder / "occ.mp4")
    write_groundtruth(scene, folder / "occ.gt.txt")
    return folder / "occ.mp4", folder / "occ.gt.txt"


def test_ground_truth_from_an_endless_device_is_one_line(clip, tmp_path: Path) -> None:
    result = vtrack("run", str(clip[0]), "--gt", "/dev/zero", "-c", "s0", "--no-video",
                    "-o", str(tmp_path / "o"))
    assert_one_line_error(result, "/dev/zero", "too large")
    assert result.returncode == 2 and not (tmp_path / "o").exists()
    done = vtrack("run", str(clip[0]), "--init", "20,15,12,10", "-c", "s0", "--no-video",
                  "-o", str(tmp_path / "r"))
    assert done.returncode == 0, done.stderr.decode()
    result = vtrack("report", str(tmp_path / "r"), "--gt", "/dev/zero", "-o", str(tmp_path / "p"))
    assert_one_line_error(result, "/dev/zero", "too large")


def test_a_huge_sidecar_and_config_are_one_line(clip, tmp_path: Path) -> None:
    video = tmp_path / "v.mp4"
    video.symlink_to(clip[0])
    with (tmp_path / "v.init.txt").open("wb") as handle:  # 1 GB, sparse: nothing on disk
        handle.truncate(1 << 30)
    result = vtrack("run", str(video), "-c", "s0", "--no-video", "-o", str(tmp_path / "o"))
    assert_one_line_error(result, "v.init.txt", "too large")
    with (tmp_path / "c.toml").open("wb") as handle:
        handle.truncate(1 << 30)
    result = vtrack("run", str(clip[0]), "-c", str(tmp_path / "c.toml"), "--gt", str(clip[1]),
                    "-o", str(tmp_path / "o"))
    assert_one_line_error(result, "c.toml", "too large")


def test_a_byte_order_mark_is_accepted_in_a_sidecar_and_a_config(clip, tmp_path: Path) -> None:
    video = tmp_path / "v.mp4"
    video.symlink_to(clip[0])
    first = clip[1].read_text().splitlines()[0]
    (tmp_path / "v.init.txt").write_bytes(codecs.BOM_UTF8 + first.encode() + b"\n")
    shipped = (Path(__file__).parents[1] / "vtrack" / "configs" / "s0.toml").read_bytes()
    (tmp_path / "mine.toml").write_bytes(codecs.BOM_UTF8 + shipped)
    result = vtrack("run", str(video), "-c", str(tmp_path / "mine.toml"), "--no-video",
                    "-o", str(tmp_path / "o"))
    assert result.returncode == 0, result.stderr.decode()
    record = json.loads((tmp_path / "o" / "run.json").read_text())
    assert record["init_from"].endswith("v.init.txt")


@pytest.fixture(scope="module")
def multi(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("multi")
    scene = make_scene("multi", seed=0, width=160, height=120, frames=60, fps=30.0)
    files = write_clip(scene, folder / "m.mp4", preset="veryfast")
    assert files.mot is not None
    return files.clip, files.mot


def test_mot_ground_truth_with_a_duplicate_row_is_refused(multi, tmp_path: Path) -> None:
    lines = multi[1].read_text().splitlines()
    bad = tmp_path / "dup.txt"
    bad.write_text("\n".join([*lines, lines[3]]) + "\n")
    result = vtrack("run", str(multi[0]), "-c", "s4_multi", "--gt", str(bad), "--no-video",
                    "-o", str(tmp_path / "o"))
    line = assert_one_line_error(result, "dup.txt", f"line {len(lines) + 1}", "line 4")
    assert "second box" in line and result.returncode == 2


def test_mot_ground_truth_past_the_end_is_a_warning(multi, tmp_path: Path) -> None:
    lines = multi[1].read_text().splitlines()
    longer = tmp_path / "long.txt"
    extra = lines[0].split(",")
    extra[0] = "99"
    longer.write_text("\n".join([*lines, ",".join(extra)]) + "\n")
    result = vtrack("run", str(multi[0]), "-c", "s4_multi", "--gt", str(longer), "--no-video",
                    "-o", str(tmp_path / "o"))
    stderr = result.stderr.decode()
    assert result.returncode == 0, stderr
    assert "vtrack: warning:" in stderr and "past the input's 60 frames" in stderr, stderr
    assert "up to frame 99" in stderr


def test_a_bounded_read_holds_what_the_file_holds_not_the_limit(tmp_path: Path) -> None:
    """Reading ground truth allocated its 256 MB ceiling at once (one read of limit + 1
    bytes); it now reads in pieces, so a 40 KB file costs about 40 KB, and the ceiling holds."""
    import tracemalloc

    from vtrack.errors import InputError
    from vtrack.io.limits import read_bounded

    path = tmp_path / "gt.txt"
    path.write_text("10,20,30,40\n" * 3500)
    tracemalloc.start()
    try:
        data = read_bounded(path, 256 << 20, "ground truth")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert data == path.read_bytes()
    assert peak < 4 << 20  # a few pieces, not the 256 MB ceiling
    with pytest.raises(InputError, match="larger than 40 KB"):
        read_bounded(path, 40 << 10, "ground truth")
