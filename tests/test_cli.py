"""`vtrack run` end to end as a user runs it: real generated video in, real files out.

Every case runs the installed command (``python -m vtrack``) in a subprocess, so what is checked
is exactly what a user sees: exit codes, the one-line errors on stderr, and the files left behind.
"""

from __future__ import annotations

import csv
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import av
import numpy as np
import pytest
from conftest import START_BOUND_S, wait_for_stop_handlers

from vtrack.geometry import Box, iou
from vtrack.run import TRACK_COLUMNS
from vtrack.scenes import (
    make_scene,
    write_groundtruth,
    write_image_sequence,
    write_raw,
    write_video,
)

W, H, FPS = 320, 240, 30


def vtrack(*args: str, stdin: bytes | None = None, cwd: Path | None = None,
           timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], input=stdin,
                          capture_output=True, cwd=cwd, timeout=timeout, check=False)


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def decoded_frames(path: Path) -> tuple[int, int, int]:
    with av.open(str(path)) as container:
        frames = [f for f in container.decode(video=0)]
    return len(frames), frames[0].width, frames[0].height


def assert_one_line_error(result: subprocess.CompletedProcess, *needles: str) -> str:
    """Non-zero exit, no traceback, and the error line names every needle."""
    stderr = result.stderr.decode()
    assert result.returncode != 0, stderr
    assert "Traceback" not in stderr, stderr
    errors = [line for line in stderr.splitlines() if line.startswith(("vtrack: error", "Error"))]
    assert len(errors) == 1, stderr
    for needle in needles:
        assert needle in errors[0], (needle, errors[0])
    return errors[0]


@pytest.fixture(scope="module")
def occlusion_clip(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, object]:
    folder = tmp_path_factory.mktemp("occlusion")
    scene = make_scene("occlusion", seed=3, width=W, height=H, frames=120, fps=FPS)
    clip, gt = folder / "occ.mp4", folder / "occ.gt.txt"
    write_video(scene, clip)
    write_groundtruth(scene, gt)
    return clip, gt, scene


@pytest.fixture(scope="module")
def smooth_scene():
    return make_scene("smooth", seed=5, width=W, height=H, frames=60, fps=FPS)


def test_run_video_with_ground_truth(occlusion_clip, tmp_path: Path) -> None:
    clip, gt, scene = occlusion_clip
    out = tmp_path / "out"
    result = vtrack("run", str(clip), "-c", "s0", "--gt", str(gt), "--out", str(out))
    assert result.returncode == 0, result.stderr.decode()
    summary = result.stdout.decode().strip().splitlines()[-1]
    assert "120 frames" in summary and "mean overlap" in summary and str(out) in summary

    rows = read_csv(out / "track.csv")
    assert len(rows) == 120
    assert tuple(rows[0])[: len(TRACK_COLUMNS)] == TRACK_COLUMNS
    assert {"pred_cx", "pred_cy", "iterations", "bp_mass"} <= set(rows[0])
    assert [int(r["frame"]) for r in rows] == list(range(120))
    assert float(rows[1]["time_s"]) == pytest.approx(1 / FPS, abs=1e-3)

    # S0 stays on the target where it is visible, and says "occluded" on the hidden span.
    visible = [i for i, v in enumerate(scene.visibility) if v > 0.5]
    overlaps = [float(rows[i]["overlap"]) for i in visible]
    assert np.mean(overlaps) >= 0.7
    start, end = scene.events["occluded"]
    occluded = [i for i, r in enumerate(rows) if r["state"] == "occluded"]
    assert occluded, "no frame reported occluded"
    assert abs(occluded[0] - start) <= 3 and abs(occluded[-1] + 1 - end) <= 3

    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "complete" and record["frames"] == 120
    assert [s["name"] for s in record["config"]["stages"]] == [
        "hue", "backproject", "meanshift", "occlusion", "kalman"]
    assert record["input"]["width"] == W and record["input"]["height"] == H
    assert set(record["timing"]["stage_us_per_frame"]) == {
        "hue", "backproject", "meanshift", "occlusion", "kalman"}
    # the loop thread's CPU clock: some work per frame, never more than the loop's wall time
    loop_cpu_s = record["timing"]["loop_cpu_us_per_frame"] * 120 / 1e6
    assert 0 < loop_cpu_s <= record["timing"]["seconds"]
    assert record["metrics"]["auc"] == pytest.approx(
        np.mean([np.mean(np.array(overlaps_all(rows)) > t) for t in np.arange(21) / 20]),
        abs=1e-3)
    tracking = [float(r["overlap"]) == 0.0 for r in rows if r["state"] == "tracking"]
    assert record["metrics"]["tracking_miss"] == pytest.approx(np.mean(tracking))
    assert {"vtrack", "pyav", "opencv", "numpy"} <= set(record["versions"])

    assert decoded_frames(out / "annotated.mp4") == (120, W, H)
    assert not list(out.glob("*.part")) and not list(out.glob(".*tmp*"))


def overlaps_all(rows: list[dict[str, str]]) -> list[float]:
    return [float(r["overlap"]) for r in rows if r["overlap"] != ""]


def test_run_image_folder_and_set_override(smooth_scene, tmp_path: Path) -> None:
    folder = tmp_path / "seq"
    write_image_sequence(smooth_scene, folder)
    out = tmp_path / "out"
    gt_file = next(folder.glob("groundtruth*.txt"))
    result = vtrack("run", str(folder), "--gt", str(gt_file), "--gt-origin", "1", "--out", str(out),
                    "--no-video", "-c", "s0",
                    "--set", "meanshift.iterations=5")
    assert result.returncode == 0, result.stderr.decode()
    rows = read_csv(out / "track.csv")
    assert len(rows) == 60
    assert np.mean(overlaps_all(rows)) >= 0.7
    assert max(int(r["iterations"]) for r in rows) > 1
    record = json.loads((out / "run.json").read_text())
    meanshift = next(s for s in record["config"]["stages"] if s["name"] == "meanshift")
    assert meanshift["iterations"] == 5
    assert not (out / "annotated.mp4").exists()


def test_raw_stdin_end_to_end(smooth_scene, tmp_path: Path) -> None:
    raw = tmp_path / "frames.bgr"
    write_raw(smooth_scene, raw, "bgr24")
    box = smooth_scene.boxes[0]
    out = tmp_path / "out"
    result = vtrack("run", "-", "--raw", f"{W}x{H}", "--pix-fmt", "bgr24", "--fps", "30",
                    "--init", ",".join(f"{v:.2f}" for v in box), "--out", str(out),
                    stdin=raw.read_bytes())
    assert result.returncode == 0, result.stderr.decode()
    rows = read_csv(out / "track.csv")
    assert len(rows) == 60
    tracked = [Box(*(float(r[k]) for k in "xywh")) for r in rows]
    assert np.mean([iou(a, b) for a, b in zip(tracked, smooth_scene.boxes, strict=True)]) >= 0.7
    assert decoded_frames(out / "annotated.mp4") == (60, W, H)


def test_stages_lists_every_parameter() -> None:
    from vtrack.stages.base import all_stages

    result = vtrack("stages")
    assert result.returncode == 0
    text = result.stdout.decode()
    for name, cls in all_stages().items():
        assert f"{name}:" in text
        for param in cls.params:
            assert param.describe() in text


# --- bad input: one clear line, non-zero exit, valid outputs -----------------------------------


def test_missing_input(tmp_path: Path) -> None:
    result = vtrack("run", str(tmp_path / "nope.mp4"), "--init", "1,1,5,5", "--out",
                    str(tmp_path / "o"))
    assert_one_line_error(result, "nope.mp4")


def test_not_a_video(tmp_path: Path) -> None:
    fake = tmp_path / "notes.mp4"
    fake.write_text("this is not a video\n" * 50)
    result = vtrack("run", str(fake), "--init", "1,1,5,5", "--out", str(tmp_path / "o"))
    assert_one_line_error(result, "notes.mp4")


def test_truncated_video_tracks_what_decodes(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=90, fps=FPS)
    clip = tmp_path / "clip.mkv"
    write_video(scene, clip)
    data = clip.read_bytes()
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(data[: len(data) // 2])
    out = tmp_path / "out"
    result = vtrack("run", str(cut), "--init", ",".join(map(str, scene.boxes[0])), "--out",
                    str(out))
    line = assert_one_line_error(result, "cut.mkv", "frame")
    assert result.returncode == 1, line
    rows = read_csv(out / "track.csv")
    assert 0 < len(rows) < 90
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "partial" and record["frames"] == len(rows)
    assert decoded_frames(out / "annotated.mp4")[0] == len(rows)


def test_raw_stream_with_partial_frame(smooth_scene, tmp_path: Path) -> None:
    """Raw stdin is named ``-``, as it was given, in the error as in the summary line (and as
    a container on stdin is): the error said 'stdin: raw stream ended ...' where the summary
    line said '- (partial): 10 frames'. run.json's input.name, the output folder's name, is
    ``stdin`` (``vtrack-out/stdin/``), as for a container on stdin."""
    raw = tmp_path / "frames.bgr"
    write_raw(smooth_scene, raw, "bgr24")
    data = raw.read_bytes()[: W * H * 3 * 10 + 1234]
    out = tmp_path / "out"
    result = vtrack("run", "-", "--raw", f"{W}x{H}", "--fps", "30", "--init",
                    ",".join(map(str, smooth_scene.boxes[0])), "--out", str(out), stdin=data)
    said = "-: raw stream ended with 1234 stray bytes after 10 whole frames"
    assert assert_one_line_error(result, said).startswith(f"vtrack: error: {said}")
    assert result.stdout.decode().startswith("- (partial): 10 frames")
    assert len(read_csv(out / "track.csv")) == 10
    record = json.loads((out / "run.json").read_text())
    assert record["error"].startswith(said)
    assert (record["input"]["path"], record["input"]["name"]) == ("-", "stdin")
    empty = vtrack("run", "-", "--raw", f"{W}x{H}", "--init", "10,10,20,20", "--out",
                   str(tmp_path / "empty"), stdin=b"")
    assert assert_one_line_error(empty) == "vtrack: error: -: no raw frames (the input is empty)"


@pytest.mark.parametrize(("init", "needle"), [
    ("400,300,20,20", "outside"),
    ("10,10,0,5", "--init"),
    ("10,10,abc", "--init"),
    ("", "--init"),
])
def test_bad_init(occlusion_clip, tmp_path: Path, init: str, needle: str) -> None:
    clip, _, _ = occlusion_clip
    result = vtrack("run", str(clip), "--init", init, "--out", str(tmp_path / "o"))
    assert_one_line_error(result, needle)


def test_ground_truth_shorter_and_longer(occlusion_clip, tmp_path: Path) -> None:
    clip, gt, _ = occlusion_clip
    lines = gt.read_text().splitlines()
    short = tmp_path / "short.txt"
    short.write_text("\n".join(lines[:100]) + "\n")
    result = vtrack("run", str(clip), "--gt", str(short), "--out", str(tmp_path / "a"),
                    "--no-video")
    assert result.returncode == 0
    assert "warning" in result.stderr.decode() and "short.txt" in result.stderr.decode()
    rows = read_csv(tmp_path / "a" / "track.csv")
    assert rows[99]["overlap"] != "" and rows[100]["overlap"] == "" and len(rows) == 120
    long = tmp_path / "long.txt"
    long.write_text("\n".join(lines + lines[:10]) + "\n")
    result = vtrack("run", str(clip), "--gt", str(long), "--out", str(tmp_path / "b"),
                    "--no-video")
    assert result.returncode == 0 and "long.txt" in result.stderr.decode()


def test_ground_truth_that_marks_the_target_absent_throughout_is_a_warning(
        occlusion_clip, tmp_path: Path) -> None:
    """Probe 52b: --gt with every box 0,0,0,0 (the target out of view throughout: a file for
    another clip, or a mistaken export) scored nothing without a word: the summary line just
    had no overlap, AUC or precision, where MOT ground truth whose rows are all ignored is a
    warning. Now it is one too, also in run.json; a file with some boxes is none."""
    clip, gt, _ = occlusion_clip
    lines = gt.read_text().splitlines()
    for name, text in (("absent", "0,0,0,0\n" * len(lines)),
                       ("half", "NaN,NaN,NaN,NaN\n" * 60 + "\n".join(lines[60:]) + "\n")):
        path = tmp_path / f"{name}.txt"
        path.write_text(text)
        out = tmp_path / name
        result = vtrack("run", str(clip), "--gt", str(path), "--init", lines[0], "-c", "s0",
                        "--no-video", "--out", str(out))
        assert result.returncode == 0, result.stderr
        record = json.loads((out / "run.json").read_text())
        stderr = result.stderr.decode()
        if name == "half":
            assert record["metrics"]["frames_evaluated"] == len(lines) - 60
            assert record["warnings"] == [] and "warning" not in stderr, stderr
            continue
        note = (f"{path}: the ground truth marks the target absent (NaN, or w or h <= 0) in all "
                f"{len(lines)} frames of the run it has boxes for: no frame is scored "
                "(frames_evaluated 0; mean_overlap, auc, precision20 null)")
        assert record["metrics"]["frames_evaluated"] == 0 and record["warnings"] == [note]
        assert stderr == f"vtrack: warning: {note}\n"


def test_bad_ground_truth_file(occlusion_clip, tmp_path: Path) -> None:
    clip, _, _ = occlusion_clip
    bad = tmp_path / "bad.txt"
    bad.write_text("1,2,3,4\n5,6,seven,8\n")
    result = vtrack("run", str(clip), "--gt", str(bad), "--out", str(tmp_path / "o"))
    assert_one_line_error(result, "bad.txt", "2")


@pytest.mark.parametrize(("body", "needles"), [
    ('[[stage]]\nname = "huee"\n', ("cfg.toml", "huee")),
    ('[[stage]]\nname = "hue"\nbinz = 3\n', ("cfg.toml", "hue", "binz")),
    ('[[stage]]\nname = "meanshift"\niterations = "many"\n',
     ("cfg.toml", "meanshift", "iterations")),
    ('[[stage]\nname = "hue"\n', ("cfg.toml", "TOML")),
])
def test_bad_config(occlusion_clip, tmp_path: Path, body: str, needles: tuple[str, ...]) -> None:
    clip, gt, _ = occlusion_clip
    config = tmp_path / "cfg.toml"
    config.write_text(body)
    result = vtrack("run", str(clip), "--gt", str(gt), "--config", str(config), "--out",
                    str(tmp_path / "o"))
    assert_one_line_error(result, *needles)


def test_bad_set_override(occlusion_clip, tmp_path: Path) -> None:
    clip, gt, _ = occlusion_clip
    result = vtrack("run", str(clip), "--gt", str(gt), "--set", "kalman.q=lots", "--out",
                    str(tmp_path / "o"))
    assert_one_line_error(result, "kalman", "q")


def test_unwritable_output(occlusion_clip, tmp_path: Path) -> None:
    clip, gt, _ = occlusion_clip
    blocker = tmp_path / "file"
    blocker.write_text("x")
    result = vtrack("run", str(clip), "--gt", str(gt), "--out", str(blocker / "out"))
    assert_one_line_error(result, str(blocker / "out"))


def test_ctrl_c_leaves_valid_partial_outputs(smooth_scene, tmp_path: Path) -> None:
    frames = [f for f in smooth_scene.frames()]
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-m", "vtrack", "run", "-", "--raw", f"{W}x{H}", "--fps", "30",
         "--init", ",".join(map(str, smooth_scene.boxes[0])), "--out", str(out)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdin is not None
    for frame in frames[:30]:
        process.stdin.write(frame.tobytes())
    process.stdin.flush()
    wait_for_stop_handlers(process)  # its start-up over, however loaded the machine
    deadline = time.monotonic() + START_BOUND_S
    while not ((partial := list(out.glob("*track*.csv")))
               and len(partial[0].read_text().splitlines()) >= 20):
        assert process.poll() is None, "vtrack ended before it wrote 20 rows"
        assert time.monotonic() < deadline, "vtrack wrote no 20 rows within the time"
        time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr.decode()
    assert "Traceback" not in stderr.decode()
    rows = read_csv(out / "track.csv")
    assert 20 <= len(rows) <= 30
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "interrupted" and record["frames"] == len(rows)
    assert decoded_frames(out / "annotated.mp4")[0] == len(rows)



def test_odd_sized_image_folder_gets_an_even_cropped_video(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=2, width=161, height=121, frames=20, fps=FPS)
    folder = tmp_path / "odd"
    write_image_sequence(scene, folder)
    out = tmp_path / "out"
    result = vtrack("run", str(folder), "--gt", str(folder / "groundtruth_rect.txt"),
                    "--gt-origin", "1", "--out", str(out))
    assert result.returncode == 0, result.stderr.decode()
    assert len(read_csv(out / "track.csv")) == 20
    assert decoded_frames(out / "annotated.mp4") == (20, 160, 120)


@pytest.mark.parametrize("option", [
    ["--follow", "nan"], ["--follow", "inf"], ["--follow", "1e9"], ["--timeout", "nan"],
    ["--stats-period", "inf"], ["--seed", "-1"], ["--seed", "4294967296"],
])
def test_values_outside_an_options_range_are_refused_before_anything_runs(
        tmp_path: Path, option: list[str]) -> None:
    """`--follow nan` waited forever (click's ranges let nan through), `--seed -1` failed after
    tracking started with a NumPy traceback."""
    clip = tmp_path / "c.mp4"
    write_video(make_scene("smooth", 0, 160, 120, 10, FPS), clip, preset="ultrafast")
    out = tmp_path / "out"
    result = vtrack("run", str(clip), "--init", "10,10,20,20", "-o", str(out), *option)
    error = result.stderr.decode()
    assert result.returncode == 2, error
    assert f"Invalid value for '{option[0]}'" in error
    assert "Traceback" not in error and not out.exists()


@pytest.mark.parametrize(("args", "problem"), [
    (["--frames", "5"], "--frames 5: must be from 10 (what scenario 'smooth' needs) to 108000"),
    (["--size", "10x10"], "--size 10x10: must be from 64x48 to 7680x4320"),
    (["--fps", "0"], "--fps 0: must be from 0.01 to 10000"),
])
def test_vtrack_scene_names_the_option_given_and_its_range(
        tmp_path: Path, args: list[str], problem: str) -> None:
    """The errors said "scene fps 0", "scene size 10x10", "scenario 'smooth' needs at least 10
    frames": not the option the user gave."""
    result = vtrack("scene", "smooth", "c.mp4", *args, cwd=tmp_path)
    error = result.stderr.decode()
    assert result.returncode == 2, error
    assert error == f"vtrack: error: {problem}\n"
    assert not (tmp_path / "c.mp4").exists()


@pytest.mark.parametrize(("args", "problem"), [
    (["x.txt"], "no video container format for this file name"),
    (["noext"], "no video container format for this file name"),
    (["c.mp4", "--frames", "99999999999"], "--frames 99999999999: at most 108000"),
    # the name first, as for the default pixel format (was: "libx264 does not take ... rgb24")
    (["t.out", "--pix-fmt", "rgb24"], "t.out: no video container format for this file name"),
])
def test_vtrack_scene_refuses_what_it_cannot_write_in_one_line(
        tmp_path: Path, args: list[str], problem: str) -> None:
    result = vtrack("scene", "smooth", *args, "--size", "160x120", cwd=tmp_path)
    error = result.stderr.decode()
    assert result.returncode == 2, error
    assert problem in error and error.count("\n") == 1
    assert not list(tmp_path.iterdir())


def test_vtrack_scene_images_over_a_file_says_it_is_a_file(tmp_path: Path) -> None:
    """`--format images` with OUT an existing file said "OUT/img: cannot write (File
    exists)"."""
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "0001.jpg").write_bytes(b"a picture")
    result = vtrack("scene", "smooth", "a/0001.jpg", "--format", "images", "--size", "160x120",
                    cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert result.stderr.decode() == ("vtrack: error: a/0001.jpg: is a file; --format images "
                                      "writes a folder there (img/0001.jpg ... and its ground "
                                      "truth): name a folder\n")
    assert [p.name for p in tmp_path.rglob("*")] == ["a", "0001.jpg"]
    assert (tmp_path / "a" / "0001.jpg").read_bytes() == b"a picture"


def test_a_start_frame_that_does_not_decode_is_refused(tmp_path: Path) -> None:
    """The next frame was tracked from the start frame's ground-truth box, and the run said
    `complete` (mean overlap 0.02)."""
    sequence = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 30, FPS), sequence)
    (sequence / "img" / "0011.jpg").write_text("not a picture")  # frame 10
    gt = str(sequence / "groundtruth_rect.txt")
    refused = vtrack("run", str(sequence), "--gt", gt, "--start", "10", "--no-video", "-o",
                     str(tmp_path / "a"))
    error = refused.stderr.decode()
    assert refused.returncode == 2, error
    assert "--start 10: frame 10 of" in error and "could not be decoded" in error
    assert "Traceback" not in error and not (tmp_path / "a").exists()
    after = vtrack("run", str(sequence), "--gt", gt, "--start", "11", "--no-video", "-o",
                   str(tmp_path / "b"))
    assert after.returncode == 0, after.stderr.decode()
    assert read_csv(tmp_path / "b" / "track.csv")[0]["frame"] == "11"
    picture = vtrack("frame", str(sequence), "--at", "10", "-o", str(tmp_path / "f.png"))
    error = picture.stderr.decode()  # was: "has no frame 10 (frames 0..29)"
    assert picture.returncode != 0 and "Traceback" not in error
    assert "frame 10 could not be decoded (damaged); the next frame it has is frame 11" in error


def test_paths_holding_bytes_that_are_not_utf8_work(tmp_path: Path) -> None:
    """An output folder named with a byte that is no UTF-8 (a Latin-1 file system's `\\xff`)
    failed with a UnicodeEncodeError traceback, leaving a folder with only its lock."""
    odd = os.fsdecode(b"\xff")
    clip = tmp_path / f"in{odd}.mp4"
    scene = make_scene("smooth", 0, 160, 120, 10, FPS)
    write_video(scene, clip, preset="ultrafast")
    out = tmp_path / f"out{odd}"
    done = vtrack("run", str(clip), "--init", ",".join(f"{v:g}" for v in scene.boxes[0]),
                  "-o", str(out))
    assert done.returncode == 0, done.stderr.decode(errors="replace")
    assert len(read_csv(out / "track.csv")) == 10
    assert json.loads((out / "run.json").read_text())["status"] == "complete"


@pytest.mark.parametrize(("options", "flag"), [
    (("--pix-fmt", "gray"), "--pix-fmt is the pixel format of raw input"),
    (("--raw", f"{W}x{H}", "-f", "mpegts"), "--format is for inputs FFmpeg reads"),
    (("--raw", f"{W}x{H}", "--input-option", "probesize=32"), "--input-option is for inputs"),
])
def test_an_option_the_input_would_ignore_is_refused(occlusion_clip, tmp_path: Path,
                                                     options: tuple[str, ...],
                                                     flag: str) -> None:
    """`--pix-fmt gray` on an MP4, `-f mpegts` with --raw: accepted and ignored (exit 0)."""
    clip, _, _ = occlusion_clip
    assert_one_line_error(vtrack("run", str(clip), *options, "--init", "10,10,20,20",
                                 "--no-video", "--out", str(tmp_path / "o")), flag)


def test_vtrack_batch_says_a_missing_folder_is_missing(tmp_path: Path) -> None:
    """`vtrack batch footag/` (a typo) said 'footag: not a folder', as for a file, where
    `vtrack run` says 'no such file' and `vtrack report` 'no such file or folder'. `vtrack
    batch clip.mp4` said only 'clip.mp4: not a folder': it now points at `vtrack run`, with a
    name starting with '-' as ./-x.mp4 (`vtrack run -x.mp4` reads an option)."""
    for name in ("clip.mp4", "my clip.MOV", "notes.txt", "-x.mp4"):
        (tmp_path / name).write_bytes(b"")
    (tmp_path / "gone").symlink_to(tmp_path / "nowhere")
    one_input = "not a folder: a batch tracks the inputs in a folder; vtrack run"
    for name, problem in (("footag", "no such folder"), ("gone", "no such folder (broken link)"),
                          ("clip.mp4", f"{one_input} clip.mp4 tracks one input"),
                          ("my clip.MOV", f"{one_input} 'my clip.MOV' tracks one input"),
                          ("notes.txt", "not a folder"),
                          ("./-x.mp4", f"{one_input} ./-x.mp4 tracks one input")):
        line = assert_one_line_error(vtrack("batch", name, "-o", "res", cwd=tmp_path))
        assert line == f"vtrack: error: {name.removeprefix('./')}: {problem}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["-x.mp4", "clip.mp4", "gone",
                                                         "my clip.MOV", "notes.txt"]


def test_an_error_naming_a_file_with_a_newline_is_one_line(occlusion_clip,
                                                           tmp_path: Path) -> None:
    """`vtrack run $'a\\nb.mp4'` without a box said '... write x,y,w,h into a' and, on the next
    line, 'b.init.txt (vtrack select INPUT picks it)': the file's newline broke the one error
    line; it is now written '\\n', as the summary line and vtrack batch's labels write it."""
    clip, _, _ = occlusion_clip
    odd = tmp_path / "a\nb.mp4"
    odd.write_bytes(clip.read_bytes())
    result = vtrack("run", odd.name, "-c", "s0", "-o", "out", cwd=tmp_path)
    line = assert_one_line_error(result, "this tracker needs an initial box")
    assert result.stderr.decode().count("\n") == 1
    assert "into a\\nb.init.txt (vtrack select 'a\\nb.mp4' picks it)" in line


def test_a_run_without_a_box_names_where_its_sidecar_goes(occlusion_clip,
                                                          tmp_path: Path) -> None:
    """`vtrack run footage/occ.mp4 -c s0` (no box) said 'write x,y,w,h into occ.init.txt
    (vtrack select INPUT picks it)': a file written as told, in the folder the run was started
    in, was never read (the sidecar is footage/occ.init.txt). The line names the sidecar's
    path and the select command of this input; a box written there is the run's first box."""
    clip, gt, _ = occlusion_clip
    footage = tmp_path / "my footage"
    footage.mkdir()
    (footage / clip.name).write_bytes(clip.read_bytes())
    given = f"my footage/{clip.name}"
    line = assert_one_line_error(vtrack("run", given, "-c", "s0", "-o", "out", cwd=tmp_path))
    assert line.endswith("or write x,y,w,h into my footage/occ.init.txt "
                         "(vtrack select 'my footage/occ.mp4' picks it)"), line
    first = ",".join(gt.read_text().splitlines()[0].split(",")[:4])
    (tmp_path / "my footage/occ.init.txt").write_text(first + "\n")
    done = vtrack("run", given, "-c", "s0", "--no-video", "-o", "out", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert json.loads((tmp_path / "out/run.json").read_text())["init_from"].endswith(
        "occ.init.txt")


def test_a_raw_run_without_a_box_names_no_sidecar_and_no_select(tmp_path: Path) -> None:
    """`vtrack run clip.raw --raw 64x48 -c s0` (no box) said 'write x,y,w,h into clip.init.txt
    (vtrack select clip.raw picks it)': a run of raw frames reads no sidecar, and vtrack select
    refuses raw input. The line names --init and --gt only, and why."""
    scene = make_scene("smooth", seed=2, width=64, height=48, frames=10, fps=FPS)
    write_raw(scene, tmp_path / "clip.raw", "bgr24")
    line = assert_one_line_error(vtrack("run", "clip.raw", "--raw", "64x48", "-c", "s0",
                                        "-o", "out", cwd=tmp_path))
    assert line == ("vtrack: error: s0: this tracker needs an initial box: give --init x,y,w,h "
                    "(or --gt FILE); raw frames have no sidecar file"), line
    assert not (tmp_path / "out").exists()


def test_run_of_a_sequence_of_two_targets_names_their_files_and_a_gt_for_each(
        tmp_path: Path) -> None:
    """`vtrack run Jogging` (OTB: img/, groundtruth_rect.1.txt and groundtruth_rect.2.txt, no
    --gt or --init) said 'this tracker needs an initial box: give --gt FILE, --init x,y,w,h or
    write x,y,w,h into init.txt', as if the sequence had no ground truth. It names the two
    files and the --gt that tracks each now (given the sequence or its img/, from the start or
    --start 3); the --gt it names runs."""
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=12, fps=FPS)
    sequence = write_image_sequence(scene, tmp_path / "Jogging")
    (sequence / "groundtruth_rect.txt").rename(sequence / "groundtruth_rect.1.txt")
    (sequence / "groundtruth_rect.2.txt").write_bytes(
        (sequence / "groundtruth_rect.1.txt").read_bytes())
    for given, start in (("Jogging", []), ("Jogging/img", ["--start", "3"])):
        line = assert_one_line_error(vtrack("run", given, "-c", "s0", "-o", "out", *start,
                                            cwd=tmp_path))
        needs = "the target's box in frame 3" if start else "an initial box"
        assert line == (
            f"vtrack: error: s0: this tracker needs {needs}, and Jogging has 2 targets' ground "
            "truth (groundtruth_rect.1.txt, groundtruth_rect.2.txt), none of which a run takes "
            "by itself: give one per run (--gt Jogging/groundtruth_rect.1.txt, --gt "
            "Jogging/groundtruth_rect.2.txt), or --init x,y,w,h")
    _refused_then_runs_with_gt(tmp_path, "Jogging", "Jogging/groundtruth_rect.2.txt")


def _refused_then_runs_with_gt(tmp_path: Path, given: str, gt: str) -> None:
    """The refused run made no output folder, and the --gt its line names tracks ``given``."""
    assert not (tmp_path / "out").exists()
    done = vtrack("run", given, "-c", "s0", "--no-video", "-o", "out", "--gt", gt, cwd=tmp_path)
    assert done.returncode == 0, done.stderr


def test_run_of_a_sequences_img_without_a_box_names_the_sequences_ground_truth(
        tmp_path: Path) -> None:
    """`vtrack run seq/img -c s0 -o out` (an OTB folder: img/ and groundtruth_rect.txt, no --gt
    or --init) said 'give --gt FILE' though seq/groundtruth_rect.txt exists (given `seq`, it
    named the file): the hint looked inside img/ only. It names the sequence's file now, and
    the --gt it names runs."""
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=12, fps=FPS)
    write_image_sequence(scene, tmp_path / "seq")
    line = assert_one_line_error(vtrack("run", "seq/img", "-c", "s0", "-o", "out",
                                        cwd=tmp_path))
    assert line == (
        "vtrack: error: s0: this tracker needs an initial box: give --gt "
        "seq/groundtruth_rect.txt (its ground truth, which vtrack batch takes by itself), "
        "--init x,y,w,h or write x,y,w,h into seq/init.txt (vtrack select seq/img picks it)")
    _refused_then_runs_with_gt(tmp_path, "seq/img", "seq/groundtruth_rect.txt")


def test_run_of_a_sequence_of_targets_names_its_other_ground_truth_and_quotes_the_gt(
        tmp_path: Path) -> None:
    """An OTB folder holding groundtruth_rect.txt beside groundtruth_rect.1.txt and .2.txt
    named only the numbered files (its groundtruth_rect.txt, which the message named before
    the targets were, was left out); one holding groundtruth_rect.1.txt alone said '1 targets'
    ground truth ..., none of which ...: give one per run (...)'; and a folder named with a
    space gave '--gt my seq/groundtruth_rect.1.txt', which breaks when pasted. Now every file
    is named, one file is given as one --gt, and the paths are quoted for a shell."""
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=12, fps=FPS)
    both = write_image_sequence(scene, tmp_path / "J3")
    for number in (1, 2):
        (both / f"groundtruth_rect.{number}.txt").write_bytes(
            (both / "groundtruth_rect.txt").read_bytes())
    line = assert_one_line_error(vtrack("run", "J3", "-c", "s0", "-o", "out", cwd=tmp_path))
    assert line == (
        "vtrack: error: s0: this tracker needs an initial box, and J3 has groundtruth_rect.txt "
        "and 2 targets' ground truth (groundtruth_rect.1.txt, groundtruth_rect.2.txt), none of "
        "which a run takes by itself: give one per run (--gt J3/groundtruth_rect.txt, --gt "
        "J3/groundtruth_rect.1.txt, --gt J3/groundtruth_rect.2.txt), or --init x,y,w,h")
    one = write_image_sequence(scene, tmp_path / "my seq")
    (one / "groundtruth_rect.txt").rename(one / "groundtruth_rect.1.txt")
    line = assert_one_line_error(vtrack("run", "my seq/img", "-c", "s0", "-o", "out",
                                        "--start", "2", cwd=tmp_path))
    assert line == (
        "vtrack: error: s0: this tracker needs the target's box in frame 2, and my seq has 1 "
        "target's ground truth (groundtruth_rect.1.txt), which a run does not take by itself: "
        "give --gt 'my seq/groundtruth_rect.1.txt' or --init x,y,w,h")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command, option, limits", [
    ("run", "--fps", ("0.01", "10000")),
    ("run", "--start", ("1000000000000", "31622400s")),
    ("run", "--frames", ("1000000000000", "31622400s")),
    ("scene", "--frames", ("108000",)),
    ("scene", "--size", ("64x48", "7680x4320")),
    ("scene", "--fps", ("0.01", "10000")),
    ("run", "--raw", ("1x1", "16384x16384")),
    ("vectors", "--frames", ("1 to 300",)),
])
def test_an_options_help_says_its_range(command: str, option: str, limits: tuple[str, ...]
                                        ) -> None:
    """Every value a user gives has a declared range, and --help says it (run's --fps,
    --start, --frames and scene's --frames, --size, --fps said none, though each is refused
    outside it; so did run's --raw and vectors' --frames, which said only its upper end)."""
    help_text = vtrack(command, "--help").stdout.decode()
    row = re.search(rf"^ +(-\w, )?{option} .*?(?=^ +-)", help_text, re.M | re.S)
    assert row is not None, help_text
    entry = " ".join(row.group().split())
    for limit in limits:
        assert limit in entry, (option, entry)


def test_every_command_prints_its_help_as_a_result() -> None:
    """Each command's ``--help`` is printed by vtrack's own callback (so a full standard
    output is one line, not click's traceback) because each command, and each group under a
    command, is a ``HelpPrinted``: the group no longer patches the commands it loads, so a
    plain ``click.Command`` added as a module's ``command`` would escape."""
    import click

    from vtrack.cli import main
    from vtrack.cli._options import HelpPrinted, print_help

    def commands(group: click.Group, ctx: click.Context) -> list[click.Command]:
        found = []
        for name in group.list_commands(ctx):
            command = group.get_command(ctx, name)
            assert command is not None, name
            found.append(command)
            if isinstance(command, click.Group):
                found += commands(command, click.Context(command, parent=ctx))
        return found

    ctx = click.Context(main)
    every = commands(main, ctx)
    assert {c.name for c in every} >= {"run", "batch", "report", "scene", "stages"}
    for command in [main, *every]:
        assert isinstance(command, HelpPrinted), command.name
        option = command.get_help_option(click.Context(command, parent=ctx))
        assert option is not None and option.callback is print_help, command.name


@pytest.mark.parametrize(("command", "option"), [("frame", "--at"), ("run", "--start")])
def test_the_time_forms_a_help_names_are_the_ones_taken(command: str, option: str) -> None:
    """frame --at and run --start said a time works "like ffmpeg -ss", yet 00:00:00.5 and a
    bare 2.5 (both ffmpeg -ss forms) are refused: the help names the forms taken and the ones
    refused, and the parser agrees with each."""
    import click

    from vtrack.cli._options import StartPoint

    help_text = vtrack(command, "--help").stdout.decode()
    row = re.search(rf"^ +(-\w, )?{option} .*?(?=^ +-)", help_text, re.M | re.S)
    assert row is not None, help_text
    entry = " ".join(row.group().split())
    forms = re.search(r"time T in seconds ending in s \(([^;]+); not (.+?), which", entry)
    assert forms is not None, entry
    taken, refused = forms.group(1).split(", "), forms.group(2).split(" nor ")
    assert any(":" in form for form in refused) and any("." in f for f in refused), refused
    for form in taken:
        assert StartPoint().convert(form, None, None)[1] is not None, form
    for form in refused:
        with pytest.raises(click.BadParameter):
            StartPoint().convert(form, None, None)
