"""Annotator: shapes land in the Y, U and V planes where they belong, and nowhere else."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from vtrack.annotate import (
    GROUND_TRUTH,
    PARTICLES,
    TRACK_PALETTE,
    TRACKED,
    WINDOW,
    Annotator,
    Yuv,
)
from vtrack.geometry import Box, Window
from vtrack.io.planes import i420_planes, rotate_i420
from vtrack.overlays import Particles, SearchWindow
from vtrack.pipeline import FrameResult
from vtrack.stages.base import Track, TrackState, TrackStatus

W, H = 320, 240


def blank() -> np.ndarray:
    return cv2.cvtColor(np.full((H, W, 3), 100, np.uint8), cv2.COLOR_BGR2YUV_I420)


GREY = int(blank()[0, 0])  # the background's luma


BOX = Box(100, 80, 60, 50)


def result(index: int = 0, box: Box | None = BOX, state: TrackState = TrackState.TRACKING,
           **kwargs) -> FrameResult:
    return FrameResult(index, index / 30, box, state, 1.0, None, **kwargs)


def planes(buffer: np.ndarray) -> tuple[np.ndarray, ...]:
    return i420_planes(buffer, W, H)


def test_colours_are_opencv_bt601_conversions():
    assert Yuv.from_bgr(255, 255, 255) == (235, 128, 128)
    assert Yuv.from_bgr(0, 0, 0) == (16, 128, 128)
    green = GROUND_TRUTH
    assert green.u < 128 and green.v < 128
    bgr = cv2.cvtColor(np.array([[TRACKED.y] * 2] * 2 + [[TRACKED.u, TRACKED.v]], np.uint8),
                       cv2.COLOR_YUV2BGR_I420)
    assert np.abs(bgr[0, 0].astype(int) - (0, 255, 255)).max() <= 6


def test_box_and_centre_are_drawn_in_all_planes_and_nothing_else_changes():
    buf = blank()
    before = buf.copy()
    Annotator(W, H).draw(buf, result())
    y, u, v = planes(buf)
    y0, u0, v0 = planes(before)
    assert y[80:130, 100].tolist() == [TRACKED.y] * 50  # left edge, full resolution
    assert u[50, 50] == TRACKED.u and v[50, 50] == TRACKED.v  # left edge, half resolution
    assert y[105, 130] == TRACKED.y  # the centre dot
    changed = np.argwhere(y[20:] != y0[20:]) + (20, 0)  # below the caption: the box only
    assert changed[:, 0].min() >= 78 and changed[:, 1].min() >= 98
    assert changed[:, 0].max() <= 131 and changed[:, 1].max() <= 161
    assert (u != u0).any() and (v != v0).any()


def test_lost_draws_caption_top_right_and_no_box():
    annotator = Annotator(W, H)
    buf = blank()
    annotator.draw(buf, result(box=None, state=TrackState.LOST))
    y = planes(buf)[0]
    assert (y[:15, W - 40 :] != GREY).any()  # the caption, top right
    assert (y[:15, :60] == GREY).all()  # nothing top left
    assert (y[30:, :] == GREY).all()  # no box


@pytest.mark.parametrize("state", [TrackState.TRACKING, TrackState.OCCLUDED])
def test_state_caption_top_left(state):
    buf = blank()
    Annotator(W, H).draw(buf, result(state=state))
    y = planes(buf)[0]
    assert (y[:15, :60] != GREY).any() and (y[:15, W - 40 :] == GREY).all()


def test_ground_truth_overlays_and_trail():
    gt = [Box(20, 150, 40, 40)] * 10
    annotator = Annotator(W, H, gt=gt, trail=5)
    particles = (Box(200, 200, 10, 10), Box(250, 30, 4, 4))
    for i in range(4):  # the box moves right 10 px per frame
        buf = blank()
        annotator.draw(buf, result(i, Box(100 + 10 * i, 80, 60, 50), overlays=[
            SearchWindow(Window(90, 60, 230, 150).as_box()), Particles(particles),
        ]))
    y, u, v = planes(buf)
    assert y[160, 20] == GROUND_TRUTH.y and u[80, 10] == GROUND_TRUTH.u
    assert y[100, 90] == WINDOW.y  # thin search window
    assert y[205, 205] == PARTICLES.y and v[102, 102] == PARTICLES.v  # particle centre dot
    assert y[32, 252] == PARTICLES.y
    assert (y[103:108, 145] != GREY).any()  # trail between earlier centres


def test_confirmed_tracks_get_stable_colours_and_ids():
    annotator = Annotator(W, H)
    for i in range(3):
        buf = blank()
        annotator.draw(buf, result(i, box=None, tracks=[
            Track(3, Box(40 + 5 * i, 40, 30, 60), 0.9, TrackStatus.CONFIRMED),
            Track(4, Box(200, 150, 30, 30), 0.2, TrackStatus.TENTATIVE),
        ]))
    y, u, _ = planes(buf)
    colour = TRACK_PALETTE[3 % len(TRACK_PALETTE)]
    assert y[60, 50] == colour.y and u[30, 25] == colour.u
    assert (y[20:38, 50:70] != GREY).any()  # the id above the box
    assert (y[140:190, 190:240] == GREY).all()  # tentative tracks are not drawn


def test_an_overlay_of_unknown_kind_is_an_error():
    with pytest.raises(TypeError, match="overlay"):
        Annotator(W, H).draw(blank(), result(overlays=[("window", Box(1, 1, 5, 5))]))


def test_boxes_far_outside_or_invalid_are_harmless():
    buf = blank()
    annotator = Annotator(W, H, gt=[Box(float("nan"), 0, 10, 10)])
    annotator.draw(buf, result(box=Box(-1e12, 5e11, 1e13, 3)))
    annotator.draw(buf, result(1, box=Box(10, 10, 0, 0)))
    y, u, v = planes(buf)
    # only the state caption (top left) was drawn: no box, centre, trail or ground truth
    assert (y[20:, :] == GREY).all() and (y[:, 80:] == GREY).all()
    assert (y[:15, :60] != GREY).any()


def test_rotate_i420_turns_every_plane():
    buf = blank()
    y, u, v = planes(buf)
    y[:2, :2] = 250
    u[0, 0] = 10
    turned = rotate_i420(buf, W, H, 90)
    ty, tu, tv = i420_planes(turned, H, W)
    assert ty.shape == (W, H) and tu.shape == (W // 2, H // 2)
    assert (ty[-2:, :2] == 250).all() and tu[-1, 0] == 10
    np.testing.assert_array_equal(rotate_i420(rotate_i420(buf, W, H, 180), W, H, 180), buf)
