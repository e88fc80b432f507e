"""The library entry point ``vtrack.track`` on a real encoded clip and on in-memory frames."""

from __future__ import annotations

import contextlib
import csv
import os
import re
import threading
import warnings
from collections.abc import Iterator
from dataclasses import replace
from decimal import Decimal
from pathlib import Path

import cv2
import numpy as np
import pytest
from test_cli import vtrack as vtrack_command
from test_io import _remuxed as remuxed
from test_io import pictures
from test_io import write_video as encode_pictures

import vtrack
from vtrack.errors import ConfigError, InputError, PartialInputError
from vtrack.geometry import center_error
from vtrack.run import run
from vtrack.scenes import (
    make_scene,
    write_groundtruth,
    write_image_sequence,
    write_raw,
    write_video,
)


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
    as_bytes = [r.box for r in vtrack.track(bytes(clip), "s0", start)]  # a path, not frames
    assert as_bytes == typed
    # a grey image is a frame too (for a grey tracker)
    grey = [np.ascontiguousarray(f[:, :, 1]) for f in scene.frames()]
    assert len(list(vtrack.track(grey, "s2", start))) == 20


def test_track_rejects_values_it_cannot_use_with_a_clear_message() -> None:
    frames = [np.zeros((48, 64, 3), np.uint8)] * 2
    with pytest.raises(ConfigError, match="4 numbers"):
        list(vtrack.track(frames, "s0", (1, 2, 3)))
    with pytest.raises(ConfigError, match=r"the box 1,2,0,5 is empty \(width and height must "
                       r"be > 0\)"):
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
    # track.csv holds pixels to a thousandth (a rounding to 2 decimals of both sides flipped
    # where x sat at .xx5)
    assert [float(row["x"]) for row in rows] == pytest.approx([r.box.x for r in results],
                                                              abs=5.1e-4)


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


def _red_block(count: int = 3) -> list[np.ndarray]:
    """A red block on black, ``count`` BGR frames of 160x120."""
    frames = [np.zeros((120, 160, 3), np.uint8) for _ in range(count)]
    for frame in frames:
        frame[40:70, 50:90] = (0, 0, 255)
    return frames


def test_a_source_closed_while_it_is_read_ends_its_reading_with_one_error(
        tmp_path: Path) -> None:
    """`it = iter(source); next(it); source.close(); next(it)` waited for ever (the reader
    thread stopped without a word and the consumer waited on its queue), as did a loop over a
    source another thread closed (a camera's stop button). The reading ends with one
    RuntimeError saying the source was closed, not as if the input had ended."""
    clip = write_video(make_scene("smooth", seed=2, width=96, height=72, frames=30, fps=30),
                       tmp_path / "clip.mp4")
    source = vtrack.open_source(clip)
    frames = iter(source)
    assert next(frames).index == 0
    source.close()
    result: list[BaseException] = []

    def read_on() -> None:
        try:
            list(frames)
        except RuntimeError as error:
            result.append(error)

    reader = threading.Thread(target=read_on, daemon=True)
    reader.start()
    reader.join(timeout=60)
    assert not reader.is_alive(), "iterating a closed source still waits"
    assert [str(error) for error in result] == [
        f"{clip}: the source was closed while it was read"]


@pytest.mark.parametrize("live", [False, True])
def test_a_source_closed_after_its_input_ended_ends_its_reading_as_the_end_does(
        tmp_path: Path, live: bool) -> None:
    """Every frame read, the reader thread at the input's end, then ``close()``: the next
    ``next()`` raised RuntimeError "the source was closed while it was read" (close() threw
    the queued end away; a live source's reader ended as a stopped one), where the input had
    ended: it is StopIteration now, for a live source too."""
    clip = write_video(make_scene("smooth", seed=2, width=96, height=72, frames=30, fps=30),
                       tmp_path / "clip.mp4")
    source = vtrack.open_source(clip, live=live)
    frames = iter(source)
    taken = 0
    while taken + source.frames_passed < 30:
        next(frames)
        taken += 1
    reader = f"vtrack-read:{source.info.name}"
    for _ in range(600):  # the reader thread has gone past the last frame and ended
        if not any(thread.name == reader for thread in threading.enumerate()):
            break
        threading.Event().wait(0.05)
    source.close()
    with pytest.raises(StopIteration):
        next(frames)


def test_open_source_takes_a_path_and_the_raw_size_as_vtrack_run_does(tmp_path: Path) -> None:
    """``open_source(pathlib.Path)`` raised TypeError (``'PosixPath' is not iterable``) and
    ``raw="320x240"`` AttributeError (``'str' object has no attribute 'frame_bytes'``)."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    with vtrack.open_source(clip) as source:
        assert (source.info.width, source.info.height) == (96, 72)
        assert sum(1 for _ in source) == 10
    raw = write_raw(scene, tmp_path / "clip.bgr")
    with vtrack.open_source(raw, raw="96x72", fps=10) as source:  # (frames reuse a ring)
        read = [(f.time_s, np.array_equal(f.bgr(), image))
                for f, image in zip(source, scene.frames(), strict=True)]
    assert read == [(pytest.approx(i / 10), True) for i in range(10)]
    with vtrack.open_source(raw, raw="96x72", pix_fmt="gray") as source:
        assert (source.info.pix_fmt, source.info.frame_count) == ("gray", 30)  # 1/3 the bytes
    with pytest.raises(ConfigError, match=r"^raw '96x7x': expected WIDTHxHEIGHT"):
        vtrack.open_source(raw, raw="96x7x")
    with pytest.raises(ConfigError, match="raw: expected a vtrack.io.RawFormat or "
                       "'WIDTHxHEIGHT', got int"):
        vtrack.open_source(raw, raw=96)


def test_open_source_checks_live_as_a_run_request_does(tmp_path: Path) -> None:
    """open_source(clip, live="no") read the file live ("no" is true to Python): a slow reader
    was handed 24 of 151 frames; open_source(clip, bogus=1) named source_opener()."""
    clip = write_video(make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30),
                       tmp_path / "clip.mp4")
    for given in ("no", "yes", 2):
        with pytest.raises(ConfigError, match=r"^live .*: must be True or False \(or the "
                           r"integers 1 or 0\)$"):
            vtrack.open_source(clip, live=given)
    for given, live in ((0, False), (False, False), (1, True), (True, True)):
        with vtrack.open_source(clip, live=given) as source:
            assert source.live is live  # (frames alone: a fast reader gets them all live too)
            assert sum(1 for _ in source) == 10
    with pytest.raises(TypeError, match=r"open_source\(\) got an unexpected keyword argument "
                       "'bogus'"):
        vtrack.open_source(clip, bogus=1)  # type: ignore[call-arg]


@pytest.mark.parametrize(("given", "said"), [
    ({"raw": "96x72", "pix_fmt": "gray", "fps": 0}, "fps 0: must be a frame rate from 0.01"),
    ({"raw": "96x72", "pix_fmt": "bgra"}, "pix_fmt 'bgra': expected one of bgr24, rgb24"),
    ({"raw": "96x"}, "raw '96x': expected WIDTHxHEIGHT"),
    ({"raw": "0x72"}, "raw '0x72': width and height must be positive"),
    ({"raw": "95x72", "pix_fmt": "yuv420p"}, "raw '95x72': yuv420p frames need an even"),
])
def test_open_source_names_its_own_arguments_for_a_raw_format_it_cannot_read(
        tmp_path: Path, given: dict, said: str) -> None:
    """open_source("f.bgr", raw="96x72", pix_fmt="gray", fps=0) said '--fps 0: ...' and a bad
    pix_fmt '--pix-fmt 'bgra': ...', naming vtrack run's options, not the arguments given."""
    path = tmp_path / "f.bgr"
    path.write_bytes(bytes(96 * 72 * 3))
    with pytest.raises(ConfigError) as caught:
        vtrack.open_source(path, **given)
    assert str(caught.value).startswith(said)


@pytest.mark.parametrize(("box", "problem"), [
    ((100, 100, 0, 40), r"the box 100,100,0,40 is empty \(width and height must be > 0\)"),
    ((100, 100, -40, 40), r"the box 100,100,-40,40 is empty"),
    ((100, 100, 2, 2), "the box 100,100,2,2 is smaller than 4x4"),
    ((1, 2, 3), r"expected 4 numbers \(x, y, w, h\), got 3"),
    ("1234", r"expected \(x, y, w, h\) numbers, got '1234'"),
    ("abc", r"expected \(x, y, w, h\) numbers, got 'abc'"),
    ((True, 100, 40, 40), r"expected \(x, y, w, h\) numbers, got \(True, 100, 40, 40\)"),
    (("100", 100, 40, 40), r"expected \(x, y, w, h\) numbers, got \('100', 100, 40, 40\)"),
    (vtrack.Box("100", 100, 40, 40), r"expected \(x, y, w, h\) numbers, got Box\(x='100'"),
])
def test_every_bad_first_box_is_a_config_error_as_with_vtrack_run_init(box: object,
                                                                       problem: str) -> None:
    """An empty box or one of 3 numbers raised builtins.ValueError, a 2x2 one ConfigError (what
    ``vtrack run --init`` raises for each); "1234" was taken as the box 1,2,3,4, (True, ...)
    as x = 1 and ("100", ...) as x = 100; Box("100", ...) raised "Unknown format code 'g'"."""
    with pytest.raises(ConfigError, match=f"^init_box: {problem}"):
        vtrack.Tracker("s0").init(np.zeros((240, 320, 3), np.uint8), box)


def test_a_pyav_object_that_is_no_picture_vtrack_reads_is_a_type_error() -> None:
    """An av.AudioFrame raised AttributeError ('rotation') and an rgb4 picture, which FFmpeg
    cannot convert, a bare OSError [Errno 95]; a pal8 one is converted and tracked."""
    import av

    with pytest.raises(TypeError, match="frame 0: expected a vtrack.Frame, a NumPy image or "
                       "an av.VideoFrame, got AudioFrame"):
        vtrack.Tracker("s0").init(av.AudioFrame(format="s16", layout="mono", samples=10),
                                  (1, 1, 4, 4))
    with pytest.raises(TypeError, match=r"frame 0: FFmpeg cannot convert an av.VideoFrame of "
                       r"pixel format rgb4 to BGR \(.+\)"):
        vtrack.Tracker("robust").init(av.VideoFrame(64, 48, "rgb4"), (1, 1, 8, 8))
    palette = np.zeros((256, 4), np.uint8)
    palette[1] = (0, 0, 255, 255)
    indices = np.zeros((120, 160), np.uint8)
    indices[40:70, 50:90] = 1
    pal8 = av.VideoFrame.from_ndarray((indices, palette), format="pal8")
    result = vtrack.Tracker("robust", keep_frames=True).init(pal8, (50, 40, 40, 30))
    assert np.array_equal(result.frame.bgr(), pal8.to_ndarray(format="bgr24"))
    assert result.frame.bgr()[50, 60].any() and not result.frame.bgr()[0, 0].any()


def test_a_pyav_frame_with_a_pts_but_no_time_base_is_refused_naming_what_is_missing() -> None:
    """A frame made with av.VideoFrame.from_ndarray and given a pts but no time_base (PyAV's
    time: NaN) was refused as "frame 1: time_s nan is not a finite number", a value the caller
    never gave; with a time_base it is timed by it, with no pts at index / fps."""
    from fractions import Fraction

    import av

    images = _red_block(2)
    frames = [av.VideoFrame.from_ndarray(image, format="bgr24") for image in images]
    frames[1].pts = 5
    tracker = vtrack.Tracker("robust")
    assert tracker.init(frames[0], (50, 40, 40, 30)).time_s == 0.0
    with pytest.raises(ValueError, match=r"^frame 1: an av.VideoFrame with pts 5 but no "
                       r"time_base: its time cannot be told \(set its time_base, or its pts "
                       r"to None to have it timed as a NumPy image is\)$"):
        tracker.update(frames[1])
    frames[1].time_base = Fraction(1, 10)
    assert tracker.update(frames[1]).time_s == 0.5


def test_one_image_given_as_the_frames_is_refused_not_read_row_by_row() -> None:
    """One 240x320x3 image was tracked as 240 grey 3x320 frames: "the box ... is larger than
    the 3x320 frame"."""
    image = _red_block(1)[0]
    with pytest.raises(TypeError, match=r"frames: expected an iterable of frames, got one "
                       r"image of 120x160x3 \(give \[image\] for a single frame\)"):
        list(vtrack.track(image, "robust", (50, 40, 40, 30)))
    with pytest.raises(TypeError, match="got one image of 120x160 "):
        list(vtrack.track(image[:, :, 2].copy(), "s2", (50, 40, 40, 30)))
    with pytest.raises(TypeError, match="got one BgrFrame"):
        list(vtrack.track(vtrack.BgrFrame(0, 0.0, image), "robust", (50, 40, 40, 30)))
    assert [r.index for r in vtrack.track([image], "robust", (50, 40, 40, 30))] == [0]
    stack = np.stack(_red_block(3))  # N x H x W x 3: a sequence of 3 frames
    assert [r.index for r in vtrack.track(stack, "robust", (50, 40, 40, 30))] == [0, 1, 2]


@pytest.mark.parametrize("config", ["s0", "robust"])
def test_pipeline_checks_its_frames_and_first_box_as_the_tracker_does(config: str) -> None:
    """Pipeline.track raised AttributeError for a NumPy frame ('width') and a tuple box ('cx'),
    a bare AssertionError or InputError for Box(100, 100, -40, -40), and returned a 1e9 box."""
    frames = [vtrack.BgrFrame(i, i / 30, image) for i, image in enumerate(_red_block())]

    def track(frames: list, box: object) -> list:
        return list(vtrack.Pipeline(vtrack.load_config(config).build()).track(frames, box))

    by_tuple = track(frames, (50, 40, 40, 30))
    by_box = track(frames, vtrack.Box(50, 40, 40, 30))
    assert [r.box for r in by_tuple] == [r.box for r in by_box] and len(by_box) == 3
    with pytest.raises(TypeError, match="Pipeline takes vtrack.Frame objects .*got ndarray"):
        track(_red_block(), vtrack.Box(50, 40, 40, 30))
    with pytest.raises(ConfigError, match=r"init_box: the box 100,100,-40,-40 is empty"):
        track(frames, vtrack.Box(100, 100, -40, -40))
    with pytest.raises(ConfigError, match="init_box: the box 0,0,1e.09,1e.09 is larger than "
                       "the 160x120 frame"):
        track(frames, vtrack.Box(0, 0, 1e9, 1e9))


def test_pipeline_process_before_begin_says_to_begin_or_begins_a_detecting_chain() -> None:
    """Pipeline(...).process(frame) before begin() raised AttributeError: 'Pipeline' object has
    no attribute '_shape'; so did process() after a begin(None) refused for s0. A begin(None)
    refused during a track left that track going (the next frame followed it), where
    Tracker.init refused ends it."""
    frame = vtrack.BgrFrame(0, 0.0, _red_block(1)[0])
    pipeline = vtrack.Pipeline(vtrack.load_config("s0").build())
    with pytest.raises(ConfigError, match=r"^pipeline: no track begun: call begin\(\(x, y, w, "
                       r"h\)\) with the target's box in the first frame, then process\(frame\)$"):
        pipeline.process(frame)
    with pytest.raises(ConfigError, match="needs an initial box"):
        pipeline.begin(None)
    with pytest.raises(ConfigError, match="no track begun"):
        pipeline.process(frame)
    pipeline.begin((50, 40, 40, 30))
    assert pipeline.process(frame).box == vtrack.Box(50, 40, 40, 30)
    with pytest.raises(ConfigError, match="needs an initial box"):
        pipeline.begin(None)
    with pytest.raises(ConfigError, match="no track begun"):
        pipeline.process(vtrack.BgrFrame(1, 1 / 30, _red_block(1)[0]))
    detecting = vtrack.Pipeline(vtrack.load_config("s4_multi").build())  # begins as update()
    then = vtrack.BgrFrame(1, 1 / 30, _red_block(1)[0])
    assert [detecting.process(f).index for f in (frame, then)] == [0, 1]


def test_frame_constructors_refuse_what_the_tracker_refuses_with_its_message() -> None:
    """BgrFrame took float32 pixels (and failed later: "no pixel of the initial box passes
    the hue stage's mask"), GrayFrame an HxWx3 array, and either a time of NaN."""
    image = _red_block(1)[0]
    with pytest.raises(TypeError, match="^frame 4: expected uint8 pixels, got float32$"):
        vtrack.BgrFrame(4, 0.0, image.astype(np.float32))
    with pytest.raises(TypeError, match="^frame 0: expected uint8 pixels, got float32$"):
        vtrack.Tracker("s0").init(image.astype(np.float32), (50, 40, 40, 30))  # as_frame's
    with pytest.raises(TypeError, match=r"^frame 0: expected an HxW grey image, got shape "
                       r"\(120, 160, 3\)$"):
        vtrack.GrayFrame(0, 0.0, image)
    with pytest.raises(TypeError, match=r"^frame 0: expected an HxWx3 BGR image, got shape "
                       r"\(120, 160\)$"):
        vtrack.BgrFrame(0, 0.0, image[:, :, 0])
    for time_s in (float("nan"), float("inf")):
        with pytest.raises(ValueError, match=f"^frame 2: time_s {time_s} is not a finite "):
            vtrack.BgrFrame(2, time_s, image)
    with pytest.raises(ValueError, match=r"^frame 0: the frame size 160x0 is empty$"):
        vtrack.GrayFrame(0, 0.0, np.zeros((0, 160), np.uint8))
    with pytest.raises(TypeError, match=r"^frame 0: expected an \(h \* 3 // 2\)xW I420 image "
                       r"of even width and height, got shape \(100, 160\)$"):
        vtrack.I420Frame(0, 0.0, np.zeros((100, 160), np.uint8))
    assert vtrack.I420Frame(0, 0.0, np.zeros((180, 160), np.uint8)).height == 120


@pytest.mark.parametrize("config", ["s0", "s0-fixed", "robust"])
def test_pipeline_refuses_a_frame_of_another_size_or_kind_than_the_first(config: str) -> None:
    """Pipeline.track took a 40x30 frame after a 160x120 one and said 'tracking' with the box
    120,80,20,20 wholly outside it (s0-fixed: a box at -4.5,-4.5); vtrack.Tracker refused it."""
    first = _red_block(1)[0]
    pipeline = vtrack.Pipeline(vtrack.load_config(config).build())
    results = pipeline.track([vtrack.BgrFrame(0, 0.0, first),
                              vtrack.BgrFrame(1, 0.1, np.zeros((30, 40, 3), np.uint8))],
                             (50, 40, 40, 30))
    assert next(results).index == 0
    with pytest.raises(InputError, match=r"^frame 1: 40x30 colour, the first frame was 160x120 "
                       r"colour \(one track follows one sequence: Tracker.reset\(\) or "
                       r"Pipeline.begin\(\) starts another\)$"):
        next(results)
    grey = pipeline.track([vtrack.BgrFrame(0, 0.0, first),
                           vtrack.GrayFrame(1, 0.1, first[:, :, 2].copy())], (50, 40, 40, 30))
    assert next(grey).index == 0
    with pytest.raises(InputError, match="^frame 1: 160x120 grey, the first frame was 160x120 "
                       "colour"):
        next(grey)
    small = np.zeros((30, 40, 3), np.uint8)
    small[5:25, 5:25] = (0, 0, 255)
    again = pipeline.track([vtrack.BgrFrame(0, 0.0, small)], (5, 5, 20, 20))  # any size
    assert [r.index for r in again] == [0]
    # a first frame refused (the box outside it) is not the track's first: it was, and a
    # frame of the box's size was then refused as 'the first frame was 40x30'
    pipeline.begin((50, 40, 40, 30))
    with pytest.raises(ConfigError, match="^init_box: the box 50,40,40,30 lies outside the "
                       "40x30 frame"):
        pipeline.process(vtrack.BgrFrame(0, 0.0, small))
    assert pipeline.process(vtrack.BgrFrame(0, 0.0, first)).box == vtrack.Box(50, 40, 40, 30)


def test_a_frame_index_that_is_not_a_frame_number_is_one_line_naming_it() -> None:
    """BgrFrame(image, 0, 0.0) (arguments swapped) raised 'frame [[[0 0 0] ...' with the whole
    image printed over dozens of lines; an index of 'a', -1 or 1.5 made a frame. BgrFrame(-1,
    ...) then raised a TypeError ('got -1'), though -1 is of the right type: a ValueError."""
    image = _red_block(1)[0]
    with pytest.raises(TypeError, match=r"^frame index: expected a whole number >= 0 \(the "
                       r"frame's 0-based number, the first argument\), got ndarray$"):
        vtrack.BgrFrame(image, 0, 0.0)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^frame index: .*got ndarray$"):
        vtrack.GrayFrame(image[:, :, 0], 0, 0.0)  # type: ignore[arg-type]
    for index, shown in (("a", "str"), (1.5, "float"), (True, "bool")):
        with pytest.raises(TypeError, match=f"^frame index: .*got {shown}$"):
            vtrack.BgrFrame(index, 0.0, image)  # type: ignore[arg-type]
    # a negative index is of the right type: a ValueError, in the same words
    negative = (r"^frame index: expected a whole number >= 0 \(the frame's 0-based number, "
                r"the first argument\), got -1$")
    with pytest.raises(ValueError, match=negative):
        vtrack.I420Frame(-1, 0.0, np.zeros((180, 160), np.uint8))
    with pytest.raises(ValueError, match=negative):
        vtrack.BgrFrame(-1, 0.0, image)
    with pytest.raises(ValueError, match=negative):
        vtrack.GrayFrame(np.int64(-1), 0.0, image[:, :, 0])
    assert vtrack.BgrFrame(np.int64(3), 0.1, image).index == 3


@pytest.mark.parametrize("frames", [5, None])
def test_what_is_neither_a_path_nor_frames_is_one_line_naming_the_argument(frames: object
                                                                          ) -> None:
    """track(5) raised "'int' object is not iterable", track([image], 5) and Tracker(5)
    "expected str, bytes or os.PathLike object, not int" and open_source(None) the same
    ("not NoneType"): none named the argument."""
    image = _red_block(1)[0]
    kind = type(frames).__name__
    with pytest.raises(TypeError, match=r"^frames: expected a path \(str or pathlib.Path\), a "
                       f"RunRequest or an iterable of frames, got {kind}$"):
        list(vtrack.track(frames, "s0", (50, 40, 40, 30)))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"^spec: expected a path \(str or pathlib.Path\), a "
                       f"URL or a device, got {kind}$"):
        vtrack.open_source(frames)  # type: ignore[arg-type]
    config = r"^config: expected a shipped config name, a TOML file path or a vtrack.Config"
    with pytest.raises(TypeError, match=f"{config}, got int$"):
        list(vtrack.track([image], 5, (50, 40, 40, 30)))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=f"{config}, got list$"):
        vtrack.Tracker(["s0"])  # type: ignore[arg-type]


def test_track_without_the_first_box_a_config_needs_names_init_box() -> None:
    """vtrack.track(frames, "s0") said 'call init(frame, (x, y, w, h))', a method the caller of
    track never sees, and only after opening the input and decoding its first frame."""
    with pytest.raises(ConfigError, match=r"^init_box: s0 starts from the target's first box: "
                       r"give init_box=\(x, y, w, h\)$"):
        next(vtrack.track("no-such-clip.mp4", "s0"))  # not opened: the box is asked for first
    assert [r.index for r in vtrack.track(_red_block(2), "s4_multi")] == [0, 1]


def test_track_checks_its_arguments_when_called_and_opens_its_input_at_the_first_result(
        tmp_path: Path) -> None:
    """vtrack.track("missing.mp4", "s0", box), an unknown config or a request for a missing
    file returned a generator and said nothing until its first next() (track was a generator
    function): each is raised by the call. The input itself is opened at the first next():
    track opened it (and decoded a frame) in the call, so each generator not yet iterated held
    files open (100 of them under `ulimit -n 64`: "Too many open files"), and a FIFO without a
    writer blocked inside track(). Frames are taken as results are."""
    missing = tmp_path / "missing.mp4"
    request = vtrack.RunRequest(str(missing), tmp_path / "out", vtrack.load_config("s0"),
                                init_box=(50, 40, 40, 30))
    no_video = tmp_path / "notes.mp4"
    no_video.write_bytes(b"\0" * 4096)
    for call, error, said in (
            (lambda: vtrack.track(missing, "s0", (50, 40, 40, 30)), InputError,
             f"{missing}: no such file"),
            (lambda: vtrack.track(_red_block(2), "no-such-config", (50, 40, 40, 30)),
             ConfigError, "no-such-config: no such config file or shipped config"),
            (lambda: vtrack.track(request), InputError, f"{missing}: no such file"),
            (lambda: vtrack.track(tmp_path, "s0", (50, 40, 40, 30)), InputError,
             f"{tmp_path}: no images")):
        with pytest.raises(error) as caught:
            call()  # no next()
        assert str(caught.value).startswith(said)
    unreadable = vtrack.track(no_video, "s0", (50, 40, 40, 30))  # (a file: not read yet)
    with pytest.raises(InputError, match=f"^{re.escape(str(no_video))}: "):
        next(unreadable)
    taken: list[int] = []

    def frames() -> Iterator[np.ndarray]:
        for n, image in enumerate(_red_block(3)):
            taken.append(n)
            yield image

    results = vtrack.track(frames(), "s0", (50, 40, 40, 30))
    assert taken == []
    assert next(results).index == 0 and taken == [0]
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    folder = tmp_path / "frames"
    folder.mkdir()
    for n, image in enumerate(_red_block(3)):
        cv2.imwrite(str(folder / f"{n:04d}.png"), image)
    open_files = len(os.listdir("/proc/self/fd"))
    waiting = [vtrack.track(clip, "s0", scene.boxes[0]) for _ in range(5)]
    waiting += [vtrack.track(folder, "s0", (50, 40, 40, 30)) for _ in range(5)]
    waiting.append(vtrack.track(replace(request, input=str(clip), init_box=scene.boxes[0])))
    assert len(os.listdir("/proc/self/fd")) == open_files  # none opened yet
    fifo = tmp_path / "fifo.ts"
    os.mkfifo(fifo)
    vtrack.track(fifo, "s0", scene.boxes[0])  # (returns: nothing opened, so no writer waited for)
    assert [r.index for r in waiting[0]] == list(range(10))
    assert [r.index for r in waiting[-1]] == list(range(10))
    assert [r.index for r in waiting[5]] == [0, 1, 2]


def test_track_warns_of_the_frames_a_damaged_input_skipped_as_vtrack_run_does(
        tmp_path: Path) -> None:
    """A transport stream that lost five pictures (frames 20-24): vtrack.track yielded 35
    results, a gap in their index and no word, where vtrack run printed 'vtrack: warning:
    cut.ts: 5 damaged frames could not be decoded and were skipped'. The library warns with
    that line (vtrack.InputWarning), at the caller's line, however the results end."""
    clip = encode_pictures(tmp_path / "intra.ts", pictures(40), fmt="mpegts",
                           x264_params="keyint=1")
    cut = remuxed(clip, tmp_path / "cut.ts", lambda i, p: None if 20 <= i < 25 else p,
                  fmt="mpegts")
    said = f"{cut}: 5 damaged frames could not be decoded and were skipped"
    with pytest.warns(vtrack.InputWarning) as caught:
        results = list(vtrack.track(cut, "s0", (0, 40, 20, 20)))
    assert [r.index for r in results] == list(range(20)) + list(range(25, 40))
    assert [(str(w.message), w.filename) for w in caught] == [(said, __file__)]
    command = vtrack_command("run", str(cut), "-c", "s0", "--init", "0,40,20,20", "--out",
                             str(tmp_path / "out"), "--no-video")
    assert f"vtrack: warning: {said}" in command.stderr.decode()
    with pytest.warns(vtrack.InputWarning, match="5 damaged frames"):  # stopped part way
        for result in vtrack.track(cut, "s0", (0, 40, 20, 20)):
            if result.index == 30:
                break
    with warnings.catch_warnings():  # made an error: raised by close(), as the README says
        warnings.simplefilter("error", vtrack.InputWarning)
        with pytest.raises(vtrack.InputWarning, match="5 damaged frames"), \
                contextlib.closing(vtrack.track(cut, "s0", (0, 40, 20, 20))) as results:
            for result in results:
                if result.index == 30:
                    break


@pytest.mark.filterwarnings("ignore::vtrack.errors.InputWarning")  # (the cut frame's)
def test_an_input_cut_short_yields_its_frames_then_raises_partial_input_error(
        tmp_path: Path) -> None:
    """vtrack.PartialInputError, which track raises after the good frames' results (a
    transport stream cut mid-packet), was not exported with the other errors (only as
    vtrack.errors.PartialInputError) and the README did not name it."""
    assert "PartialInputError" in vtrack.__all__
    assert vtrack.PartialInputError is PartialInputError
    assert issubclass(vtrack.PartialInputError, vtrack.InputError)
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=30, fps=30)
    whole = write_video(scene, tmp_path / "whole.ts").read_bytes()
    cut = tmp_path / "cut.ts"
    cut.write_bytes(whole[:len(whole) * 2 // 3 + 100])
    taken = []
    with pytest.raises(vtrack.PartialInputError) as caught:
        for result in vtrack.track(cut, "s0", scene.boxes[0]):
            taken.append(result.index)
    assert taken and taken[-1] < caught.value.frames_done < 30
    assert str(caught.value).startswith(f"{cut}: decoding stopped at frame "
                                        f"{caught.value.frames_done}")


def test_a_warning_made_an_error_does_not_hide_partial_input_error(tmp_path: Path) -> None:
    """With warnings.simplefilter("error", vtrack.InputWarning), as the README suggests, the
    InputWarning of a cut transport stream's damaged frame replaced the PartialInputError on
    its way out ("except vtrack.PartialInputError" caught nothing): it is now a note of the
    PartialInputError; when the results end without an error it is still raised."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=30, fps=30)
    whole = write_video(scene, tmp_path / "whole.ts").read_bytes()
    cut = tmp_path / "cut.ts"
    cut.write_bytes(whole[:len(whole) * 2 // 3 + 100])
    with warnings.catch_warnings():
        warnings.simplefilter("error", vtrack.InputWarning)
        with pytest.raises(vtrack.PartialInputError) as caught:
            for _ in vtrack.track(cut, "s0", scene.boxes[0]):
                pass
        assert caught.value.__notes__ == [f"InputWarning: {cut}: 1 damaged frame could not be "
                                          "decoded and was skipped"]
        clip = encode_pictures(tmp_path / "intra.ts", pictures(40), fmt="mpegts",
                               x264_params="keyint=1")
        lost = remuxed(clip, tmp_path / "lost.ts", lambda i, p: None if 20 <= i < 25 else p,
                       fmt="mpegts")
        with pytest.raises(vtrack.InputWarning, match="^.*lost.ts: 5 damaged frames "):
            for _ in vtrack.track(lost, "s0", (0, 40, 20, 20)):  # (no error: raised)
                pass


@pytest.mark.parametrize("channels", [4, 1])
def test_one_bgra_or_one_channel_image_as_the_frames_is_refused_not_read_row_by_row(
        channels: int) -> None:
    """One 120x160x4 BGRA image (a PNG read with its alpha) given as ``frames`` was tracked as
    120 grey frames of 4x160: track(image, "robust", (0, 10, 4, 20)) yielded 120 results;
    a 0-d array raised NumPy's own 'iteration over a 0-d array'."""
    image = np.zeros((120, 160, channels), np.uint8)
    image[40:70, 50:90] = 255
    with pytest.raises(TypeError, match=r"^frames: expected an iterable of frames, got one "
                       rf"image of 120x160x{channels} \(give \[image\] for a single frame\)$"):
        list(vtrack.track(image, "robust", (0, 10, 4, 20)))
    with pytest.raises(TypeError, match=r"^frames: expected an iterable of frames, got a NumPy "
                       r"array of shape \(\), no picture$"):
        list(vtrack.track(np.array(5), "robust", (0, 10, 4, 20)))


@pytest.mark.parametrize("value", ["no", 2, None, 1.0])
def test_keep_frames_other_than_true_or_false_is_refused_naming_it(value: object) -> None:
    """track(frames, keep_frames="no") kept every frame ("no" is true to Python), as did
    Tracker(keep_frames="no"): a value that says the opposite of what it did. 1.0 is refused
    too, and the message says the 1 or 0 taken are integers."""
    image = _red_block(1)[0]
    said = (rf"^keep_frames {re.escape(repr(value))}: must be True or False \(or the integers 1 "
            r"or 0\)$")
    with pytest.raises(ConfigError, match=said):
        list(vtrack.track([image], "robust", (50, 40, 40, 30), keep_frames=value))
    with pytest.raises(ConfigError, match=said):
        vtrack.Tracker("robust", keep_frames=value)
    kept = vtrack.Tracker("robust", keep_frames=np.bool_(True)).init(image, (50, 40, 40, 30))
    assert kept.frame is not None


@pytest.mark.parametrize("empty", ["", " "])
def test_an_empty_input_or_config_names_the_argument(empty: str) -> None:
    """track("") said ': no such file', open_source("") the same, and load_config("") (or
    track(frames, "") and Tracker("")) ': is a folder, not a config file': a message naming
    nothing, as `vtrack run -c ""` said before the CLI refused an empty value."""
    image = _red_block(1)[0]
    with pytest.raises(InputError, match="^frames: empty; give a video file, an image folder, "
                       "a URL or a capture device$"):
        list(vtrack.track(empty, "robust", (50, 40, 40, 30)))
    with pytest.raises(InputError, match="^spec: empty; give a video file"):
        vtrack.open_source(empty)
    said = r"^config: empty; give a shipped config's name \(vtrack stages lists them\) or a TOML"
    with pytest.raises(ConfigError, match=said):
        vtrack.load_config(empty)
    with pytest.raises(ConfigError, match=said):
        list(vtrack.track([image], empty, (50, 40, 40, 30)))
    with pytest.raises(ConfigError, match=said):
        vtrack.Tracker(empty)


@pytest.mark.parametrize("empty", ["", " "])
def test_a_request_of_an_empty_input_names_its_field(empty: str, tmp_path: Path) -> None:
    """RunRequest(input="") was made: run() then said ': no such file' (naming nothing) and
    track() 'spec: empty', an argument the caller never gave; the request is refused as it is
    made, naming its field."""
    with pytest.raises(InputError, match="^input: empty; give a video file, an image folder, "
                       "a URL or a capture device$"):
        vtrack.RunRequest(input=empty, out_dir=tmp_path / "out",
                          config=vtrack.load_config("s0"), init_box=(1, 1, 10, 10))
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("empty", ["", " "])
def test_a_request_streaming_to_an_empty_name_is_refused(empty: str, tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """RunRequest(stream="") ran and failed with 'stream : No such file or directory' (naming
    nothing), and stream=" " wrote its lines into a file named " " in the current folder; both
    are refused as the request is made, as vtrack run --stream "" is."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError, match=r"^stream: empty; give a file or - \(stdout\)$"):
        vtrack.RunRequest(input=str(tmp_path), out_dir=tmp_path / "out",
                          config=vtrack.load_config("s0"), stream=empty)
    assert sorted(os.listdir(tmp_path)) == []


def test_a_config_made_in_python_is_checked_as_a_config_file_is() -> None:
    """vtrack.Config made in Python skipped the chain's checks: Config("mine", "mine", "",
    [("hue", {}), ("backproject", {})]) tracked 3 frames "tracking" at the first box (no stage
    sets a box), meanshift before hue raised a bare AssertionError, a stage named twice ran
    twice, and stages="hue" raised 'ValueError: not enough values to unpack'."""
    def chain(*names: str) -> list[tuple[str, dict]]:
        return [(name, {}) for name in names]

    with pytest.raises(ConfigError, match=r"^mine: no stage of the chain \(hue -> backproject\) "
                       "tracks: none sets the target's box"):
        vtrack.Config("mine", "mine", "", chain("hue", "backproject"))
    with pytest.raises(ConfigError, match="^mine: stage 'meanshift' needs likelihood, "
                       "search_box, target_model, window, which no earlier stage provides"):
        vtrack.Config("mine", "mine", "", chain("meanshift", "hue", "backproject"))
    with pytest.raises(ConfigError, match="^mine: stage 'meanshift' appears 2 times"):
        vtrack.Config("mine", "mine", "", chain("hue", "backproject", "meanshift", "meanshift"))
    with pytest.raises(ConfigError, match="^mine: no stages: a config is a chain of stages$"):
        vtrack.Config("mine", "mine", "", [])
    with pytest.raises(TypeError, match=r"^Config stages: expected a list of \(stage name, "
                       r"\{parameter: value\}\) pairs, got 'hue'$"):
        vtrack.Config("mine", "mine", "", "hue")  # type: ignore[arg-type]
    good = vtrack.Config("mine", "mine", "", chain("hue", "backproject", "meanshift"))
    image = _red_block(1)[0]
    assert [r.index for r in vtrack.track([image], good, (50, 40, 40, 30))] == [0]


def test_a_pipeline_checks_its_stages_as_a_config_is_checked() -> None:
    """Pipeline("s0") raised "AttributeError: 's' object has no attribute 'name'" (a str's
    characters taken for stages), Pipeline([1]) the same for 'int'; s0's stages reversed
    raised a bare AssertionError (backproject.py) on the first frame, and s0's stages twice
    over ran each twice a frame."""
    stages = vtrack.load_config("s0").build()
    for given, shown in (("s0", "'s0'"), ([1], r"\[1\]"), (None, "None")):
        with pytest.raises(TypeError, match=r"^stages: expected a list of built stages \(e.g. "
                           rf"vtrack.load_config\(name\).build\(\)\), got {shown}$"):
            vtrack.Pipeline(given)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="^pipeline: stage 'kalman' needs measurement, which "
                       r"no earlier stage provides \(check the order of the chain: measurement "
                       "comes from kernel_meanshift, kernel_meanshift_int, largest_blob, "
                       r"meanshift, meanshift_fixed, robust_search\)$"):
        vtrack.Pipeline(stages[::-1])
    with pytest.raises(ConfigError, match="^pipeline: stage 'hue' appears 2 times"):
        vtrack.Pipeline(stages + vtrack.load_config("s0").build())
    frames = [vtrack.BgrFrame(0, 0.0, _red_block(1)[0])]
    assert [r.index for r in vtrack.Pipeline(stages).track(frames, (50, 40, 40, 30))] == [0]


def test_fps_given_for_a_video_is_refused_and_a_sequence_keeps_its_own_rate(
        tmp_path: Path) -> None:
    """track("clip.mp4", ..., fps=5) ignored fps without a word (vtrack run --fps refuses it
    for a video file), and track(folder) timed a MOTChallenge sequence at 30 frames a second
    whatever its seqinfo.ini said (vtrack run takes its frameRate)."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    with pytest.raises(ConfigError, match=f"^fps: {re.escape(str(clip))} is a video file, "
                       r"whose frames carry their own timestamps; fps applies to raw "
                       r"input \(raw=\)"):
        list(vtrack.track(clip, "s0", scene.boxes[0], fps=5))
    assert len(list(vtrack.track(clip, "s0", scene.boxes[0]))) == 10
    folder = write_image_sequence(scene, tmp_path / "seq")
    (folder / "seqinfo.ini").write_text("[Sequence]\nframeRate=10\n")
    times = [r.time_s for r in vtrack.track(folder, "s0", scene.boxes[0])]
    assert times == pytest.approx([i / 10 for i in range(10)])
    frames = [r.time_s for r in vtrack.track(list(scene.frames()), "s0", scene.boxes[0])]
    assert frames == pytest.approx([i / 30 for i in range(10)])  # NumPy frames: 30 unless told


@pytest.mark.parametrize(("field", "value", "said"), [
    ("max_frames", -1, r"max_frames -1: must be a whole number from 1 to 1000000000000 \(how "
                       r"many frames to track; None: to the end\)"),
    ("max_frames", 0, "max_frames 0: must be a whole number from 1 to"),
    ("start", -5, r"start -5: must be a whole number from 0 to 1000000000000 \(the first frame "
                  r"tracked, 0-based\)"),
    ("start", "3", "start '3': must be a whole number from 0 to"),
    ("start_s", -1.0, r"start_s -1.0: must be a time in seconds from 0 to 31622400 "
                      r"\(a year\)"),
    ("max_s", float("nan"), "max_s nan: must be a time in seconds above 0 to 31622400 "),
    ("seed", -1, "seed -1: must be a whole number from 0 to 4294967295"),
])
def test_a_run_request_made_in_python_checks_its_values(field: str, value: object, said: str,
                                                        tmp_path: Path) -> None:
    """RunRequest checked nothing the CLI checks before making one: max_frames=-1 or 0 tracked
    no frame without a word, start=-5 said 'frame -5 of clip.mp4 could not be decoded
    (damaged)', start="3" raised "TypeError: '>=' not supported between instances of 'str'
    and 'int'", start_s=-1 and max_s=nan were taken, config="s0" raised "AttributeError: 'str'
    object has no attribute 'stages'"."""
    config = vtrack.load_config("s0")
    with pytest.raises(ConfigError, match=f"^{said}"):
        vtrack.RunRequest("clip.mp4", tmp_path, config, (50, 40, 40, 30), **{field: value})
    with pytest.raises(TypeError, match=r"^config: expected a vtrack.Config \(vtrack.load_"
                       r"config\(name\)\), got str$"):
        vtrack.RunRequest("clip.mp4", tmp_path, "s0")  # type: ignore[arg-type]
    request = vtrack.RunRequest("clip.mp4", tmp_path, config, (50, 40, 40, 30), max_frames=3)
    assert request.init_box == vtrack.Box(50, 40, 40, 30)


def test_track_refuses_settings_a_run_request_would_override(tmp_path: Path) -> None:
    """track(request, config="s1") tracked with the request's s0, and init_box=, seed= and fps=
    beside a request were dropped the same way, without a word."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    request = vtrack.RunRequest(str(clip), tmp_path / "out", vtrack.load_config("s0"),
                                scene.boxes[0])
    with pytest.raises(ConfigError, match=r"^config: the RunRequest carries its own; set it in "
                       r"the request \(dataclasses.replace\(request, ...\)\)$"):
        list(vtrack.track(request, "s1"))
    with pytest.raises(ConfigError, match="^init_box, seed: the RunRequest carries its own; "
                       "set them in the request"):
        list(vtrack.track(request, init_box=(1, 1, 9, 9), seed=3))
    assert len(list(vtrack.track(request))) == 10
    assert len(list(vtrack.track(clip, init_box=scene.boxes[0]))) == 10  # robust, seed 0


def test_decimal_numbers_are_taken_for_a_box_and_a_frame_rate() -> None:
    """Decimal("29.97") as fps was refused 'fps 29.97: must be a frame rate from 0.01 to 10000
    frames per second' (it is one), and a box of Decimals 'init_box: expected (x, y, w, h)
    numbers': Decimal is no numbers.Real, though it is a number (Fraction was taken)."""
    image = _red_block(1)[0]
    box = tuple(Decimal(v) for v in ("50", "40.5", "40", "30"))
    results = list(vtrack.track([image], "robust", box, fps=Decimal("29.97")))
    assert results[0].box == vtrack.Box(50, 40.5, 40, 30)
    assert vtrack.Tracker("s1", fps=Decimal("29.97")).fps == 29.97
    with pytest.raises(ConfigError, match=r"^fps Decimal\('NaN'\): must be a frame rate"):
        vtrack.Tracker("s1", fps=Decimal("NaN"))
    with pytest.raises(ConfigError, match="^fps an integer of 401 digits: must be a frame rate"):
        vtrack.Tracker("s1", fps=10**400)  # (as given: a float of it is no number)
    with pytest.raises(ConfigError, match=r"^init_box: expected \(x, y, w, h\) numbers"):
        list(vtrack.track([image], "robust", (1j, 40, 40, 30)))


def test_a_parameter_given_twice_to_the_tracker_is_refused() -> None:
    """Tracker("s0", **{"meanshift.iterations": 2}, meanshift__iterations=3) ran with 3 and
    dropped the 2 without a word (the two spellings name one parameter)."""
    with pytest.raises(ConfigError, match=r"^meanshift.iterations: given twice "
                       r"\(meanshift.iterations=2, meanshift__iterations=3\); give it once$"):
        vtrack.Tracker("s0", **{"meanshift.iterations": 2}, meanshift__iterations=3)
    tracker = vtrack.Tracker("s0", meanshift__iterations=3, kalman__q=2.0)
    assert dict(tracker.config.stages)["meanshift"]["iterations"] == 3


def test_a_keyword_that_names_no_stage_parameter_is_said_as_a_keyword() -> None:
    """Tracker("s0", iterations=3) (or a misspelt kepp_frames=True) said "iterations=3:
    expected stage.param=value": --set's syntax, not the keyword a Python caller writes."""
    for keyword, value in (("iterations", 3), ("kepp_frames", True)):
        with pytest.raises(ConfigError, match=rf"^{keyword}={value}: not an argument of "
                           r"Tracker\(\); a stage's parameter is given as stage__param=value "
                           r"\(e.g. meanshift__iterations=10\)$"):
            vtrack.Tracker("s0", **{keyword: value})


def test_the_readme_scorer_gives_the_metrics_vtrack_run_records(tmp_path: Path) -> None:
    """README's library section scores a run with vtrack.evaluate (read_boxes, summarize): the
    numbers are run.json's for the same frames (run scores the boxes as track.csv writes them,
    to a thousandth of a pixel), from an OTB folder's 1-based ground truth."""
    import json

    from vtrack.evaluate import read_boxes, summarize

    scene = make_scene("occlusion", seed=2, width=160, height=120, frames=60)
    folder = write_image_sequence(scene, tmp_path / "seq")
    truth = read_boxes(folder / "groundtruth_rect.txt", origin=1)
    results = list(vtrack.track(folder, "robust", truth[0]))
    scores = summarize([r.box for r in results], truth, [r.state for r in results])
    out = tmp_path / "out"
    run(vtrack.RunRequest(str(folder), out, vtrack.load_config("robust"),
                          gt_path=str(folder / "groundtruth_rect.txt"), gt_origin=1,
                          video=False))
    recorded = json.loads((out / "run.json").read_text())["metrics"]
    assert recorded.keys() == scores.keys() and scores["frames_evaluated"] == 60
    for name, value in scores.items():
        assert value == pytest.approx(recorded[name], abs=1e-3), name


def test_decimal_and_numpy_numbers_become_floats_in_what_a_run_writes(tmp_path: Path) -> None:
    """A Decimal frame rate was taken (d2cb0c5) but kept: track.csv's times were Decimals
    (`0E+2`, `0.03336670003336670003336670003`) and run.json's fps a string; a NumPy float32
    start_s was refused. They are floats from the request on; a signalling NaN is refused as a
    frame rate (it raised a bare ValueError)."""
    import json

    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10)
    folder = write_image_sequence(scene, tmp_path / "seq")
    times = [r.time_s for r in vtrack.track(folder, "s0", scene.boxes[0], fps=Decimal("29.97"))]
    assert all(type(t) is float for t in times) and times[1] == pytest.approx(1 / 29.97)
    request = vtrack.RunRequest(str(folder), tmp_path / "out", vtrack.load_config("s0"),
                                scene.boxes[0], fps=Decimal("29.97"), start_s=np.float32(0.0),
                                video=False)
    assert type(request.fps) is float and type(request.start_s) is float
    run(request)
    assert json.loads((tmp_path / "out" / "run.json").read_text())["request"]["fps"] == 29.97
    with (tmp_path / "out" / "track.csv").open(newline="") as handle:
        assert [row["time_s"] for row in csv.DictReader(handle)][:2] == ["0", "0.0334"]
    with pytest.raises(ConfigError, match="must be a frame rate"):
        vtrack.Tracker("s1", fps=Decimal("sNaN"))


def test_a_huge_integer_inside_a_list_is_named_in_a_short_line() -> None:
    """An integer of 5000 digits inside a list or a table of a parameter's value raised
    ValueError (Python's repr of it) while its message was made."""
    with pytest.raises(ConfigError) as caught:
        vtrack.Tracker("s0", hue__sat_min=[16**5000])
    assert "an integer of more than" in str(caught.value) and len(str(caught.value)) < 300
