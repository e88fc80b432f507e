"""Inputs FFmpeg opens beyond a file path: a container on stdin, redirected or piped."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from vtrack.scenes import make_scene, write_video


def _run(args: list[str], **kwargs: object) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", "run", *args], capture_output=True,
                          timeout=120, check=False, **kwargs)  # type: ignore[call-overload]


def test_a_container_on_stdin_gives_the_same_csv_as_its_file(tmp_path: Path) -> None:
    """``vtrack run - < clip.mp4`` (a seekable redirect) and ``cat clip.mp4 | vtrack run -``
    (a pipe, probed as ``ffmpeg -i pipe:`` does) write track.csv bit for bit as the path."""
    scene = make_scene("smooth", seed=6, width=160, height=120, frames=30, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    common = ["--config", "s2", "--init", ",".join(f"{v:g}" for v in scene.boxes[0]),
              "--no-video"]
    from_path = _run([str(clip), *common, "--out", str(tmp_path / "path")])
    assert from_path.returncode == 0, from_path.stderr
    with clip.open("rb") as redirected:
        from_redirect = _run(["-", *common, "--out", str(tmp_path / "redirect")],
                             stdin=redirected)
    assert from_redirect.returncode == 0, from_redirect.stderr
    from_pipe = _run(["-", *common, "--out", str(tmp_path / "pipe")], input=clip.read_bytes())
    assert from_pipe.returncode == 0, from_pipe.stderr
    expected = (tmp_path / "path" / "track.csv").read_bytes()
    assert expected.count(b"\n") == 31
    assert (tmp_path / "redirect" / "track.csv").read_bytes() == expected
    assert (tmp_path / "pipe" / "track.csv").read_bytes() == expected
    assert b"-: 30 frames" in from_pipe.stdout


def test_stdin_that_is_no_container_is_one_line_and_a_non_zero_exit(tmp_path: Path) -> None:
    done = _run(["-", "--init", "1,1,8,8", "--no-video", "--out", str(tmp_path / "o")],
                input=b"not a video at all\n" * 50)
    assert done.returncode != 0
    lines = done.stderr.decode().strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vtrack: error: -:"), lines
    assert b"Traceback" not in done.stderr
