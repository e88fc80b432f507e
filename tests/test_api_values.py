"""The library's values as a user gives them in Python: numbers too large to write as text,
NumPy scalars, a config given beside a RunRequest, a Config changed after its check. Each is
one ConfigError (or TypeError) naming the value, never a traceback from deep inside."""

from __future__ import annotations

import fcntl
import json
import os
import pickle
import re
import shlex
from dataclasses import replace
from decimal import Decimal
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from test_cli import assert_one_line_error
from test_cli import vtrack as vtrack_command

import vtrack
from vtrack.config import shipped_configs
from vtrack.errors import ConfigError, InputError
from vtrack.io import RawFormat
from vtrack.io.video import FFmpegInput
from vtrack.run import run
from vtrack.scenes import make_scene, write_image_sequence, write_video

#: An integer Python will not turn into text (more than 4300 digits): a message that shows it
#: with ``repr`` raises ValueError instead of saying what is wrong.
HUGE = 10**5000


def _frames(count: int = 10) -> list:
    """A few BGR frames of a target on a plain background."""
    scene = make_scene("smooth", seed=1, width=96, height=72, frames=count, fps=30.0)
    return list(scene.frames())


@pytest.mark.parametrize("make", [
    lambda: list(vtrack.track(_frames(), "s0", (10, 10, 20, 20), seed=HUGE)),
    lambda: vtrack.Tracker("s0", seed=HUGE),
    lambda: vtrack.RunRequest(input="c.mp4", out_dir=Path("out"),
                              config=vtrack.load_config("s0"), seed=HUGE),
])
def test_a_seed_too_long_to_write_is_refused_naming_seed_and_its_range(make) -> None:
    with pytest.raises(ConfigError) as caught:
        make()
    assert str(caught.value) == ("seed an integer of more than 4000 digits: must be a whole "
                                 "number from 0 to 4294967295")


@pytest.mark.parametrize("make", [
    lambda box: list(vtrack.track(_frames(), "s0", box)),
    lambda box: vtrack.RunRequest(input="c.mp4", out_dir=Path("out"),
                                  config=vtrack.load_config("s0"), init_box=box),
])
def test_a_first_box_with_a_number_too_long_to_write_is_refused_naming_init_box(make) -> None:
    with pytest.raises(ConfigError) as caught:
        make((HUGE, 1, 20, 20))
    assert str(caught.value) == ("init_box: (an integer of more than 4000 digits, 1, 20, 20): "
                                 "a number beyond a float's range (x, y, w, h are pixels of "
                                 "the frame)")
    with pytest.raises(ConfigError, match=r"^init_box: expected \(x, y, w, h\) numbers, got "
                                          r"\[an integer of more than 4000 digits, 'a'\]$"):
        make([HUGE, "a"])


@pytest.mark.parametrize(("field", "value", "said"), [
    ("start", HUGE, "start an integer of more than 4000 digits: must be a whole number from 0 "
                    "to 1000000000000 (the first frame tracked, 0-based)"),
    ("start", 10**12 + 1, "start 1000000000001: must be a whole number from 0 to "
                          "1000000000000 (the first frame tracked, 0-based)"),
    ("max_frames", HUGE, "max_frames an integer of more than 4000 digits: must be a whole "
                         "number from 1 to 1000000000000 (how many frames to track; None: to "
                         "the end)"),
    ("crf", HUGE, "crf an integer of more than 4000 digits: must be a whole number from 0 to "
                  "51 (the annotated video's x264 quality)"),
    ("crf", 52, "crf 52: must be a whole number from 0 to 51 (the annotated video's x264 "
                "quality)"),
    ("gt_origin", HUGE, "gt_origin an integer of more than 4000 digits: must be a whole number "
                        "from 0 to 1 (1: the ground truth's boxes are 1-based)"),
    ("gt_origin", 2, "gt_origin 2: must be a whole number from 0 to 1 (1: the ground truth's "
                     "boxes are 1-based)"),
], ids=["start-huge", "start-past", "max_frames-huge", "crf-huge", "crf-52", "gt_origin-huge",
        "gt_origin-2"])
def test_a_run_request_refuses_a_number_past_its_range_naming_the_field(
        field: str, value: int, said: str) -> None:
    """RunRequest(start=10**5000) was taken and vtrack.run.run of it raised 'ValueError:
    Exceeds the limit (4300 digits) for integer string conversion'; max_frames, crf and
    gt_origin the same (crf=52 or gt_origin=2 were taken, to fail as the video opened or the
    ground truth was read)."""
    with pytest.raises(ConfigError) as caught:
        vtrack.RunRequest(input="c.mp4", out_dir=Path("out"), config=vtrack.load_config("s0"),
                          **{field: value})
    assert str(caught.value) == said


@pytest.mark.parametrize(("option", "value"), [("--start", "9" * 5000), ("--frames", "9" * 5000),
                                               ("--start", str(10**12 + 1)),
                                               ("--frames", str(10**12 + 1))],
                         ids=["start-5000-digits", "frames-5000-digits", "start-past",
                              "frames-past"])
def test_a_frame_number_past_the_range_is_one_short_line_naming_the_option(
        tmp_path: Path, option: str, value: str) -> None:
    """``--frames 1000000000001`` was taken; ``--start`` of 5000 digits was refused with all
    5000 digits in its line."""
    scene = make_scene("smooth", seed=1, width=96, height=72, frames=10, fps=30.0)
    clip = write_video(scene, tmp_path / "c.mp4")
    result = vtrack_command("run", str(clip), "--init", "10,10,20,20", option, value,
                            "-o", str(tmp_path / "out"))
    line = assert_one_line_error(result, option, "at most 1000000000000" if option == "--start"
                                 else "from 1 to 1000000000000")
    assert len(line) < 400, line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("value", "got"), [
    ("robust_model.working_area=" + "9" * 5000, "in the range 32 to 250, got a 5000-digit "
                                                "integer"),
    ("robust_model.padding=" + "9" * 5000, "in the range 0.2 to 4, got a number beyond a "
                                           "float's range"),
    ("robust_model.padding=1e400", "in the range 0.2 to 4, got a number beyond a float's "
                                   "range"),
], ids=["int-5000-digits", "float-5000-digits", "float-1e400"])
def test_a_set_value_too_long_or_large_is_one_short_line_naming_the_parameter(
        tmp_path: Path, value: str, got: str) -> None:
    """``--set robust_model.working_area=`` 5000 nines was refused with all 5000 digits in its
    line (the assignment was echoed whole); a float of 5000 digits or 1e400 said 'got inf'."""
    scene = make_scene("smooth", seed=1, width=96, height=72, frames=10, fps=30.0)
    clip = write_video(scene, tmp_path / "c.mp4")
    result = vtrack_command("run", str(clip), "--init", "10,10,20,20", "--set", value,
                            "-o", str(tmp_path / "out"))
    line = assert_one_line_error(result, f"--set {value[:30]}", got)
    assert len(line) < 300, line


def test_numpy_numbers_in_a_run_request_are_kept_as_python_numbers() -> None:
    """NumPy numbers stayed NumPy in a RunRequest: RunRequest(..., start=np.int64(3)) kept an
    int64, and its to_dict() / differences() (batch's resume test) raised 'TypeError: Object
    of type int64 is not JSON serializable'."""
    config = vtrack.load_config("s0")
    request = vtrack.RunRequest(input="c.mp4", out_dir=Path("out"), config=config,
                                init_box=(np.float32(10), np.int64(10), 20, 20),
                                start=np.int64(3), max_frames=np.int32(5), crf=np.int64(20),
                                gt_origin=np.int8(1), seed=np.uint32(7), fps=np.float32(25),
                                start_s=np.float64(0.5), max_s=np.float32(2))
    plain = vtrack.RunRequest(input="c.mp4", out_dir=Path("out"), config=config,
                              init_box=(10, 10, 20, 20), start=3, max_frames=5, crf=20,
                              gt_origin=1, seed=7, fps=25.0, start_s=0.5, max_s=2.0)
    for field in ("start", "max_frames", "crf", "gt_origin", "seed"):
        assert type(getattr(request, field)) is int, field
    for field in ("fps", "start_s", "max_s"):
        assert type(getattr(request, field)) is float, field
    assert request.differences(plain.to_dict()) == []
    assert json.loads(json.dumps(request.to_dict())) == json.loads(json.dumps(plain.to_dict()))


def test_numpy_numbers_in_a_config_made_in_python_are_taken_as_python_values() -> None:
    """Config('mine', 'python', '', [('robust_model', {'working_area': np.int64(150)}), ...])
    said "python: stage 'robust_model': parameter 'working_area' must be an integer, got
    np.int64(150)", np.True_ for a true/false parameter the same, though a Tracker takes NumPy
    numbers; a NumPy float was taken but kept as np.float64 in the config's stages."""
    stages = [("robust_model", {"working_area": np.int64(150), "colour": np.True_,
                                "padding": np.float32(1.5), "lam": Fraction(1, 1000)}),
              ("robust_search", {"scales": np.uint8(17)}), ("robust_failure", {}),
              ("robust_motion", {})]
    config = vtrack.Config("mine", "python", "", stages)
    values = config.stages[0][1]
    assert values == {"working_area": 150, "colour": True, "padding": 1.5, "lam": 0.001}
    assert [type(v) for v in values.values()] == [int, bool, float, float]
    assert type(config.stages[1][1]["scales"]) is int
    json.dumps(config.stages)  # plain Python values
    with pytest.raises(ConfigError, match="parameter 'working_area' must be an integer in "
                                          "the range 32 to 250, got 150.0"):
        vtrack.Config("mine", "python", "", [("robust_model", {"working_area": np.float64(150)}),
                                             *stages[1:]])
    with pytest.raises(ConfigError, match="parameter 'colour' must be true or false, got 1"):
        vtrack.Config("mine", "python", "", [("robust_model", {"colour": np.int64(1)}),
                                             *stages[1:]])


def test_the_default_config_named_beside_a_run_request_is_refused_as_any_other(
        tmp_path: Path) -> None:
    """vtrack.track(request, "robust") tracked with the request's s0 without a word: "robust",
    the default, could not be told from no config given."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    request = vtrack.RunRequest(str(clip), tmp_path / "out", vtrack.load_config("s0"),
                                scene.boxes[0])
    for config in ("robust", vtrack.load_config("robust"), request.config):
        with pytest.raises(ConfigError, match=r"^config: the RunRequest carries its own; set it "
                           r"in the request \(dataclasses.replace\(request, ...\)\)$"):
            next(vtrack.track(request, config))
    assert len(list(vtrack.track(request))) == 10
    assert len(list(vtrack.track(request, config=None))) == 10


def test_a_config_cannot_be_changed_past_its_check() -> None:
    """A Config was a plain dataclass: config.name = "" or
    config.stages[0][1]["working_area"] = 10**6 (range 32 to 250) were taken after the check
    that refuses them when the Config is made, and the list given to Config(...) stayed its
    stages, so changing that list changed the config."""
    given = [("robust_model", {"working_area": 150}), ("robust_search", {}),
             ("robust_failure", {}), ("robust_motion", {})]
    config = vtrack.Config("mine", "python", "", given)
    with pytest.raises(AttributeError):
        config.name = ""  # type: ignore[misc]
    with pytest.raises(TypeError, match="^a Config's stage values are read-only"):
        config.stages[0][1]["working_area"] = 10**6
    with pytest.raises(TypeError, match="^a Config's stage values are read-only"):
        config.stages[0][1].update(working_area=10**6)
    with pytest.raises((TypeError, AttributeError)):
        config.stages.append(("kalman", {}))  # type: ignore[attr-defined]
    given[0][1]["working_area"] = 10**6
    assert config.stages[0][1]["working_area"] == 150
    changed = config.with_values({"robust_model.working_area": 200})
    assert (changed.stages[0][1]["working_area"], config.stages[0][1]["working_area"]) == (200, 150)
    assert pickle.loads(pickle.dumps(config)) == config  # (a Dask worker receives it)
    assert vtrack.Config(config.name, config.source, config.description, config.stages) == config


@pytest.mark.parametrize(("given", "said"), [
    ({"raw": RawFormat(HUGE, 2, "bgr24", 30.0)},
     "raw (width an integer of more than 4000 digits, height 2): larger than vtrack accepts "
     "(at most 16384x16384)"),
    ({"raw": RawFormat(-5, 2, "bgr24", 30.0)},
     "raw (width -5, height 2): width and height must be positive"),
    ({"raw": RawFormat(64, 48, "gray", 0.0)},
     "raw.fps 0: must be a frame rate from 0.01 to 10000 frames per second"),
    ({"raw": RawFormat(64, 48, "bogus", 30.0)},
     "raw.pix_fmt 'bogus': expected one of bgr24, rgb24, yuv420p, gray"),
    ({"ffmpeg": FFmpegInput(timeout_s=HUGE)},
     "ffmpeg.timeout_s an integer of more than 4000 digits: must be a time in seconds from 0.1 "
     "to 3600 (how long a network input may send nothing)"),
    ({"ffmpeg": FFmpegInput(timeout_s=1e308)},
     "ffmpeg.timeout_s 1e+308: must be a time in seconds from 0.1 to 3600 (how long a network "
     "input may send nothing)"),
    ({"ffmpeg": FFmpegInput(follow_s=HUGE)},
     "ffmpeg.follow_s an integer of more than 4000 digits: must be a time in seconds above 0 "
     "to 86400 (how long a file being written may not grow)"),
], ids=["raw-huge", "raw-negative", "raw-fps-0", "raw-pix_fmt", "timeout-huge", "timeout-1e308",
        "follow-huge"])
def test_a_run_requests_raw_format_and_input_waits_are_checked_as_the_options_are(
        given: dict, said: str) -> None:
    """RunRequest took any RawFormat and FFmpegInput: raw=RawFormat(10**5000, 2, ...) or
    RawFormat(-5, 2, ...) made vtrack.run.run raise 'ValueError: Maximum allowed dimension
    exceeded' / 'negative dimensions are not allowed', FFmpegInput(timeout_s=10**5000) or
    follow_s=10**5000 'ValueError: Exceeds the limit (4300 digits) for integer string
    conversion', and timeout_s=1e308 (past --timeout's 3600) or a raw rate of 0 were taken."""
    with pytest.raises(ConfigError) as caught:
        vtrack.RunRequest(input="-", out_dir=Path("out"), config=vtrack.load_config("s0"),
                          **given)
    assert str(caught.value) == said


@pytest.mark.parametrize(("ffmpeg", "said"), [
    (FFmpegInput(options={"probesize": "32"}),  # type: ignore[arg-type]
     'ffmpeg.options: expected (key, value) pairs of text, e.g. (("probesize", "32"),), got '
     "dict (a dict's: tuple(options.items()))"),
    (FFmpegInput(options=["probesize=32"]),  # type: ignore[list-item]
     'ffmpeg.options: expected (key, value) pairs of text, e.g. (("probesize", "32"),), got '
     "'probesize=32'"),
    (FFmpegInput(options=(("probesize", 32),)),  # type: ignore[arg-type]
     'ffmpeg.options: expected (key, value) pairs of text, e.g. (("probesize", "32"),), got '
     "('probesize', 32)"),
    (FFmpegInput(format=3),  # type: ignore[arg-type]
     "ffmpeg.format: expected a format name (text) or None, got int"),
], ids=["dict", "key=value", "number", "format-number"])
def test_ffmpeg_options_of_another_shape_are_one_type_error_naming_the_field(
        ffmpeg: FFmpegInput, said: str, tmp_path: Path) -> None:
    """FFmpegInput(options={"probesize": "32"}) (PyAV's av.open takes a dict) or
    ["probesize=32"] raised Python's own 'ValueError: too many values to unpack (expected 2)'
    from inside vtrack.open_source and RunRequest, a number for a value 'TypeError: expected
    string or bytes-like object, got 'int'', and format=3 was called '--format 3: not a format
    PyAV's FFmpeg reads', an option of a command never run."""
    clip = tmp_path / "clip.ts"
    clip.write_bytes(b"")
    with pytest.raises(TypeError) as caught:
        vtrack.open_source(clip, ffmpeg=ffmpeg)
    assert str(caught.value) == said
    with pytest.raises(TypeError) as caught:
        vtrack.RunRequest(input=str(clip), out_dir=tmp_path / "out",
                          config=vtrack.load_config("s0"), ffmpeg=ffmpeg)
    assert str(caught.value) == said
    pairs = FFmpegInput(options=[["probesize", "32"]]).checked()  # type: ignore[list-item]
    assert pairs.options == (("probesize", "32"),)


def test_open_source_checks_a_raw_format_made_in_python(tmp_path: Path) -> None:
    """vtrack.open_source('f.raw', RawFormat(-5, 2, 'bgr24', 30.0)) raised 'ValueError:
    negative dimensions are not allowed', a rate of 0 'ZeroDivisionError: float division by
    zero', and a pixel format vtrack has no reader for was taken."""
    path = tmp_path / "f.raw"
    path.write_bytes(bytes(64 * 48 * 3))
    for raw, said in ((RawFormat(-5, 2, "bgr24", 30.0), "raw (width -5, height 2): width and "
                                                         "height must be positive"),
                      (RawFormat(64, 48, "gray", 0.0), "raw.fps 0: must be a frame rate"),
                      (RawFormat(64, 48, "bogus", 30.0), "raw.pix_fmt 'bogus': expected one of")):
        with pytest.raises(ConfigError) as caught:
            vtrack.open_source(path, raw)
        assert str(caught.value).startswith(said)
    with vtrack.open_source(path, RawFormat(64, 48, "gray", 30.0)) as source:
        assert sum(1 for _ in source) == 3


def test_a_run_requests_paths_flags_and_preset_are_taken_as_a_user_gives_them(
        tmp_path: Path) -> None:
    """RunRequest(input=Path('clip.mp4'), ...) made vtrack.run.run raise "TypeError: argument
    of type 'PosixPath' is not iterable", out_dir='out' (text) "TypeError: unsupported operand
    type(s) for /: 'str' and 'str'"; video='no' wrote a video ('no' is true), live='yes' was
    taken, and preset='bogus' failed only as the video opened ('video encoder libx264 (preset
    'bogus', crf 23): Invalid argument')."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    config = vtrack.load_config("s0")
    request = vtrack.RunRequest(clip, str(tmp_path / "out"), config, scene.boxes[0],
                                gt_path=str(clip) + ".gt.txt", video=np.False_)
    assert (request.input, request.out_dir, request.gt_path) == (
        str(clip), tmp_path / "out", Path(str(clip) + ".gt.txt"))
    assert request.video is False
    summary = run(replace(request, gt_path=None))
    assert summary.status == "complete" and (tmp_path / "out" / "track.csv").is_file()
    assert not (tmp_path / "out" / "annotated.mp4").exists()
    for field, value, said in (
            ("video", "no", "video 'no': must be True or False (or the integers 1 or 0)"),
            ("live", "yes", "live 'yes': must be True or False (or the integers 1 or 0)"),
            ("preset", "bogus", "preset 'bogus': must be one of ultrafast, superfast, veryfast, "
                                "faster, fast, medium, slow, slower, veryslow, placebo (the "
                                "annotated video's x264 preset)")):
        with pytest.raises(ConfigError) as caught:
            replace(request, **{field: value})
        assert str(caught.value) == said
    for field, value in (("input", 5), ("out_dir", None), ("stream", 1)):
        with pytest.raises(TypeError, match=f"^{field}: expected "):
            replace(request, **{field: value})


def test_open_source_names_its_arguments_not_vtrack_runs_options(tmp_path: Path) -> None:
    """vtrack.open_source('z.raw', raw='160x120', live=True) said 'ConfigError --live: raw
    frames are read as they come ...', and ffmpeg=FFmpegInput(follow_s=1), format= or
    options= given where they cannot apply were called --follow, --format and
    --input-option: options of a command the caller never ran. Each now names the argument
    or field given (vtrack run's messages keep the options: tests/test_cli.py and others)."""
    raw = tmp_path / "z.raw"
    raw.write_bytes(bytes(160 * 120 * 3))
    url = "udp://127.0.0.1:9"
    cases = (
        (dict(spec=raw, raw="160x120", live=True),
         "live: raw frames are read as they come (a pipe holds the sender back); give a "
         "container (e.g. -f mpegts) to skip frames"),
        (dict(spec=url, ffmpeg=FFmpegInput(follow_s=1)),
         f"ffmpeg.follow_s reads a video file that is still being written; {url} is a stream, "
         "read until it ends (ffmpeg.timeout_s)"),
        (dict(spec=raw, raw="160x120", ffmpeg=FFmpegInput(format="mjpeg")),
         "ffmpeg.format is for inputs FFmpeg reads; raw input (raw=) is read as bare frames "
         "without it"),
        (dict(spec=raw, raw="160x120", ffmpeg=FFmpegInput(options=(("probesize", "32"),))),
         "ffmpeg.options is for inputs FFmpeg reads; raw input (raw=) is read as bare frames "
         "without it"),
    )
    for kwargs, message in cases:
        with pytest.raises(ConfigError) as refused:
            vtrack.open_source(**kwargs)
        assert str(refused.value) == message


def test_what_opening_a_video_refuses_names_the_library_arguments(tmp_path: Path) -> None:
    """vtrack.open_source (and vtrack.track) said what FFmpeg refused opening a video in
    vtrack run's words: FFmpegInput(format="nope") was '--format nope: not a format PyAV's
    FFmpeg reads (... need no --format)', options=(("nokey", "1"),) '--input-option nokey:
    FFmpeg did not use it ...', fflags=nobuffer '... or --live)', a .raw file '... raw frames
    are read only by vtrack run --raw WxH (with --pix-fmt, --fps)' and an empty followed file
    '... needs a longer --follow)': options of a command never run. They name the fields and
    arguments given; vtrack run keeps its options (tests/test_live_inputs.py and others)."""
    clip = write_video(make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30),
                       tmp_path / "clip.ts")
    raw = tmp_path / "z.raw"
    raw.write_bytes(bytes(96 * 72 * 3))
    empty = tmp_path / "empty.ts"
    empty.write_bytes(b"")
    cases = (
        (clip, FFmpegInput(format="nope"),
         "ffmpeg.format nope: not a format PyAV's FFmpeg reads (ffmpeg -formats lists them; "
         "capture devices /dev/videoN need no ffmpeg.format)"),
        (clip, FFmpegInput(options=(("nokey", "1"),)),
         f"ffmpeg.options nokey: FFmpeg did not use it opening {clip} (not an option of its "),
        (clip, FFmpegInput(options=(("fflags", "nobuffer"),)),
         f"ffmpeg.options fflags=nobuffer: FFmpeg drops the packets it reads probing {clip}, "
         "so its first frames would be lost; nobuffer is for live streams (rtsp://, udp:// "
         "..., or live=True)"),
        (raw, FFmpegInput(), f"{raw}: not a video FFmpeg can decode (Invalid argument); raw "
         "frames are read only by raw='WxH' (with pix_fmt, fps)"),
        (empty, FFmpegInput(follow_s=0.2),
         f"{empty}: stayed empty (0 bytes) for ffmpeg.follow_s's wait of 0.2 s: nothing was "
         "written to it (a writer that starts later, or holds its first bytes longer, needs "
         "a longer ffmpeg.follow_s)"),
    )
    for spec, ffmpeg, said in cases:
        with pytest.raises(InputError) as refused:
            vtrack.open_source(spec, ffmpeg=ffmpeg)
        assert str(refused.value).startswith(said), str(refused.value)
        assert "--" not in str(refused.value)


def test_library_messages_name_the_requests_fields_and_the_command_its_options(
        tmp_path: Path) -> None:
    """vtrack.run.run(RunRequest(init_box=(1e308, 1, 2, 3), ...)) said '--init: the box ...',
    and a bad frame rate in a request '--fps 0: ...' or '--fps: clip.mp4 is a video file ...;
    --fps applies to raw input (--raw WxH) ...': options of a command the caller never ran.
    The library names its fields (init_box, fps); vtrack run its options."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    folder = tmp_path / "seq"
    write_image_sequence(scene, folder)
    request = vtrack.RunRequest(clip, tmp_path / "out", vtrack.load_config("s0"),
                                (1e308, 1, 2, 3))
    cases = (
        (request, "init_box: the box 1e+308,1,2,3 is smaller than 4x4 pixels, too small to "
                  "track"),
        (replace(request, init_box=(1, 1, 9, 9), fps=25), "fps: " + str(clip) + " is a video "
         "file, whose frames carry their own timestamps; fps applies to raw input (raw=) and "
         "image folders only"),
        (replace(request, input=str(folder), init_box=(1, 1, 9, 9), fps=0),
         "fps 0: must be a frame rate from 0.01 to 10000 frames per second"),
        (replace(request, init_box=None, start=3),
         "start 3: this tracker needs the target's box in frame 3: give "
         "init_box=(x, y, w, h) or gt_path=FILE"),
        (replace(request, init_box=(1, 1, 9, 9), config=vtrack.load_config("s3")),
         "init_box: s3 finds its targets itself (it tracks several, each from where it is "
         "detected) and takes no first box; leave init_box out"),
    )
    for made, said in cases:
        with pytest.raises(ConfigError) as caught:
            run(made)
        assert str(caught.value) == said
        if made.fps is not None:  # vtrack.track of a request opens its input the same way
            with pytest.raises(ConfigError) as caught:
                list(vtrack.track(made))
            assert str(caught.value) == said
    assert not (tmp_path / "out").exists()
    for option, value, said in (
            ("--init", "1e308,1,2,3", "--init: the box 1e+308,1,2,3 is smaller than 4x4 "
                                      "pixels, too small to track"),
            ("--fps", "0", "--fps 0: must be a frame rate from 0.01 to 10000 frames per "
                           "second")):
        result = vtrack_command("run", str(folder), *(["--init", "1,1,9,9"] if option ==
                                                      "--fps" else []), option, value,
                                "-o", str(tmp_path / "cli"))
        assert_one_line_error(result, said)


def test_library_messages_name_start_gt_out_stream_and_overwrite_as_the_library_does(
        tmp_path: Path) -> None:
    """vtrack.run.run(RunRequest(start=50, ...)) said '--start 50: ...', and its other
    refusals '--gt FILE', '--stream F: ...', 'give --overwrite (-y) ..., or another --out':
    options of a command the caller never ran. The library names its fields and keywords
    (start, start_s, gt_path, stream, out_dir, overwrite=True); vtrack run keeps its options.
    So do the refusals met once the run opens its outputs, which said '--stream F: No such
    file or directory', '(--timeout)' and 'choose another --out' to the library too."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = scene.boxes[0]
    request = vtrack.RunRequest(clip, tmp_path / "out", vtrack.load_config("s0"), box,
                                video=False)
    earlier = replace(request, out_dir=tmp_path / "earlier", max_frames=2)
    assert run(earlier).status == "complete"
    filled = tmp_path / "rows.jsonl"
    filled.write_text("{}\n")
    report = tmp_path / "report"
    report.mkdir()
    for name in ("index.html", "summary.md"):  # what tells a vtrack report's folder
        (report / name).write_text("vtrack report\n")
    cases = (
        (replace(request, start=50), f"start 50: {clip}: has no frame 50 (frames 0..9)"),
        (replace(request, start_s=5), f"start_s 5: {clip}: has no frame at or after 5 s (its "
                                      "last frame is frame 9, at 0.3 s)"),
        (replace(request, init_box=None), "s0: this tracker needs an initial box: give "
         "gt_path=FILE, init_box=(x, y, w, h) or write x,y,w,h into "
         f"{tmp_path / 'clip.init.txt'} (vtrack select {shlex.quote(str(clip))} picks it)"),
        (replace(request, stream=str(clip)), f"stream {clip}: is the input of this run "
                                             f"({clip}); write the results elsewhere"),
        (replace(request, out_dir=report), f"{report}: is a vtrack report's folder "
         "(index.html); a run there would mix its files with the report's pages: choose "
         "another out_dir"),
    )
    for made, said in cases:
        with pytest.raises(vtrack.VtrackError) as caught:
            run(made)
        assert str(caught.value) == said
    with pytest.raises(vtrack.OutputError) as caught:
        run(earlier, overwrite=False)
    assert str(caught.value).endswith("; give overwrite=True to replace them, or another "
                                      "out_dir")
    with pytest.raises(vtrack.OutputError) as caught:
        run(replace(request, stream=str(filled)), overwrite=False)
    assert str(caught.value) == f"stream {filled}: holds 3 bytes already; overwrite=True " \
                                "replaces it"
    assert not (tmp_path / "out").exists()
    # The stream and the output folder refused once the run opens them: named as given too.
    fifo = tmp_path / "lines"
    os.mkfifo(fifo)
    no_dir = tmp_path / "no" / "s.jsonl"
    shelved = tmp_path / "shelved"
    (shelved / "track.csv").mkdir(parents=True)
    held = tmp_path / "held"
    held.mkdir()
    opened = (
        (replace(request, stream=str(no_dir)), f"stream {no_dir}: No such file or directory"),
        (replace(request, stream=str(fifo), ffmpeg=FFmpegInput(timeout_s=1)),
         f"stream {fifo}: a FIFO that no reader opened within 1 s (ffmpeg.timeout_s)"),
        (replace(request, out_dir=shelved), f"{shelved / 'track.csv'}: is a folder, where "
         "vtrack writes a file; move it away or choose another out_dir"))
    for made, said in opened:
        with pytest.raises(vtrack.OutputError) as caught:
            run(made)
        assert str(caught.value) == said
    with (held / ".vtrack.lock").open("w") as lock:  # another vtrack's lock on the folder
        fcntl.flock(lock, fcntl.LOCK_EX)
        with pytest.raises(vtrack.OutputError) as caught:
            run(replace(request, out_dir=held))
        assert str(caught.value).endswith("; wait for it to finish or choose another out_dir")
        result = vtrack_command("run", str(clip), "-c", "s0", "--init", box.text(), "-o",
                                str(held))
        assert result.stderr.decode().strip().endswith(
            "; wait for it to finish or choose another --out")
    for options, said in (
            (["--start", "50"], f"--start 50: {clip}: has no frame 50 (frames 0..9)"),
            (["--start", "5s"], f"--start 5s: {clip}: has no frame at or after 5 s (its last "
                                "frame is frame 9, at 0.3 s)"),
            (["--stream", str(filled)], f"--stream {filled}: holds 3 bytes already; "
                                        "--overwrite (-y) replaces it"),
            (["--stream", str(no_dir)], f"--stream {no_dir}: No such file or directory"),
            (["-o", str(shelved)], f"{shelved / 'track.csv'}: is a folder, where vtrack "
                                   "writes a file; move it away or choose another --out")):
        result = vtrack_command("run", str(clip), "-c", "s0", "--init", box.text(), "-o",
                                str(tmp_path / "cli"), *options)
        assert_one_line_error(result, said)
    result = vtrack_command("run", str(clip), "-c", "s0", "--start", "3", "-o",
                            str(tmp_path / "cli"))
    assert_one_line_error(result, "--start 3: this tracker needs the target's box in frame 3: "
                                  "give --init x,y,w,h or --gt FILE")


def test_every_x264_preset_makes_the_annotated_video_of_a_request_and_of_vtrack_run(
        tmp_path: Path) -> None:
    """RunRequest(preset='slower') (veryslow, placebo) was refused ('must be one of ultrafast,
    ..., slow') though it made the annotated video before the field was checked; the library
    and ``vtrack run --preset`` take every x264 preset (an offline file's video can be slow)."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    request = vtrack.RunRequest(clip, tmp_path / "lib", vtrack.load_config("s0"),
                                scene.boxes[0], max_frames=3, preset="slower")
    assert run(request).status == "complete"
    assert (tmp_path / "lib" / "annotated.mp4").stat().st_size > 0
    result = vtrack_command("run", str(clip), "--config", "s0", "--init",
                            ",".join(map(str, scene.boxes[0])), "--frames", "3", "--preset",
                            "placebo", "--out", str(tmp_path / "cli"))
    assert result.returncode == 0, result.stderr.decode()
    assert (tmp_path / "cli" / "annotated.mp4").stat().st_size > 0


def test_a_run_requests_stream_path_and_flags_written_1_or_0_are_taken(tmp_path: Path) -> None:
    """RunRequest(stream=Path('s.jsonl')) raised "TypeError: stream: expected text or None, got
    PosixPath", and video=0 or live=1 "ConfigError: video 0: must be True or False": both were
    taken before the fields were checked. A path is kept as its text; 1 and 0 (NumPy's too)
    are True and False, 2 is refused."""
    scene = make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    request = vtrack.RunRequest(clip, tmp_path / "out", vtrack.load_config("s0"),
                                scene.boxes[0], max_frames=3, stream=tmp_path / "s.jsonl",
                                video=0, live=np.int64(0))
    assert (request.stream, request.video, request.live) == (str(tmp_path / "s.jsonl"), False,
                                                             False)
    assert run(request).status == "complete"
    assert len((tmp_path / "s.jsonl").read_text().splitlines()) == 3
    assert not (tmp_path / "out" / "annotated.mp4").exists()
    assert (replace(request, video=1).video, replace(request, live=1).live) == (True, True)
    with pytest.raises(ConfigError, match=r"^video 2: must be True or False \(or the integers 1 "
                                          r"or 0\)$"):
        replace(request, video=2)


@pytest.mark.parametrize("value", [np.array([150]), np.array([[150]]), np.array([150, 151]),
                                   np.zeros((300, 300))])
def test_a_numpy_array_as_a_parameter_is_refused_by_its_shape(value: np.ndarray) -> None:
    """A NumPy array went through .item(): np.array([150]) and [[150]] were taken silently as
    150, and a multi-element array raised "ValueError: can only convert an array of size 1 to a
    Python scalar". Only a NumPy scalar or a 0-d array is a value; an array is refused in one
    line naming its shape."""
    rest = [("robust_search", {}), ("robust_failure", {}), ("robust_motion", {})]
    with pytest.raises(ConfigError) as caught:
        vtrack.Config("mine", "python", "", [("robust_model", {"working_area": value}), *rest])
    assert str(caught.value) == ("python: stage 'robust_model': parameter 'working_area' must "
                                 "be an integer in the range 32 to 250, got a NumPy array of "
                                 f"shape {value.shape}")
    with pytest.raises(ConfigError, match=r"got a NumPy array of shape"):
        vtrack.Tracker("robust", **{"robust_model.working_area": value})
    zero_d = vtrack.Config("mine", "python", "",
                           [("robust_model", {"working_area": np.array(150)}), *rest])
    assert type(zero_d.stages[0][1]["working_area"]) is int


@pytest.mark.parametrize(("ffmpeg", "said"), [
    (FFmpegInput(follow_s=float("nan")), "ffmpeg.follow_s nan: must be a time in seconds above "
                                         "0 to "),
    (FFmpegInput(follow_s=HUGE), "ffmpeg.follow_s an integer of more than 4000 digits: "),
    (FFmpegInput(follow_s=0), "ffmpeg.follow_s 0: must be a time in seconds above 0 to "),
    (FFmpegInput(timeout_s=-1), "ffmpeg.timeout_s -1: must be a time in seconds from 0.1 to "),
])
def test_open_source_checks_an_ffmpeg_input_made_in_python(tmp_path: Path, ffmpeg: FFmpegInput,
                                                           said: str) -> None:
    """vtrack.open_source('a.mp4', ffmpeg=FFmpegInput(follow_s=float('nan'))) took the input
    unchecked and reading it never ended (follow_s=10**5000 too; timeout_s=-1 and follow_s=0
    were taken): its waits are checked as a RunRequest's are."""
    clip = write_video(make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30),
                       tmp_path / "clip.mp4")
    with pytest.raises(ConfigError) as caught:
        vtrack.open_source(clip, ffmpeg=ffmpeg)
    assert str(caught.value).startswith(said)
    with pytest.raises(TypeError, match="^ffmpeg: expected a vtrack.io.video.FFmpegInput, got "
                                        "str$"):
        vtrack.open_source(clip, ffmpeg="-f mp4")
    with vtrack.open_source(clip, ffmpeg=FFmpegInput(follow_s=0.5)) as source:
        assert sum(1 for _ in source) == 10


def test_open_source_takes_ffmpeg_none_as_the_default(tmp_path: Path) -> None:
    """vtrack.open_source(clip, ffmpeg=None) was a TypeError ("ffmpeg: expected a
    vtrack.io.video.FFmpegInput, got NoneType") though vtrack.io.open_source declares
    ffmpeg=None its default: None is FFmpeg's default way of reading."""
    clip = write_video(make_scene("smooth", seed=4, width=96, height=72, frames=10, fps=30),
                       tmp_path / "clip.mp4")
    with vtrack.open_source(clip, ffmpeg=None) as source:
        assert sum(1 for _ in source) == 10


def test_a_raw_size_over_the_limit_is_named_once() -> None:
    """vtrack run - --raw 50000x50000 said "--raw '50000x50000': the frames are 50000x50000;
    vtrack accepts at most 16384x16384", the size twice (a RawFormat of 10**5000 x 2: "the
    frames are an integer of more than 4000 digitsx2")."""
    result = vtrack_command("run", "-", "--raw", "50000x50000", stdin=b"")
    assert assert_one_line_error(result) == ("vtrack: error: --raw '50000x50000': larger than "
                                             "vtrack accepts (at most 16384x16384)")


def test_a_long_or_non_text_parameter_key_is_named_short() -> None:
    """with_values({'robust_model.' + 'y' * 5000: 1}) and Tracker(**{that: 1}) said the key
    whole (a 5299-character ConfigError), and with_values({5: 1}) raised "AttributeError: 'int'
    object has no attribute 'strip'"."""
    config = vtrack.load_config("robust")
    key = "robust_model." + "y" * 5000
    for make in (lambda: config.with_values({key: 1}), lambda: vtrack.Tracker("robust",
                                                                           **{key: 1})):
        with pytest.raises(ConfigError) as caught:
            make()
        assert str(caught.value).startswith("robust_model.yyy")
        assert "...yyy" in str(caught.value) and len(str(caught.value)) < 500
    with pytest.raises(TypeError, match=r"^key 5: expected text, 'stage.param', got int$"):
        config.with_values({5: 1})


def test_a_time_past_a_year_names_the_year_in_seconds_written_out() -> None:
    """--start 1e9s said 'a time in seconds (2.5s, at most 3.16224e+07s)' and
    RunRequest(start_s=1e9) 'from 0 to 3.16224e+07 (a year)': a bound written as no user would
    write it."""
    for option in ("--start", "--frames"):
        error = assert_one_line_error(vtrack_command("run", "x.mp4", option, "1e9s"))
        assert "at most 31622400s)" in error


def test_a_config_and_a_run_request_are_hashable_equal_ones_alike(tmp_path: Path) -> None:
    """hash(load_config('robust')) raised "TypeError: unhashable type: 'StageValues'" though a
    Config is a frozen dataclass that cannot change (a RunRequest the same): a set or a dict
    key of configs failed."""
    robust = vtrack.load_config("robust")
    assert hash(robust) == hash(vtrack.load_config("robust"))
    changed = robust.with_values({"robust_model.working_area": 200})
    assert len({robust, vtrack.load_config("robust"), changed, vtrack.load_config("s0")}) == 3
    reordered = vtrack.Config(changed.name, changed.source, changed.description,
                              [(name, dict(reversed(list(values.items()))))
                               for name, values in changed.stages])
    assert reordered == changed and hash(reordered) == hash(changed)
    request = vtrack.RunRequest("a.mp4", tmp_path / "out", robust)
    assert hash(request) == hash(replace(request, config=vtrack.load_config("robust")))


def _python_numbers(result: vtrack.FrameResult) -> list[str]:
    """Where ``result``'s box, prediction, score and tracks hold something else than a Python
    float (an id than a Python int)."""
    found = [f"{name}.{field} {type(value).__name__}"
             for name, box in (("box", result.box), ("prediction", result.prediction))
             if box is not None for field, value in zip(box._fields, box, strict=True)
             if type(value) is not float]
    found += [] if type(result.score) is float else [f"score {type(result.score).__name__}"]
    for track in result.tracks:
        found += [f"track {track.id} box {type(v).__name__}" for v in track.box
                  if type(v) is not float]
        found += [] if type(track.id) is int else [f"track id {type(track.id).__name__}"]
    return found


@pytest.mark.parametrize("config", sorted(shipped_configs()))
def test_every_configs_results_hold_python_numbers(config: str) -> None:
    """s2's FrameResult.box held np.float64 x and y (robust's too after an occlusion) where
    every other config gave Python floats: `type(result.box.x)` depended on the config. Every
    shipped config's results now hold Python floats (and track ids Python ints), through
    vtrack.track and Tracker alike."""
    multi = vtrack.Tracker(config).multi_target
    scene = make_scene("multi" if multi else "occlusion", width=160, height=120, frames=90)
    frames = list(scene.as_frames())
    first = None if multi else scene.boxes[0]
    results = list(vtrack.track(frames, config, first))
    assert [(r.index, _python_numbers(r)) for r in results if _python_numbers(r)] == []
    tracker = vtrack.Tracker(config)
    stepped = [tracker.init(frames[0], first) if first else tracker.update(frames[0])]
    stepped += [tracker.update(frame) for frame in frames[1:]]
    assert [(r.index, _python_numbers(r)) for r in stepped if _python_numbers(r)] == []


def test_fixed_cameras_tracks_hold_python_numbers_in_a_crowd() -> None:
    """fixed_camera's tracks held np.float64 box x and y (its ByteTrack boxes centred on the
    Kalman state) from frame 10 of a 320x240 'pedestrians' scene (seed 4), where the 160x120
    'multi' scene of the test above happens to give Python floats: every track's id is now a
    Python int and its box and confidence Python floats, as the result's own box."""
    scene = make_scene("pedestrians", seed=4, width=320, height=240, frames=60)
    results = list(vtrack.track(list(scene.as_frames()), "fixed_camera"))
    assert sum(len(r.tracks) for r in results) > 0
    assert [(r.index, _python_numbers(r)) for r in results if _python_numbers(r)] == []
    assert all(type(t.confidence) is float for r in results for t in r.tracks)


def test_a_tracks_plain_copy_holds_python_numbers_and_leaves_the_track() -> None:
    """Track.plain() (what a result's tracks are made with, beside Box.plain()): the id a
    Python int, the box and confidence Python floats of the same values, the state kept, the
    track itself unchanged."""
    from vtrack.geometry import Box
    from vtrack.stages.base import Track, TrackStatus

    state = next(iter(TrackStatus))
    track = Track(np.int64(7), Box(np.float32(1.5), np.float64(2), 3, np.float32(4.25)),
                  np.float32(0.5), state)
    plain = track.plain()
    assert plain == Track(7, Box(1.5, 2.0, 3.0, 4.25), 0.5, state) and plain is not track
    assert type(plain.id) is int and type(plain.confidence) is float
    assert {type(v) for v in (plain.box.x, plain.box.y, plain.box.w, plain.box.h)} == {float}
    assert type(track.id) is np.int64 and type(track.box.x) is np.float32


def test_a_frames_number_and_time_are_python_numbers_whatever_they_were_given_as() -> None:
    """vtrack.BgrFrame(np.uint8(254), 254 / 30, image) kept its np.uint8 index: the images given
    to Tracker.update after it were numbered 255, then 0, 1 (uint8 wrapping, with NumPy's
    overflow warning), and results held np.int64 / np.float32 numbers json.dumps refuses; a
    Decimal time_s raised "TypeError: unsupported operand type(s) for +: 'decimal.Decimal'
    and 'float'" at the next image; time_s=True was taken as a time. A frame's index and
    time are now a Python int and float, and True is refused."""
    image = np.zeros((120, 160, 3), np.uint8)
    image[40:80, 60:100] = (0, 0, 255)
    tracker = vtrack.Tracker("s0")
    first = tracker.init(vtrack.BgrFrame(np.uint8(254), np.float32(254 / 30), image),
                         (60, 40, 40, 40))
    results = [first, *(tracker.update(image) for _ in range(2))]
    assert [r.index for r in results] == [254, 255, 256]
    assert all(type(r.index) is int and type(r.time_s) is float for r in results)
    json.dumps([(r.index, r.time_s) for r in results])
    tracker.init(vtrack.BgrFrame(3, Decimal("0.1"), image), (60, 40, 40, 40))
    assert tracker.update(image).time_s == pytest.approx(0.1 + 1 / 30)
    with pytest.raises(TypeError, match=r"^frame 3: time_s True is not a number$"):
        vtrack.BgrFrame(3, True, image)


def test_a_frames_time_of_another_type_is_a_type_error_its_value_shortened() -> None:
    """vtrack.BgrFrame(3, "0.1", image) raised ValueError (a wrong index type: TypeError) and
    a 10,000-character string was echoed whole in the message; a time that is no number is
    now a TypeError showing the value cut short, NaN and infinity still a ValueError."""
    image = np.zeros((120, 160, 3), np.uint8)
    with pytest.raises(TypeError, match=r"^frame 3: time_s '0\.1' is not a number$"):
        vtrack.BgrFrame(3, "0.1", image)
    with pytest.raises(TypeError, match=r"^frame 3: time_s None is not a number$"):
        vtrack.GrayFrame(3, None, image[:, :, 0])
    with pytest.raises(TypeError) as refused:
        vtrack.BgrFrame(3, "x" * 10_000, image)
    assert re.fullmatch(r"frame 3: time_s 'x+\.\.\.x+' is not a number", str(refused.value))
    assert len(str(refused.value)) < 150
    with pytest.raises(ValueError, match=r"^frame 3: time_s inf is not a finite number$"):
        vtrack.BgrFrame(3, float("inf"), image)


def test_a_container_given_to_open_source_as_raw_frames_is_told_by_raw_not_the_option(
        tmp_path: Path) -> None:
    """vtrack.open_source("clip.mp4", raw="160x120") (and vtrack.track of a RunRequest with a
    raw format) said 'clip.mp4: an MP4/QuickTime file, not raw frames: read it without --raw',
    an option of vtrack run the caller never gave; it now names the argument, raw=, as the
    library's other messages do (vtrack run's still says --raw)."""
    scene = make_scene("smooth", width=160, height=120, frames=10)
    clip = write_video(scene, tmp_path / "clip.mp4")
    with pytest.raises(vtrack.InputError) as refused:
        vtrack.open_source(str(clip), raw="160x120")
    assert str(refused.value) == (f"{clip}: an MP4/QuickTime file, not raw frames: read it "
                                  "without raw= (its frames carry their own size and pixel "
                                  "format)")


@pytest.mark.parametrize("values", [None, [("kalman.model", "ca")], "kalman.model=ca"])
def test_config_with_values_refuses_what_is_no_dict_naming_it(values: object) -> None:
    """Config.with_values(None) raised Python's "'NoneType' object is not iterable", a list
    of pairs "key ('kalman.model', 'ca'): expected text, 'stage.param', got tuple" (as if one
    key were wrong) and a --set-like string "'str' object has no attribute 'items'". Each is
    now a TypeError saying a dict was expected and showing what was given."""
    with pytest.raises(TypeError) as refused:
        vtrack.load_config("s0").with_values(values)  # type: ignore[arg-type]
    assert str(refused.value) == ("with_values: expected a dict {'stage.param': value}, got "
                                  f"{values!r}")
