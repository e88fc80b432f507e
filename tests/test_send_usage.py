"""``python -m vtrack.scenes.send``: wrong arguments get a usage line and exit code 2, a file
it cannot send one line and exit code 1, never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from conftest import START_BOUND_S

SENDER = [sys.executable, "-m", "vtrack.scenes.send"]


@pytest.mark.parametrize("args", [[], ["clip.mp4"], ["a", "b", "c", "d"]])
def test_wrong_arguments_print_the_usage(args: list[str], tmp_path: Path) -> None:
    """Too few arguments ended in an IndexError traceback."""
    done = subprocess.run([*SENDER, *args], capture_output=True, text=True, cwd=tmp_path,
                          timeout=START_BOUND_S, check=False)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("usage: python -m vtrack.scenes.send [-h] FILE URL [FORMAT]")
    assert "Traceback" not in done.stderr


def test_help_and_a_missing_file(tmp_path: Path) -> None:
    """``--help`` was an IndexError traceback; a missing file a FileNotFoundError one."""
    helped = subprocess.run([*SENDER, "--help"], capture_output=True, text=True,
                            timeout=START_BOUND_S, check=False)
    assert helped.returncode == 0 and "FILE URL [FORMAT]" in helped.stdout, helped.stderr
    missing = subprocess.run([*SENDER, str(tmp_path / "none.mp4"), "udp://127.0.0.1:9"],
                             capture_output=True, text=True, timeout=START_BOUND_S, check=False)
    assert missing.returncode == 1, missing.stderr
    assert missing.stderr.count("\n") == 1 and "none.mp4" in missing.stderr, missing.stderr
    assert "No such file" in missing.stderr


def test_a_text_file_and_a_port_out_of_range_are_one_line_naming_them(tmp_path: Path) -> None:
    """A ground-truth file was sent as FFmpeg's tty reader draws it and failed with
    '... -> udp://127.0.0.1:9: ansi'; udp://127.0.0.1:99999 sent the clip to port 34463 (99999
    mod 65536) and exited 0."""
    from vtrack.scenes import make_scene, write_groundtruth, write_video

    scene = make_scene("smooth", seed=1, width=64, height=48, frames=30, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4", preset="ultrafast")
    text = write_groundtruth(scene, tmp_path / "clip.gt.txt")
    for args, problem in (
            ([str(text), "udp://127.0.0.1:9"], f"{text}: a text file, not a video"),
            ([str(clip), "udp://127.0.0.1:99999"],
             "udp://127.0.0.1:99999: the port must be a number from 1 to 65535")):
        done = subprocess.run([*SENDER, *args], capture_output=True, text=True,
                              timeout=START_BOUND_S, check=False)
        assert done.returncode == 1, done.stderr
        assert done.stderr == f"python -m vtrack.scenes.send: error: {problem}" + (
            " (FFmpeg's tty reader would draw its characters as pictures)\n"
            if "text" in problem else "\n")
