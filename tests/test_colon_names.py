"""Local files whose names FFmpeg would read as ``protocol:rest`` (``x:y.mp4``, ``file:z.mp4``)
are read and written as the files they are."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path


def vtrack(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120, check=False)


def test_names_with_a_colon_are_local_files(tmp_path: Path) -> None:
    """``x:y.mp4`` was 'not a video FFmpeg can decode (Protocol not found)', ``file:z.mp4``
    'no such file' (FFmpeg opened z.mp4), ``-o q:r`` 'cannot write (Protocol not found)',
    ``vtrack scene smooth m:n.mp4`` the same, and images named ``a:0001.jpg`` in the
    current folder were not images FFmpeg could decode."""
    made = vtrack("scene", "smooth", "m:n.mp4", "--frames", "12", "--size", "160x120",
                  cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    for name in ("x:y.mp4", "file:z.mp4"):
        shutil.copy(tmp_path / "m:n.mp4", tmp_path / name)
        done = vtrack("run", name, "--gt", "m:n.gt.txt", "-c", "s2", "-q", "-o", f"q:{name}",
                      cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        record = json.loads((tmp_path / f"q:{name}" / "run.json").read_text())
        assert (record["status"], record["frames"]) == ("complete", 12)
        assert "annotated.mp4" in record["outputs"]
    images = tmp_path / "seq"
    assert vtrack("scene", "smooth", "seq", "--format", "images", "--frames", "12", "--size",
                  "160x120", cwd=tmp_path).returncode == 0
    for picture in (images / "img").iterdir():
        picture.rename(picture.with_name(f"a:{picture.name}"))
    done = vtrack("run", ".", "--gt", "../groundtruth_rect.txt", "--gt-origin", "1", "-c", "s2",
                  "-q", "--no-video", "-o", str(tmp_path / "images"), cwd=images / "img")
    assert done.returncode == 0, done.stderr
    assert json.loads((tmp_path / "images" / "run.json").read_text())["frames"] == 12
