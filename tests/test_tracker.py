"""``vtrack.Tracker`` (init/update/reset) gives what ``vtrack run`` writes, for every config."""

from __future__ import annotations

import csv
from pathlib import Path

import av
import numpy as np
import pytest

import vtrack
from vtrack.config import shipped_configs
from vtrack.errors import ConfigError, InputError
from vtrack.io.csvfile import DECIMALS, format_cell
from vtrack.io.raw import RawFormat
from vtrack.run import run
from vtrack.scenes import make_scene, write_raw


def _cells(columns: list[str], values: list[object]) -> list[str]:
    return [format_cell(v, DECIMALS.get(c, 3)) for c, v in zip(columns, values, strict=True)]


@pytest.mark.parametrize("name", sorted(shipped_configs()))
def test_tracker_results_equal_run_csv(tmp_path: Path, name: str) -> None:
    """Frame by frame through ``Tracker.init``/``update`` on NumPy BGR images, the same box,
    state, score and extras as the CSV that ``vtrack run`` writes for those frames."""
    detecting = name in ("s3", "s4", "s4_multi")
    frames = 60 if detecting else 24  # the multi scene's shortest
    scene = make_scene("multi" if detecting else "smooth", seed=3, width=160, height=120,
                       frames=frames, fps=30)
    raw = write_raw(scene, tmp_path / "clip.bgr")
    config = vtrack.load_config(name)
    tracker = vtrack.Tracker(name)
    # a multi-target config finds its targets itself and refuses a first box
    init = None if detecting or tracker.multi_target else scene.boxes[0]
    run(vtrack.RunRequest(str(raw), tmp_path / "out", config, init_box=init, video=False,
                          raw=RawFormat(160, 120, "bgr24", 30.0)))
    results = [tracker.init(frame, init) if i == 0 else tracker.update(frame)
               for i, frame in enumerate(scene.frames())]
    assert all(r.frame is None for r in results)  # no decoded frame is kept
    multi = (tmp_path / "out" / "tracks.csv").exists()
    with (tmp_path / "out" / ("tracks.csv" if multi else "track.csv")).open() as f:
        reader = csv.reader(f)
        header = next(reader)
        rows = list(reader)
    mine = []
    for r in results:
        if multi:
            mine += [_cells(header, [r.index + 1, t.id, t.box.x, t.box.y, t.box.w, t.box.h,
                                     t.confidence, -1, -1, -1, t.state])
                     for t in r.tracks if t.state == "confirmed"]
        else:
            geometry = [None] * 6 if r.box is None else [*r.box, r.box.cx, r.box.cy]
            extras = [r.extras.get(c) for c in header[12:]]
            mine.append(_cells(header, [r.index, r.time_s, *geometry, r.state, r.score,
                                        None, None, *extras]))
    assert len(rows) == (len(mine) if multi else frames) and rows
    assert mine == rows


def test_tracker_takes_av_frames_grey_and_resets(tmp_path: Path) -> None:
    """``av.VideoFrame``s give the track their BGR arrays give; ``reset`` then ``init`` starts
    afresh (the same results again); params override the config like ``--set``."""
    scene = make_scene("smooth", seed=5, width=160, height=120, frames=12, fps=30)
    images = list(scene.frames())
    tracker = vtrack.Tracker("s0", meanshift__iterations=3)
    first = [tracker.init(f, scene.boxes[0]) if i == 0 else tracker.update(f)
             for i, f in enumerate(images)]
    tracker.reset()
    av_frames = [av.VideoFrame.from_ndarray(f, format="bgr24") for f in images]
    again = [tracker.init(f, scene.boxes[0]) if i == 0 else tracker.update(f)
             for i, f in enumerate(av_frames)]
    assert [(r.index, r.box, r.state, r.score) for r in first] == \
        [(r.index, r.box, r.state, r.score) for r in again]
    assert first[0].box == vtrack.Box(*scene.boxes[0])
    other = vtrack.Tracker("s0")
    default = [other.init(f, scene.boxes[0]) if i == 0 else other.update(f)
               for i, f in enumerate(images)]
    assert tracker.config.resolved() != other.config.resolved()
    assert len(default) == 12
    kept = vtrack.Tracker("s2", keep_frames=True)
    grey = np.ascontiguousarray(images[0][:, :, 1])
    assert kept.init(grey, scene.boxes[0]).frame is not None
    with pytest.raises(TypeError, match="frame 1"):
        kept.update([1, 2, 3])


def test_tracker_without_a_box_is_refused_for_a_box_config() -> None:
    with pytest.raises(ConfigError, match="needs the target.s box first"):
        vtrack.Tracker("robust").update(np.zeros((48, 64, 3), np.uint8))


@pytest.mark.parametrize("config", ["s3", "s4_multi", "fixed_camera"])
def test_a_first_box_is_refused_by_a_config_that_finds_its_targets(config: str) -> None:
    """``Tracker(config).init(frame, box)`` took the box and ignored it (vtrack run refuses
    --init for these configs); without a box the same call starts the tracker."""
    frame = np.zeros((48, 64, 3), np.uint8)
    tracker = vtrack.Tracker(config)
    with pytest.raises(ConfigError, match=f"^{config} finds its targets itself .* call "
                       r"init\(frame\) without a box"):
        tracker.init(frame, (1, 1, 8, 8))
    assert tracker.init(frame).tracks == []
    assert list(vtrack.track([frame, frame], config=config))[1].tracks == []
    with pytest.raises(ConfigError, match="finds its targets itself"):
        list(vtrack.track([frame], config=config, init_box=(1, 1, 8, 8)))


@pytest.mark.parametrize("frames", [[np.zeros((48, 64, 3), np.uint8)], "no-such-clip.mp4"])
def test_vtrack_track_refuses_a_first_box_naming_its_own_argument(frames: object) -> None:
    """`vtrack.track("m.mp4", "s3", init_box=box)` said "... takes no first box; call
    init(frame) without a box, or update(frame)": Tracker's advice, for a function with no
    init(). It now names its own argument, before any input is opened."""
    with pytest.raises(ConfigError) as refused:
        list(vtrack.track(frames, config="s3", init_box=(1, 1, 8, 8)))
    assert str(refused.value) == (
        "init_box: s3 finds its targets itself (it tracks several, each from where it is "
        "detected) and takes no first box; leave init_box out")


def _frames(count: int = 3) -> list[np.ndarray]:
    """A red block on black, ``count`` frames of 160x120."""
    frames = [np.zeros((120, 160, 3), np.uint8) for _ in range(count)]
    for frame in frames:
        frame[40:70, 50:90] = (0, 0, 255)
    return frames


@pytest.mark.parametrize(("box", "problem"), [
    ((0, 0, 1e9, 1e9), "larger than the 160x120 frame"),  # s2 once took ~24 GB on this box
    ((0, 0, 200, 150), "larger than the 160x120 frame"),
    ((50, 40, 1, 1), "smaller than 4x4"),
    ((float("nan"), 40, 40, 30), "not a finite number"),
    ((50, 40, float("inf"), 30), "not a finite number"),
    ((500, 400, 20, 20), "outside the 160x120 frame"),
])
@pytest.mark.parametrize("config", ["s0", "s1", "s2"])
def test_the_api_refuses_the_boxes_vtrack_run_refuses(config: str, box: tuple, problem: str
                                                      ) -> None:
    with pytest.raises(ConfigError, match=f"init_box: .*{problem}"):
        list(vtrack.track(_frames(), config, box))


def test_the_api_refuses_a_number_too_large_for_a_box() -> None:
    with pytest.raises(ConfigError, match=r"init_box: \(an integer of 401 digits, 0, 4, 4\): a "
                                          r"number beyond a float.s range"):
        vtrack.Tracker("s0").init(_frames()[0], (10**400, 0, 4, 4))


@pytest.mark.parametrize("seed", [-1, 2**32, 1.5, "a", True])
def test_a_seed_outside_its_range_is_a_config_error(seed: object) -> None:
    with pytest.raises(ConfigError, match="seed .*: must be a whole number from 0 to 4294967295"):
        vtrack.Tracker("s1", seed=seed)  # type: ignore[arg-type]


def test_a_numpy_seed_is_a_seed() -> None:
    results = list(vtrack.track(_frames(), "s1", (50, 40, 40, 30), seed=np.int64(7)))
    assert results[-1].box is not None


@pytest.mark.parametrize("fps", [0, -5, 1e200, 1e-300, float("nan"), "30"])
def test_a_frame_rate_outside_its_range_is_a_config_error(fps: object) -> None:
    with pytest.raises(ConfigError, match="fps .*: must be a frame rate from 0.01 to 10000"):
        vtrack.Tracker("s2", fps=fps)  # type: ignore[arg-type]


@pytest.mark.parametrize("config", ["s4", "s4_multi", "s0"])
def test_a_frame_of_another_size_mid_sequence_is_refused(config: str) -> None:
    frames = _frames()
    tracker = vtrack.Tracker(config)
    if tracker.multi_target or config == "s4":
        tracker.update(frames[0])
    else:
        tracker.init(frames[0], (50, 40, 40, 30))
    tracker.update(frames[1])
    with pytest.raises(InputError,
                       match="frame 2: 80x60 colour, the first frame was 160x120 colour"):
        tracker.update(np.zeros((60, 80, 3), np.uint8))
    with pytest.raises(InputError, match="160x120 grey, the first frame"):
        tracker.update(np.zeros((120, 160), np.uint8))
    tracker.reset()  # another sequence starts afresh
    if tracker.multi_target or config == "s4":
        assert tracker.update(np.zeros((60, 80, 3), np.uint8)).index == 0  # any size now
    else:
        assert tracker.init(_frames()[0], (50, 40, 40, 30)).index == 0


def test_keyword_parameters_take_python_and_numpy_values_as_a_config_file_does() -> None:
    """A text value (``kalman__model="ca"``) was quoted and refused, a NumPy integer too."""
    tracker = vtrack.Tracker("s0", kalman__model="ca", meanshift__iterations=np.int64(7),
                             **{"occlusion.threshold": np.float32(0.25)})
    values = dict(tracker.config.stages)
    assert values["kalman"]["model"] == "ca" and values["meanshift"]["iterations"] == 7
    assert values["occlusion"]["threshold"] == pytest.approx(0.25)
    with pytest.raises(ConfigError, match="'model' must be one of 'cv', 'ca', 'gravity', got 'zz'"):
        vtrack.Tracker("s0", kalman__model="zz")
    with pytest.raises(ConfigError, match="'iterations' must be an integer in the range 1 to 100, "
                                          "got '7'"):
        vtrack.Tracker("s0", meanshift__iterations="7")
    assert vtrack.Tracker(None).config.name == vtrack.load_config(None).name


def test_a_tracker_whose_first_frame_failed_is_not_started() -> None:
    """After ``init`` raised on its frame, ``update`` met half-started stages (AttributeError)."""
    tracker = vtrack.Tracker("s0")
    grey_black = np.zeros((120, 160, 3), np.uint8)
    with pytest.raises(InputError, match="no pixel of the initial box"):
        tracker.init(grey_black, (10, 10, 20, 20))
    with pytest.raises(ConfigError, match=r"s0: this tracker needs the target's box first: "
                       r"call init\(frame, \(x, y, w, h\)\)"):  # not a command-line flag
        tracker.update(grey_black)
    coloured = grey_black.copy()
    coloured[40:60, 50:80] = (0, 0, 230)
    assert tracker.init(coloured, (50, 40, 30, 20)).index == 0  # starts afresh


@pytest.mark.parametrize("config", ["s3", "s4", "s4_multi", "fixed_camera", "robust"])
@pytest.mark.parametrize("shape", [(0, 0), (10, 0), (0, 10, 3)])
def test_an_empty_image_is_refused_by_every_config(config: str, shape: tuple[int, ...]) -> None:
    """The detecting configs raised OpenCV's own error (``!_src0.empty()`` in medianBlur)."""
    tracker = vtrack.Tracker(config)
    with pytest.raises(ValueError, match=r"frame 0: the frame size \d+x\d+ is empty"):
        if tracker.multi_target:
            tracker.update(np.zeros(shape, np.uint8))
        else:
            tracker.init(np.zeros(shape, np.uint8), (0, 0, 4, 4))


def test_a_pyav_frame_of_phone_footage_is_turned_as_vtrack_run_turns_it(tmp_path) -> None:
    """A 320x240 clip marked rotated by 90 degrees: vtrack run tracks a 240x320 picture, the
    API took the stored 320x240 one and refused the box that run accepts."""
    from test_io import pictures, write_video

    clip = write_video(tmp_path / "phone.mp4", pictures(3, 320, 240), rotation=90)
    with av.open(str(clip)) as container:
        first = next(container.decode(video=0))
    tracker = vtrack.Tracker("robust")
    result = tracker.init(first, (100, 270, 40, 30))  # inside 240x320 only
    assert result.box == (100, 270, 40, 30) and result.state.value == "tracking"
    with pytest.raises(ConfigError, match="outside the 240x320 frame"):
        tracker.init(first, (250, 10, 40, 30))  # inside the stored 320x240 only


def test_images_after_a_frame_numbered_by_the_camera_are_numbered_on_from_it() -> None:
    """A camera that dropped frames 4..6 gives frame 7 as a BgrFrame numbered 7 and the next
    ones as images: they were numbered 5, 6, 7 (the count of frames given), back in time after 7,
    so the track's numbers and times ran backwards and S0's Kalman filter ignored the time."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=12, fps=30)
    images = list(scene.frames())
    kept = [0, 1, 2, 3, 7, 8, 9, 10]
    mixed = vtrack.Tracker("s0")
    given = [images[i] if i != 7 else vtrack.BgrFrame(7, 7 / 30, images[7]) for i in kept]
    got = [mixed.init(f, scene.boxes[0]) if n == 0 else mixed.update(f)
           for n, f in enumerate(given)]
    assert [r.index for r in got] == kept
    assert [r.time_s for r in got] == [i / 30 for i in kept]
    numbered = vtrack.Tracker("s0")  # every frame numbered by the caller
    frames = [vtrack.BgrFrame(i, i / 30, images[i]) for i in kept]
    want = [numbered.init(f, scene.boxes[0]) if n == 0 else numbered.update(f)
            for n, f in enumerate(frames)]
    assert [(r.box, r.state, r.score) for r in got] == [(r.box, r.state, r.score) for r in want]


@pytest.mark.parametrize("pix_fmt", ["bgr24", "yuv420p"])
def test_kept_frames_keep_their_own_pixels(tmp_path: Path, pix_fmt: str) -> None:
    """``keep_frames=True`` kept a raw input's frame in the reader's ring of buffers, refilled
    with later frames (143 of a 150-frame clip's kept frames showed another frame's pixels),
    and a camera's array refilled after update() changed the kept frame too."""
    scene = make_scene("smooth", seed=2, width=160, height=120, frames=20, fps=30)
    images = list(scene.frames())
    raw = write_raw(scene, tmp_path / "clip.raw", pix_fmt)
    with vtrack.open_source(raw, raw="160x120", pix_fmt=pix_fmt) as source:
        results = list(vtrack.track(source, "s0", scene.boxes[0], keep_frames=True))
    with vtrack.open_source(raw, raw="160x120", pix_fmt=pix_fmt) as source:
        want = [frame.bgr().copy() for frame in source]  # each copied before the next is read
    assert len(results) == len(want) == 20
    assert all(np.array_equal(r.frame.bgr(), want[r.index]) for r in results)
    camera = np.empty_like(images[0])  # one buffer the driver refills for every frame
    tracker = vtrack.Tracker("s0", keep_frames=True)
    kept = []
    for n, image in enumerate(images[:5]):
        camera[:] = image
        kept.append(tracker.init(camera, scene.boxes[0]) if n == 0 else tracker.update(camera))
    assert all(np.array_equal(r.frame.bgr(), images[r.index]) for r in kept)


def test_a_one_channel_image_is_grey_and_a_four_channel_one_is_refused_with_a_way_out() -> None:
    """A camera's HxWx1 image was refused by Tracker and track ('expected an HxWx3 BGR or HxW
    grey image, got shape (120, 160, 1)') while track([image]) counts it as an image; an HxWx4
    one too, with the same words, not saying what to give. HxWx1 is grey now (the results of
    its HxW view); 4 channels are refused, naming them and giving the BGR slice."""
    scene = make_scene("smooth", seed=5, width=160, height=120, frames=10, fps=30)
    grey = [np.ascontiguousarray(image[:, :, 1]) for image in scene.frames()]
    box = scene.boxes[0]

    def results(frames: list[np.ndarray]) -> list[tuple]:
        tracker = vtrack.Tracker("robust")
        by_tracker = [tracker.init(f, box) if i == 0 else tracker.update(f)
                      for i, f in enumerate(frames)]
        by_track = list(vtrack.track(frames, "robust", box))
        assert [(r.index, r.box, r.score) for r in by_track] == \
            [(r.index, r.box, r.score) for r in by_tracker]
        return [(r.index, r.box, r.state, r.score) for r in by_tracker]

    assert results([image[:, :, None] for image in grey]) == results(grey)
    bgra = [np.dstack([image, np.full(image.shape[:2], 255, np.uint8)])
            for image in scene.frames()]
    said = (r"^frame 0: a 4-channel image 120x160x4 \(BGRA\?\) is not read: give its BGR "
            r"colour, image\[:, :, :3\] \(cv2.cvtColor\(image, cv2.COLOR_RGBA2BGR\) for RGBA\)$")
    with pytest.raises(TypeError, match=said):
        vtrack.Tracker("robust").init(bgra[0], box)
    with pytest.raises(TypeError, match=said):
        list(vtrack.track(bgra, "robust", box))
    assert results([image[:, :, :3] for image in bgra]) == results(list(scene.frames()))


def test_images_after_a_frame_on_a_camera_clock_are_timed_on_from_it() -> None:
    """``t.init(img0, box); t.update(vtrack.BgrFrame(1, 100.0, img1)); t.update(img2)`` timed
    the images after the camera's frame ``index / fps``: 0, 100.0, 0.0667, 0.1 (back in time).
    They are timed on from the camera's frame: 100 + (index - 1) / fps."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=10, fps=30)
    images = list(scene.frames())[:5]
    tracker = vtrack.Tracker("s0")
    got = [tracker.init(images[0], scene.boxes[0]),
           tracker.update(vtrack.BgrFrame(1, 100.0, images[1])),
           *(tracker.update(image) for image in images[2:])]
    assert [r.index for r in got] == [0, 1, 2, 3, 4]
    assert [r.time_s for r in got] == [0.0, 100.0, 100.0 + 1 / 30, 100.0 + 2 / 30, 100.0 + 3 / 30]
    assert tracker.init(images[0], scene.boxes[0]).time_s == 0.0  # a new track starts at 0
    assert tracker.update(images[1]).time_s == 1 / 30
    # a frame back on the index / fps clock is the clock the images after it follow
    tracker.init(vtrack.BgrFrame(0, 50.0, images[0]), scene.boxes[0])
    back = [tracker.update(images[1]), tracker.update(vtrack.BgrFrame(2, 2 / 30, images[2])),
            tracker.update(images[3])]
    assert [r.time_s for r in back] == [50.0 + 1 / 30, 2 / 30, 3 / 30]
