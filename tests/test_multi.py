"""Multi-target tracking: detection stages, S3 (mht), S4 (background + Kalman, one target and per
track), public detections, and the CLEAR MOT / identity metrics.

Metrics are checked against hand-computed cases (and against py-motmetrics when it is
installed); the trackers end to end on generated scenes with exact ground truth: the ``multi``
scene (4 small bright blobs: two cross through the same point and merge into one blob for
~10 frames, one leaves through the left side, one enters from the right) and ``bounce``.
"""

from __future__ import annotations

import csv
import dataclasses
import itertools
import json
import math
import shutil

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import one_error_line

from vtrack.cli import main
from vtrack.config import load_config
from vtrack.errors import ConfigError, InputError
from vtrack.evaluate.mot import evaluate_mot, mot_summary
from vtrack.frame import GrayFrame
from vtrack.geometry import Box, center_error, iou
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.scenes import Scene
from vtrack.stages import detect
from vtrack.stages.base import Stage, TrackContext, TrackState, TrackStatus, build_stage
from vtrack.stages.detect import (
    AdaptiveThreshold,
    Background,
    Blobs,
    Detection,
    LargestBlob,
)
from vtrack.stages.kalman_tracks import KalmanTracks
from vtrack.stages.mht import MultipleHypothesis, predict_position
from vtrack.stages.mot_detections import MotDetections

OURS: tuple[type[Stage], ...] = (
    Background, AdaptiveThreshold, Blobs, LargestBlob, MultipleHypothesis, KalmanTracks,
    MotDetections,
)
MULTI_FRAMES = 150  # the multi scenario's default length: the crossing is at frame 74

# --- CLEAR MOT and identity measures, hand-computed ---------------------------------------------

A = Box(0, 0, 10, 10)
B = Box(100, 100, 10, 10)
FAR = Box(300, 300, 10, 10)


def test_a_perfect_track_scores_one() -> None:
    gt = {f: [(1, A), (2, B)] for f in range(5)}
    scores = evaluate_mot(gt, {f: [(7, A), (9, B)] for f in range(5)}, 5)
    assert scores["mota"] == 1.0 and scores["idf1"] == 1.0 and scores["motp"] == 1.0
    assert scores["id_switches"] == scores["false_positives"] == scores["misses"] == 0
    assert (scores["mostly_tracked"], scores["mostly_lost"], scores["gt_ids"]) == (2, 0, 2)
    assert (scores["gt_boxes"], scores["track_boxes"], scores["matches"]) == (10, 10, 10)


def test_an_id_switch_is_counted_once() -> None:
    gt = {f: [(1, A)] for f in range(4)}
    tracks = {0: [(1, A)], 1: [(1, A)], 2: [(2, A)], 3: [(2, A)]}
    scores = evaluate_mot(gt, tracks, 4)
    assert scores["id_switches"] == 1
    assert scores["mota"] == pytest.approx(1 - 1 / 4)
    # IDF1: object 1 is paired with track 1 (or 2): 2 identity true positives of 4 + 4 boxes.
    assert scores["idf1"] == pytest.approx(2 * 2 / (4 + 4))
    assert scores["idp"] == scores["idr"] == pytest.approx(0.5)


def test_a_false_positive_and_a_miss() -> None:
    shifted = Box(2, 0, 10, 10)  # IoU with A: 80 / 120
    gt = {0: [(1, A)], 1: [(1, A)]}
    tracks = {0: [(5, shifted)], 1: [(5, FAR)]}
    scores = evaluate_mot(gt, tracks, 2)
    assert (scores["false_positives"], scores["misses"], scores["id_switches"]) == (1, 1, 0)
    assert scores["mota"] == pytest.approx(1 - 2 / 2)
    assert scores["motp"] == pytest.approx(80 / 120)
    assert scores["idf1"] == pytest.approx(2 * 1 / (2 + 2))
    assert scores["mostly_tracked"] == 0 and scores["partially_tracked"] == 1


def test_iou_one_half_matches_and_just_below_does_not() -> None:
    half = Box(0, 0, 10, 20)  # IoU with A: 100 / 200
    assert evaluate_mot({0: [(1, A)]}, {0: [(1, half)]}, 1)["misses"] == 0
    below = Box(0, 0, 10, 20.01)
    assert evaluate_mot({0: [(1, A)]}, {0: [(1, below)]}, 1)["misses"] == 1


def test_an_earlier_match_is_kept_over_a_better_new_one() -> None:
    """CLEAR MOT: a correspondence that still may be matched is kept (no switch) even when
    another track fits better in this frame."""
    near = Box(1, 0, 10, 10)  # IoU 90/110 with A
    gt = {0: [(1, A)], 1: [(1, A)]}
    tracks = {0: [(1, near)], 1: [(1, near), (2, A)]}
    scores = evaluate_mot(gt, tracks, 2)
    assert (scores["id_switches"], scores["false_positives"]) == (0, 1)


def test_undefined_scores_are_none_and_other_frames_are_ignored() -> None:
    scores = evaluate_mot({}, {0: [(1, A)], 5: [(1, A)]}, 3)
    assert scores["mota"] is None and scores["motp"] is None and scores["idr"] is None
    assert scores["false_positives"] == 1 and scores["idf1"] == 0.0
    assert evaluate_mot({}, {}, 3)["idf1"] is None


def test_mot_summary_reads_the_ground_truth_file(tmp_path) -> None:
    path = tmp_path / "gt.txt"
    path.write_text("1,1,0,0,10,10,1,1,1\n2,1,0,0,10,10,1,1,1\n3,1,0,0,10,10,1,1,1\n")
    scores = mot_summary({0: [(4, A)], 1: [(4, A)]}, path, 2)  # frame 3 was not processed
    assert scores["mota"] == 1.0 and scores["gt_boxes"] == 2 and scores["frames"] == 2
    with pytest.raises(InputError):
        mot_summary({}, tmp_path / "missing.txt", 2)


def test_track_boxes_on_distractors_are_taken_out_as_trackeval_does(tmp_path) -> None:
    """Probe 51c: a track on a static person (class 7), a distractor (8), a reflection (12) or a
    person on a vehicle (2) counted as a false positive on every frame; TrackEval, whose reading
    the README promises, takes such track boxes out before scoring. A track on a car (class 3,
    no distractor) stays a false positive, and the assignment gives a box covering both a
    pedestrian and a distractor to the one it overlaps more."""
    car, walker, static = Box(200, 0, 10, 10), A, B
    near_static = Box(101, 100, 10, 10)  # IoU 0.82 with the static person, 0 with the walker
    path = tmp_path / "gt.txt"
    path.write_text("1,1,0,0,10,10,1,1,1\n1,2,100,100,10,10,1,7,1\n1,3,200,0,10,10,1,3,1\n"
                    "2,1,0,0,10,10,1,1,1\n2,2,100,100,10,10,0,8,1\n"
                    "3,1,0,0,10,10,1,1,1\n3,2,100,100,10,10,1,12,0.2\n3,5,1,0,10,10,1,2,1\n")
    tracks = {0: [(1, walker), (2, static), (3, car)], 1: [(1, walker), (2, near_static)],
              2: [(1, walker), (2, static)]}
    scores = mot_summary(tracks, path, 3)
    # by hand: the walker matched on all 3 frames; the static person's track taken out on all
    # 3 (class 7, then 8 with consider 0, then 12); the car's a false positive; frame 3's person
    # on a vehicle (IoU 0.82 with the walker's box) takes no box, the walker's row wins it
    assert (scores["matches"], scores["false_positives"], scores["misses"]) == (3, 1, 0)
    assert scores["track_boxes"] == 4 and scores["track_ids"] == 2
    assert scores["mota"] == pytest.approx(1 - 1 / 3) and scores["idf1"] == pytest.approx(6 / 7)


def test_the_metrics_agree_with_py_motmetrics() -> None:
    mm = pytest.importorskip("motmetrics")
    rng = np.random.default_rng(3)
    for _ in range(10):
        gt: dict[int, list[tuple[int, Box]]] = {}
        tracks: dict[int, list[tuple[int, Box]]] = {}
        for frame in range(25):
            for obj in range(4):
                if rng.random() < 0.85:
                    box = Box(12 * obj + frame * 0.7, 6 * obj + rng.normal(0, 1), 10, 10)
                    gt.setdefault(frame, []).append((obj, box))
                    hid = obj if rng.random() < 0.9 else 10 + obj
                    if rng.random() < 0.8:
                        moved = box._replace(x=box.x + rng.normal(0, 2), y=box.y + rng.normal(0, 2))
                        tracks.setdefault(frame, []).append((hid, moved))
        accumulator = mm.MOTAccumulator(auto_id=True)
        for frame in range(25):
            objects, hyps = gt.get(frame, []), tracks.get(frame, [])
            distance = np.array([[1 - iou(o, h) for _, h in hyps] for _, o in objects]).reshape(
                len(objects), len(hyps))
            distance[distance > 0.5] = np.nan
            accumulator.update([o for o, _ in objects], [h for h, _ in hyps], distance)
        theirs = mm.metrics.create().compute(
            accumulator, metrics=["mota", "motp", "idf1", "num_switches", "num_false_positives",
                                  "num_misses", "mostly_tracked", "mostly_lost"], name="x")
        ours = evaluate_mot(gt, tracks, 25)
        assert ours["mota"] == pytest.approx(theirs["mota"].iloc[0])
        assert ours["motp"] == pytest.approx(1 - theirs["motp"].iloc[0])
        assert ours["idf1"] == pytest.approx(theirs["idf1"].iloc[0])
        assert ours["id_switches"] == theirs["num_switches"].iloc[0]
        assert ours["false_positives"] == theirs["num_false_positives"].iloc[0]
        assert ours["misses"] == theirs["num_misses"].iloc[0]
        assert ours["mostly_tracked"] == theirs["mostly_tracked"].iloc[0]
        assert ours["mostly_lost"] == theirs["mostly_lost"].iloc[0]


# --- parameters ---------------------------------------------------------------------------------

WRONG = {int: "3", float: "1.5", str: 7, bool: "yes"}


@pytest.mark.parametrize(
    ("stage", "param"), [(cls.name, p.name) for cls in OURS for p in cls.params]
)
def test_every_parameter_rejects_a_wrong_type(stage: str, param: str) -> None:
    declared = {p.name: p for cls in OURS if cls.name == stage for p in cls.params}
    with pytest.raises(ConfigError) as error:
        build_stage(stage, {param: WRONG[declared[param].type]}, "mine.toml")
    assert f"'{param}'" in str(error.value) and "mine.toml" in str(error.value)


@pytest.mark.parametrize("name", ["s3", "s4", "s4_multi"])
def test_the_shipped_configs_load_and_need_no_initial_box(name: str) -> None:
    pipeline = Pipeline(load_config(name).build())
    assert not pipeline.needs_init_box
    assert pipeline.multi_target == (name != "s4")


# --- detection stages ---------------------------------------------------------------------------


def run_stages(stages: list[Stage], frames: list[np.ndarray]) -> list[TrackContext]:
    """Run stages over grey frames; a snapshot of the context after each frame."""
    ctx = TrackContext(frame=GrayFrame(0, 0.0, frames[0]), seed=0)
    snapshots = []
    for index, grey in enumerate(frames):
        ctx.new_frame(GrayFrame(index, index / 30, grey))
        for stage in stages:
            (stage.start if index == 0 else stage.step)(ctx)
        snapshots.append(dataclasses.replace(ctx))
    return snapshots


def frame_with(spots: list[tuple[int, int, int, int]], base: int = 20) -> np.ndarray:
    """A 60x80 grey frame with squares ``(x, y, size, grey)``."""
    grey = np.full((60, 80), base, np.uint8)
    for x, y, size, value in spots:
        grey[y : y + size, x : x + size] = value
    return grey


def test_mean_background_detects_nothing_while_learning_then_the_difference() -> None:
    frames = [frame_with([]) for _ in range(3)] + [frame_with([(10, 20, 5, 60)])]
    after = run_stages([Background(frames=3, threshold=40.0), Blobs()], frames)
    assert all(not ctx.likelihood.any() and not ctx.detections for ctx in after[:3])
    assert after[3].detections == [Detection(Box(10, 20, 5, 5), 12.0, 22.0, 25.0, 60.0)]
    # |60 - 20| = 40 >= Th is foreground; 59 is not.
    frames[3] = frame_with([(10, 20, 5, 59)])
    assert not run_stages([Background(frames=3, threshold=40.0), Blobs()], frames)[3].detections


def test_mog2_background_detects_from_the_second_frame() -> None:
    frames = [frame_with([])] * 5 + [frame_with([(30, 30, 6, 200)])]
    after = run_stages([Background(method="mog2"), Blobs()], frames)
    assert not after[0].detections
    assert [tuple(d.box) for d in after[5].detections] == [(30, 30, 6, 6)]


def test_adaptive_threshold_follows_the_last_candidates_grey() -> None:
    stage = AdaptiveThreshold(offset=50.0, initial=100.0, floor=40.0)
    assert stage.threshold(None) == 100.0  # S3 sec. 2.1: nothing learnt yet
    assert stage.threshold(180.0) == 130.0  # mean candidate grey - offset
    assert stage.threshold(70.0) == 40.0  # never below the floor
    frames = [frame_with([(5, 5, 6, 180), (40, 30, 6, 120)])] * 2
    first, second = run_stages([AdaptiveThreshold(offset=20.0, median=1), Blobs()], frames)
    assert len(first.detections) == 2  # threshold 100 (initial): both
    assert first.candidate_grey == pytest.approx(150.0)
    assert [d.grey for d in second.detections] == [180.0]  # threshold 150 - 20 = 130
    kept = second.likelihood
    assert kept is not None and kept[7, 7] == 180 and kept[0, 0] == 0  # pixels keep their grey


def test_the_median_filter_removes_fragments() -> None:
    grey = frame_with([(5, 5, 8, 200)])
    grey[40, 40] = grey[41, 60] = 200  # one-pixel fragments
    (ctx,) = run_stages([AdaptiveThreshold(median=3), Blobs(min_area=1)], [grey])
    assert [tuple(d.box) for d in ctx.detections] == [(5, 5, 8, 8)]


def test_blobs_area_limits_and_the_cap_keeps_the_largest() -> None:
    grey = frame_with([(2, 2, 2, 200), (10, 10, 4, 200), (30, 10, 6, 200), (50, 30, 9, 200)])
    (ctx,) = run_stages([AdaptiveThreshold(median=1), Blobs(min_area=5, max_area=40)], [grey])
    assert sorted(d.area for d in ctx.detections) == [16.0, 36.0]
    (ctx,) = run_stages([AdaptiveThreshold(median=1), Blobs(max_blobs=2)], [grey])
    assert sorted(d.area for d in ctx.detections) == [36.0, 81.0]


def test_labelling_only_the_foreground_regions_finds_what_the_whole_frame_has(
        monkeypatch) -> None:
    """Blobs of every shape and place: crossing tile borders, an L around another region's
    tiles, specks, touching the frame edges; the same detections whichever way they are found."""
    rng = np.random.default_rng(5)
    grey = np.zeros((130, 210), np.uint8)
    specks = grey[70:, :170]
    specks[rng.random(specks.shape) < 0.001] = 150
    grey[10:60, 30:34] = grey[56:60, 30:90] = 200  # an L ...
    grey[18:28, 66:76] = 220  # ... around another blob, a tile apart
    grey[100:130, 180:210] = 90  # in the corner
    grey[14:18, 0:40] = 120  # across tiles, from the left edge
    assert len(detect.foreground_regions(grey)) >= 3
    labelled = []
    for regions in (detect._MAX_REGIONS, 0):  # 0: always the whole frame at once
        monkeypatch.setattr(detect, "_MAX_REGIONS", regions)
        (ctx,) = run_stages([AdaptiveThreshold(initial=50.0, median=1), Blobs(min_area=1)],
                            [grey])
        labelled.append(ctx.detections)
    assert labelled[0] == labelled[1] and len(labelled[0]) > 8
    assert detect.foreground_regions(np.zeros((40, 40), np.uint8)) == []


def test_opening_and_closing_clean_the_background_foreground() -> None:
    frames = [frame_with([])] * 2 + [frame_with([(10, 10, 6, 200), (17, 10, 6, 200),
                                                 (50, 40, 1, 200)])]
    plain = run_stages([Background(frames=2), Blobs(min_area=1)], frames)[2]
    assert len(plain.detections) == 3  # two halves of a target and a speck
    cleaned = run_stages([Background(frames=2, open=3, close=5), Blobs(min_area=1)], frames)[2]
    assert [tuple(d.box) for d in cleaned.detections] == [(10, 10, 13, 6)]


def test_largest_blob_is_the_measurement_and_sets_the_state() -> None:
    ctx = TrackContext(frame=GrayFrame(0, 0.0, frame_with([])), seed=0)
    LargestBlob().step(ctx)
    assert ctx.measurement is None and ctx.state == TrackState.LOST
    ctx.detections = [Detection(Box(0, 0, 2, 2), 1, 1, 4), Detection(Box(10, 10, 4, 2), 12.5,
                                                                       11, 8)]
    LargestBlob().step(ctx)
    assert ctx.measurement == Box(10.5, 10, 4, 2) and ctx.state == TrackState.TRACKING
    ctx.box, ctx.detections = ctx.measurement, []
    LargestBlob().step(ctx)
    assert ctx.state == TrackState.OCCLUDED


# --- the MHT's predictor and bounded work -------------------------------------------------------


def test_quadratic_predictor_is_s3_eq_6_with_constant_velocity_fallbacks() -> None:
    parabola = [(t, 2 * t * t - t) for t in (0.0, 1.0, 2.0)]
    assert predict_position(parabola, 3) == (3.0, 15.0)  # exact for a parabola
    # Least-squares velocity of (0, 1, 6) is 3 per frame.
    assert predict_position(parabola, 2) == pytest.approx((3.0, 6.0 + 3.0))
    assert predict_position([(1.0, 1.0), (2.0, 3.0)], 2) == (3.0, 5.0)
    assert predict_position([(4.0, 5.0)], 1) == (4.0, 5.0)


def points_frame(index: int, points: list[tuple[float, float]]) -> TrackContext:
    """A context whose detections are 6x6 boxes centred on ``points``, in a 320x240 frame
    (the generated scenes' size: a tracker drops what lies wholly outside the frame)."""
    ctx = TrackContext(frame=GrayFrame(index, 0.0, np.zeros((240, 320), np.uint8)),
                       seed=0)
    ctx.detections = [Detection(Box.from_center(x, y, 6, 6), x, y, 36.0) for x, y in points]
    return ctx


def feed(stage: Stage, frames: list[list[tuple[float, float]]]) -> list[list]:
    """Run a tracking stage on point detections; the tracks of every frame."""
    out = []
    for index, points in enumerate(frames):
        ctx = points_frame(index, points)
        (stage.start if index == 0 else stage.step)(ctx)
        out.append(ctx.tracks)
    return out


def crossing(frames: int = 60, merged: int = 8) -> list[list[tuple[float, float]]]:
    """Two targets crossing at frame 30; within ``merged`` frames of it they are one blob."""
    out = []
    for k in range(frames):
        a, b = (10 + 2 * k, 20 + 1.5 * k), (10 + 2 * k, 110 - 1.5 * k)
        if abs(k - 30) < merged:
            out.append([((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)])
        else:
            out.append([a, b])
    return out


def id_near(tracks: list, point: tuple[float, float]) -> int | None:
    near = [t.id for t in tracks if t.state == TrackStatus.CONFIRMED
            and math.hypot(t.box.cx - point[0], t.box.cy - point[1]) < 3]
    return near[0] if len(near) == 1 else None


@pytest.mark.parametrize("stage", [MultipleHypothesis(), KalmanTracks()], ids=["mht", "kalman"])
def test_identities_survive_two_targets_merging_into_one_blob(stage: Stage) -> None:
    frames = crossing()
    out = feed(stage, frames)
    before = [id_near(out[20], p) for p in frames[20]]
    after = [id_near(out[45], p) for p in frames[45]]
    assert None not in before and len(set(before)) == 2 and before == after


@pytest.mark.parametrize("model", ["cv", "ca", "gravity"])
def test_kalman_tracks_follow_an_accelerating_target_with_any_motion_model(model: str) -> None:
    # x = 10 + 0.1 k^2: every model keeps one confirmed identity on it; the models that know
    # acceleration (ca; gravity only vertically) predict it closer than constant velocity.
    path = [[(10.0 + 0.1 * k * k, 40.0)] for k in range(25)]
    stage = KalmanTracks(model=model, gate=20.0)
    out = feed(stage, path)
    assert {t.id for tracks in out[3:] for t in tracks} == {1}
    assert all(t.state == TrackStatus.CONFIRMED for t in out[-1])
    assert out[-1][0].box.cx == pytest.approx(path[-1][0][0], abs=3.0)


def test_mht_work_stays_bounded_in_clutter() -> None:
    rng = np.random.default_rng(0)
    stage = MultipleHypothesis(max_hypotheses=4, max_branches=2)
    frames = [[(50 + 2 * k, 50.0)] + [tuple(p) for p in rng.uniform(30, 90, (30, 2))]
              for k in range(12)]
    out = feed(stage, frames)
    assert len(stage._hypotheses) <= 4
    assert all(len({t.id for t in tracks}) == len(tracks) for tracks in out)


def test_kalman_tracks_confirm_and_delete_by_counts() -> None:
    stage = KalmanTracks(confirm=3, max_coast=2)
    path = [[(10.0 + k, 10.0)] for k in range(4)] + [[]] * 4 + [[(60.0, 60.0)], []]
    out = feed(stage, path)
    assert [t.state for t in out[1]] == [TrackStatus.TENTATIVE]
    assert [(t.id, t.state) for t in out[2]] == [(1, TrackStatus.CONFIRMED)]
    assert [t.state for t in out[5]] == [TrackStatus.COASTING]  # 2 misses: still kept
    assert out[6] == []  # 3 misses > max_coast: deleted
    assert [(t.id, t.state) for t in out[8]] == [(2, TrackStatus.TENTATIVE)]  # a new id
    assert out[9] == []  # a tentative track dies on its first miss


# --- end to end on the generated multi scene ----------------------------------------------------


def track(scene: Scene, config: str, *overrides: str) -> list[FrameResult]:
    stages = load_config(config).with_overrides(list(overrides)).build()
    return list(Pipeline(stages).track(scene.as_frames()))


def matched_ids(scene: Scene, results: list[FrameResult]) -> dict[int, dict[int, int]]:
    """``{gt id: {frame: id of the confirmed track overlapping it}}`` (IoU >= 0.3)."""
    ids: dict[int, dict[int, int]] = {}
    for result in results:
        for gid, box in scene.tracks[result.index]:
            for t in result.tracks:
                if t.state == TrackStatus.CONFIRMED and iou(t.box, box) >= 0.3:
                    ids.setdefault(gid, {})[result.index] = t.id
    return ids


MULTI_RUNS = [("s3", 0), ("s3", 1), ("s4_multi", 0)]


@pytest.fixture(scope="module", params=MULTI_RUNS, ids=[f"{c}-seed{s}" for c, s in MULTI_RUNS])
def multi_run(request, scene_factory) -> tuple[Scene, list[FrameResult], int]:
    config, seed = request.param
    scene = scene_factory("multi", seed=seed, frames=MULTI_FRAMES)
    # S4's mean background would need 30 target-free frames: MOG2 learns while detecting.
    overrides = ["background.method=mog2"] if config == "s4_multi" else []
    stage = load_config(config).build()[-1]
    return scene, track(scene, config, *overrides), stage.max_coast


def test_every_target_is_confirmed_within_5_frames_of_appearing(multi_run) -> None:
    scene, results, _ = multi_run
    ids = matched_ids(scene, results)
    for gid in {gid for frame in scene.tracks for gid, _ in frame}:
        appears = next(i for i, frame in enumerate(scene.tracks) if gid in dict(frame))
        assert min(ids[gid]) - appears <= 5, gid


def test_no_identity_switch_where_two_targets_cross(multi_run) -> None:
    scene, results, _ = multi_run
    ids = matched_ids(scene, results)
    cross = scene.events["cross"]
    for gid in scene.events["cross_ids"]:
        before = {ids[gid][f] for f in range(cross - 20, cross - 10) if f in ids[gid]}
        after = {ids[gid][f] for f in range(cross + 10, cross + 20) if f in ids[gid]}
        assert len(before) == 1 and before == after, gid
    gt = {i: frame for i, frame in enumerate(scene.tracks)}
    confirmed = {r.index: [(t.id, t.box) for t in r.tracks if t.state == TrackStatus.CONFIRMED]
                 for r in results}
    assert evaluate_mot(gt, confirmed, len(scene))["id_switches"] == 0


def test_a_target_that_leaves_is_deleted_within_max_coast_frames(multi_run) -> None:
    scene, results, max_coast = multi_run
    exit_frame, gid = scene.events["exit"], scene.events["exit_id"]
    (leaver,) = {track for f, track in matched_ids(scene, results)[gid].items()
                 if exit_frame - 15 <= f < exit_frame - 5}
    alive = [r.index for r in results if any(t.id == leaver for t in r.tracks)]
    assert max(alive) <= exit_frame + max_coast


def test_an_identity_is_never_reused(multi_run) -> None:
    _, results, _ = multi_run
    frames_of: dict[int, list[int]] = {}
    for result in results:
        for t in result.tracks:
            frames_of.setdefault(t.id, []).append(result.index)
    for frames in frames_of.values():  # one unbroken run of frames per id
        assert frames == list(range(frames[0], frames[-1] + 1))


# --- where the ids start -------------------------------------------------------------------------


@pytest.mark.parametrize("config", ["s3", "s4_multi", "fixed_camera"])
def test_a_first_track_id_numbers_the_tracks_on_from_it(scene_factory, config: str) -> None:
    """Every multi-target tracker (mht, kalman_tracks, byte_tracks) numbered its tracks from 1
    whatever the caller wanted (`vtrack.track(frames, config, first_track_id=40)` was a
    TypeError), so a run taken up after an interruption gave the first run's ids to other
    tracks. Now ``first_track_id`` (Tracker's, track's, a RunRequest's, ``--first-id``) is the
    first id: the same tracks, boxes and states as from 1, each id 39 more."""
    import vtrack

    frames = list(scene_factory("pedestrians", seed=4, frames=150).as_frames())
    ones = list(vtrack.track(frames, config))
    on = list(vtrack.track(frames, config, first_track_id=40))
    numbered = sorted({t.id for r in ones for t in r.tracks})
    assert numbered and numbered[0] == 1, numbered  # (tracks were made: ids to move on)
    assert [[(t.id + 39, t.box, t.state) for t in r.tracks] for r in ones] == \
        [[(t.id, t.box, t.state) for t in r.tracks] for r in on]


def test_a_first_track_id_is_refused_where_no_track_is_numbered(
        clip_factory, tmp_path) -> None:
    """`vtrack run clip.mp4 -c s0 --first-id 3` and its library forms: a single-target config
    numbers no tracks, so a first track id other than 1 is refused in one line naming what was
    given (before the output folder is made), as one out of its range (1 to 2**53) is;
    1 is every config's (the default). The line named `vtrack configs`, no command (probe RD):
    it names `vtrack stages`, which lists the shipped configs."""
    import vtrack
    from vtrack.request import RunRequest

    clip = clip_factory("smooth", width=160, height=120, frames=10)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "-c", "s0", "--first-id", "3",
                                       "--gt", str(clip.gt), "-o", str(out)])
    assert one_error_line(result) == (
        "vtrack: error: --first-id 3: s0 tracks one target and numbers no tracks; only a "
        "multi-target config (s3, s4_multi, fixed_camera, ...: vtrack stages lists the shipped "
        "configs) takes a first track id")
    assert not out.exists()
    result = CliRunner().invoke(main, ["run", str(clip.path), "-c", "s3", "--first-id", "0",
                                       "-o", str(out)])
    assert "--first-id" in one_error_line(result) and "1<=x<=9007199254740992" in result.stderr
    said = "first_track_id 3: s0 tracks one target and numbers no tracks"
    with pytest.raises(ConfigError, match=said):
        vtrack.Tracker("s0", first_track_id=3)
    with pytest.raises(ConfigError, match=said):
        RunRequest(input=str(clip.path), out_dir=out, config=load_config("s0"),
                   first_track_id=3)
    with pytest.raises(ConfigError, match=said):
        vtrack.track(clip.path, "s0", init_box=clip.scene.boxes[0], first_track_id=3)
    for wrong in (0, 2**53 + 1, True, 2.0, "5"):
        with pytest.raises(ConfigError, match="first_track_id .*: must be a whole number from "
                                              "1 to 9007199254740992"):
            vtrack.Tracker("s3", first_track_id=wrong)
    request = RunRequest(input=str(clip.path), out_dir=out, config=load_config("s3"),
                         first_track_id=np.int64(7))
    assert type(request.first_track_id) is int and request.first_track_id == 7
    with pytest.raises(ConfigError, match="first_track_id: the RunRequest carries its own"):
        vtrack.track(request, first_track_id=7)
    assert vtrack.Tracker("s0", first_track_id=1).first_track_id == 1


def test_track_ids_used_up_stay_a_config_error_on_every_later_frame(scene_factory) -> None:
    """`Tracker("fixed_camera", first_track_id=2**53)` on a 'pedestrians' clip: the second new
    track raised the ConfigError naming the used-up ids, and every later update that made a
    track raised a bare StopIteration (the ids were a generator, finished once it had raised).
    Each such update now raises the same ConfigError, naming its own frame."""
    import vtrack

    tracker = vtrack.Tracker("fixed_camera", first_track_id=2**53)
    failed: list[tuple[int, str]] = []
    for index, frame in enumerate(scene_factory("pedestrians", seed=4, frames=300).as_frames()):
        try:
            tracker.update(frame)
        except ConfigError as error:
            failed.append((index, str(error)))
    assert len(failed) > 1, failed  # (a first error, then later frames that needed an id)
    for index, said in failed:
        assert said.startswith(f"the track ids from {2**53} are used up at frame {index} "
                               f"(frame {index + 1} counted from 1, as tracks.csv and "
                               "MOTChallenge number them): "), said


# --- S4 on the bounce scene ---------------------------------------------------------------------


def test_s4_error_returns_under_2_px_within_10_frames_after_a_bounce(scene_factory) -> None:
    scene = scene_factory("bounce", seed=0, frames=150)
    results = track(scene, "s4")
    errors = np.array([center_error(r.box, g) if r.box and g else np.inf
                       for r, g in zip(results, scene.boxes, strict=True)])
    learning = load_config("s4").build()[0].frames
    assert np.isinf(errors[:learning]).all()  # no detection while the background is learnt
    bounces = scene.events["bounce"]
    checked = 0
    for bounce, following in itertools.pairwise(bounces):
        if bounce < learning + 5 or following - bounce <= 10:
            continue
        assert (errors[bounce + 10 : following] < 2.0).all(), bounce
        checked += 1
    assert checked >= 3


# --- public detections --------------------------------------------------------------------------


def test_mot_detections_feed_the_trackers(tmp_path, scene_factory) -> None:
    scene = scene_factory("multi", seed=0, frames=MULTI_FRAMES)
    det = tmp_path / "det.txt"
    det.write_text("".join(
        f"{i + 1},-1,{b.x},{b.y},{b.w},{b.h},{0.5 if gid == 4 else 0.9}\n"
        for i, frame in enumerate(scene.tracks) for gid, b in frame))
    stage = MotDetections(path=str(det), min_score=0.6)
    ctx = points_frame(0, [])
    stage.start(ctx)
    assert [d.box for d in ctx.detections] == [b for _, b in scene.tracks[0]]
    assert all(d.score == 0.9 and d.area == d.box.area for d in ctx.detections)
    results = list(Pipeline([MotDetections(path=str(det)), MultipleHypothesis()]).track(
        scene.as_frames()))
    confirmed = {r.index: [(t.id, t.box) for t in r.tracks if t.state == TrackStatus.CONFIRMED]
                 for r in results}
    scores = evaluate_mot(dict(enumerate(scene.tracks)), confirmed, len(scene))
    assert scores["mota"] > 0.9 and scores["id_switches"] == 0


def test_mot_detections_needs_a_readable_file(tmp_path) -> None:
    with pytest.raises(ConfigError, match="path"):
        MotDetections().start(points_frame(0, []))
    with pytest.raises(InputError):
        MotDetections(path=str(tmp_path / "none.txt")).start(points_frame(0, []))


# --- through the command line -------------------------------------------------------------------


def test_vtrack_run_s3_with_mot_ground_truth_and_no_init(tmp_path, clip_factory) -> None:
    clip = clip_factory("multi", seed=0, frames=MULTI_FRAMES)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt",
                                       str(clip.mot), "--no-video", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    with open(out / "tracks.csv", newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["frame", "id", "x", "y", "w", "h", "conf", "wx", "wy", "wz", "state"]
    assert len(rows) > 300 and {row[-1] for row in rows[1:]} == {"confirmed"}
    metrics = json.loads((out / "run.json").read_text())["metrics"]
    assert metrics["mota"] > 0.85 and metrics["idf1"] > 0.9


@pytest.mark.parametrize("seed", range(2))
def test_tracks_csv_sizes_stay_positive_and_scored_as_written(tmp_path, clip_factory,
                                                               seed: int) -> None:
    """A det.txt's boxes of 0.0001 pixels (w > 0, so kept) were written to tracks.csv with
    w and h 0, rows no MOTChallenge box has; they are the least size the cells hold now, and
    run.json's metrics are those of the boxes as written."""
    clip = clip_factory("multi", seed=seed, frames=MULTI_FRAMES)
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{i + 1},-1,{b.cx},{b.cy},0.0001,0.0001,0.9\n"
                           for i, frame in enumerate(clip.scene.tracks) for _, b in frame))
    config = tmp_path / "tiny.toml"
    config.write_text(f'name = "tiny"\n[[stage]]\nname = "mot_detections"\npath = "{det}"\n'
                      '[[stage]]\nname = "byte_tracks"\n')
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "-c", str(config), "--gt",
                                       str(clip.mot), "--no-video", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    with open(out / "tracks.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) > 100
    assert all(float(row["w"]) > 0 and float(row["h"]) > 0 for row in rows)
    tracks: dict[int, list] = {}
    for row in rows:
        tracks.setdefault(int(row["frame"]) - 1, []).append(
            (int(row["id"]), Box(*(float(row[k]) for k in "xywh"))))
    metrics = json.loads((out / "run.json").read_text())["metrics"]
    assert mot_summary(tracks, clip.mot, MULTI_FRAMES) == metrics


def _rewritten_mot(clip, tmp_path, columns: str):
    """The clip's MOTChallenge ground truth with columns 7.. replaced by ``columns``."""
    rows = clip.mot.read_text().splitlines()
    path = tmp_path / "gt.txt"
    path.write_text("".join(",".join(row.split(",")[:6]) + columns + "\n" for row in rows))
    return path, len(rows)


@pytest.mark.parametrize(("columns", "reason"), [
    (",0", "the consider flag 0 in column 7"),
    (",1,7,1", "class 7 in column 8, not pedestrian 1"),
])
def test_ground_truth_whose_every_row_is_ignored_is_a_warning(tmp_path, clip_factory, columns,
                                                               reason) -> None:
    """Probe 48 item 2: every row dropped (not to be considered, or static persons) was scored
    silently as gt_boxes 0, mota null. As in TrackEval the run goes on, and it says so."""
    clip = clip_factory("multi", seed=0, frames=MULTI_FRAMES)
    gt, rows = _rewritten_mot(clip, tmp_path, columns)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt", str(gt),
                                       "--no-video", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    note = f"{gt}: all {rows} ground-truth rows are ignored ({rows} with {reason})"
    assert f"vtrack: warning: {note}" in result.stderr
    record = json.loads((out / "run.json").read_text())
    assert record["metrics"]["gt_boxes"] == 0 and any(note in w for w in record["warnings"])


def _scored_with_warning(clip, gt, out, note: str) -> dict:
    """The run.json of ``vtrack run CLIP -c s3 --gt GT`` into ``out``, which succeeded with
    ``note`` as its only warning, on stderr and in run.json."""
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt", str(gt),
                                       "--no-video", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    assert result.stderr == f"vtrack: warning: {note}\n"
    record = json.loads((out / "run.json").read_text())
    assert note in record["warnings"]
    return record


@pytest.mark.parametrize("text", ["", "\n \n"])
def test_empty_ground_truth_of_a_scene_without_targets_scores_its_false_positives(
        tmp_path, clip_factory, text) -> None:
    """An empty MOTChallenge gt.txt (a scene with no target: its false alarms are what a
    surveillance user measures) was refused, "gt.txt: MOT file is empty", while a file whose
    every row is ignored scored with a warning. It scores the same way now: every track box a
    false positive, gt_boxes 0, mota null, and a warning; a single target's empty ground truth
    is still refused."""
    clip = clip_factory("multi", seed=0, frames=MULTI_FRAMES)
    gt = tmp_path / "gt.txt"
    gt.write_text(text)
    out = tmp_path / "out"
    note = (f"{gt}: no ground-truth rows (a scene without targets): every track box is a false "
            "positive (gt_boxes 0, mota null)")
    metrics = _scored_with_warning(clip, gt, out, note)["metrics"]
    assert metrics["gt_boxes"] == 0 and metrics["mota"] is None
    tracked = len((out / "tracks.csv").read_text().splitlines()) - 1
    assert tracked > 0 and metrics["false_positives"] == tracked
    single = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s0", "--gt", str(gt),
                                       "--no-video", "--out", str(tmp_path / "one"), "--quiet"])
    assert single.exit_code != 0 and f"{gt}: ground-truth file is empty" in single.output


def test_ground_truth_rows_with_an_empty_box_are_a_warning(tmp_path, clip_factory) -> None:
    """Rows of a MOTChallenge gt.txt with a negative width or height were dropped without a
    word (the run's MOTA went up: those targets were no longer missed). The run now warns how
    many there are and the line of the first, on stderr and in run.json."""
    clip = clip_factory("multi", seed=0, frames=MULTI_FRAMES)
    rows = clip.mot.read_text().splitlines()
    bad = [2, 5, 9]  # 0-based: lines 3, 6 and 10
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(
        (",".join([*row.split(",")[:4], f"-{row.split(',')[4]}", *row.split(",")[5:]])
         if index in bad else row) + "\n" for index, row in enumerate(rows)))
    note = (f"{gt}: 3 ground-truth rows with w or h <= 0 ignored (the first on line 3): not "
            "scored, as if the file did not have them")
    record = _scored_with_warning(clip, gt, tmp_path / "out", note)
    assert record["metrics"]["gt_boxes"] == len(rows) - 3


def test_a_class_column_that_holds_no_motchallenge_class_is_refused(tmp_path,
                                                                    clip_factory) -> None:
    """Probe 48 item 2: MOT15 rows cut to 9 columns (world coordinates -1 read as the class) were
    all dropped silently; TrackEval refuses a class outside 1-13, and so does vtrack run."""
    clip = clip_factory("multi", seed=0, frames=MULTI_FRAMES)
    gt, _ = _rewritten_mot(clip, tmp_path, ",1,-1,-1")
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt", str(gt),
                                       "--no-video", "--out", str(tmp_path / "out"), "--quiet"])
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith(f"vtrack: error: {gt} line 1: column 8 is -1, not a "
                                    "MOTChallenge class")
    assert len(result.stderr.splitlines()) == 1 and not (tmp_path / "out").exists()


def test_a_run_takes_its_track_boxes_on_distractors_out_of_the_score(tmp_path,
                                                                      clip_factory) -> None:
    """Probe 51c: with one of the scene's four targets marked a static person (class 7) in
    gt.txt, vtrack run counted every box of the track following it as a false positive. Its
    run.json now scores its tracks.csv as TrackEval does, those boxes taken out."""
    from vtrack.evaluate.groundtruth import read_mot_counting

    clip = clip_factory("multi", seed=0, frames=MULTI_FRAMES)
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{row.rsplit(',', 2)[0]},{7 if row.split(',')[1] == '2' else 1},1\n"
                          for row in clip.mot.read_text().splitlines()))
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt", str(gt),
                                       "--no-video", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    tracks: dict[int, list[tuple[int, Box]]] = {}
    with open(out / "tracks.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            box = Box(*(float(row[k]) for k in ("x", "y", "w", "h")))
            tracks.setdefault(int(row["frame"]) - 1, []).append((int(row["id"]), box))
    truth = read_mot_counting(gt)
    metrics = json.loads((out / "run.json").read_text())["metrics"]
    expected = evaluate_mot(truth.boxes, tracks, MULTI_FRAMES, truth.distractors)
    for key, value in expected.items():
        assert metrics[key] == pytest.approx(value, rel=1e-9), key
    counted = evaluate_mot(truth.boxes, tracks, MULTI_FRAMES)  # the static person's track kept
    assert metrics["false_positives"] + 30 < counted["false_positives"]
    assert metrics["track_boxes"] + 30 < sum(len(boxes) for boxes in tracks.values())


def test_ground_truth_that_ends_before_the_run_says_what_it_costs(tmp_path,
                                                                   clip_factory) -> None:
    """Probe 51c: MOT ground truth of a clip's first 60 frames given to a run of all 150 made
    every track box after frame 60 a false positive (MOTA below 0) without a word, where
    single-target ground truth that is too short is a warning. Now it is one too, counting
    them; full ground truth gives none."""
    clip = clip_factory("multi", seed=0, frames=MULTI_FRAMES)
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{row}\n" for row in clip.mot.read_text().splitlines()
                          if int(row.split(",")[0]) <= 60))
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt", str(gt),
                                       "--no-video", "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    with open(out / "tracks.csv", newline="") as handle:
        after = sum(int(row["frame"]) > 60 for row in csv.DictReader(handle))
    note = (f"{gt}: ground truth ends at frame 60 (MOTChallenge's 1-based numbering, as "
            f"tracks.csv's), before the run's last frame 150; the {after} track boxes after it "
            "count as false positives")
    assert after > 100 and result.stderr == f"vtrack: warning: {note}\n"
    record = json.loads((out / "run.json").read_text())
    assert record["warnings"] == [note] and record["metrics"]["false_positives"] >= after
    full = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt",
                                     str(clip.mot), "--no-video", "--out", str(tmp_path / "b"),
                                     "--quiet"])
    assert full.exit_code == 0 and full.stderr == ""


def test_ground_truth_past_the_end_counts_the_inputs_frames_not_those_tracked(
        tmp_path, clip_factory) -> None:
    """Probe 52b: a multi-target run of a sequence with an image missing from its numbering
    (or from --start 10) warned that ground truth of its own last frame lay 'past the input's
    49 frames ... not evaluated', though that frame was tracked and scored: the frames were
    counted as those tracked, not the input's up to the run's end. Now only rows after the
    run's last frame are named, against the input's 60 frames."""
    clip = clip_factory("multi", seed=0, frames=60, fmt="images")
    folder = tmp_path / "seq"
    shutil.copytree(clip.path, folder)
    (folder / "img" / "0021.jpg").unlink()  # frame 20: skipped, its number kept
    rows = clip.mot.read_text().splitlines()
    longer = tmp_path / "longer.txt"
    longer.write_text("\n".join([*rows, "62,1,40,40,10,10,1,1,1"]) + "\n")
    warnings = []
    for gt in (clip.mot, longer):
        out = tmp_path / gt.stem
        result = CliRunner().invoke(main, ["run", str(folder), "--config", "s3", "--gt",
                                           str(gt), "--start", "10", "--no-video", "--out",
                                           str(out), "--quiet"])
        assert result.exit_code == 0, result.output
        record = json.loads((out / "run.json").read_text())
        assert record["frames"] == 49 and record["summary"]["frames_skipped"] == 1
        with open(out / "tracks.csv", newline="") as handle:
            assert max(int(row["frame"]) for row in csv.DictReader(handle)) == 60
        warnings.append(record["warnings"])
    assert not any("ground truth" in w for w in warnings[0]), warnings[0]
    assert [w for w in warnings[1] if "ground truth" in w] == [
        f"{longer}: ground truth has boxes in 1 frame past the input's 60 frames (up to frame "
        "62); they are not evaluated"]


def test_detections_past_the_end_are_a_warning_as_ground_truth_is(tmp_path,
                                                                    clip_factory) -> None:
    """Probe 52: a mot_detections det.txt with rows past the input's last frame gave no word
    (ground truth past the end does). It is now a warning alike, unless --frames ended the
    run before the input's end."""
    clip = clip_factory("smooth", width=160, height=120, frames=20)
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{i},-1,40,40,20,20,0.9\n" for i in (*range(1, 21), 22, 25)))
    config = tmp_path / "det.toml"
    config.write_text(f'[[stage]]\nname = "mot_detections"\npath = "{det}"\n'
                      '[[stage]]\nname = "byte_tracks"\n')
    warnings = []
    for extra in ([], ["--frames", "10"]):
        out = tmp_path / f"out{len(extra)}"
        result = CliRunner().invoke(main, ["run", str(clip.path), "-c", str(config),
                                           "--no-video", "--out", str(out), "--quiet", *extra])
        assert result.exit_code == 0, result.output
        warnings.append(json.loads((out / "run.json").read_text())["warnings"])
    assert warnings == [[f"{det}: the file has detections in 2 frames past the input's 20 "
                         "frames (up to frame 25); they were not used (is it this input's "
                         "det.txt?)"], []]


def test_detections_ending_well_before_the_end_are_a_warning_as_those_past_it_are(
        tmp_path, clip_factory) -> None:
    """A det.txt whose last detection is in frame 12 of a 40-frame input (written for a shorter
    clip) is a warning alike those past the end, counting the frames the run processed after
    it. A correct file whose scene is empty for its last few frames (its last row in frame 39)
    is none, as is a file whose rows end after fewer than half the frames the run processed
    (--start 10, rows to frame 26: 14 of 30); with --start 30 and rows to frame 12 the run's
    10 frames had none (the old note warned of the one frame early, said 28 frames there, and
    warned at --start 10). No warning when --frames ended
    the run before the input's end (its length is then not known), nor for a file whose rows
    reach the last frame."""
    clip = clip_factory("smooth", width=160, height=120, frames=40)
    warnings = []
    runs = ((39, []), (12, []), (12, ["--start", "30"]), (26, ["--start", "10"]),
            (12, ["--frames", "15"]), (40, []))
    for number, (last, extra) in enumerate(runs):
        det = tmp_path / f"det{last}.txt"
        det.write_text("".join(f"{i},-1,40,40,20,20,0.9\n" for i in range(1, last + 1)))
        config = tmp_path / f"det{last}.toml"
        config.write_text(f'[[stage]]\nname = "mot_detections"\npath = "{det}"\n'
                          '[[stage]]\nname = "byte_tracks"\n')
        out = tmp_path / f"out{number}"
        result = CliRunner().invoke(main, ["run", str(clip.path), "-c", str(config),
                                           "--no-video", "--out", str(out), *extra])
        assert result.exit_code == 0, result.output
        recorded = json.loads((out / "run.json").read_text())["warnings"]
        assert [f"vtrack: warning: {w}" for w in recorded] == [
            line for line in result.stderr.splitlines() if line.startswith("vtrack: warning")]
        warnings.append(recorded)
    det = tmp_path / "det12.txt"
    ended = (f"{det}: the file's detections end at frame 12, before the input's last frame 40; "
             "the {} frames after it had none (is it this input's det.txt?)")
    assert warnings == [[], [ended.format(28)], [ended.format(10)], [], [], []]


@pytest.mark.parametrize("start", [0, 40])
def test_a_run_scores_as_it_goes_what_its_tracks_csv_scores(tmp_path, clip_factory,
                                                           start) -> None:
    """Issue 21 item 11: a multi-target run with ground truth scored its confirmed boxes only at
    the end, keeping every frame's boxes until then. It now scores each frame as it goes
    (MotScore): run.json's measures are those of its own tracks.csv scored afterwards."""
    clip = clip_factory("multi", seed=1, frames=MULTI_FRAMES)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s3", "--gt",
                                       str(clip.mot), "--no-video", "--out", str(out), "--quiet",
                                       "--start", str(start)])
    assert result.exit_code == 0, result.output
    tracks: dict[int, list[tuple[int, Box]]] = {}
    with open(out / "tracks.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            box = Box(*(float(row[k]) for k in ("x", "y", "w", "h")))
            tracks.setdefault(int(row["frame"]) - 1 - start, []).append((int(row["id"]), box))
    from vtrack.evaluate.groundtruth import read_mot
    gt = {k - start: v for k, v in read_mot(clip.mot).items() if k >= start}
    expected = evaluate_mot(gt, tracks, MULTI_FRAMES - start)
    metrics = json.loads((out / "run.json").read_text())["metrics"]
    assert expected["id_switches"] + expected["misses"] > 0  # not a trivial score
    for key, value in expected.items():
        assert metrics[key] == pytest.approx(value, rel=1e-9), key


def test_the_mot_score_keeps_nothing_per_frame() -> None:
    """Its state grows with the ids and (object, track) pairs, not with the frames."""
    from vtrack.evaluate.mot import MotScore

    def size(frames: int) -> int:
        score = MotScore()
        for f in range(frames):
            score.add([(1, Box(10 + f % 7, 10, 20, 20)), (2, Box(60, 60, 20, 20))],
                      [(5, Box(11, 10, 20, 20)), (6, Box(200, 60, 20, 20))])
        return sum(len(v) for v in vars(score).values() if isinstance(v, dict))

    assert size(10) == size(2000)


def test_vtrack_run_s4_needs_no_init(tmp_path, clip_factory) -> None:
    clip = clip_factory("bounce", seed=0, frames=90)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(clip.path), "--config", "s4", "--no-video",
                                       "--out", str(out), "--quiet"])
    assert result.exit_code == 0, result.output
    with open(out / "track.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert {row["state"] for row in rows[:30]} == {"lost"}  # learning the background
    assert {row["state"] for row in rows[30:]} == {"tracking"}



def test_a_score_is_given_exactly_by_the_chains_that_declare_one(scene_factory) -> None:
    """Probe 48 item 4: the stages reference says which shipped configs give no score (S4:
    its document defines no confidence, so track.csv's score is empty); that declaration
    (``Pipeline.gives_score``: a stage provides ``score``) is what each single-target config
    does on a clip."""
    from vtrack import track
    from vtrack.config import shipped_configs

    scene = scene_factory("bounce", 0, 160, 120, 40)
    first = scene.boxes[0]
    assert first is not None
    frames = list(scene.frames())
    unscored = []
    for name in sorted(shipped_configs()):
        pipeline = Pipeline(load_config(name).build())
        if pipeline.multi_target:
            continue
        init = None if not pipeline.needs_init_box else first
        scores = [r.score for r in track(frames, name, init_box=init)]
        assert any(math.isfinite(s) for s in scores) == pipeline.gives_score, name
        if not pipeline.gives_score:
            unscored.append(name)
    assert unscored == ["s4"]
    from vtrack.cli.stages import stages_text

    reference = stages_text(markdown=True)
    assert [line for line in reference.splitlines() if "no score" in line] == [
        next(line for line in reference.splitlines() if line.startswith("- `s4`:"))]


def test_motchallenge_ground_truth_is_read_as_written_whatever_gt_origin_says(
        clip_factory, tmp_path) -> None:
    """`vtrack run m.mp4 -c s3 --gt m.mot.txt --gt-origin 1` scored exactly as --gt-origin 0,
    while --help said the option sets the origin of ground-truth boxes: MOTChallenge ground
    truth is read as written (as TrackEval reads it). --help now says the option is for
    single-target ground truth."""
    clip = clip_factory("multi", width=160, height=120, frames=60)
    scores = []
    for origin in ("0", "1"):
        out = tmp_path / origin
        result = CliRunner().invoke(main, ["run", str(clip.path), "-c", "s3", "--gt",
                                           str(clip.mot), "--gt-origin", origin, "--no-video",
                                           "-q", "-o", str(out)])
        assert result.exit_code == 0, result.output
        scores.append(json.loads((out / "run.json").read_text())["metrics"])
    assert scores[0] == scores[1] and scores[0]["motp"] is not None
    text = " ".join(CliRunner().invoke(main, ["run", "--help"]).output.split())
    assert "Origin of single-target ground-truth boxes" in text
    assert "MOTChallenge ground truth is read as written" in text


def test_a_box_as_written_keeps_sizes_positive_rounds_like_the_cells_and_keeps_nan():
    """box_as_written: pixels to a thousandth as the cells hold them, a width or height never
    under 0.001 (a det.txt's box of 1e-06 pixels was written 0), a non-finite value kept (its
    cell is empty; it raised ValueError)."""
    import math

    from vtrack.geometry import Box
    from vtrack.io.csvfile import box_as_written

    assert tuple(box_as_written(Box(1.23449, 2.0005001, 1e-06, 0.0))) == (1.234, 2.001, 0.001,
                                                                          0.001)
    assert tuple(box_as_written(Box(10.0, 20.0, 30.4444, 40.5556))) == (10.0, 20.0, 30.444,
                                                                         40.556)
    kept = box_as_written(Box(math.nan, 1.0, 5.0, math.nan))
    assert math.isnan(kept.x) and math.isnan(kept.h) and (kept.y, kept.w) == (1.0, 5.0)
