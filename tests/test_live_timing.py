"""What a run's ``timing`` counts: the frames, not the waits around them; its ``versions``."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import av
from conftest import LinesAsTheyCome

from vtrack.scenes import make_scene, write_raw, write_video

W, H = 160, 120


def test_seconds_end_when_the_last_frame_is_handled_not_when_the_input_closes(
        tmp_path: Path) -> None:
    """Stdin stays open after the last frame's line came out, for longer than everything
    before it took: that wait only finds the end of the input, so ``timing.seconds`` (and fps)
    leave it out. The bound is causal, not a speed: the tracked span ended before the test
    read the last line, and with the wait counted ``seconds`` would exceed it by 2 s whatever
    vtrack's start-up cost."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    raw = write_raw(scene, tmp_path / "clip.bgr").read_bytes()
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    spawned = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "vtrack", "run", "-", "--raw", f"{W}x{H}",
                             "--config", "s0", "--init", box, "--no-video", "--out", str(out),
                             "--stream", "-", "-q"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    assert proc.stdin is not None and proc.stdout is not None
    try:
        lines = LinesAsTheyCome(proc.stdout)
        proc.stdin.write(raw)
        proc.stdin.flush()
        for index in range(10):
            line = lines.next(120)  # a bound, not a measure
            assert line, f"no line for frame {index}"
            assert json.loads(line)["frame"] == index
        last_line = time.perf_counter()
        # the input stays open, with nothing more in it, longer than all that came before
        time.sleep(last_line - spawned + 2)
        proc.stdin.close()
        assert proc.wait(timeout=120) == 0
    finally:
        proc.kill()
        proc.wait()
    record = json.loads((out / "run.json").read_text())
    seconds = record["timing"]["seconds"]
    # the tracked span lies between the spawn and the last line read; counting the wait
    # would add more than that whole time, however slow vtrack's start-up was
    assert 0 < seconds < last_line - spawned + 1
    assert record["timing"]["fps"] == record["frames"] / seconds


def test_seconds_leave_out_the_wait_that_found_the_end_of_a_followed_file(
        tmp_path: Path) -> None:
    """``--follow F`` on a finished file waits F seconds after its last growth before the end
    is found, and the decoder's frame threads hand over the last frames only then: that wait
    counted in ``timing.seconds`` (3.1 s for 30 frames with ``--follow 3``). The bound is
    causal, not a speed: the wait (at least F) and the tracked span both lie inside the
    process's life, so the span without the wait is at most that life less F. (With the wait
    counted it would fail wherever start-up and closing take less than F: F is 5.)"""
    follow_s = 5
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=30, fps=30)
    clip = write_video(scene, tmp_path / "clip.ts")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    spawned = time.perf_counter()
    subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "--follow", str(follow_s),
                    "-c", "s0", "--init", box, "--no-video", "-o", str(out), "-q"],
                   check=True, timeout=120, capture_output=True)
    lived = time.perf_counter() - spawned
    record = json.loads((out / "run.json").read_text())
    assert record["frames"] == 30
    assert 0 < record["timing"]["seconds"] <= lived - follow_s


def test_versions_name_ffmpeg_s_release_and_libavcodec_s_own(tmp_path: Path) -> None:
    """``versions.ffmpeg`` is FFmpeg's release (what a paper cites), not libavcodec's number,
    which is kept as ``versions.libavcodec``."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    raw = write_raw(scene, tmp_path / "clip.bgr")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    subprocess.run([sys.executable, "-m", "vtrack", "run", str(raw), "--raw", f"{W}x{H}",
                    "-c", "s0", "--init", box, "--no-video", "-o", str(out), "-q"],
                   check=True, timeout=120, capture_output=True)
    versions = json.loads((out / "run.json").read_text())["versions"]
    assert versions["ffmpeg"] == str(av.ffmpeg_version_info)
    assert versions["libavcodec"] == ".".join(map(str, av.library_versions["libavcodec"]))
    assert versions["ffmpeg"] != versions["libavcodec"]


def test_timestamps_that_go_back_are_one_warning_with_their_count(tmp_path: Path) -> None:
    """A source whose timestamps start again (a sender restarted; here one MPEG-TS recording
    three times over) while frame numbers carry on: one warning in run.json and on stderr,
    counting the jumps, naming the first, and the ground truth's caveat."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.ts")
    joined = tmp_path / "joined.ts"
    joined.write_bytes(clip.read_bytes() * 3)
    gt = tmp_path / "joined.gt.txt"
    gt.write_text("".join(",".join(f"{v:g}" for v in b) + "\n" for b in scene.boxes) * 3)
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(joined), "-c", "s0",
                           "--gt", str(gt), "--no-video", "-o", str(out)],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    record = json.loads((out / "run.json").read_text())
    jumps = [w for w in record["warnings"] if "timestamps jumped back" in w]
    assert len(jumps) == 1
    assert "2 times" in jumps[0] and "first at frame 10" in jumps[0] and str(gt) in jumps[0]
    assert done.stderr.count("timestamps jumped back") == 1
    assert record["frames"] == 30
