"""A write that fails part way (here: the file-size limit ``prlimit --fsize``, as a full disk
would) leaves no file that looks complete and keeps the good one that was there.

The commands run as a user runs them, in subprocesses on generated clips.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

#: Bytes a file may grow to under :func:`limited`: less than any image, clip or raw stream below.
LIMIT = 20_000

pytestmark = pytest.mark.skipif(shutil.which("prlimit") is None,
                                reason="prlimit (util-linux) is not installed: no way to make "
                                       "a write fail part way without root")


def vtrack(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300, check=False)


def limited(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """``vtrack ARGS`` with files limited to :data:`LIMIT` bytes."""
    return subprocess.run(["prlimit", f"--fsize={LIMIT}", sys.executable, "-m", "vtrack", *args],
                          capture_output=True, text=True, cwd=cwd, timeout=300, check=False)


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (hidden ones too) with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def one_error(result: subprocess.CompletedProcess, needle: str) -> None:
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr, result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("vtrack: error:")]
    assert len(errors) == 1 and needle in errors[0] and "File too large" in errors[0], errors


def test_a_failed_frame_keeps_the_image_that_was_there(tmp_path: Path) -> None:
    assert vtrack("scene", "smooth", "in.mp4", "--frames", "30", "--preset", "ultrafast",
                  cwd=tmp_path).returncode == 0
    assert vtrack("frame", "in.mp4", "-o", "fr/a.png", cwd=tmp_path).returncode == 2  # no fr/
    (tmp_path / "fr").mkdir()
    assert vtrack("frame", "in.mp4", "-o", "fr/a.png", cwd=tmp_path).returncode == 0
    before = snapshot(tmp_path / "fr")
    assert len(before["a.png"]) > LIMIT
    one_error(limited("frame", "in.mp4", "--at", "5", "-o", "fr/a.png", "-y", cwd=tmp_path),
              "fr/a.png")
    assert snapshot(tmp_path / "fr") == before  # the good image whole, no temporary file left


@pytest.mark.parametrize("fmt,out", [("mp4", "sc/fs.mp4"), ("raw", "sc/fs.raw"),
                                     ("images", "sc/fs")])
def test_a_failed_scene_leaves_no_partial_clip_and_keeps_the_earlier_one(
        tmp_path: Path, fmt: str, out: str) -> None:
    fresh = limited("scene", "smooth", out, "--frames", "60", "--format", fmt, cwd=tmp_path)
    one_error(fresh, out)
    assert snapshot(tmp_path / "sc") == {}  # nothing that could be taken for the clip
    assert vtrack("scene", "smooth", out, "--frames", "30", "--format", fmt,
                  cwd=tmp_path).returncode == 0
    before = snapshot(tmp_path / "sc")
    one_error(limited("scene", "smooth", out, "--frames", "60", "--format", fmt, "-y",
                      cwd=tmp_path), out)
    after = snapshot(tmp_path / "sc")
    assert after == before  # the 30-frame clip and its 30-line ground truth, as they were
    assert sum(name.endswith("gt.txt") or name.endswith("rect.txt") for name in after) == 1


def test_a_stream_file_cut_by_a_full_disk_holds_whole_lines(tmp_path: Path) -> None:
    """vtrack run --stream s.jsonl on a full disk ended 'failed' as it should, but s.jsonl
    ended inside a line ('{"frame":1367,...,"state":"tracking","'): a reader of JSON lines
    then fails on it. The file is now cut back to its last whole line, as track.csv is to its
    last whole row."""
    import csv
    import json

    assert vtrack("scene", "smooth", "in.mp4", "--frames", "300", "--size", "160x120",
                  "--preset", "ultrafast", cwd=tmp_path).returncode == 0
    result = limited("run", "in.mp4", "--gt", "in.gt.txt", "-c", "s0", "--no-video",
                     "--stream", "s.jsonl", "-o", "out", cwd=tmp_path)
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr
    assert "vtrack: error: --stream s.jsonl: File too large" in result.stderr
    data = (tmp_path / "s.jsonl").read_bytes()
    assert 0 < len(data) <= LIMIT and data.endswith(b"\n")
    frames = [json.loads(line)["frame"] for line in data.decode().splitlines()]
    with open(tmp_path / "out" / "track.csv", newline="") as rows:
        tracked = [int(row["frame"]) for row in csv.DictReader(rows)]
    assert frames == tracked[:len(frames)] and len(frames) >= len(tracked) - 1
