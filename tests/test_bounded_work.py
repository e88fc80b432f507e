"""Issue 21 items 11 and 12: work and memory per frame stay bounded at every declared value.
Multi-target runs keep no boxes for metrics without ground truth; `kalman_tracks` and
`byte_tracks` keep at most `max_tracks` tracks, `mht` as many per hypothesis; large morphology
kernels, many particles over a large box and many kernel mean-shift steps over a large box are
capped per frame, while the shipped configs' own values give exactly what they gave before."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import vtrack
from vtrack.geometry import Box
from vtrack.pipeline import FrameResult
from vtrack.run import _MultiTargetRows
from vtrack.scenes import make_scene
from vtrack.stages.base import Track, TrackStatus
from vtrack.stages.detect import MAX_KERNEL, _morphology, cleaning_steps
from vtrack.stages.kernel_meanshift import ITERATION_BUDGET, SAMPLED_ABOVE, sampling_stride


def specks(count: int, width: int = 160, height: int = 120, speck: int = 2) -> list[np.ndarray]:
    """A black frame, then frames of 60 white ``speck`` x ``speck`` squares at new random places
    each."""
    rng = np.random.default_rng(0)
    frames = [np.zeros((height, width, 3), np.uint8)]
    for _ in range(count - 1):
        frame = np.zeros((height, width, 3), np.uint8)
        for x, y in zip(rng.integers(0, width - speck, 60),
                        rng.integers(0, height - speck, 60), strict=True):
            frame[y:y + speck, x:x + speck] = 255
        frames.append(frame)
    return frames


def test_tracks_are_capped_whatever_max_coast_lets_live() -> None:
    tracker = vtrack.Tracker("s4_multi", background__frames=1, blobs__min_area=1,
                             kalman_tracks__max_coast=100000, kalman_tracks__confirm=1,
                             kalman_tracks__max_tracks=40)
    frames = specks(30)
    tracker.init(frames[0])
    counts = [len(tracker.update(frame).tracks) for frame in frames[1:]]
    assert max(counts) == 40  # the specks make far more; the cap holds every frame


def test_mht_tracks_are_capped_whatever_miss_delete_and_max_coast_let_live() -> None:
    # P_R never falls (miss 0) and no branch is deleted for 100000 frames: without the cap each
    # frame's specks start tracks that all live on, and a frame's work grows with the run
    tracker = vtrack.Tracker("s3", threshold__median=1, blobs__min_area=1, mht__miss=0.0,
                             mht__delete=-1e6, mht__max_coast=100000, mht__confirm=1.0,
                             mht__max_tracks=40)
    frames = specks(30)
    tracker.init(frames[0])
    counts = [len(tracker.update(frame).tracks) for frame in frames[1:]]
    assert max(counts) == 40  # the specks make far more; the cap holds every frame


def test_byte_tracks_are_capped_whatever_max_coast_lets_live() -> None:
    # fixed_camera set to keep every speck (no opening, no learnt shape) and never match one to
    # a track (no motion gate to speak of): each frame's specks start tracks that all coast on
    tracker = vtrack.Tracker(
        "fixed_camera", background__method="mean", background__frames=1, background__open=1,
        background__close=1, background__open_share=0.0, background__close_share=0.0,
        background__max_pixels=0, background__gain=False, blobs__min_area=1,
        blobs__min_area_share=0.0, group_blobs__aspect=1.0, group_blobs__learn=False,
        group_blobs__split=0.0, group_blobs__max_shape=100.0, group_blobs__min_share=0.0,
        byte_tracks__max_coast=100000, byte_tracks__confirm=1, byte_tracks__colour_gate=1.0,
        byte_tracks__q=0.0, byte_tracks__p0=0.0, byte_tracks__gate=0.1,
        byte_tracks__max_tracks=40)
    frames = specks(30, speck=6)
    tracker.init(frames[0])
    counts = [len(tracker.update(frame).tracks) for frame in frames[1:]]
    assert max(counts) == 40  # the specks make far more; the cap holds every frame


def test_no_boxes_are_kept_per_frame_with_or_without_ground_truth() -> None:
    """Without ground truth nothing is scored; with it each frame is scored as it goes (the
    scorer's counts grow with ids, not frames) and the run's measures come out at the end."""
    track = Track(1, Box(1, 2, 3, 4), 1.0, TrackStatus.CONFIRMED)
    truth = {index: [(7, Box(1, 2, 3, 4))] for index in range(400)}
    scored, plain = _MultiTargetRows(truth, 0), _MultiTargetRows(None, 0)
    sizes = []
    for index in range(400):
        result = FrameResult(index=index, time_s=index / 30, box=None, state="tracking",
                             score=None, prediction=None, tracks=[track])
        assert scored.rows(result) == plain.rows(result)
        if index in (49, 399):
            sizes.append(sum(len(v) for v in vars(scored.score).values() if isinstance(v, dict)))
    assert plain.score is None and sizes[0] == sizes[1]
    measures = scored.mot(400)
    assert measures["mota"] == 1.0 and measures["matches"] == 400


@pytest.mark.parametrize("size", [3, 17, 31])
def test_kernels_up_to_the_cap_are_cv2_morphology_exactly(size: int) -> None:
    mask = (np.random.default_rng(size).random((120, 160)) > 0.8).astype(np.uint8) * 255
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))
    for operation in (cv2.MORPH_OPEN, cv2.MORPH_CLOSE):
        assert np.array_equal(_morphology(mask, operation, kernel, 1),
                              cv2.morphologyEx(mask, operation, kernel))


def test_a_larger_kernel_runs_on_a_shrunk_mask() -> None:
    steps = cleaning_steps(255.0, 255.0, 1)
    assert all(size <= MAX_KERNEL for _, size, _ in steps)
    assert [factor for _, _, factor in steps] == [9, 9]  # 255 / 9 = 28 <= 31
    tracker = vtrack.Tracker("s4", background__open=255, background__close=255)
    scene = make_scene("bounce", 0, 320, 240, 60, 30.0)
    result = tracker.init(scene.frame(0))
    for index in range(1, 40):
        result = tracker.update(scene.frame(index))
    assert result.index == 39


def test_kernel_mean_shift_steps_over_a_large_box_stop_at_the_budget() -> None:
    scene = make_scene("smooth", 0, 160, 120, 30, 30.0)
    steps = {}
    for name, box in (("whole", (0, 0, 160, 120)), ("small", scene.boxes[0])):
        tracker = vtrack.Tracker("s2", kernel_meanshift__max_iterations=100,
                                 kernel_meanshift__epsilon=0, kernel_meanshift__bins=256,
                                 kernel_meanshift__failure_logic=False)
        tracker.init(scene.frame(0), box)
        steps[name] = max(int(tracker.update(scene.frame(i)).extras["iterations"])
                          for i in range(1, 10))
    # three bandwidths, each within budget (the smallest, 0.9 of the box, gets one more step);
    # each step reads the whole-frame window on every second row and column
    assert sampling_stride(160 * 120, 160 * 120) == 2
    assert steps["whole"] <= 3 * (ITERATION_BUDGET + 1)
    assert steps["small"] > 3 * (ITERATION_BUDGET + 1)  # a small box still steps as asked


def test_fixed_kernel_mean_shift_over_a_whole_frame_box_stops_at_the_budget() -> None:
    scene = make_scene("smooth", 0, 160, 120, 30, 30.0)
    tracker = vtrack.Tracker("s2-fixed", kernel_meanshift_int__max_iterations=100,
                             kernel_meanshift_int__failure_logic=False)
    tracker.init(scene.frame(0), (0, 0, 160, 120))
    steps = max(int(tracker.update(scene.frame(i)).extras["iterations"]) for i in range(1, 10))
    assert 3 <= steps <= 3 * ITERATION_BUDGET


@pytest.mark.parametrize("share", [0.01, 0.3, SAMPLED_ABOVE, 0.51, 1.0, 1.44, 4.0])
def test_kernel_mean_shift_reads_at_most_its_share_of_the_frame(share: float) -> None:
    frame_pixels = 1280 * 720
    window_pixels = round(share * frame_pixels)
    stride = sampling_stride(window_pixels, frame_pixels)
    assert window_pixels / stride**2 <= SAMPLED_ABOVE * frame_pixels
    # every pixel up to the bound (the real sequences' boxes), the coarsest grid no coarser
    # than needed above it
    assert (stride == 1) == (share <= SAMPLED_ABOVE)
    assert stride == 1 or window_pixels / (stride - 1) ** 2 > SAMPLED_ABOVE * frame_pixels
