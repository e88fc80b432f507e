"""Values at and beyond a limit, as a hostile probe gave them: a det.txt with absurd or
off-frame boxes, a number a hair past a bound (the message must not round it onto the bound),
a pixel format libx264 does not take, a config given as a pipe or a device."""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line

from vtrack.cli import main
from vtrack.errors import ConfigError
from vtrack.frame import GrayFrame
from vtrack.geometry import Box
from vtrack.scenes import write_video
from vtrack.stages.base import Stage, TrackContext, TrackStatus
from vtrack.stages.detect import Detection
from vtrack.stages.kalman_bytetrack import ByteTracks
from vtrack.stages.kalman_tracks import KalmanTracks
from vtrack.stages.mht import MultipleHypothesis
from vtrack.stages.mot_detections import MotDetections

if TYPE_CHECKING:
    from conftest import ClipFactory


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args))


def _detections(clip, tmp_path: Path, name: str, shift: float = 0.0,
                at: float | None = None) -> Path:
    """The clip's MOTChallenge ground truth as a det.txt (columns 1-6, then ``1,-1,-1,-1``),
    every box moved by ``shift`` pixels or put at ``(at, at)``."""
    path = tmp_path / name
    lines = []
    for row in clip.mot.read_text().splitlines():
        frame, ident, x, y, w, h = row.split(",")[:6]
        x, y = (str(at), str(at)) if at is not None else (str(float(x) + shift),
                                                         str(float(y) + shift))
        lines.append(",".join([frame, ident, x, y, w, h, "1", "-1", "-1", "-1"]))
    path.write_text("\n".join(lines) + "\n")
    return path


def _config(tmp_path: Path, det: Path, tracker: str) -> Path:
    path = tmp_path / f"{det.stem}_{tracker}.toml"
    path.write_text(f'name = "h"\n[[stage]]\nname = "mot_detections"\npath = "{det}"\n'
                    f'[[stage]]\nname = "{tracker}"\n')
    return path


@pytest.mark.parametrize("tracker", ["byte_tracks", "kalman_tracks"])
def test_a_det_txt_with_a_coordinate_beyond_the_limit_is_refused(
        tmp_path: Path, clip_factory: ClipFactory, tracker: str) -> None:
    clip = clip_factory("multi", frames=60)
    det = _detections(clip, tmp_path, "det_huge.txt", at=1e300)
    out = tmp_path / "out"
    line = one_error_line(vtrack("run", str(clip.path), "-c", str(_config(tmp_path, det, tracker)),
                            "--no-video", "-o", str(out), "-y"))
    assert f"{det} line 1: coordinate beyond +-1e+06 pixels" in line
    assert not out.exists()


@pytest.mark.parametrize("tracker", ["byte_tracks", "kalman_tracks"])
def test_detections_wholly_outside_the_frame_are_dropped_with_a_warning(
        tmp_path: Path, clip_factory: ClipFactory, tracker: str) -> None:
    clip = clip_factory("multi", frames=60)
    det = _detections(clip, tmp_path, "det_off.txt", shift=5000)
    rows = len(clip.mot.read_text().splitlines())
    out = tmp_path / "out"
    result = vtrack("run", str(clip.path), "-c", str(_config(tmp_path, det, tracker)),
                    "--no-video", "-o", str(out), "-y")
    assert result.exit_code == 0, result.output
    assert (f"vtrack: warning: {det}: {rows} detections lay wholly outside the 320x240 frame "
            "and were ignored") in result.stderr
    with open(out / "tracks.csv", newline="") as handle:
        tracks = list(csv.DictReader(handle))
    assert not [row for row in tracks
                if Box(*(float(row[k]) for k in "xywh")).outside(320, 240)]


def test_a_det_txt_crowding_a_frame_gives_its_highest_scoring_detections_with_a_warning(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    # the docs bound a frame's detections (blobs.max_blobs <= 1000); a det.txt listing 5,000 in
    # a frame made byte_tracks take 11 s and 1.6 GB a frame: now its highest-scoring are kept
    clip = clip_factory("multi", frames=60)
    det = tmp_path / "det_crowded.txt"
    det.write_text("".join(f"{frame},-1,{10 + 7 * (n % 40)},{10 + 7 * (n // 40)},5,5,{n},-1,-1,-1\n"
                           for frame in (1, 2) for n in range(1, 9)))
    stage = MotDetections(path=str(det), max_detections=5)
    ctx = TrackContext(frame=GrayFrame(0, 0.0, np.zeros((240, 320), np.uint8)), seed=0)
    stage.start(ctx)
    assert [d.score for d in ctx.detections] == [8, 7, 6, 5, 4]
    out = tmp_path / "out"
    result = vtrack("run", str(clip.path), "-c", str(_config(tmp_path, det, "kalman_tracks")),
                    "-s", "mot_detections.max_detections=5", "--no-video", "-o", str(out))
    assert result.exit_code == 0, result.output
    assert (f"vtrack: warning: {det}: 2 frames listed more than 5 detections; each kept its 5 "
            "highest-scoring (mot_detections.max_detections)") in result.stderr


@pytest.mark.parametrize("stage", [KalmanTracks(confirm=1), ByteTracks(confirm=1)],
                         ids=["kalman_tracks", "byte_tracks"])
def test_no_track_is_reported_wholly_outside_the_frame(stage: Stage) -> None:
    # detections given straight to the stage (not through mot_detections, which drops them)
    for index in range(5):
        ctx = TrackContext(frame=GrayFrame(index, 0.0, np.zeros((240, 320), np.uint8)), seed=0)
        ctx.detections = [
            Detection(Box(5000.0 + 3 * index, 40.0, 10, 10), 5005.0, 45.0, 100.0, score=1.0),
            Detection(Box(100.0 + 3 * index, 40.0, 10, 10), 105.0, 45.0, 100.0, score=1.0)]
        (stage.start if index == 0 else stage.step)(ctx)
        assert not [t for t in ctx.tracks if t.box.outside(320, 240)]
    assert [t.state for t in ctx.tracks] == [TrackStatus.CONFIRMED]


def test_an_mht_track_coasting_out_of_the_frame_is_not_reported() -> None:
    # S3's defaults: a blob moving right is measured until it reaches the frame's edge, then
    # its confirmed track coasts on the predictor past the edge (up to max_coast frames)
    stage = MultipleHypothesis()
    coasting = 0
    for index in range(30):
        ctx = TrackContext(frame=GrayFrame(index, 0.0, np.zeros((120, 160), np.uint8)), seed=0)
        x = 100.0 + 6 * index
        ctx.detections = [Detection(Box(x, 40.0, 10, 10), x + 5, 45.0, 100.0)] if x + 10 <= 160 \
            else []
        (stage.start if index == 0 else stage.step)(ctx)
        assert not [t for t in ctx.tracks if t.box.outside(160, 120)], index
        coasting += sum(t.state is TrackStatus.COASTING for t in ctx.tracks)
    assert coasting  # it was reported while its box still overlapped the frame


# --- a value a hair past a limit is not shown as the limit --------------------------------------


@pytest.mark.parametrize(("option", "value", "shown"), [
    ("--set", "particle.spread=10.000000000000001",
     "must be in the range 0 to 10, got 10.000000000000002"),
    ("--init", "0,0,320.0001,240", "the box 0,0,320.0001,240 is larger than the 320x240 frame"),
    ("--init", "10,10,3.9999,40", "the box 10,10,3.9999,40 is smaller than 4x4 pixels"),
    ("--init", "10,10,1e-300,40", "the box 10,10,1e-300,40 is smaller than 4x4 pixels"),
    # ordinary values read as before
    ("--set", "particle.spread=11", "must be in the range 0 to 10, got 11"),
    ("--init", "10,10,3,40", "the box 10,10,3,40 is smaller than 4x4 pixels"),
])
def test_a_refused_value_is_shown_as_given_not_rounded_onto_the_limit(
        tmp_path: Path, clip_factory: ClipFactory, option: str, value: str, shown: str) -> None:
    clip = clip_factory("smooth", frames=10)
    line = one_error_line(vtrack("run", str(clip.path), "-c", "s1", option, value, "--no-video",
                            "-o", str(tmp_path / "out"), "-y"))
    assert shown in line


def test_a_scene_frame_rate_past_the_limit_is_shown_as_given(tmp_path: Path) -> None:
    line = one_error_line(vtrack("scene", "smooth", str(tmp_path / "a.mp4"), "--frames", "10",
                            "--fps", "10000.00001"))
    assert "--fps 10000.00001: must be from 0.01 to 10000" in line


# --- a pixel format libx264 cannot encode is refused before anything is written -----------------


@pytest.mark.parametrize(("size", "pix_fmt", "problem"), [
    ("320x240", "rgb24", "libx264 does not take pixel format rgb24; it takes yuv420p"),
    ("320x240", "bgr24", "libx264 does not take pixel format bgr24"),
    ("320x240", "gbrp", "libx264 does not take pixel format gbrp"),
    # (`--pix-fmt gray` wrote a yuv420p clip, exit 0: x264 takes grey frames, writes colour)
    ("320x240", "gray", "libx264 does not take pixel format gray (it writes grey as yuv420p); "
                        "it takes yuv420p"),
    # (gray10le was said to be written as yuv420p: x264 writes it as yuv420p10le, High 10)
    ("320x240", "gray10le", "libx264 does not take pixel format gray10le (it writes grey as "
                            "yuv420p10le); it takes yuv420p"),
    ("641x479", "yuv422p", "pixel format yuv422p needs an even width, the scene is 641x479"),
    ("641x479", "nv12", "pixel format nv12 needs an even width and height, the scene is 641x479"),
    ("320x239", "nv12", "pixel format nv12 needs an even width and height"),
])
def test_a_pixel_format_the_encoder_cannot_write_is_one_line(
        tmp_path: Path, size: str, pix_fmt: str, problem: str) -> None:
    out = tmp_path / "a.mp4"
    line = one_error_line(vtrack("scene", "smooth", str(out), "--frames", "10", "--size", size,
                            "--pix-fmt", pix_fmt))
    assert f"{out}: {problem}" in line
    assert list(tmp_path.iterdir()) == []


def test_an_encoder_without_grey_is_not_said_to_write_it_as_colour(
        tmp_path: Path, scene_factory) -> None:
    """mpeg4 takes only yuv420p: its refusal of gray said "(it writes grey as yuv420p)", as
    only libx264 (which takes grey frames and writes colour) does."""
    out = tmp_path / "a.mp4"
    with pytest.raises(ConfigError) as info:
        write_video(scene_factory("smooth", frames=10), out, codec="mpeg4", pix_fmt="gray")
    assert str(info.value) == f"{out}: mpeg4 does not take pixel format gray; it takes yuv420p"
    assert list(tmp_path.iterdir()) == []


def test_h264_is_checked_and_written_as_libx264_is(tmp_path: Path, scene_factory) -> None:
    """``codec="h264"`` opens libx264, but the checks were keyed on the name ``libx264``: a
    gray clip was written as yuv420p without a word, a preset x264 lacks failed as "cannot
    write (Invalid argument)", and the bytes differed from libx264's (no
    DETERMINISTIC_X264)."""
    scene = scene_factory("smooth", width=64, height=48, frames=10)
    out = tmp_path / "a.mp4"
    with pytest.raises(ConfigError) as info:
        write_video(scene, out, codec="h264", pix_fmt="gray")
    assert str(info.value).startswith(
        f"{out}: h264 does not take pixel format gray (it writes grey as yuv420p); it takes "
        "yuv420p, ")
    with pytest.raises(ConfigError, match=r"preset 'bogus': choose one of ultrafast, "):
        write_video(scene, out, codec="h264", preset="bogus")
    assert list(tmp_path.iterdir()) == []
    named = write_video(scene, tmp_path / "h264.mp4", codec="h264", preset="veryfast")
    default = write_video(scene, tmp_path / "libx264.mp4", preset="veryfast")
    assert named.read_bytes() == default.read_bytes()


@pytest.mark.parametrize(("size", "pix_fmt"), [("640x479", "yuv422p"), ("641x479", "yuv444p"),
                                               ("641x479", "yuv444p10le")])
def test_a_pixel_format_whose_chroma_is_not_halved_that_way_takes_an_odd_size(
        tmp_path: Path, size: str, pix_fmt: str) -> None:
    out = tmp_path / "a.mp4"
    result = vtrack("scene", "smooth", str(out), "--frames", "10", "--size", size,
                    "--pix-fmt", pix_fmt)
    assert result.exit_code == 0, result.output
    assert out.stat().st_size > 0


@pytest.mark.parametrize("size", ["1x1", "1x1000"])
def test_a_picture_too_small_for_the_video_says_the_way_out_before_tracking(
        tmp_path: Path, size: str) -> None:
    """`vtrack run r.raw --raw 1x1 --pix-fmt gray -c s4` said 'annotated.mp4: cannot encode a
    1x1 video', exit 2, and not that --no-video tracks it. It says so, before a frame is
    tracked (no results folder), and --no-video tracks it."""
    width, height = (int(n) for n in size.split("x"))
    raw = tmp_path / "r.raw"
    raw.write_bytes(np.random.default_rng(0).integers(0, 256, 100 * width * height,
                                                      np.uint8).tobytes())
    args = ["run", str(raw), "--raw", size, "--pix-fmt", "gray", "-c", "s4"]
    line = one_error_line(vtrack(*args, "-o", str(tmp_path / "out")))
    assert line == (f"vtrack: error: {tmp_path / 'out' / 'annotated.mp4'}: cannot encode a "
                    f"{size} video (H.264 in yuv420p needs at least 2x2 pixels); give "
                    "--no-video to track it without the video")
    assert not (tmp_path / "out").exists()
    # with --video-out the way out is both: without it the video is annotated.mp4, as small
    line = one_error_line(vtrack(*args, "--video-out", "udp://127.0.0.1:9", "-o",
                                 str(tmp_path / "out")))
    assert line.endswith("; leave --video-out out and give --no-video to track it without the "
                         "video"), line
    done = vtrack(*args, "--no-video", "-o", str(tmp_path / "out"))
    assert done.exit_code == 0, done.output


# --- a config given as a pipe or a device -------------------------------------------------------


def test_a_config_given_as_a_pipe_says_so(tmp_path: Path, clip_factory: ClipFactory) -> None:
    clip = clip_factory("smooth", frames=10)
    read, write = os.pipe()
    try:
        line = one_error_line(vtrack("run", str(clip.path), "--config", f"/dev/fd/{read}",
                                "--no-video", "-o", str(tmp_path / "out"), "-y"))
    finally:
        os.close(read)
        os.close(write)
    assert line == (f"vtrack: error: /dev/fd/{read}: a FIFO, not a file: give the config as "
                    "a file")


def test_a_config_given_as_dev_null_says_what_it_is(tmp_path: Path,
                                                    clip_factory: ClipFactory) -> None:
    clip = clip_factory("smooth", frames=10)
    line = one_error_line(vtrack("run", str(clip.path), "--config", "/dev/null", "--no-video",
                            "-o", str(tmp_path / "out"), "-y"))
    assert line == ("vtrack: error: /dev/null: a character device, not a file: give the "
                    "config as a file")
