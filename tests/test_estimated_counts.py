"""A Matroska file lists no frame count: it is estimated as its duration times its nominal rate,
which a gap in the timestamps or a variable rate makes wrong. The estimate is neither recorded
as the input's count nor shown as the progress total once the timestamps depart from it."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import av
import pytest

from vtrack.io import open_source
from vtrack.scenes import make_scene

FRAMES = 40


def _mkv(path: Path, times_ms: list[int]) -> Path:
    """A Matroska H.264 clip of a generated scene, one picture at each of ``times_ms``
    (nominal rate 30 fps)."""
    scene = make_scene("smooth", seed=4, width=160, height=120, frames=len(times_ms), fps=30)
    with av.open(str(path), "w") as out:
        stream = out.add_stream("libx264", rate=30, options={"preset": "ultrafast"})
        stream.width, stream.height, stream.pix_fmt = 160, 120, "yuv420p"
        stream.codec_context.time_base = Fraction(1, 1000)
        for ms, picture in zip(times_ms, scene.frames(), strict=True):
            frame = av.VideoFrame.from_ndarray(picture, format="bgr24")
            frame.pts, frame.time_base = ms, Fraction(1, 1000)
            out.mux(stream.encode(frame))
        out.mux(stream.encode())
    return path


CLIPS = {
    # 20 frames, then a jump of 1000000 s in the timestamps, then 20 more: ~30000020 estimated
    "gap": [33 * i for i in range(20)] + [10**9 + 33 * i for i in range(20)],
    # 20 frames 10 ms apart, then 20 frames 100 ms apart: a variable rate (~230 estimated)
    "vfr": [10 * i for i in range(20)] + [300 + 100 * i for i in range(20)],
}


@pytest.mark.parametrize("name", sorted(CLIPS))
def test_run_records_the_frames_read_and_progress_drops_a_departed_estimate(
        name: str, tmp_path: Path) -> None:
    """run.json's ``input.frame_count`` was the estimate (30000020 for 40 frames) and the
    progress lines counted towards it (``37/30000020 frames (0%) ... 15:50:51 left``); the
    count is now the frames read, and no line past the departure shows a total but 40."""
    clip = _mkv(tmp_path / f"{name}.mkv", CLIPS[name])
    with open_source(str(clip)) as source:
        assert source.info.frame_count_estimated and source.info.frame_count != FRAMES
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "--init",
                           "40,40,30,30", "-c", "s2", "--no-video", "--stats-period", "0",
                           "-o", str(out)], capture_output=True, text=True, timeout=120,
                          check=False)
    assert done.returncode == 0, done.stderr
    record = json.loads((out / "run.json").read_text())
    assert record["frames"] == FRAMES
    assert (record["input"]["frame_count"], record["input"]["frame_count_estimated"]) == (
        FRAMES, False)
    # (progress names the input as given, as the summary does)
    counts = re.findall(rf"^{re.escape(str(clip))}: (\d+)(?:/(\d+))? frames", done.stderr,
                        re.MULTILINE)
    # the last line's total depends on whether the reader thread reached the end first
    assert counts and counts[-1][0] == str(FRAMES), done.stderr
    late = {total for frames, total in counts if int(frames) > 25}
    assert late <= {"", str(FRAMES)}, done.stderr


def test_an_estimate_left_standing_is_marked(tmp_path: Path) -> None:
    """A run stopped by ``--frames`` before the end of a steady Matroska clip keeps the
    estimate, marked ``frame_count_estimated``."""
    clip = _mkv(tmp_path / "steady.mkv", [33 * i for i in range(FRAMES)])
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "--init",
                           "40,40,30,30", "-c", "s0", "--no-video", "--frames", "10", "-q",
                           "-o", str(out)], capture_output=True, text=True, timeout=120,
                          check=False)
    assert done.returncode == 0, done.stderr
    recorded = json.loads((out / "run.json").read_text())["input"]
    assert recorded["frame_count_estimated"] is True
    assert abs(recorded["frame_count"] - FRAMES) <= 1
