"""The annotated video keeps every frame's time over long spans (its clock: vtrack.io.videoclock).

An MP4 keeps the step between two pictures in 32 bits: at 90 kHz a step past ~6.6 h used to
put every later frame one tick after the one before (a video that looked whole), exit 0. An
input of unknown length whose step no clock can hold ends the video there, not the run.
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import av
import numpy as np
import pytest
from click.testing import CliRunner

from tests.conftest import one_error_line
from vtrack.cli import main
from vtrack.io.videowriter import VideoWriter, verify_video


def _clip(path: Path, times_s: list[float], codec: str = "ffv1") -> Path:
    """A 64x48 clip (FFV1 Matroska, or as ``codec`` in the container ``path``'s suffix names)
    of a red 20x20 target moving right a pixel a frame, its frames at ``times_s``
    (milliseconds, Matroska's clock)."""
    with av.open(str(path), "w") as out:
        stream = out.add_stream(codec, rate=25)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        if codec == "libx264":
            stream.options = {"preset": "ultrafast", "qp": "0"}
        stream.codec_context.time_base = Fraction(1, 1000)
        for i, time_s in enumerate(times_s):
            pixels = np.full((48, 64, 3), 90, np.uint8)
            pixels[10:30, 5 + i:25 + i] = (40, 60, 210)
            picture = av.VideoFrame.from_ndarray(pixels, format="bgr24")
            picture.pts, picture.time_base = round(time_s * 1000), Fraction(1, 1000)
            for packet in stream.encode(picture):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return path


#: One gap of ~13.9 h after five frames at 25 fps; a step of ~27.8 h between every frame.
GAP = [i / 25 for i in range(5)] + [50000 + i / 25 for i in range(5, 10)]
EVERY = [i * 100000.0 for i in range(8)]


@pytest.mark.parametrize(("times", "preset"), [(GAP, "ultrafast"), (EVERY, "medium"),
                                               (GAP, "placebo")])
def test_a_long_span_keeps_every_frame_time(tmp_path: Path, times: list[float],
                                            preset: str) -> None:
    clip = _clip(tmp_path / "long.mkv", times)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip), "--init", "5,10,20,20", "--preset",
                                       preset, "-o", str(out)])
    assert result.exit_code == 0, result.output
    with (out / "track.csv").open(newline="") as handle:
        written = [float(row["time_s"]) for row in csv.DictReader(handle)]
    assert written == pytest.approx(times, abs=1e-3)
    with av.open(str(out / "annotated.mp4")) as video:
        stream = video.streams.video[0]
        shown = [float(frame.time) for frame in video.decode(stream)]
        tick = float(stream.time_base)
    assert len(shown) == len(written)
    assert all(later > earlier for earlier, later in zip(shown, shown[1:], strict=False))
    assert all(abs(s - w) <= tick + 1e-9 for s, w in zip(shown, written, strict=True)), shown


def test_a_span_no_clock_holds_is_refused_before_tracking(tmp_path: Path) -> None:
    clip = _clip(tmp_path / "ages.mkv", [i * 3e9 for i in range(3)])  # ~95 years apart
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip), "--init", "5,10,20,20", "-o",
                                       str(out)])
    line = one_error_line(result)
    assert "annotated.mp4: the input spans 6e+09 s, more than the video's timestamps" in line
    assert line.endswith("give --no-video to track it without the video"), line
    assert not out.exists()


def _shown(path: Path) -> list[float]:
    """The times of the pictures of the video at ``path``, decoded."""
    with av.open(str(path)) as video:
        return [float(frame.time) for frame in video.decode(video.streams.video[0])]


def test_a_step_an_unknown_span_cannot_hold_ends_the_video_there(tmp_path: Path) -> None:
    """The writer raised, and threw the whole video away on close."""
    path = tmp_path / "v.mp4"
    writer = VideoWriter(path, 64, 48, 25.0)  # no span: a live input's, a followed file's
    picture = np.zeros((72, 64), np.uint8)
    assert writer.write(picture, time_s=0.0) and writer.write(picture, time_s=0.04)
    assert writer.ended is None
    assert not writer.write(picture, time_s=30000.0)  # 2.7e9 ticks of 90 kHz
    assert writer.ended == ("it comes 29999.96 s after the frame before it, more than the "
                            "video's timestamps hold (23860.9294 s with preset ultrafast)")
    assert not writer.write(picture, time_s=30000.04)  # ended: nothing after it either
    writer.close()
    assert writer.frames_written == 2 and verify_video(path, 2) is None
    assert _shown(path) == pytest.approx([0.0, 0.04], abs=1e-4)


def test_an_input_of_unknown_length_is_tracked_past_the_videos_end(tmp_path: Path) -> None:
    """An MPEG-TS on stdin (no duration: 90 kHz) with a ~13.9 h gap after frame 4 failed the
    run at frame 5 (exit 1, annotated.mp4 removed, track.csv cut there): now the video ends at
    frame 4, one warning says where and why, and every frame is tracked."""
    clip = _clip(tmp_path / "gap.ts", GAP, codec="libx264")
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", "--init", "5,10,20,20",
                           "-o", str(out)], input=clip.read_bytes(), capture_output=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    said = (f"{out / 'annotated.mp4'}: ends at frame 4 (0.16 s; 5 frames of the run's 10): "
            "frame 1250005 (50000.2 s) is left out, it comes 50000.04 s after the frame before "
            "it, more than the video's timestamps hold (23860.9294 s with preset ultrafast); "
            "track.csv goes on to frame 1250009")
    assert done.stderr.decode().splitlines().count(f"vtrack: warning: {said}") == 1
    with (out / "track.csv").open(newline="") as handle:
        written = [float(row["time_s"]) for row in csv.DictReader(handle)]
    assert written == pytest.approx(GAP, abs=1e-3)
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "complete" and record["warnings"].count(said) == 1
    assert (record["frames"], record["video_frames"]) == (10, 5)
    assert "annotated.mp4" in record["outputs"]
    assert _shown(out / "annotated.mp4") == pytest.approx(GAP[:5], abs=1e-4)
