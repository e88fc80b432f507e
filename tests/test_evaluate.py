"""Ground-truth readers and OTB single-target metrics, checked against hand-computed values."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from vtrack.errors import ConfigError, InputError, number_text
from vtrack.evaluate import (
    ERROR_THRESHOLDS,
    OVERLAP_THRESHOLDS,
    auc,
    flagged_miss_rate,
    frame_scores,
    mean_center_error,
    mean_overlap,
    negative_note,
    parse_box,
    precision_at,
    precision_curve,
    read_boxes,
    read_mot,
    read_mot_detections,
    read_truth,
    success_curve,
    summarize,
    tracking_miss_rate,
)
from vtrack.evaluate.groundtruth import MultiTargetTruthError
from vtrack.geometry import Box, center_error, iou, iou_matrix
from vtrack.io.sidecar import parse_sidecar

G = Box(0, 0, 10, 10)


def write(tmp_path, text, name="gt.txt"):
    path = tmp_path / name
    path.write_text(text)
    return path


# --- per-frame IoU and centre error -------------------------------------------------------------


@pytest.mark.parametrize(
    ("pred", "expected"),
    [
        (Box(0, 0, 10, 10), 1.0),  # identical
        (Box(20, 20, 10, 10), 0.0),  # disjoint
        (Box(10, 0, 10, 10), 0.0),  # touching edges
        (Box(5, 0, 10, 10), 50 / 150),  # half of each overlaps: 50 / (100 + 100 - 50)
        (Box(2, 2, 4, 4), 16 / 100),  # contained
        (Box(0, 0, 10, 5), 0.5),  # top half
    ],
)
def test_iou_of_known_boxes(pred, expected):
    assert iou(pred, G) == pytest.approx(expected)
    assert frame_scores([pred], [G])[0] == [pytest.approx(expected)]


def test_center_error_is_euclidean_distance_of_centres():
    assert center_error(Box(3, 4, 10, 10), G) == pytest.approx(5.0)
    assert frame_scores([Box(3, 4, 10, 10)], [G])[1] == [pytest.approx(5.0)]


def test_lost_frame_scores_zero_overlap_and_infinite_error():
    overlaps, errors = frame_scores([None, Box(0, 0, 0, 0)], [G, G])
    assert overlaps == [0.0, 0.0]
    assert errors == [math.inf, math.inf]


def test_absent_or_missing_ground_truth_is_not_evaluated():
    pred = [G, G, G, G]
    overlaps, errors = frame_scores(pred, [None, Box(0, 0, 0, 0), G])  # gt ends before pred
    assert overlaps == [None, None, 1.0, None]
    assert errors == [None, None, 0.0, None]
    assert frame_scores([G], [G, G]) == ([1.0], [0.0])  # gt beyond pred is not scored


# --- success / AUC ------------------------------------------------------------------------------


def test_thresholds_are_otb_grids():
    assert OVERLAP_THRESHOLDS.shape == (21,)
    assert OVERLAP_THRESHOLDS[0] == 0.0 and OVERLAP_THRESHOLDS[-1] == 1.0
    assert OVERLAP_THRESHOLDS[6] == 0.3  # exact, so "IoU == threshold" behaves as written
    np.testing.assert_array_equal(ERROR_THRESHOLDS, np.arange(51))
    with pytest.raises(ValueError):
        OVERLAP_THRESHOLDS[0] = 1.0


def test_auc_of_known_overlaps():
    # Evaluated IoUs 0, 0.5, 1 (None is excluded). IoU > t: t = 0..0.45 (10 thresholds) -> 2/3,
    # t = 0.5..0.95 (10) -> 1/3 (0.5 is not > 0.5), t = 1 -> 0. Mean = (20/3 + 10/3) / 21 = 10/21.
    overlaps = [0.0, 0.5, 1.0, None]
    expected = np.array([2 / 3] * 10 + [1 / 3] * 10 + [0.0])
    np.testing.assert_allclose(success_curve(overlaps), expected)
    assert auc(overlaps) == pytest.approx(10 / 21)
    assert mean_overlap(overlaps) == pytest.approx(0.5)


def test_success_is_strictly_greater():
    # IoU exactly 0.3 passes t = 0..0.25 (6 thresholds) but not t = 0.3.
    curve = success_curve([0.3])
    np.testing.assert_array_equal(curve, [1.0] * 6 + [0.0] * 15)
    assert auc([0.3]) == pytest.approx(6 / 21)
    # From real boxes: IoU exactly 0.5 does not count at t = 0.5.
    overlaps, _ = frame_scores([Box(0, 0, 10, 5)], [G])
    assert success_curve(overlaps)[10] == 0.0 and success_curve(overlaps)[9] == 1.0
    # A perfect tracker scores 20/21, since no IoU is > 1.
    assert auc([1.0]) == pytest.approx(20 / 21)


# --- precision ----------------------------------------------------------------------------------


def test_precision_counts_error_equal_to_threshold():
    _, errors = frame_scores([Box(20, 0, 10, 10)], [G])  # centres exactly 20 px apart
    assert errors == [20.0]
    assert precision_at(errors, 20) == 1.0
    assert precision_at([20.000001], 20) == 0.0
    curve = precision_curve(errors)
    assert curve.shape == (51,)
    np.testing.assert_array_equal(curve, [0.0] * 20 + [1.0] * 31)
    assert precision_curve(errors, max_px=10).shape == (11,)


def test_lost_frames_fail_every_threshold():
    overlaps, errors = frame_scores([None, G], [G, G])
    np.testing.assert_array_equal(success_curve(overlaps), [0.5] * 20 + [0.0])
    np.testing.assert_array_equal(precision_curve(errors), [0.5] * 51)
    assert mean_center_error(errors) == 0.0  # finite mean over frames with a box


def test_no_evaluated_frames_gives_nan():
    assert np.isnan(success_curve([None, None])).all()
    assert np.isnan(precision_curve([])).all()
    assert math.isnan(auc([])) and math.isnan(mean_overlap([None]))
    assert math.isnan(precision_at([])) and math.isnan(mean_center_error([math.inf]))


# --- summary ------------------------------------------------------------------------------------


def test_summarize_hand_computed():
    pred = [G, Box(5, 0, 10, 10), None, G]
    gt = [G, G, G, None]
    # Evaluated: frames 0-2, IoUs 1, 1/3, 0; errors 0, 5, inf.
    # IoU > t: t = 0..0.30 (7 thresholds) -> 2/3; t = 0.35..0.95 (13) -> 1/3; t = 1 -> 0.
    summary = summarize(pred, gt)
    assert list(summary) == [
        "frames_evaluated",
        "mean_overlap",
        "auc",
        "precision20",
        "mean_center_error",
    ]
    assert summary["frames_evaluated"] == 3
    assert summary["mean_overlap"] == pytest.approx(4 / 9)
    assert summary["auc"] == pytest.approx((7 * 2 / 3 + 13 / 3) / 21)
    assert summary["precision20"] == pytest.approx(2 / 3)
    assert summary["mean_center_error"] == pytest.approx(2.5)


def test_state_honesty_hand_computed():
    far = Box(50, 50, 10, 10)
    pred = [G, far, far, None, far, G, far]
    gt = [G, G, G, G, G, G, None]
    states = ["tracking", "tracking", "occluded", "lost", "tracking", "occluded", "tracking"]
    # Evaluated: frames 0-5 (frame 6 has no target). Misses: 1, 2, 3, 4 (IoU 0 or no box).
    # Called tracking and evaluated: 0, 1, 4 -> 2 of 3 miss. Misses flagged: 2, 3 -> 2 of 4.
    summary = summarize(pred, gt, states)
    assert summary["tracking_miss"] == pytest.approx(2 / 3)
    assert summary["miss_flagged"] == pytest.approx(2 / 4)
    overlaps, _ = frame_scores(pred, gt)
    assert tracking_miss_rate(states, overlaps) == pytest.approx(2 / 3)
    assert flagged_miss_rate(states, overlaps) == pytest.approx(1 / 2)
    # Nothing called tracking / nothing missed: not computable, JSON null in the summary.
    assert math.isnan(tracking_miss_rate(["lost"], [0.0]))
    assert summarize([G], [G], ["tracking"])["miss_flagged"] is None
    with pytest.raises(ValueError, match="2 states for 1"):
        flagged_miss_rate(["lost", "lost"], [0.0])


def test_summarize_without_evaluated_frames_is_json_null():
    summary = summarize([G, None], [None])
    assert summary["frames_evaluated"] == 0
    assert json.loads(json.dumps(summary))["auc"] is None
    assert summarize([None], [G])["mean_center_error"] is None  # always lost: no finite error


# --- read_boxes ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "line",
    [
        "10,20,30,40",
        "10\t20\t30\t40",
        "10 20 30 40",
        "10,20\t30  40",
        "10, 20, 30, 40",
        "10,20,30,40,",
    ],
)
def test_read_boxes_otb_separators(tmp_path, line):
    path = write(tmp_path, f"{line}\n1.5,2.5,3.5,4.5\n")
    assert read_boxes(path) == [Box(10, 20, 30, 40), Box(1.5, 2.5, 3.5, 4.5)]


def test_read_boxes_vot_polygon_and_rectangle(tmp_path):
    path = write(
        tmp_path,
        "1,2,11,2,11,22,1,22\n"  # axis-aligned polygon
        "0,5,5,0,10,5,5,10\n"  # rotated square (diamond)
        "3,4,5,6\n",  # VOT rectangle
    )
    assert read_boxes(path) == [Box(1, 2, 10, 20), Box(0, 0, 10, 10), Box(3, 4, 5, 6)]


def test_a_polygon_that_reads_as_a_motchallenge_row_is_a_polygon_after_the_first_line(
        tmp_path):
    """Probe 52b: a VOT polygon file was refused as MOTChallenge ground truth at its line 6,
    5,2,25,2,25,12,1,12 (an axis-aligned box by the frame's top-left corner: frame 5, id 2,
    consider 1, class 12 to a MOTChallenge reader), though its first 5 lines were polygons.
    The first line tells the file's kind; a MOTChallenge file is still named as such."""
    path = write(tmp_path, "10,20,30,20,30,40,10,40\n5,2,25,2,25,12,1,12\n")
    assert read_boxes(path) == [Box(10, 20, 20, 20), Box(1, 2, 24, 10)]
    with pytest.raises(MultiTargetTruthError, match="line 1: this is MOTChallenge"):
        read_boxes(write(tmp_path, "5,2,25,2,25,12,1,12\n10,20,30,20,30,40,10,40\n"))


def test_read_boxes_absent_frames(tmp_path):
    path = write(
        tmp_path,
        "1,2,3,4\nNaN,NaN,NaN,NaN\n0,0,0,0\nnan,nan,nan,nan,nan,nan,nan,nan\n5,5,0,10\n5,5,10,-1\n"
        "\n\n",  # trailing blank lines are ignored
    )
    assert read_boxes(path) == [Box(1, 2, 3, 4), None, None, None, None, None]


def test_read_boxes_origin_one(tmp_path):
    path = write(tmp_path, "1,1,10,10\n0,0,0,0\n")
    assert read_boxes(path, origin=1) == [Box(0, 0, 10, 10), None]
    with pytest.raises(ConfigError, match="origin"):
        read_boxes(path, origin=2)


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("1,2,3,4\nabc\n", "line 2: expected 4 or 8 numbers, got 'abc'"),
        ("1,2,3\n", "line 1: expected 4 or 8 numbers, got '1,2,3'"),
        ("1,2,3,4\n\n1,2,3,4\n", "line 2: blank; the file holds one box per frame (0,0,0,0 "
         "or NaN where the target is out of view)"),
        ("x,y,w,h\n1,2,3,4\n", "line 1: expected 4 or 8 numbers, got 'x,y,w,h' (no header "
         "line: the file holds only numbers)"),
        ("1,2,inf,4\n", "line 1: infinite coordinate"),
        # Probe R: a semicolon CSV (a spreadsheet's where the comma is the decimal mark) was
        # told "(no header line: the file holds only numbers)", which it does
        ("262.2;71.35;40.8;31.2\n", "line 1: expected 4 or 8 numbers, got "
         "'262.2;71.35;40.8;31.2' (numbers are separated by commas, tabs or spaces, not ';')"),
        ("1,2,3,4\n5|6|7|8\n", "line 2: expected 4 or 8 numbers, got '5|6|7|8' (numbers are "
         "separated by commas, tabs or spaces, not '|')"),
        # the same with decimal commas: told to separate by commas, which read '262,20;71,35;
        # 40,80;31,20' as 8 numbers, a polygon, without a word
        ("262,20;71,35;40,80;31,20\n", "line 1: expected 4 or 8 numbers, got "
         "'262,20;71,35;40,80;31,20' (decimal commas: write 262.20, not 262,20; numbers are "
         "separated by commas, tabs or spaces, not ';')"),
        # decimal commas between spaces were read as 8 numbers, a polygon (Box(x=31.0, y=2.0,
        # ...)), without a word; a polygon's points written x,y apart are as ambiguous
        ("1,2,3,4\n262,2 71,35 40,8 31,2\n", "line 2: '262,2 71,35 40,8 31,2' is 8 numbers "
         "only if its commas separate numbers as its spaces do (decimal commas: write 262.2, "
         "not 262,2; numbers are separated by commas, tabs or spaces; a polygon's four x,y "
         "points: commas between them too)"),
    ],
)
def test_read_boxes_malformed_line_names_file_and_line(tmp_path, text, problem):
    path = write(tmp_path, text)
    with pytest.raises(InputError) as info:
        read_boxes(path)
    assert str(info.value).startswith(f"{path} {problem}")
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(("read", "text", "line", "shown"), [
    # read as Box(10, 20, 30, 40): the 20 meant for y taken as x's neighbour, all shifted
    (read_boxes, "1,2,3,4\n10,,20,30,40\n", 2, "'10,,20,30,40'"),
    (read_boxes, ",10,20,30,40\n", 1, "',10,20,30,40'"),
    (read_boxes, "1,2,3,4\n10, ,20,30\n", 2, "'10, ,20,30'"),
    # x left out: read as x 0, y 10, w 10, h 1, consider 1, class 1, scored without a word
    (read_mot, "1,1,,0,10,10,1,1,1\n", 1, "'1,1,,0,10,10,1,1,1'"),
    (read_mot_detections, "1,-1,5,5,10,10,0.9\n2,-1,,5,10,10,0.9,1\n", 2,
     "'2,-1,,5,10,10,0.9,1'"),
    # padded as a spreadsheet pads a short row, but a number is still left out before them
    (read_boxes, "10,,20,30,40,,,\n", 1, "'10,,20,30,40,,,'"),
])
def test_an_empty_field_is_refused_not_closed_up(tmp_path, read, text, line, shown):
    """An empty field between commas was skipped, the numbers after it read into the columns
    before (``10,,20,30,40`` the box 10,20,30,40): a number left out is named, as ``--init``
    names ``10,,20,30,40``."""
    path = write(tmp_path, text)
    with pytest.raises(InputError) as info:
        read(path)
    assert str(info.value) == (f"{path} line {line}: an empty field in {shown} (a number left "
                               "out: the numbers after it would be read into the wrong columns)")


@pytest.mark.parametrize(("read", "text", "expected"), [
    (read_boxes, "10,20,30,40,\n", [Box(10, 20, 30, 40)]),
    # a spreadsheet's CSV export pads short rows with empty fields: no number moves
    (read_boxes, "10,20,30,40,,,,\n", [Box(10, 20, 30, 40)]),
    (read_boxes, "10,20,30,40, ,\n", [Box(10, 20, 30, 40)]),
    (read_mot, "1,1,10,20,30,40,1,1,1,,\n", {0: [(1, Box(10, 20, 30, 40))]}),
    (read_mot_detections, "1,-1,10,20,30,40,0.9,,,\n", {0: [(Box(10, 20, 30, 40), 0.9)]}),
])
def test_empty_fields_after_the_last_number_are_taken(tmp_path, read, text, expected):
    """The empty-field refusal above took a row's padding after its last number
    (``10,20,30,40,,,,``) for a number left out and refused a file read before: nothing
    follows those fields, so no number is in the wrong column."""
    assert read(write(tmp_path, text)) == expected


def test_the_negative_size_note_is_reachable_from_vtrack_evaluate(tmp_path):
    """read_boxes reads a box of negative width or height as the target absent, and
    ``vtrack run --gt`` warns of it; the library's readers in vtrack.evaluate had no way to
    that warning (read_truth and negative_note were in vtrack.evaluate.groundtruth only)."""
    path = write(tmp_path, "10,20,30,40\n5,5,-3,4\n0,0,0,0\n")
    truth = read_truth(path)
    assert truth.boxes == read_boxes(path) == [Box(10, 20, 30, 40), None, None]
    assert truth.negative == [2]
    assert negative_note(path, truth) == (f"{path}: 1 box with a negative width or height (the "
                                          "first on line 2) read as the target absent: its "
                                          "frame is not scored")
    assert negative_note(path, read_truth(write(tmp_path, "1,2,3,4\n", "ok.txt"))) is None


def test_read_boxes_unreadable_or_empty(tmp_path):
    with pytest.raises(InputError, match="missing.txt"):
        read_boxes(tmp_path / "missing.txt")
    with pytest.raises(InputError, match="cannot read"):
        read_boxes(tmp_path)  # a directory
    with pytest.raises(InputError, match="empty"):
        read_boxes(write(tmp_path, ""))
    with pytest.raises(InputError, match="empty"):
        read_boxes(write(tmp_path, "\n \n"))
    binary = tmp_path / "gt.bin"
    binary.write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(InputError, match="not text"):
        read_boxes(binary)


# --- MOTChallenge -------------------------------------------------------------------------------


def test_read_mot_ground_truth_mot17_layout(tmp_path):
    path = write(
        tmp_path,
        "1,1,10,20,30,40,1,1,0.9\n"
        "1,2,50,60,10,10,1,1,1.0\n"
        "1,3,0,0,10,10,0,1,1.0\n"  # consider flag 0: ignored
        "2,1,11,21,30,40,1,1,0.8\n"
        "2,4,5,5,10,10,1,7,1.0\n"  # static person (class 7): not a pedestrian
        "\n"
        "5,2,1,2,3,4,1,1,0.5\n",
    )
    assert read_mot(path) == {
        0: [(1, Box(10, 20, 30, 40)), (2, Box(50, 60, 10, 10))],
        1: [(1, Box(11, 21, 30, 40))],
        4: [(2, Box(1, 2, 3, 4))],
    }


def test_read_mot_mot15_layout_has_no_class_column(tmp_path):
    path = write(tmp_path, "2,7,10,20,30,40,1,-1,-1,-1\n1,3,1,2,3,4,1,-1,-1,-1\n1,5,1,2,3,4\n")
    assert read_mot(path) == {
        0: [(3, Box(1, 2, 3, 4)), (5, Box(1, 2, 3, 4))],
        1: [(7, Box(10, 20, 30, 40))],
    }


def test_read_mot_detections(tmp_path):
    path = write(
        tmp_path,
        "1,-1,1359.1,413.27,120.26,362.77,2.3092,-1,-1,-1\n"
        "1,-1,10,10,5,5,-0.5,-1,-1,-1\n"  # negative scores are kept
        "3,-1,1,2,3,4,0,-1,-1,-1\n",
        name="det.txt",
    )
    assert read_mot_detections(path) == {
        0: [(Box(1359.1, 413.27, 120.26, 362.77), 2.3092), (Box(10, 10, 5, 5), -0.5)],
        2: [(Box(1, 2, 3, 4), 0.0)],
    }


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("1,1,1,2,3,4\n0,1,1,2,3,4\n", "line 2: frame must be an integer >= 1"),
        ("1.5,1,1,2,3,4\n", "line 1: frame must be an integer >= 1"),
        ("1,1,1,2,3\n", "line 1: expected at least 6 numbers"),
        ("1,x,1,2,3,4\n", "line 1: expected at least 6 numbers"),
        ("1,1.5,1,2,3,4\n", "line 1: id must be an integer, got 1.5"),
        # a value a hair off an integer read 'got 1' or 'column 8 is 1, not a ... class'
        ("1,1.0000001,1,2,3,4\n", "line 1: id must be an integer, got 1.0000001"),
        ("1,1,1,2,3,4,1,1.0000001\n", "line 1: column 8 is 1.0000001, not a MOTChallenge class"),
        ("1,1,nan,2,3,4\n", "line 1: non-finite number"),
        # probe 51c: taken, and printed whole (301 digits) in the 'past the input' warning
        ("1,1,1,2,3,4\n1e300,1,1,2,3,4\n", "line 2: frame beyond 1,000,000,000 in '1e300,"),
    ],
)
def test_read_mot_malformed_line_names_file_and_line(tmp_path, text, problem):
    path = write(tmp_path, text)
    with pytest.raises(InputError) as info:
        read_mot(path)
    assert str(info.value).startswith(f"{path} {problem}")


@pytest.mark.parametrize(("row", "got"), [
    ("2,-1,10,10,-20,20,0.9", "w -20, h 20"),
    ("2,-1,10,10,20,0,0.9", "w 20, h 0"),
    ("2,-1,10,10,-0,20,0.9", "w 0, h 20"),  # (it said "w -0")
    ("2,-1,10,10,-20.000001,-0.0,0.9", "w -20.000001, h 0"),
], ids=["negative-w", "zero-h", "minus-zero-w", "minus-zero-h"])
def test_read_mot_detections_refuses_an_empty_box_naming_file_and_line(tmp_path, row, got):
    """A det.txt row of negative or zero width or height was dropped without a word (a run on
    it exited 0): no detector gives such a box, the file is wrong there. It is refused as
    other malformed rows are, naming the file and line, its numbers shown as written (-0 as
    0, as --init reads it; it said "w -0"; a value a hair past another not rounded to it)."""
    path = write(tmp_path, f"1,-1,10,10,20,20,0.9\n{row}\n", name="det.txt")
    with pytest.raises(InputError) as info:
        read_mot_detections(path)
    assert str(info.value) == f"{path} line 2: a detection's w and h must be > 0, got {got}"


def test_read_mot_detections_needs_confidence(tmp_path):
    with pytest.raises(InputError, match="line 1: expected at least 7 numbers"):
        read_mot_detections(write(tmp_path, "1,-1,1,2,3,4\n"))


# --- --init -------------------------------------------------------------------------------------


def test_parse_box():
    assert parse_box("10,20,30,40") == Box(10, 20, 30, 40)
    assert parse_box(" 1.5, 2, 3 ,4") == Box(1.5, 2, 3, 4)


@pytest.mark.parametrize("text", ["64 177 40 31", "64\t177\t40\t31", "64, 177, 40, 31"])
def test_init_takes_the_forms_a_sidecar_file_takes(text: str) -> None:
    """``--init "64 177 40 31"`` was refused while a sidecar file holding that line was taken."""
    assert parse_box(text) == parse_sidecar(text, "init.txt") == Box(64, 177, 40, 31)


def test_a_box_written_with_minus_zero_is_recorded_as_zero() -> None:
    """``vtrack run clip.mp4 --init -0,-0,20,20`` recorded and echoed the box as -0,-0,20,20
    (run.json: ``"init": [-0.0, -0.0, 20.0, 20.0]``): -0 is the number 0, in --init and in a
    sidecar file alike."""
    for box in (parse_box("-0,-0,20,20"), parse_sidecar("-0 -0.0 20 20", "init.txt")):
        assert ",".join(number_text(v) for v in box) == "0,0,20,20"
        assert json.dumps(list(box)) == "[0.0, 0.0, 20.0, 20.0]"


@pytest.mark.parametrize("text", ["1,2,3", "a,b,c,d", "1,2,3,4,5", "1,2,nan,4", "", "1 2 3",
                                  "10,,20,30,40", "1,2,3,4,", ",1,2,3,4"])
def test_parse_box_rejects_malformed(text):
    """The message lists the forms --init takes."""
    with pytest.raises(ConfigError, match=r"^--init: expected x,y,w,h or x y w h \(4 numbers "
                                          r"separated by commas, spaces or tabs\), got '"):
        parse_box(text)


@pytest.mark.parametrize("text", ["1,2,0,4", "1,2,3,-4"])
def test_parse_box_rejects_empty_box(text):
    with pytest.raises(ConfigError, match="--init: width and height must be positive"):
        parse_box(text)


def test_success_rates_and_normalised_precision_by_hand() -> None:
    from vtrack.evaluate.metrics import (
        normalized_center_errors,
        normalized_precision,
        success_rate,
    )

    overlaps = [0.9, 0.6, 0.5, 0.1, None]
    assert success_rate(overlaps, 0.5) == pytest.approx(2 / 4)  # strictly above, None skipped
    assert success_rate(overlaps, 0.75) == pytest.approx(1 / 4)
    assert math.isnan(success_rate([None], 0.5))
    gt = [Box(0, 0, 40, 20), Box(0, 0, 40, 20), None, Box(0, 0, 40, 20)]
    pred = [Box(4, 0, 40, 20), Box(0, 6, 40, 20), Box(0, 0, 1, 1), None]
    errors = normalized_center_errors(pred, gt)
    assert errors[0] == pytest.approx(0.1) and errors[1] == pytest.approx(0.3)
    assert errors[2] is None and errors[3] == math.inf
    # thresholds 0, 0.01, ..., 0.5: 0.1 passes 41 of 51, 0.3 passes 21, inf none
    assert normalized_precision(errors) == pytest.approx((41 + 21) / 51 / 3)


def test_the_overlap_of_a_box_with_itself_is_exactly_one() -> None:
    """Rounding gave 1.0000000000000007: a mean overlap above 1, an AUC counting the bin above
    1.0."""
    box = Box(57.82, 68.03, 40.8, 31.2)
    assert iou(box, box) == 1.0
    overlaps, _ = frame_scores([box], [box])
    assert auc(overlaps) == pytest.approx(20 / 21)


def test_the_overlaps_of_all_pairs_at_once_are_iou_of_each_pair_bit_for_bit() -> None:
    """The tracker's association, the blobs that persist and the MOT metrics take every pair's
    IoU at once; the multi-target tracker's own matrix gave 1.0000000000000002 for a box with
    itself where iou gives 1.0 (one less the cost of a pair, a different assignment)."""
    rng = np.random.default_rng(7)
    boxes = [Box(*(float(v) for v in rng.uniform(0, 300, 2)), *(float(v) for v in
                                                                 rng.uniform(1, 80, 2)))
             for _ in range(40)]
    boxes += [Box(117.48570015844837, 267.0823056014377, 18.945449889137, 50.23178443019735),
              Box(10, 10, 20, 20), Box(30, 10, 20, 20), Box(15, 15, 5, 5), Box(12, 12, 0, 8)]
    others = boxes[::-1] + [Box(14, 12, 20, 20)]
    overlaps = iou_matrix(boxes, others)
    assert overlaps.shape == (len(boxes), len(others))
    assert overlaps.tolist() == [[iou(a, b) for b in others] for a in boxes]
    assert np.diagonal(iou_matrix(boxes, boxes)).tolist() == [iou(b, b) for b in boxes]
    assert overlaps.max() == 1.0  # never a hair above
    assert iou_matrix([], boxes).shape == (0, len(boxes))
    assert iou_matrix(boxes, np.zeros((0, 4))).shape == (len(boxes), 0)
