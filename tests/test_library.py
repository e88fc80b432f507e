"""The library entry point ``vtrack.track`` on a real encoded clip and on in-memory frames."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import vtrack
from vtrack.geometry import center_error
from vtrack.run import run
from vtrack.scenes import make_scene, write_groundtruth, write_image_sequence, write_video


def test_track_a_path_and_frames_follow_the_target_alike(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=4, width=320, height=240, frames=40, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    from_file = list(vtrack.track(str(clip), "s0", scene.boxes[0]))
    in_memory = list(vtrack.track(scene.as_frames(), vtrack.load_config("s0"), scene.boxes[0]))
    assert [r.index for r in from_file] == [r.index for r in in_memory] == list(range(40))
    for results in (from_file, in_memory):
        errors = [center_error(r.box, gt) for r, gt in zip(results, scene.boxes, strict=True)]
        assert np.mean(errors) < 10.0 and max(errors) < 25.0
    # a run request gives the same results as the path it names, up to its frame limit
    request = vtrack.RunRequest(str(clip), tmp_path / "unused", vtrack.load_config("s0"),
                                init_box=scene.boxes[0], max_frames=12)
    from_request = list(vtrack.track(request))
    assert [(r.index, r.box) for r in from_request] == [(r.index, r.box) for r in from_file[:12]]
    assert not (tmp_path / "unused").exists()  # nothing is written
    # the decoded clip differs from the rendered frames only by compression
    drift = [center_error(a.box, b.box) for a, b in zip(from_file, in_memory, strict=True)]
    assert np.median(drift) < 3.0


def test_track_takes_plain_values_path_tuple_and_numpy_frames(tmp_path: Path) -> None:
    """Issue 12 item 4: a pathlib.Path, a tuple box and NumPy BGR arrays give the same track
    as the library's own types."""
    scene = make_scene("smooth", seed=2, width=160, height=120, frames=20, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    start = tuple(float(v) for v in scene.boxes[0])
    typed = [r.box for r in vtrack.track(str(clip), "s0", vtrack.Box(*start))]
    plain = [r.box for r in vtrack.track(clip, "s0", start)]  # pathlib.Path, tuple
    assert plain == typed and len(plain) == 20
    from_arrays = list(vtrack.track(scene.frames(), "s0", list(start)))
    from_frames = list(vtrack.track(scene.as_frames(), "s0", vtrack.Box(*start)))
    assert [r.box for r in from_arrays] == [r.box for r in from_frames]
    assert [r.time_s for r in from_arrays] == [r.time_s for r in from_frames]
    # a grey image is a frame too (for a grey tracker)
    grey = [np.ascontiguousarray(f[:, :, 1]) for f in scene.frames()]
    assert len(list(vtrack.track(grey, "s2", start))) == 20


def test_track_rejects_values_it_cannot_use_with_a_clear_message() -> None:
    frames = [np.zeros((48, 64, 3), np.uint8)] * 2
    with pytest.raises(ValueError, match="4 numbers"):
        list(vtrack.track(frames, "s0", (1, 2, 3)))
    with pytest.raises(ValueError, match="positive"):
        list(vtrack.track(frames, "s0", (1, 2, 0, 5)))
    with pytest.raises(TypeError, match="frame 0.*float32"):
        list(vtrack.track([np.zeros((48, 64, 3), np.float32)], "s0", (1, 2, 8, 8)))
    with pytest.raises(TypeError, match="frame 1.*str"):
        list(vtrack.track([frames[0], "frame.png"], "s2", (1, 2, 8, 8)))


def test_frame_types_are_exported_and_construct_frames() -> None:
    bgr = np.full((24, 32, 3), 90, np.uint8)
    for frame in (vtrack.BgrFrame(0, 0.0, bgr), vtrack.GrayFrame(0, 0.0, bgr[:, :, 0].copy())):
        assert isinstance(frame, vtrack.Frame) and (frame.width, frame.height) == (32, 24)
    assert {"Box", "Frame", "BgrFrame", "GrayFrame", "I420Frame", "track"} <= set(vtrack.__all__)


def test_a_run_request_is_tracked_from_its_start_with_its_ground_truths_box(
        tmp_path: Path) -> None:
    """``vtrack.track(RunRequest)`` tracked frames 0.. with frame ``start``'s box, and without
    ``init_box`` refused although the request names a ground truth (as ``vtrack run`` takes it)."""
    scene = make_scene("smooth", seed=4, width=160, height=120, frames=40, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    gt = tmp_path / "clip.gt.txt"
    write_groundtruth(scene, gt)
    request = vtrack.RunRequest(str(clip), tmp_path / "unused", vtrack.load_config("s0"),
                                gt_path=str(gt), start=20, max_frames=5)
    results = list(vtrack.track(request))
    assert [r.index for r in results] == list(range(20, 25))
    assert center_error(results[0].box, scene.boxes[20]) < 1.0
    from_cli = tmp_path / "cli"
    run(replace(request, out_dir=from_cli, video=False))
    with (from_cli / "track.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [int(row["frame"]) for row in rows] == [r.index for r in results]
    assert [round(float(row["x"]), 2) for row in rows] == [round(r.box.x, 2) for r in results]


def test_an_image_folder_is_timed_at_the_frame_rate_given(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    folder = write_image_sequence(scene, tmp_path / "seq")
    times = [r.time_s for r in vtrack.track(folder, "s0", scene.boxes[0], fps=10)]
    assert times == pytest.approx([i / 10 for i in range(10)])


@pytest.mark.parametrize("config", ["s0", "s2", "robust"])
def test_decoded_av_frames_give_the_boxes_vtrack_run_gives(tmp_path: Path, config: str) -> None:
    """PyAV frames were converted by FFmpeg's BGR converter, the reader's I420 planes by
    OpenCV's: up to 149 of 150 boxes differed from track.csv."""
    import av

    scene = make_scene("exit_return", seed=5, width=320, height=240, frames=60, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    by_path = [r.box for r in vtrack.track(clip, config, scene.boxes[0])]
    with av.open(str(clip)) as container:
        decoded = [r.box for r in vtrack.track(container.decode(video=0), config,
                                                scene.boxes[0])]
    assert decoded == by_path
