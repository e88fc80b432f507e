"""Many targets on fixed-camera footage: the ``fixed_camera`` config and its stages.

``background`` (KNN, shadow removal, reduced resolution), ``group_blobs`` (fragments merged,
side-by-side targets split, scores), ``byte_tracks`` (ByteTrack's two passes over Kalman
tracks), and the chain end to end on the generated ``pedestrians`` scene (people crossing,
hiding each other, entering and leaving, with shadows and a slowly changing brightness) and on
the infrared-like ``multi`` scene.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import ClipFactory

from vtrack.cli import main
from vtrack.config import load_config, parse_config
from vtrack.errors import ConfigError
from vtrack.evaluate.mot import evaluate_mot
from vtrack.frame import BgrFrame
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.scenes import make_scene
from vtrack.stages.base import Stage, TargetShape, TrackContext, TrackStatus
from vtrack.stages.detect import Background, Blobs, Detection
from vtrack.stages.detection_colours import DetectionColours
from vtrack.stages.group_blobs import GroupBlobs, PersistentBlobs
from vtrack.stages.kalman_bytetrack import ByteTracks, colour_distances


def run_stages(stages: list[Stage], frames: list[np.ndarray]) -> list[TrackContext]:
    """Run stages over BGR frames; after each frame, (a shallow copy of) the context."""
    ctx = TrackContext(frame=BgrFrame(0, 0.0, frames[0]))
    seen = []
    for index, bgr in enumerate(frames):
        ctx.new_frame(BgrFrame(index, index / 25, bgr))
        for stage in stages:
            (stage.start if index == 0 else stage.step)(ctx)
        seen.append(TrackContext(**{k: getattr(ctx, k) for k in (
            "frame", "likelihood", "detections", "tracks", "target_shape", "feature_scale")}))
    return seen


def ground(height: int = 120, width: int = 160, level: int = 150) -> np.ndarray:
    """A plain BGR frame of a slightly textured ground (sensor-like noise, fixed seed)."""
    rng = np.random.default_rng(0)
    return np.clip(level + rng.normal(0, 2, (height, width, 3)), 0, 255).astype(np.uint8)


def scored(config: str, scene_name: str, seed: int, overrides: list[str] | None = None,
           size: tuple[int, int] = (320, 240), frames: int | None = None,
           black: int = 0, dimmed: float = 1.0) -> dict:
    """MOT scores of ``config`` on a generated scene whose first ``black`` frames are black and
    whose frames after the first are ``dimmed`` (their levels scaled by it)."""
    scene = make_scene(scene_name, seed, *size, frames)
    pipeline = Pipeline(load_config(config).with_overrides(overrides or []).build())
    shown = (BgrFrame(f.index, f.time_s, np.zeros_like(f.bgr())) if f.index < black
             else BgrFrame(f.index, f.time_s, cv2.convertScaleAbs(f.bgr(), alpha=dimmed))
             if f.index and dimmed != 1.0 else f
             for f in scene.as_frames())
    tracks = {r.index: [(t.id, t.box) for t in r.tracks if t.state == TrackStatus.CONFIRMED]
              for r in pipeline.track(shown)}
    return evaluate_mot(dict(enumerate(scene.tracks)), tracks, len(scene))


# --- background ---------------------------------------------------------------------------------


def test_the_shipped_config_detects_by_itself_and_writes_tracks() -> None:
    pipeline = Pipeline(load_config("fixed_camera").build())
    assert not pipeline.needs_init_box and pipeline.multi_target
    assert [s.name for s in pipeline.stages] == ["background", "blobs", "group_blobs",
                                                 "detection_colours", "byte_tracks"]


def test_knn_detects_from_the_second_frame() -> None:
    frames = [ground()] * 6
    frames[5] = frames[5].copy()
    frames[5][40:60, 30:45] = 30
    after = run_stages([Background(method="knn"), Blobs()], frames)
    assert not after[0].detections
    assert [tuple(d.box) for d in after[5].detections] == [(30, 40, 15, 20)]


@pytest.mark.parametrize("method", ["mog2", "knn"])
def test_shadows_are_removed_and_dark_clothes_kept(method: str) -> None:
    """A patch at 80% of the ground's brightness, same colour, is a shadow; a dark one is not."""
    frames = [ground()] * 8
    last = frames[-1].astype(np.float64)
    last[70:90, 20:80] *= 0.8  # a shadow
    last[20:50, 100:115] = 40  # dark trousers
    frames[-1] = last.astype(np.uint8)
    kept = run_stages([Background(method=method, shadows=True, colour=True), Blobs()], frames)
    assert [tuple(d.box) for d in kept[-1].detections] == [(100, 20, 15, 30)]
    plain = run_stages([Background(method=method, colour=True), Blobs()], frames)
    assert len(plain[-1].detections) == 2


@pytest.mark.parametrize("method", ["mog2", "knn"])
@pytest.mark.parametrize("brighter", [1.1, 1.25])
def test_gain_keeps_a_global_change_of_light_out_of_the_foreground(method: str,
                                                                   brighter: float) -> None:
    """After the model has settled (200 frames), the whole scene brightens by 10-25% over 10
    frames (exposure, a cloud), then a dark target steps in: the pixel models alone call most
    of the ground foreground; with ``gain`` only the target is."""
    base = ground(60, 80).astype(np.float64)
    frames = []
    for i in range(215):
        frame = base * (1 + (brighter - 1) * min(max(i - 200, 0) / 10, 1.0))
        if i >= 212:
            frame[20:35, 30:38] = 30  # the target, dark whatever the light
        frames.append(np.clip(frame, 0, 255).astype(np.uint8))
    shares = {}
    for gain in (False, True):
        last = run_stages([Background(method=method, colour=True, gain=gain), Blobs()],
                          frames)[-1]
        shares[gain] = float(np.mean(last.likelihood > 0))
        if gain:
            assert [tuple(d.box) for d in last.detections] == [(30, 20, 8, 15)], shares
    target_share = 8 * 15 / (60 * 80)
    assert shares[False] > 0.5 and shares[True] <= target_share * 1.2, shares


@pytest.mark.parametrize("seed", range(3))
def test_gain_waits_for_the_lit_scene_after_black_first_frames(seed: int) -> None:
    """A camera's first frames black (a capture starting, a cut from black): scaled to the
    background the model had learnt from them, every later frame was as dark (a median of 17
    grey levels of 141), for good, and fixed_camera found almost no one in the whole clip
    (MOTA <= 0). The gain now starts once the model has learnt the lit scene."""
    scores = scored("fixed_camera", "pedestrians", seed, frames=100, black=3)
    assert scores["mota"] > 0.3 and scores["idf1"] > 0.4, scores


@pytest.mark.parametrize("seed", [0, 2])
def test_gain_undoes_a_drop_of_light_right_after_the_first_frame(seed: int) -> None:
    """Waiting for the lit scene (above) also held the gain back when the light fell by 30%
    after the first frame: the frame, darker than the background, is no background still being
    learnt, and is scaled up at once (MOTA 0.21 and 0.15 on seeds 0 and 2 while it waited;
    0.64 and 0.50 scaled)."""
    scores = scored("fixed_camera", "pedestrians", seed, frames=100, dimmed=0.7)
    assert scores["mota"] > 0.4, scores


def test_a_reduced_resolution_gives_boxes_in_frame_pixels() -> None:
    frames = [ground(480, 640)] * 4
    frames[3] = frames[3].copy()
    frames[3][100:180, 200:240] = 30
    full, reduced = (run_stages([Background(method="mog2", max_pixels=pixels), Blobs()], frames)
                     for pixels in (0, 640 * 480 // 16))
    assert reduced[3].likelihood.shape == (120, 160) and reduced[3].feature_scale == 4.0
    (a,), (b,) = full[3].detections, reduced[3].detections
    assert tuple(a.box) == (200, 100, 40, 80)
    assert all(abs(p - q) <= 4 for p, q in zip(a.box, b.box, strict=True))
    assert math.hypot(a.cx - b.cx, a.cy - b.cy) < 1.0 and b.area == pytest.approx(a.area, 0.1)


@pytest.mark.parametrize("method, shape", [("mog2", (360, 640)), ("knn", (360, 640)),
                                           ("mean", (720, 1280))])
def test_the_adaptive_models_work_on_at_most_a_quarter_of_1080p(method: str, shape) -> None:
    """``max_pixels=0`` (full resolution) on a 1280x720 frame: MOG2 and KNN still work on it
    halved (at most 518,400 pixels: their work per frame stays bounded), S4's mean model on
    every pixel, as its document does."""
    frames = [ground(720, 1280)] * 2
    (_, second) = run_stages([Background(method=method, max_pixels=0, frames=1)], frames)
    assert second.likelihood.shape == shape


def test_the_cleaning_follows_the_size_of_the_targets_the_tracker_measured() -> None:
    """Two people 12 pixels wide stand 10 pixels apart: a closing of 25 frame pixels (sized
    for people ten times as wide) joins them into one blob. Once the tracker has measured
    people that narrow (``ctx.target_shape``), the opening and the closing follow their width
    and the two stay apart; with few measured boxes the given sizes still weigh most."""
    frames = [ground(120, 160)] * 6
    frames[5] = frames[5].copy()
    frames[5][40:70, 50:62] = 30
    frames[5][40:70, 72:84] = 30
    narrow = TargetShape(aspect=2.5, area=12 * 30, samples=1000)

    def found(shape: TargetShape | None, **params) -> list[tuple[int, ...]]:
        stages = [Background(method="mog2", open=5, close=25, **params), Blobs(min_area=20)]
        ctx = TrackContext(frame=BgrFrame(0, 0.0, frames[0]))
        for index, bgr in enumerate(frames):
            ctx.new_frame(BgrFrame(index, index / 25, bgr))
            ctx.target_shape = shape
            for stage in stages:
                (stage.start if index == 0 else stage.step)(ctx)
        return sorted(tuple(d.box) for d in ctx.detections)

    shares = {"open_share": 0.04, "close_share": 0.15}
    assert found(None, **shares) == found(narrow) == [(50, 40, 34, 30)]
    assert found(narrow, **shares) == [(50, 40, 12, 30), (72, 40, 12, 30)]
    assert found(replace(narrow, samples=5), **shares) == [(50, 40, 34, 30)]


def test_the_least_blob_follows_small_targets_down_and_never_up() -> None:
    """With a least area of 30 pixels, a 25-pixel blob is noise beside people of 35,000
    pixels but a person beside measured people of 60 (kept with ``min_area_share``); a
    40-pixel fragment of a large person is kept as before (the learnt area never raises the
    floor above ``min_area``)."""
    mask = np.zeros((120, 160), np.uint8)
    mask[10:15, 10:15] = 255  # 25 pixels
    mask[50:60, 50:54] = 255  # 40 pixels

    def kept(shape: TargetShape | None, **params) -> list[float]:
        ctx = TrackContext(frame=BgrFrame(0, 0.0, ground()), target_shape=shape)
        ctx.likelihood, ctx.feature = mask, mask
        ctx.window = ctx.frame.full_window()
        Blobs(min_area=30, **params).step(ctx)
        return sorted(d.area for d in ctx.detections)

    small, large = (TargetShape(2.5, area, 1000) for area in (60.0, 35000.0))
    assert kept(small) == kept(None, min_area_share=0.05) == [40.0]
    assert kept(large, min_area_share=0.05) == [40.0]
    assert kept(small, min_area_share=0.05) == [25.0, 40.0]


# --- group_blobs --------------------------------------------------------------------------------


def grouped(mask: np.ndarray, shape: TargetShape | None = None, **params) -> list[Detection]:
    (found,) = grouped_over_frames([mask], shape, **params)
    return found


def grouped_over_frames(masks: list[np.ndarray], shape: TargetShape | None = None,
                        **params) -> list[list[Detection]]:
    """One GroupBlobs stage over a sequence of foregrounds (the tracker's learnt ``shape``
    given): each frame's detections."""
    stage, seen = GroupBlobs(**params), []
    for index, mask in enumerate(masks):
        ctx = TrackContext(frame=BgrFrame(index, index / 25, ground(*mask.shape)),
                           target_shape=shape)
        ctx.likelihood, ctx.feature = mask, mask
        ctx.window = ctx.frame.full_window()
        Blobs(min_area=1).step(ctx)
        (stage.start if index == 0 else stage.step)(ctx)
        seen.append(ctx.detections)
    return seen


def test_the_fragments_of_one_person_are_one_detection() -> None:
    mask = np.zeros((200, 200), np.uint8)
    mask[40:100, 80:120] = 255  # torso
    mask[110:170, 84:116] = 255  # legs, a gap below
    (person,) = grouped(mask)
    assert tuple(person.box) == (80, 40, 40, 130) and 0.7 < person.score <= 1.0
    assert len(grouped(mask, merge_gap=0.0)) == 2


def test_two_people_side_by_side_are_split_where_they_touch_least() -> None:
    mask = np.zeros((200, 200), np.uint8)
    mask[40:160, 50:96] = 255
    mask[44:164, 100:146] = 255
    mask[90:100, 96:100] = 255  # their arms touch
    left, right = sorted(grouped(mask), key=lambda d: d.box.x)
    assert abs(left.box.x - 50) <= 1 and abs(left.box.x + left.box.w - 96) <= 4
    assert abs(right.box.x + right.box.w - 146) <= 1 and right.box.y == 44
    assert len(grouped(mask, split=0.0)) == 1


def test_heads_cut_people_one_behind_another_where_no_column_is_a_valley() -> None:
    """Two people, the one behind half hidden: every column between them is as full as the
    fullest, so the split by columns finds no valley and leaves them one detection. With
    ``heads`` (W4) the blob is cut at the lowest point of its top contour between the two
    heads; a dip shallower than half a head (1/16 of the height) is no second head."""
    mask = np.zeros((200, 200), np.uint8)
    mask[46:56, 62:78] = 255  # the front person's head ...
    mask[56:166, 52:110] = 255  # ... and body
    mask[48:64, 116:132] = 255  # the head of the one behind ...
    mask[64:160, 84:140] = 255  # ... and the body beside and behind the first one's
    (group,) = grouped(mask)
    assert tuple(group.box) == (52, 46, 88, 120)
    front, behind = sorted(grouped(mask, heads=True), key=lambda d: d.box.x)
    assert front.box.x == 52 and front.box.y == 46 and 108 <= front.box.x + front.box.w <= 116
    assert behind.box.x == front.box.x + front.box.w and behind.box.y == 48
    assert behind.box.x + behind.box.w == 140
    mask[54:64, 78:116] = 255  # the contour between the heads 6 rows under the lower one's
    assert len(grouped(mask, heads=True)) == 1  # top: under 1/16 of 120
    mask[54:56, 78:116] = 0  # 8 rows under it
    assert len(grouped(mask, heads=True)) == 2


def test_scores_and_limits_follow_the_learnt_shape() -> None:
    mask = np.zeros((200, 300), np.uint8)
    mask[20:140, 20:68] = 255  # a person (aspect 2.5)
    mask[150:170, 100:260] = 255  # a bar lying flat: 8 times too wide
    mask[20:30, 200:204] = 255  # a speck
    found = grouped(mask)
    assert [tuple(d.box) for d in found] == [(20, 20, 48, 120), (200, 20, 4, 10)]
    assert found[0].score == pytest.approx(1.0)
    # Once the tracker has seen people of ~5000 px, a 40 px speck is no person.
    learnt = grouped(mask, TargetShape(aspect=2.5, area=5000.0, samples=500))
    assert [tuple(d.box) for d in learnt] == [(20, 20, 48, 120)]
    # Learnt square targets: the person's shape now scores lower (2.5 times too tall).
    square = grouped(mask, TargetShape(aspect=1.0, area=5000.0, samples=5000))
    assert square[0].score < 0.5


def test_a_wide_target_that_persists_teaches_its_shape() -> None:
    """A blob 2.5 times as wide as tall, told a person's aspect (2.5 times as tall as wide),
    was dropped on every frame; the tracker learns only from what it confirms, so the shape was
    never learnt. A blob that persists with a steady shape is a sample now: once there are as
    many samples as the given aspect counts for (50), more than a factor 2 off it, theirs is
    the aspect."""
    masks = []
    for index in range(60):
        mask = np.zeros((200, 300), np.uint8)
        mask[80:120, 20 + 2 * index:120 + 2 * index] = 255  # 100 x 40, moving right
        mask[10:40, 250:260] = 255 if index % 2 else 0  # a flicker: never the same blob
        masks.append(mask)
    told = grouped_over_frames(masks, persist=0)
    assert all(not any(d.box.w == 100 for d in found) for found in told)
    taught = grouped_over_frames(masks, persist=3)
    # samples from the third frame on (0-based 2); the 50th on frame 51 sets the aspect
    first = next(i for i, found in enumerate(taught) if any(d.box.w == 100 for d in found))
    assert first == 52
    (car,) = [d for d in taught[-1] if d.box.w == 100]
    assert tuple(car.box) == (138, 80, 100, 40) and car.score == pytest.approx(1.0)
    # one that changes its shape (or touches the border) is no sample
    blob = PersistentBlobs(3)
    for width in (40, 60, 40, 60, 40, 60):
        blob.see([Box(100, 50, width, 40)], 300, 200, 1.0)
    assert blob.shape() is None
    for _ in range(4):  # steady for more than `frames` frames, but at the left border
        blob.see([Box(0, 50, 40, 40)], 300, 200, 1.0)
    assert blob.shape() is None


def test_a_target_cut_by_the_frames_border_is_carried_on_beyond_it() -> None:
    mask = np.zeros((200, 300), np.uint8)
    mask[40:160, 0:24] = 255  # half a person (aspect 2.5: 48 wide), entering on the left
    mask[40:160, 280:300] = 255  # ... leaving on the right, 20 of its 48 columns in view
    mask[150:200, 190:238] = 255  # the top of one below the bottom border (120 tall)
    mask[20:140, 100:148] = 255  # one in full view
    found = sorted(grouped(mask), key=lambda d: d.box.x)
    assert [tuple(d.box) for d in found] == [(-24, 40, 48, 120), (100, 20, 48, 120),
                                             (190, 150, 48, 120), (280, 40, 48, 120)]
    # each scores the share of it in view (its visible part is full and of the right shape):
    # one half out of view is a low-score detection, which continues a track but starts none
    assert [d.score for d in found] == pytest.approx([0.5, 1.0, 50 / 120, 20 / 48])
    visible = sorted(grouped(mask, border=False), key=lambda d: d.box.x)
    assert [tuple(d.box) for d in visible] == [(0, 40, 24, 120), (100, 20, 48, 120),
                                               (190, 150, 48, 50), (280, 40, 20, 120)]


def test_a_box_spans_the_bulk_of_the_foreground_not_its_farthest_pixels() -> None:
    mask = np.zeros((200, 300), np.uint8)
    mask[40:160, 100:140] = 255  # a body, 40 wide
    mask[150:160, 90:100] = 255  # a foot mid-stride: 100 pixels of 4900
    mask[60:64, 140:152] = 255  # an arm: 48 pixels
    (full,) = grouped(mask)
    assert tuple(full.box) == (90, 40, 62, 120)
    (bulk,) = grouped(mask, trim=0.03)  # 3% of 4948 pixels: more than the foot, the arm
    assert tuple(bulk.box) == (100, 40, 40, 120)
    mask[:, :] = 0
    mask[40:160, 0:30] = 255  # at the left border: that side stays for the completion
    mask[40:160, 30:34] = 255
    (cut,) = grouped(mask, trim=0.1)
    assert cut.box.x < 0 and cut.box.x + cut.box.w < 34


# --- detection_colours --------------------------------------------------------------------------


def test_each_detection_gets_the_colours_of_its_own_foreground_pixels() -> None:
    frame = ground(120, 160)
    frame[20:60, 20:40] = (0, 0, 220)  # a red person
    frame[20:60, 100:120] = (220, 0, 0)  # a blue one
    frame[90:94, 70:74] = (0, 220, 0)  # a speck of 16 pixels
    mask = np.zeros((120, 160), np.uint8)
    mask[20:60, 20:40] = mask[20:60, 100:120] = mask[90:94, 70:74] = 255
    ctx = TrackContext(frame=BgrFrame(0, 0.0, frame))
    ctx.likelihood = mask
    # boxes wider than the people: the ground around them must not count
    ctx.detections = [Detection(Box(x, 10, 40, 60), x + 20, 40, 800) for x in (10, 90)]
    ctx.detections.append(Detection(Box(66, 86, 12, 12), 72, 92, 16))
    DetectionColours().step(ctx)
    red, blue, speck = (d.colours for d in ctx.detections)
    assert red is not None and blue is not None and speck is None  # 16 < min_pixels
    assert red.sum() == pytest.approx(1) and red.max() == pytest.approx(1)  # one bin: no ground
    assert np.argmax(red) != np.argmax(blue)
    assert colour_distances([red], [blue, red]) == pytest.approx(np.array([[1.0, 0.0]]))
    # at half resolution (a reduced foreground): the same bins
    ctx.likelihood, ctx.feature_scale = mask[::2, ::2], 2.0
    ctx.detections = [Detection(Box(10, 10, 40, 60), 30, 40, 800)]
    DetectionColours(min_pixels=50).step(ctx)
    assert np.argmax(ctx.detections[0].colours) == np.argmax(red)


# --- byte_tracks --------------------------------------------------------------------------------


def tracked(frames: list[list[tuple[Box, float]]], colours: list[list] | None = None,
            **params) -> list[list]:
    """byte_tracks over given detections (box, score) per frame (and their colour histograms,
    ``colours``): each frame's tracks."""
    stage = ByteTracks(**params)
    ctx = TrackContext(frame=BgrFrame(0, 0.0, ground(480, 640)))
    out = []
    for index, detections in enumerate(frames):
        ctx.new_frame(BgrFrame(index, index / 25, ctx.frame.bgr()))
        hues = colours[index] if colours else [None] * len(detections)
        ctx.detections = [Detection(b, b.cx, b.cy, b.area, score=s, colours=h)
                          for (b, s), h in zip(detections, hues, strict=True)]
        (stage.start if index == 0 else stage.step)(ctx)
        out.append(ctx.tracks)
    return out


def test_the_colour_gate_is_refused_without_the_stage_that_gives_the_colours() -> None:
    gated = [{"name": "background"}, {"name": "blobs"},
             {"name": "byte_tracks", "colour_gate": 0.5}]
    with pytest.raises(ConfigError, match="colour_gate below 1 needs the detection_colours"):
        parse_config({"stage": gated}, "gated")
    plain = parse_config({"stage": [{"name": "background"}, {"name": "blobs"},
                                    {"name": "byte_tracks"}]}, "plain")
    with pytest.raises(ConfigError, match="detection_colours"):
        plain.with_overrides(["byte_tracks.colour_gate=0.5"])
    shipped = load_config("fixed_camera").with_overrides(["byte_tracks.colour_gate=0.3"])
    assert dict(shipped.stages)["byte_tracks"]["colour_gate"] == 0.3


def test_the_colour_gate_keeps_a_hidden_persons_track_off_a_passer_by() -> None:
    """A walker in red is hidden (no detection) while one in blue passes where the red one's
    track predicts it: without the gate the red track takes the blue walker over; with it the
    blue walker gets a track of its own and the red track coasts on."""
    red, blue = np.eye(4)[0], np.eye(4)[3]
    frames, colours = [], []
    for i in range(16):
        if i < 10:
            frames.append([(walker(50 + 3 * i), 0.9)])
            colours.append([red])
        else:  # the red walker hidden; a blue one where it would be
            frames.append([(walker(50 + 3 * i + 4), 0.9)])
            colours.append([blue])
    for gate, takes_over in ((1.0, True), (0.5, False)):
        out = tracked(frames, colours, colour_gate=gate)
        red_track = [t for t in out[-1] if t.id == 1]
        assert (red_track[0].state == TrackStatus.CONFIRMED) == takes_over
        assert ({t.id for t in out[-1]} == {1}) == takes_over


def walker(x: float, step: float = 3.0) -> Box:
    return Box(x, 100.0, 40.0, 100.0)


def test_a_track_is_confirmed_keeps_its_id_through_a_gap_and_is_deleted_after() -> None:
    frames = [[(walker(50 + 3 * i), 0.9)] if not 10 <= i < 18 else [] for i in range(30)]
    frames += [[] for _ in range(40)]
    out = tracked(frames, max_coast=30)
    states = [[t.state for t in tracks] for tracks in out]
    assert states[0] == states[1] == [TrackStatus.TENTATIVE]
    assert states[2] == [TrackStatus.CONFIRMED]
    assert states[12] == [TrackStatus.COASTING]
    assert {t.id for tracks in out[:30] for t in tracks} == {1}  # the same id after the gap
    assert out[18][0].state == TrackStatus.CONFIRMED
    assert abs(out[15][0].box.x - (50 + 45)) < 6  # coasted at its velocity
    assert out[29 + 31] == []  # deleted after 30 unmeasured frames


def test_low_score_detections_continue_tracks_but_never_start_one() -> None:
    frames = [[(walker(50 + 3 * i), 0.9 if i < 5 else 0.3), (walker(400), 0.3)]
              for i in range(12)]
    out = tracked(frames)
    assert [(t.id, t.state) for t in out[11]] == [(1, TrackStatus.CONFIRMED)]


def test_two_walkers_crossing_keep_their_ids() -> None:
    frames = []
    for i in range(60):
        a, b = walker(100 + 4 * i), walker(400 - 4 * i)._replace(y=110.0)
        frames.append([(a, 0.9), (b, 0.9)] if abs(a.x - b.x) > 30 else [(a, 0.9)])
    out = tracked(frames)
    start = {t.id: t.box.x for t in out[5]}
    end = {t.id: t.box.x for t in out[-1]}
    assert set(start) == set(end) == {1, 2}
    assert (start[1] < start[2]) and (end[1] > end[2])  # each id crossed with its walker


def test_the_tracker_teaches_the_grouping_the_targets_shape() -> None:
    frames = [[(walker(50 + 3 * i), 0.9)] for i in range(10)]
    stage = ByteTracks()
    ctx = TrackContext(frame=BgrFrame(0, 0.0, ground()))
    for index, detections in enumerate(frames):
        ctx.new_frame(ctx.frame)
        ctx.detections = [Detection(b, b.cx, b.cy, b.area, score=s) for b, s in detections]
        (stage.start if index == 0 else stage.step)(ctx)
    assert ctx.target_shape == TargetShape(2.5, 4000.0, 8)


# --- end to end ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["pedestrians", "vehicles"])
def test_the_street_scenes_cross_hide_enter_and_leave(name: str) -> None:
    for seed in range(3):
        scene = make_scene(name, seed, 320, 240, 100)
        ids = [{i for i, _ in tracks} for tracks in scene.tracks]
        assert 1 in ids[0] and 4 not in ids[0]
        assert 4 in ids[scene.events["appear"]] and 3 not in ids[scene.events["exit"]]
        boxes = dict(scene.tracks[scene.events["cross"]])
        a, b = boxes[1], boxes[2]
        assert min(a.x + a.w, b.x + b.w) - max(a.x, b.x) > 0  # one hides the other
        assert 4 <= scene.events["walkers"] <= 6


def test_fixed_camera_tracks_people_where_the_documents_chains_fail() -> None:
    ours = [scored("fixed_camera", "pedestrians", seed) for seed in range(2)]
    theirs = scored("s4_multi", "pedestrians", 0)
    assert all(s["mota"] > 0.15 and s["idf1"] > 0.3 for s in ours)
    assert all(s["false_positives"] < 0.2 * s["gt_boxes"] for s in ours)
    assert theirs["mota"] < -1.0


def test_fixed_camera_holds_small_warm_targets_on_grey_footage() -> None:
    small = ["group_blobs.aspect=1", "blobs.min_area=4", "background.open=1",
             "background.close=1"]
    scores = scored("fixed_camera", "multi", 0, small)
    assert scores["mota"] > 0.8 and scores["idf1"] > 0.85 and scores["id_switches"] <= 1


# --- wide targets: vehicles ---------------------------------------------------------------------


def test_the_vehicles_scene_is_the_pedestrians_street_with_wide_targets() -> None:
    """`vtrack scene vehicles`: the pedestrians scene's events with vehicles, h/w 0.3-0.8."""
    for seed in range(3):
        scene = make_scene("vehicles", seed, 320, 240, 100)
        assert scene.events["vehicles"] == list(range(1, scene.events["walkers"] + 1))
        whole = [b for tracks in scene.tracks for _, b in tracks
                 if b.x >= 0 and b.x + b.w <= scene.width]
        assert whole and all(0.3 <= b.h / b.w <= 0.8 for b in whole)
    mixed = make_scene("street", 1, 320, 240, 100).events
    assert 0 < len(mixed["vehicles"]) < mixed["walkers"]


@pytest.mark.parametrize("seed", [0, 1])
def test_fixed_camera_finds_vehicles_without_being_told_their_shape(
        clip_factory: ClipFactory, tmp_path: Path, seed: int) -> None:
    """Told a person's aspect (2.5), fixed_camera found next to none of the generated vehicles
    (h/w 0.3-0.8): wide blobs were dropped or cut into "people" before any track was
    confirmed, so their shape was never learnt (`vtrack run` IDF1 0.066 and 0.047 on these
    seeds). Blobs that persist with a steady shape teach it now (0.353 and 0.212)."""
    clip = clip_factory("vehicles", seed, 320, 240, 150, 25.0)
    result = CliRunner().invoke(main, ["run", str(clip.path), "-c", "fixed_camera", "--gt",
                                       str(clip.mot), "--no-video", "-o", str(tmp_path / "run")])
    assert result.exit_code == 0, result.output
    found = re.search(r"idf1 ([0-9.]+)", result.stdout)
    assert found is not None, result.stdout
    assert float(found.group(1)) > 0.13, result.stdout
