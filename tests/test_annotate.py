"""Annotator: shapes land in the Y, U and V planes where they belong, and nowhere else."""

from __future__ import annotations

import csv

import cv2
import numpy as np
import pytest

from vtrack.annotate import (
    GROUND_TRUTH,
    GROUND_TRUTH_BGR,
    LEGEND_MAX_SHARE,
    LEGEND_ROWS,
    PARTICLES,
    PREDICTION,
    TRACK_PALETTE,
    TRACK_PALETTE_BGR,
    TRACKED,
    WINDOW,
    Annotator,
    Legend,
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
    Annotator(W, H, legend=False).draw(buf, result())
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
    annotator = Annotator(W, H, legend=False)
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
    particles = np.array([[205.0, 205.0], [252.0, 32.0]])  # centres
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
    annotator = Annotator(W, H, gt=[Box(float("nan"), 0, 10, 10)], legend=False)
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


def test_the_prediction_is_a_thin_box_in_its_own_colour():
    buf = blank()
    Annotator(W, H, legend=False).draw(buf, FrameResult(0, 0.0, BOX, TrackState.TRACKING, 1.0,
                                                        Box(200, 20, 40, 30)))
    y, u, v = planes(buf)
    assert y[35, 200] == PREDICTION.y and u[17, 100] == PREDICTION.u
    assert y[35, 201] == GREY  # one pixel wide


def legend_block(y: np.ndarray) -> np.ndarray:
    """The bottom-left rows the legend may use."""
    return y[H - int(LEGEND_MAX_SHARE * H):, : W // 2]


def test_legend_and_frame_number_bottom_left():
    annotator = Annotator(W, H, gt=[BOX] * 3)
    shown = []
    for index in (0, 7):
        buf = blank()
        annotator.draw(buf, result(index))
        y, u, v = planes(buf)
        block = legend_block(y)
        assert (block == 16).any()  # the legend's black background
        # each colour's swatch is there, luma and chroma (chroma at half resolution)
        legend = annotator.legend
        assert legend is not None and legend.rows == ("box", "ground truth")
        ph, pw = legend.y.shape
        corner_u = u[legend.y0 // 2:(legend.y0 + ph) // 2, : pw // 2]
        for colour in (TRACKED, GROUND_TRUTH):
            assert ((np.abs(corner_u.astype(int) - colour.u) <= 2).sum()) >= 4, colour
        shown.append(y[legend.y0:legend.y0 + legend.row, :pw].copy())
    assert (shown[0] != shown[1]).any()  # the frame number changed
    without_gt = Annotator(W, H)
    without_gt.draw(blank(), result())
    assert without_gt.legend is not None and without_gt.legend.rows == ("box",)


def test_the_legend_lists_what_this_run_drew_as_it_first_appears():
    """Issue 22: the legend was the same for every tracker (a search window and a prediction
    for trackers without them, no row for particles or LOST). Rows now appear with the first
    frame that draws them, in one fixed order, and stay."""
    annotator = Annotator(W, H)
    frames = [
        result(0, overlays=[Particles(np.array([[205.0, 205.0]]))]),
        result(1, box=None, state=TrackState.LOST),
        result(2, state=TrackState.OCCLUDED, overlays=[SearchWindow(Box(90, 60, 140, 90))]),
        FrameResult(3, 0.1, BOX, TrackState.TRACKING, 1.0, Box(200, 20, 40, 30)),
    ]
    rows = []
    for frame in frames:
        buf = blank()
        annotator.draw(buf, frame)
        assert annotator.legend is not None
        rows.append(annotator.legend.rows)
    assert rows == [
        ("box", "particles"),
        ("box", "lost (no box)", "particles"),
        ("box", "occluded", "lost (no box)", "search window", "particles"),
        ("box", "occluded", "lost (no box)", "prediction", "search window", "particles"),
    ]
    legend = annotator.legend
    ph, pw = legend.y.shape
    u = planes(buf)[1][legend.y0 // 2:(legend.y0 + ph) // 2, : pw // 2].astype(int)
    for label in legend.rows:
        colour = Yuv.from_bgr(*LEGEND_ROWS[label][0])
        assert (np.abs(u - colour.u) <= 2).sum() >= 4, label
    assert legend.y.size <= 0.1 * W * H  # 6 rows at 320x240: under a tenth of the frame


@pytest.mark.parametrize(("width", "height", "size"), [(320, 240, 2), (1280, 720, 4),
                                                       (1920, 1080, 6)])
def test_particles_are_dots_that_grow_with_the_frame(width, height, size):
    buf = cv2.cvtColor(np.full((height, width, 3), 100, np.uint8), cv2.COLOR_BGR2YUV_I420)
    grey = int(buf[0, 0])
    Annotator(width, height, legend=False).draw(buf, result(
        box=None, state=TrackState.LOST, overlays=[Particles(np.array([[110.0, 110.0]]))]))
    y = i420_planes(buf, width, height)[0]
    dot = np.argwhere(y[60:, :] == PARTICLES.y) + (60, 0)
    assert len(dot) == size * size
    assert np.ptp(dot[:, 0]) == size - 1 and np.ptp(dot[:, 1]) == size - 1
    assert abs(dot[:, 0].mean() - 110) <= 1 and abs(dot[:, 1].mean() - 110) <= 1
    assert (y[60:] != grey).sum() == size * size  # nothing else below the caption


def test_an_annotated_clip_shows_the_legend_and_the_frame_number(clip_factory, tmp_path):
    """Decode a real annotated.mp4: the legend's colours are in the bottom-left corner of
    every frame and the frame-number row changes from frame to frame."""
    import av
    from click.testing import CliRunner

    from vtrack.cli import main

    clip = clip_factory("smooth", width=W, height=H, frames=16)
    out = tmp_path / "out"
    done = CliRunner().invoke(main, ["run", str(clip.path), "--gt", str(clip.gt), "-o", str(out),
                                     "-c", "s1", "--set", "particle.draw_particles=true"])
    assert done.exit_code == 0, done.output
    with (out / "track.csv").open() as f:
        lost = [row["state"] == "lost" for row in csv.DictReader(f)]
    with av.open(str(out / "annotated.mp4")) as container:
        frames = [f.to_ndarray(format="bgr24") for f in container.decode(video=0)]
    assert len(frames) == 16
    font_scale = Annotator(W, H).font_scale
    number_rows = []
    for index in (2, 12):
        # what s1 has drawn by then: its box, its particles (asked for), the ground truth,
        # and the lost caption once it has been lost
        drawn = ("box", "particles", "ground truth") + (
            ("lost (no box)",) if any(lost[:index + 1]) else ())
        legend = Legend(W, H, font_scale, drawn)
        assert set(legend.rows) == set(drawn)
        ph, pw = legend.y.shape
        corner = frames[index][legend.y0:legend.y0 + ph, :pw].astype(int)
        assert (corner.max(axis=2) < 40).mean() > 0.5  # mostly the black background
        for colour in (LEGEND_ROWS[label][0] for label in drawn):
            near = np.abs(corner - colour).max(axis=2) < 60
            assert near.sum() >= 6, colour
        number_rows.append(corner[:legend.row, :, 1])
    # "frame 2" vs "frame 12": white vs black
    assert np.abs(number_rows[0] - number_rows[1]).max() > 120


def test_a_multi_target_frame_counts_its_tracks_and_explains_the_id_colours():
    """No single-target TRACKING caption: the caption counts the confirmed tracks, the legend
    has the per-id colours, each track is drawn in its id's colour, ground truth thin green."""
    tracks = [Track(1, Box(40, 60, 30, 70), 0.9, TrackStatus.CONFIRMED),
              Track(2, Box(200, 60, 30, 70), 0.9, TrackStatus.CONFIRMED),
              Track(3, Box(120, 60, 30, 70), 0.9, TrackStatus.COASTING)]
    truth = {0: [(7, Box(20, 150, 40, 40))]}
    annotator = Annotator(W, H, multi_target=True, gt_tracks=truth)
    buf = blank()
    annotator.draw(buf, result(box=None, tracks=tracks))
    assert annotator.legend is not None and annotator.legend.rows == ("track id", "ground truth")
    y, u, v = planes(buf)
    for track in tracks[:2]:
        colour = TRACK_PALETTE[track.id % len(TRACK_PALETTE)]
        assert y[int(track.box.y) + 35, int(track.box.x)] == colour.y
    assert (y[95, 120:150] == GREY).all()  # the coasting track is not drawn
    assert y[170, 20] == GROUND_TRUTH.y
    single = blank()
    Annotator(W, H).draw(single, result(box=None))
    caption = (slice(0, 14), slice(0, 80))
    assert not np.array_equal(y[caption], planes(single)[0][caption])  # "2 TRACKS", not TRACKING
    without_truth = Annotator(W, H, multi_target=True)
    without_truth.draw(blank(), result(box=None, tracks=tracks))
    assert without_truth.legend.rows == ("track id",)


def test_a_multi_target_frame_is_numbered_as_its_tracks_csv_rows() -> None:
    """Probe 51c: a multi-target video wrote 'frame 30' on the frame whose boxes tracks.csv
    (1-based, MOTChallenge) lists as frame 31, while its frame 30 rows held the boxes of the
    frame before. The label is now tracks.csv's number: frame index 30 reads 'frame 31', as a
    single-target frame index 31 does (track.csv is 0-based)."""
    def label(annotator: Annotator, index: int) -> np.ndarray:
        buf = blank()
        annotator.draw(buf, result(index, box=None))
        legend = annotator.legend
        assert legend is not None
        return planes(buf)[0][legend.y0:legend.y0 + legend.row, :legend.y.shape[1]].copy()

    multi = label(Annotator(W, H, multi_target=True), 30)
    assert np.array_equal(multi, label(Annotator(W, H), 31))
    assert not np.array_equal(multi, label(Annotator(W, H), 30))


def test_no_track_colour_passes_for_the_ground_truths_green() -> None:
    """Tracks 3 and 5 were drawn in (0, 255, 128) and (128, 255, 0): on a multi-target run
    with ground truth they could not be told from its green boxes."""
    def hsv(bgr: tuple[int, int, int]) -> tuple[int, int, int]:
        return tuple(int(v) for v in cv2.cvtColor(np.uint8([[bgr]]), cv2.COLOR_BGR2HSV)[0, 0])

    truth_hue = hsv(GROUND_TRUTH_BGR)[0]
    for colour in TRACK_PALETTE_BGR:
        hue, saturation, _ = hsv(colour)
        distance = min(abs(hue - truth_hue), 180 - abs(hue - truth_hue))  # OpenCV: 0..180
        assert saturation < 64 or distance >= 30, colour


@pytest.mark.parametrize("box", [Box(-40, 60, 80, 70), Box(150, -20, 40, 80),
                                 Box(290, 0, 60, 70), Box(-30, -30, 70, 90)],
                         ids=["left", "top", "right-top", "top-left"])
def test_a_track_cut_by_the_frames_border_shows_its_id(box: Box) -> None:
    """Probe O: a track boxed beyond the frame's left or top border (fixed_camera boxes a person
    cut by the border whole) had its id drawn above its top-left corner, outside the frame: the
    box was there, its id nowhere. Tracks 1 and 11 share a colour: only their ids differ."""
    def drawn(track_id: int) -> np.ndarray:
        buf = blank()
        Annotator(W, H, multi_target=True, legend=False).draw(
            buf, result(box=None, tracks=[Track(track_id, box, 0.9, TrackStatus.CONFIRMED)]))
        return planes(buf)[0].copy()

    assert TRACK_PALETTE[1] == TRACK_PALETTE[11 % len(TRACK_PALETTE)]
    one, eleven = drawn(1), drawn(11)
    differ = np.argwhere(one != eleven)
    assert len(differ) > 10  # the ids are written where they can be seen
    caption_h = 20  # the "1 TRACK" caption covers the top-left corner
    assert ((differ[:, 0] >= caption_h) | (differ[:, 1] >= 80)).any()


def test_a_tracks_id_reads_on_a_target_of_its_own_colour() -> None:
    """Probe O: ids were bare text in the track's colour: on `vtrack scene street` track 25's
    magenta id over a magenta vehicle could not be read. An id is now on a black plate."""
    colour = TRACK_PALETTE_BGR[5 % len(TRACK_PALETTE_BGR)]
    frame = cv2.cvtColor(np.full((H, W, 3), colour, np.uint8), cv2.COLOR_BGR2YUV_I420)
    box = Box(100, 100, 60, 80)
    Annotator(W, H, multi_target=True, legend=False).draw(
        frame, result(box=None, tracks=[Track(5, box, 0.9, TrackStatus.CONFIRMED)]))
    y = planes(frame)[0]
    above = y[60:int(box.y) - 1, int(box.x):int(box.x) + 30]  # where the id is written
    assert int(above.min()) <= 40 < TRACK_PALETTE[5].y - 40  # dark under the id: it reads
