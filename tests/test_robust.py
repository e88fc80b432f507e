"""The ``robust`` tracker (issue 14): holds on generated scenes, says when it has lost the target.

End to end through the shipped config on generated scenes (in memory for speed, and one clip
written and decoded by ``vtrack run`` for the CSV contract), plus the colour model's promises and
parameter validation. The accuracy bars are the issue's (mean IoU >= 0.7 per scene kind).
"""

from __future__ import annotations

import csv
import math
from itertools import islice
from pathlib import Path

import cv2
import numpy as np
import pytest
from test_io import write_video

from vtrack import Tracker
from vtrack.config import load_config
from vtrack.errors import ConfigError
from vtrack.evaluate.metrics import frame_scores, mean_overlap
from vtrack.frame import BgrFrame, GrayFrame
from vtrack.geometry import Box
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.request import RunRequest
from vtrack.run import TRACK_COLUMNS, run
from vtrack.scenes import Scene
from vtrack.stages.base import TrackState

#: Six seeds: a scene's mean IoU over two moved by 0.03 with the FFT's rounding alone.
SEEDS = range(6)


def track(scene: Scene, overrides: list[str] | None = None, grey: bool = False,
          frames: int | None = None) -> list[FrameResult]:
    """Run ``robust`` (with ``overrides``) over a scene's frames (its first ``frames``), BGR or
    converted to grey."""
    config = load_config("robust").with_overrides(overrides or [])
    images = islice(scene.frames(), frames)
    frames_in = (
        GrayFrame(i, i / scene.fps, cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)) if grey
        else BgrFrame(i, i / scene.fps, bgr)
        for i, bgr in enumerate(images)
    )
    assert scene.boxes[0] is not None
    return list(Pipeline(config.build()).track(frames_in, scene.boxes[0]))


def overlap(scene: Scene, results: list[FrameResult]) -> float:
    overlaps, _ = frame_scores([r.box for r in results], scene.boxes)
    return mean_overlap(overlaps)


def overlaps_over_seeds(scene_factory, scenario: str,
                        overrides: list[str] | None = None) -> list[float]:
    """Mean IoU of ``robust`` (with ``overrides``) on the 150-frame scene of each seed."""
    return [overlap(scene, track(scene, overrides))
            for scene in (scene_factory(scenario, seed, frames=150) for seed in SEEDS)]


@pytest.mark.parametrize("scenario", ["smooth", "lighting", "distractor", "scale", "occlusion"])
def test_robust_holds_on_generated_scenes(scene_factory, scenario: str) -> None:
    """Mean IoU >= 0.7 over six seeds on each kind of scene (the issue's bar)."""
    values = overlaps_over_seeds(scene_factory, scenario)
    assert float(np.mean(values)) >= 0.7, values


def test_a_doubtful_frame_is_learnt_only_when_the_colours_agree(scene_factory,
                                                                monkeypatch) -> None:
    """The target passes behind a plain occluder, whose edge gives sharp but weak peaks
    (doubtful frames: called occluded, still followed). Without the colour check
    (``doubtful_colour`` 0) such frames are learnt; with a check no colour response can pass,
    none is, while the target is still followed and the first frames learnt. (What the
    shipped 0.7 gains on these scenes is measured over held-out seeds in
    benchmarks/RESULTS.md section 8: one seed's outcome moves with rounding.)"""
    from vtrack.stages.robust_model import RobustTarget

    learn = RobustTarget.learn
    scene = scene_factory("occlusion", 1, frames=150)
    learnt_doubtful = {}
    for check in (0.0, 10.0):
        learnt: list[int] = []
        monkeypatch.setattr(
            RobustTarget, "learn",
            lambda self, frame, *a, _learnt=learnt, **k: _learnt.append(frame.index)
            or learn(self, frame, *a, **k))
        results = track(scene, [f"robust_failure.doubtful_colour={check}"])
        learnt_doubtful[check] = [i for i in learnt
                                  if results[i].state == TrackState.OCCLUDED]
        assert len(learnt) > 20, (check, len(learnt))
    assert learnt_doubtful[0.0] and not learnt_doubtful[10.0], learnt_doubtful


def test_an_occluded_frame_is_learnt_only_with_learn_occluded_and_agreeing_colours(
        scene_factory, monkeypatch) -> None:
    """Below MOSSE's PSR of 7 a frame is occluded. With ``learn_occluded`` off nothing is
    learnt there (every learnt frame has a PSR of 7 or more), even without a colour check; on,
    such frames are learnt without a colour check, and none when no colour response can pass
    it. (With the shipped check this scene's plain occluder is never learnt.)"""
    from vtrack.stages.robust_model import RobustTarget

    learn = RobustTarget.learn
    scene = scene_factory("occlusion", 1, frames=150)
    low_psr_learnt = {}
    for learn_occluded, check in (("false", 0), ("true", 0), ("true", 10)):
        overrides = [f"robust_failure.learn_occluded={learn_occluded}",
                     f"robust_failure.doubtful_colour={check}"]
        psrs: list[float] = []
        monkeypatch.setattr(
            RobustTarget, "learn",
            lambda self, *a, _psrs=psrs, **k: _psrs.append(self.psr) or learn(self, *a, **k))
        track(scene, overrides)
        assert len(psrs) > 20, (overrides, len(psrs))
        low_psr_learnt[" ".join(overrides)] = sum(p < 7.0 for p in psrs[1:])  # [0]: 1st frame
    off, on, disagreeing = low_psr_learnt.values()
    assert off == 0 and on > 0 and disagreeing == 0, low_psr_learnt


def test_no_frame_called_occluded_measures_the_size(scene_factory) -> None:
    """A frame called occluded, hidden or doubtful (a sharp but weak peak), keeps the size of
    the frame before: fDSST's scale samples there show what hides the target too (a slow pass
    behind a plain occluder grew the box by a quarter on the occluder's edge). On frames called
    tracking the size is still measured: a growing target's box grows."""
    held = 0
    for seed in (0, 1, 2):
        results = track(scene_factory("occlusion", seed, frames=150))
        for before, frame in zip(results[:-1], results[1:], strict=True):
            if frame.state == TrackState.OCCLUDED and frame.box and before.box:
                held += 1
                assert (frame.box.w, frame.box.h) == pytest.approx((before.box.w, before.box.h))
    assert held > 10, held
    widths = [r.box.w for r in track(scene_factory("scale", 0, frames=150)) if r.box]
    assert max(widths) > 1.2 * min(widths), (min(widths), max(widths))


@pytest.mark.parametrize("scenario", ["smooth", "scale"])
def test_learning_from_the_moved_sample_cuts_fewer_regions_and_still_follows(
        scene_factory, monkeypatch, scenario: str) -> None:
    """``shift_within`` (ECO's shortcut): near the chosen region's centre the filter learns
    from that region's spectrum moved there, so fewer regions are cut and described a frame,
    and the target is still followed."""
    from vtrack.stages.robust_model import RobustTarget

    cut = RobustTarget.region
    scene = scene_factory(scenario, 0, frames=90)
    counts, results = {}, {}
    for within in (0.0, 1.0):
        calls = []
        monkeypatch.setattr(RobustTarget, "region",
                            lambda self, *a, _calls=calls: _calls.append(1) or cut(self, *a))
        results[within] = track(scene, [f"robust_model.shift_within={within}"])
        counts[within] = len(calls)
    assert counts[1.0] < 0.8 * counts[0.0], counts
    assert overlap(scene, results[1.0]) >= 0.7


def test_the_frame_wide_search_reads_a_small_targets_frame_at_its_own_detail(
        scene_factory, monkeypatch) -> None:
    """A small target's working scale enlarges the frame 2 times or more: the frame-wide
    search then reads the frame at half that scale on cells of half the pixels (the same
    cells, a quarter of the pixels), and peaks where the search at the full working scale
    does, to within a cell, on nearly every frame."""
    import vtrack.stages.robust_model as robust_model

    search = robust_model._filter_peak
    scene = scene_factory("fast", 0, frames=40)  # a ~25 px target, found far away each frame
    distances = []

    def both(frame, target, cx, cy):
        assert robust_model._wide_reduction(target.factor, target.cell) == 2
        reduced = search(frame, target, cx, cy)
        monkeypatch.setattr(robust_model, "WIDE_REDUCTION", 1)
        full = search(frame, target, cx, cy)
        monkeypatch.setattr(robust_model, "WIDE_REDUCTION", 2)
        distances.append(math.dist(reduced, full) * target.factor / target.cell)
        return reduced

    monkeypatch.setattr(robust_model, "_filter_peak", both)
    track(scene)
    assert len(distances) > 20
    assert np.mean(np.array(distances) <= 1.5) >= 0.9, np.round(distances, 1)


def test_a_tracked_frame_converts_its_pixels_once_for_its_cuts(scene_factory, monkeypatch) -> None:
    """A decoded (I420) frame's pixels are converted to BGR once for the frame's two search
    regions (the last box's and the motion model's), and its learning sample and scale
    samples are cut from that conversion where it reaches them: fewer than two conversions a
    frame, not one per cut (3.7 a frame on this scene when each converted its own), and the
    target is still followed. The converted pixels (and their frame) are let go once the
    frame's cuts are done, not held while the next frame is read nor after the track."""
    from vtrack.frame import I420Frame

    convert = I420Frame.bgr
    calls = []
    monkeypatch.setattr(I420Frame, "bgr",
                        lambda self, *a: calls.append(1) or convert(self, *a))
    scene = scene_factory("smooth", 0, frames=60)
    frames = (I420Frame(i, i / scene.fps, cv2.cvtColor(bgr, cv2.COLOR_BGR2YUV_I420))
              for i, bgr in enumerate(scene.frames()))
    assert scene.boxes[0] is not None
    pipeline = Pipeline(load_config("robust").build())
    results = []
    for result in pipeline.track(frames, scene.boxes[0]):
        results.append(result)
        target = pipeline._ctx.robust  # type: ignore[union-attr]
        assert target is not None and target.converted is None, result.index
    assert len(calls) < 2 * len(results), len(calls) / len(results)
    assert overlap(scene, results) >= 0.7


def test_grey_target_is_tracked_not_refused(scene_factory) -> None:
    """Grey frames (no hue at all): fHOG and the grey-level histogram carry the target."""
    scene = scene_factory("smooth", 0)
    assert overlap(scene, track(scene, grey=True)) >= 0.7


def test_lost_target_claims_no_box(scene_factory) -> None:
    """Out of the frame: lost (no box claimed) after occluded frames, tracking once back."""
    scene = scene_factory("leave_return", 0, frames=150)
    results = track(scene, ["robust_failure.lost_after=5"])
    gone = [i for i, box in enumerate(scene.boxes) if box is None]
    assert gone, "the scene has frames with the target out of view"
    lost = [r for r in results if r.state == TrackState.LOST]
    assert lost and all(r.box is None for r in lost)
    assert sum(results[i].state != TrackState.TRACKING for i in gone) >= 0.8 * len(gone)
    back = max(gone) + 1
    visible = next(i for i in range(back, len(scene)) if scene.visibility[i] >= 1.0)
    assert any(r.state == TrackState.TRACKING for r in results[visible: visible + 10])
    assert results[-1].state == TrackState.TRACKING


def test_every_part_can_be_switched_off(scene_factory) -> None:
    """Each ablation switch yields a working tracker (the smooth scene is still followed)."""
    scene = scene_factory("smooth", 1)
    for switch in ("robust_model.colour=false", "robust_model.grey_channel=false",
                   "robust_search.merge=0", "robust_search.scale=false",
                   "robust_failure.update=false", "robust_failure.redetect=false",
                   "robust_failure.update_apce=0", "robust_failure.hidden_psr=0",
                   "robust_model.filter_redetect=false", "robust_failure.coast=true",
                   "robust_failure.learn_occluded=false",
                   "robust_failure.redetect_on_colour=false"):
        assert overlap(scene, track(scene, [switch])) >= 0.6, switch


def test_first_filter_constrained_to_the_box_holds_on_the_occlusion_scene(scene_factory) -> None:
    """``robust_model.first_support`` (CSR-DCF/BACF's constrained filter on the first frame)
    keeps the issue's bar where a filter learnt without its background is most tried: a target
    hidden and seen again (the option is off by default; ``smooth`` and ``distractor``, which
    it also held, were dropped to keep the suite within its time)."""
    values = overlaps_over_seeds(scene_factory, "occlusion", ["robust_model.first_support=1"])
    assert float(np.mean(values)) >= 0.7, values


def test_score_says_box_on_target(scene_factory) -> None:
    """The score (the response's strength against its usual value) is in 0..1, and while the
    target is hidden it is under half of what it is while the target is in full view."""
    scene = scene_factory("occlusion", 0, frames=150)
    results = track(scene)
    scores = np.array([r.score for r in results])
    assert np.all((scores >= 0) & (scores <= 1))
    visible = np.array(scene.visibility)
    assert scores[visible == 0.0].mean() < 0.5 * scores[visible >= 1.0].mean()


def test_first_frame_score_says_whether_the_target_is_still_in_view(scene_factory) -> None:
    """The first frame after the given box has no usual response yet: its score is the colour
    response at the found peak against the given box's. A target that moved more than its own
    size (``fast``) leaves the search region: a box that misses it scores low (it scored 1,
    and moved the Kalman filter as a sure measurement would); one still on the target scores
    near 1."""
    from vtrack.geometry import iou

    missed, held = [], []
    for seed in SEEDS:
        scene = scene_factory("fast", seed, frames=10)
        first = track(scene, frames=2)[1]
        assert first.box is not None and scene.boxes[1] is not None
        if iou(first.box, scene.boxes[1]) == 0.0:
            missed.append(first.score)
        for scenario in ("smooth", "occlusion", "lighting"):
            held.append(track(scene_factory(scenario, seed), frames=2)[1].score)
    assert len(missed) >= 3, missed
    assert max(missed) < 0.25, missed
    assert min(held) > 0.8, held


def test_run_writes_empty_box_while_lost(clip_factory, tmp_path: Path) -> None:
    """Through ``vtrack run`` on a decoded H.264 clip: lost rows have empty box columns."""
    clip = clip_factory("leave_return", 0, frames=150)
    config = load_config("robust").with_overrides(["robust_failure.lost_after=5"])
    run(RunRequest(input=str(clip.path), out_dir=tmp_path, config=config, gt_path=clip.gt,
                   video=False))
    with open(tmp_path / "track.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    lost = [row for row in rows if row["state"] == "lost"]
    assert lost and all(row["x"] == "" and row["w"] == "" for row in lost)
    tracked = [row for row in rows if row["state"] == "tracking"]
    assert tracked and all(0.0 <= float(row["score"]) <= 1.0 for row in tracked)


def test_track_csv_gives_the_score_once(clip_factory, tmp_path: Path) -> None:
    """robust's track.csv had a ``confidence`` column that was ``score`` again (rounded to 3
    decimals instead of 4): the row's confidence is ``score`` alone, ``psr`` its own column."""
    clip = clip_factory("occlusion", 0, frames=60)
    run(RunRequest(input=str(clip.path), out_dir=tmp_path, config=load_config("robust"),
                   gt_path=clip.gt, video=False))
    with open(tmp_path / "track.csv", newline="") as handle:
        header = next(csv.reader(handle))
    assert header == [*TRACK_COLUMNS, "psr"]


@pytest.mark.parametrize("override", [
    "robust_model.working_area=2", "robust_model.bins=7", "robust_search.scale_step=3",
    "robust_failure.hidden_psr=-0.1", "robust_motion.r_rel=0", "robust_model.colour=maybe",
    "robust_model.first_support=3.5",
])
def test_parameters_are_validated(override: str) -> None:
    with pytest.raises(ConfigError, match=override.split("=")[0].split(".")[1]):
        load_config("robust").with_overrides([override])


def test_initial_box_outside_frame_is_a_user_error() -> None:
    """Refused by the pipeline before any stage starts, as ``vtrack run --init`` refuses it."""
    from vtrack.errors import ConfigError

    frames = [BgrFrame(0, 0.0, np.zeros((48, 64, 3), np.uint8))]
    with pytest.raises(ConfigError, match="^init_box: the box 100,100,10,10 lies outside the "
                       "64x48 frame$"):
        list(Pipeline(load_config("robust").build()).track(frames, Box(100, 100, 10, 10)))


def test_a_featureless_frame_changes_no_size() -> None:
    """On black frames every scale matches alike; the first scale (the smallest) was taken each
    frame and the box shrank from 40x30 to the least size within 8 frames."""
    tracker = Tracker("robust")
    black = np.zeros((240, 320, 3), np.uint8)
    results = [tracker.init(black, (100, 100, 40, 30))]
    results += [tracker.update(black) for _ in range(20)]
    assert all(r.box is not None and (r.box.w, r.box.h) == (40, 30) for r in results)


def test_a_box_mostly_outside_the_frame_is_never_called_tracking(tmp_path: Path) -> None:
    """A box given as the whole frame over black frames, then a red square appears: the
    filter's strong peak on the replicated border put the box wholly past the frame's edge
    (176,101 in a 160x120 frame), called `tracking`."""
    black = np.zeros((120, 160, 3), np.uint8)
    square = black.copy()
    square[40:70, 60:90] = (0, 0, 255)
    clip = write_video(tmp_path / "appear.mp4", [black] * 5 + [square] * 35)
    out_dir = tmp_path / "out"
    run(RunRequest(input=str(clip), out_dir=out_dir, config=load_config("robust"),
                   init_box=Box(0, 0, 160, 120), video=False))
    with (out_dir / "track.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 40
    for row in rows:
        if row["state"] == "tracking":
            box = Box(*(float(row[k]) for k in "xywh"))
            window = box.window(160, 120)
            assert window is not None and window.width * window.height >= 0.5 * box.area, row


@pytest.mark.parametrize("seed", [1, 4, 6, 11, 14])
def test_a_first_box_thinner_than_min_side_is_not_stretched(scene_factory, seed: int) -> None:
    """Each blob of the `multi` scene (640x480) halved to 320x240 that is 4 to 4.7 pixels
    across: a legal first box (at least 4x4). The size floor (min_side 5) was applied to it on
    the first update, so the box jumped to 5x5 (x1.10 to x1.24) whatever the target did; the
    scale filter itself moves the size by up to three steps of 2% a frame (x1.061)."""
    scene = scene_factory("multi", seed, width=640, height=480, frames=120)
    half = [cv2.resize(scene.frame(i), (320, 240), interpolation=cv2.INTER_AREA)
            for i in range(2)]
    steps = 1.02**3 + 1e-3  # three scale steps of 2%
    # blobs that a stretch to 5 px would grow by more than the steps (under 4.7 px across)
    thin = [Box(b.x / 2, b.y / 2, b.w / 2, b.h / 2) for _, b in scene.tracks[0]
            if min(b.w, b.h) / 2 >= 4.0 and 5.0 / min(b.w, b.h) * 2 > steps]
    assert thin
    for first in thin:
        tracker = Tracker("robust")
        tracker.init(half[0], first)
        box = tracker.update(half[1]).box
        assert box is not None and box.w / first.w < steps and box.h / first.h < steps, (
            box, first)
