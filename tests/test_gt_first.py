"""Ground truth whose first box is of a later frame (OTB's David: img/0001.jpg..0770.jpg, boxes
for images 300..770; UAV123's sub-sequences): ``--gt-first N`` aligns it, for ``vtrack run``,
the library's ``RunRequest``, ``vtrack report`` (recorded and ``--gt``), and the warning of a
file with fewer boxes than frames says how (``vtrack batch`` too). Real image sequences."""

from __future__ import annotations

import csv
import json
import os
import shutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line, run_after_start

from vtrack.cli import main
from vtrack.config import load_config
from vtrack.errors import ConfigError
from vtrack.request import RunRequest

if TYPE_CHECKING:
    from conftest import ClipFactory

FRAMES = 30
#: The file's first box is of this frame (OTB's startFrame less the first image's number).
LATER = 10


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, [*args], catch_exceptions=False)


@pytest.fixture
def david(tmp_path: Path, clip_factory: ClipFactory) -> tuple[Path, Path, Path]:
    """(a sequence folder whose groundtruth_rect.txt holds only the boxes of frames LATER..,
    as OTB's David's does, the whole file, the sequence's own folder)."""
    clip = clip_factory("smooth", frames=FRAMES, fmt="images")
    folder = tmp_path / "dav"
    shutil.copytree(clip.path / "img", folder / "img")
    whole = Path(clip.gt)
    lines = whole.read_text().splitlines(keepends=True)
    (folder / "groundtruth_rect.txt").write_text("".join(lines[LATER:]))
    return folder, whole, Path(clip.path)


def recorded(out: Path) -> dict:
    return json.loads((out / "run.json").read_text())


def overlaps(out: Path) -> list[str]:
    with (out / "track.csv").open(newline="") as handle:
        return [row["overlap"] for row in csv.DictReader(handle)]


def test_a_file_starting_later_scores_as_the_aligned_one(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """Probe N: a groundtruth_rect.txt of the boxes of frames 10..29 beside 30 images was
    scored against frames 0..19 (AUC 0.124 on `vtrack scene smooth`'s 20 frames, a warning of
    fewer boxes only); `--start 10` took the file's row 10. `--gt-first 10` now aligns it:
    with `--start 10` the run is the one against the whole file, score for score; from frame 0
    (an --init box) frames 0..9 are not scored and the others as against the whole file."""
    folder, whole, _ = david
    gt = folder / "groundtruth_rect.txt"
    aligned, truth = tmp_path / "aligned", tmp_path / "truth"
    result = vtrack("run", str(folder), "--gt", str(gt), "--gt-first", str(LATER), "--start",
                    str(LATER), "-c", "s0", "--no-video", "-o", str(aligned), "-q")
    assert result.exit_code == 0, result.output
    assert result.stderr == "", result.stderr  # no warning: the boxes fit
    result = vtrack("run", str(folder), "--gt", str(whole), "--start", str(LATER), "-c", "s0",
                    "--no-video", "-o", str(truth), "-q")
    assert result.exit_code == 0, result.output
    mine, theirs = recorded(aligned), recorded(truth)
    assert mine["request"]["gt_first"] == LATER
    for key in ("frames_evaluated", "auc", "precision20", "mean_overlap"):
        assert mine["metrics"][key] == theirs["metrics"][key], key
    assert mine["metrics"]["frames_evaluated"] == FRAMES - LATER
    assert overlaps(aligned) == overlaps(truth)

    first = whole.read_text().splitlines()[0]
    from_zero, whole_zero = tmp_path / "from0", tmp_path / "whole0"
    for out, file, extra in ((from_zero, gt, ("--gt-first", str(LATER))),
                             (whole_zero, whole, ())):
        result = vtrack("run", str(folder), "--gt", str(file), *extra, "--init", first,
                        "-c", "s0", "--no-video", "-o", str(out), "-q")
        assert result.exit_code == 0, result.output
        assert result.stderr == "", result.stderr
    assert recorded(from_zero)["metrics"]["frames_evaluated"] == FRAMES - LATER
    assert overlaps(from_zero)[:LATER] == [""] * LATER
    assert overlaps(from_zero)[LATER:] == overlaps(whole_zero)[LATER:]


def test_the_library_takes_it_and_refuses_out_of_range(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """`vtrack.RunRequest(gt_first=...)` aligns as `--gt-first` does, and a value out of 0 to
    10^12 (or no whole number) is refused naming the field."""
    from vtrack.run import run

    folder, whole, _ = david
    gt = folder / "groundtruth_rect.txt"
    mine, theirs = (run(RunRequest(input=str(folder), out_dir=tmp_path / name,
                                   config=load_config("s0"), gt_path=path, gt_origin=1,
                                   gt_first=first, start=LATER, video=False))
                    for name, path, first in (("lib", gt, LATER), ("whole", whole, 0)))
    assert mine.warnings == [] and mine.auc is not None and mine.auc == theirs.auc
    assert mine.mean_overlap == theirs.mean_overlap
    for bad in (-1, 10**12 + 1, 2.5, "3"):
        with pytest.raises((ConfigError, TypeError), match="gt_first"):
            RunRequest(input=str(folder), out_dir=tmp_path / "x", config=load_config("s0"),
                       gt_path=gt, gt_first=bad)


@pytest.mark.parametrize("value", ["-1", "1000000000001", "many", "2.5"])
def test_a_first_frame_out_of_range_is_one_line(
        tmp_path: Path, david: tuple[Path, Path, Path], value: str) -> None:
    folder, _, _ = david
    for command in (("run", str(folder)), ("report", str(tmp_path))):
        line = one_error_line(vtrack(*command, "--gt", str(folder / "groundtruth_rect.txt"),
                                     "--gt-first", value, "-o", str(tmp_path / "o")))
        assert "--gt-first" in line and value in line and "1000000000000" in line, line


def test_without_gt_or_with_a_multi_target_config_it_is_refused(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    folder, _, _ = david
    line = one_error_line(vtrack("run", str(folder), "--init", "10,10,20,20", "--gt-first", "3",
                                 "-o", str(tmp_path / "o")))
    assert line.startswith("vtrack: error: --gt-first 3: ") and "no --gt" in line, line
    line = one_error_line(vtrack("report", str(tmp_path), "--gt-first", "3"))
    assert line.startswith("vtrack: error: --gt-first 3: ") and "no --gt" in line, line
    line = one_error_line(vtrack("run", str(folder), "-c", "s3", "--gt",
                                 str(folder / "groundtruth_rect.txt"), "--gt-first", "3",
                                 "-o", str(tmp_path / "o")))
    assert "--gt-first 3: s3 reads MOTChallenge ground truth" in line, line


def test_a_run_before_the_first_box_needs_a_start_or_a_box(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    folder, _, _ = david
    line = one_error_line(vtrack("run", str(folder), "--gt", str(folder / "groundtruth_rect.txt"),
                                 "--gt-first", str(LATER), "-o", str(tmp_path / "o")))
    assert f"the file's boxes begin at frame {LATER} (--gt-first {LATER}); give --start " \
           f"{LATER} to track from there, or --init x,y,w,h" in line, line


def test_the_fewer_boxes_warning_says_how_to_align(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """The warning of a file with fewer boxes than frames (run and batch alike) names the
    --gt-first that ends the file at the input's last frame."""
    folder, _, _ = david
    result = vtrack("run", str(folder), "--gt", str(folder / "groundtruth_rect.txt"), "-c",
                    "robust", "--no-video", "-o", str(tmp_path / "o"), "-q")
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines() == [
        f"vtrack: warning: {folder / 'groundtruth_rect.txt'}: ground truth has 20 boxes for 30 "
        "frames (fewer); overlap is empty from frame 20 on; if its first box is of a later "
        f"frame, give --gt-first {LATER} (its last box then the last frame's)"], result.stderr
    batch_in = tmp_path / "in"
    shutil.copytree(folder, batch_in / "dav")
    result = vtrack("batch", str(batch_in), "-c", "robust", "--no-video", "-j", "1", "-o",
                    str(tmp_path / "b"), "-q")
    assert result.exit_code == 0, result.output
    assert f"give vtrack run --gt-first {LATER} (its last box" in result.stderr, result.stderr


def test_the_report_rescored_as_the_run(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """`vtrack report` re-scores a run with the gt_first it recorded (its AUC the run's), and
    its own `--gt FILE --gt-first N` scores a run made without ground truth as the run with it
    scored itself; without --gt-first that file does not fit, and the warning says how."""
    folder, _, _ = david
    gt = folder / "groundtruth_rect.txt"
    first = Path(david[1]).read_text().splitlines()[0]
    scored, bare = tmp_path / "runs" / "scored", tmp_path / "bare" / "run"
    result = vtrack("run", str(folder), "--gt", str(gt), "--gt-first", str(LATER), "--init",
                    first, "-c", "s0", "--no-video", "-o", str(scored), "-q")
    assert result.exit_code == 0, result.output
    result = vtrack("run", str(folder), "--init", first, "-c", "s0", "--no-video", "-o",
                    str(bare), "-q")
    assert result.exit_code == 0, result.output
    auc = recorded(scored)["metrics"]["auc"]

    def report_auc(*args: str) -> str:
        result = vtrack("report", *args, "-q")
        assert result.exit_code == 0, result.output
        with (Path(args[args.index("-o") + 1]) / "summary.csv").open(newline="") as handle:
            return next(csv.DictReader(handle))["auc"]

    assert float(report_auc(str(scored.parent), "-o", str(tmp_path / "r1"))) == \
        pytest.approx(auc, abs=1e-6)
    assert float(report_auc(str(bare.parent), "-o", str(tmp_path / "r2"), "--gt", str(gt),
                            "--gt-first", str(LATER))) == pytest.approx(auc, abs=1e-6)
    result = vtrack("report", str(bare.parent), "-o", str(tmp_path / "r3"), "--gt", str(gt),
                    "-q")
    assert f"has 20 boxes for its 30 frames; if its first box is of a later frame, give " \
           f"--gt-first {LATER}" in result.stderr, result.stderr


def test_a_first_frame_far_past_the_input_is_not_padded(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """Review: `--gt-first 1000000000000` (in range) made a list of 10^12 Nones: MemoryError
    and a traceback from vtrack run and vtrack report. The frames before the first box are not
    stored; vtrack run refuses a first frame past the input's last in one line, the report
    reads the file at once and does not score the run with it."""
    from vtrack.evaluate import read_truth

    folder, _, _ = david
    gt = folder / "groundtruth_rect.txt"
    far = 10**12
    boxes = read_truth(gt, first=far).boxes
    assert len(boxes) == far + FRAMES - LATER
    assert boxes[far] is not None and boxes[far - 1] is None and boxes[5] is None
    assert boxes[far:] == read_truth(gt).boxes and len(boxes[3:8]) == 5
    assert list(boxes[far - 2:far + 1]) == [None, None, boxes[far]]
    for value in (str(far), str(FRAMES)):
        line = one_error_line(vtrack("run", str(folder), "--gt", str(gt), "--gt-first", value,
                                     "--start", "3", "--no-video", "-o", str(tmp_path / "o")))
        assert line == (f"vtrack: error: --gt-first {value}: {folder}: has no frame {value} "
                        f"(frames 0..{FRAMES - 1}); the file's first box is of one of its "
                        "frames"), line
    run_dir = tmp_path / "runs" / "n0"
    first = Path(david[1]).read_text().splitlines()[0]
    result = vtrack("run", str(folder), "--init", first, "-c", "s0", "--no-video",
                    "-o", str(run_dir), "-q")
    assert result.exit_code == 0, result.output
    result = vtrack("report", str(run_dir.parent), "--gt", str(gt), "--gt-first", str(far),
                    "-o", str(tmp_path / "rep"), "-q")
    assert result.exit_code == 0, result.output
    assert "not scored" in result.stderr, result.stderr


def test_frames_before_the_first_box_are_not_counted_as_the_file_s(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """Review: the run counted the frames before --gt-first as the file's: `--frames 5` before
    the first box warned the target "absent in all 5 frames"; a file of absent boxes from
    frame 10 "absent in all 30 frames"; a --start past the file's end said "boxes for frames
    0..N" whatever --gt-first said."""
    folder, whole, _ = david
    gt = folder / "groundtruth_rect.txt"
    first = whole.read_text().splitlines()[0]
    result = vtrack("run", str(folder), "--gt", str(gt), "--gt-first", str(LATER), "--init",
                    first, "--frames", "5", "-c", "s0", "--no-video", "-o",
                    str(tmp_path / "a"), "-q")
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines() == [
        f"vtrack: warning: {gt}: the file's boxes begin at frame {LATER} (--gt-first {LATER}), "
        "after the run's last frame (4): no frame is scored"], result.stderr
    absent = tmp_path / "absent.txt"
    absent.write_text("0,0,0,0\n" * (FRAMES - LATER))
    result = vtrack("run", str(folder), "--gt", str(absent), "--gt-first", str(LATER), "--init",
                    first, "-c", "s0", "--no-video", "-o", str(tmp_path / "b"), "-q")
    assert result.exit_code == 0, result.output
    assert f"in all {FRAMES - LATER} frames of the run it has boxes for" in result.stderr, \
        result.stderr
    short = tmp_path / "short.txt"
    short.write_text("".join(whole.read_text().splitlines(keepends=True)[:5]))
    line = one_error_line(vtrack("run", str(folder), "--gt", str(short), "--gt-first", "5",
                                 "--start", "12", "-o", str(tmp_path / "c")))
    assert "the file has boxes for frames 5..9 only" in line, line


def test_the_counts_of_a_later_run_or_file_explain_themselves(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """Review: a run from frame 5 and a file of as many boxes from frame 0 was refused by the
    report saying "has 25 boxes for its 25 frames from frame 5", vtrack run warned "25 boxes
    for 25 frames from frame 5 (fewer)": the boxes' frames are named now."""
    folder, whole, _ = david
    lines = whole.read_text().splitlines(keepends=True)
    gt = tmp_path / "dgt.txt"
    gt.write_text("".join(lines[5:]))
    run_dir = tmp_path / "runs" / "n5"
    result = vtrack("run", str(folder), "--gt", str(gt), "--init", lines[5].strip(), "--start",
                    "5", "-c", "s0", "--no-video", "-o", str(run_dir), "-q")
    assert result.exit_code == 0, result.output
    assert f"{gt}: ground truth has 25 boxes, frames 0..24, for 25 frames from frame 5 " \
           "(fewer); overlap is empty from frame 25 on" in result.stderr, result.stderr
    bare = tmp_path / "bare" / "n5"
    result = vtrack("run", str(folder), "--init", lines[5].strip(), "--start", "5", "-c", "s0",
                    "--no-video", "-o", str(bare), "-q")
    assert result.exit_code == 0, result.output
    result = vtrack("report", str(bare.parent), "--gt", str(gt), "-o", str(tmp_path / "r"),
                    "-q")
    assert result.exit_code == 0, result.output
    assert f"{gt} has 25 boxes, frames 0..24, for its 25 frames from frame 5;" \
        in result.stderr, result.stderr


def test_boxes_from_frame_0_are_a_list_and_later_ones_are_not_walked(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """Review: read_boxes and read_truth(...).boxes came back as a FrameBoxes even with no
    first frame given, and library code that took them as a list failed (json.dumps, t +
    [None], [None] + t, t.append, t[0] = ..., isinstance(t, list)); a list now, a FrameBoxes
    only for a file whose first box is of a later frame. Its stepped slices, ``in``, index,
    count and reversed visited each of 10^12 frames before the first box (a MemoryError or
    minutes); they count them now."""
    from vtrack.evaluate import read_boxes, read_truth
    from vtrack.geometry import Box

    gt = tmp_path / "gt.txt"
    gt.write_text("1,2,3,4\n0,0,0,0\n5,6,7,8\n")
    boxes = read_boxes(gt)
    assert isinstance(boxes, list) and isinstance(read_truth(gt).boxes, list)
    assert json.loads(json.dumps(boxes)) == [[1, 2, 3, 4], None, [5, 6, 7, 8]]
    assert boxes + [None] == [*boxes, None] and [None] + boxes == [None, *boxes]
    boxes.append(None)
    boxes[0] = Box(0, 0, 1, 1)
    assert boxes == [Box(0, 0, 1, 1), None, Box(5, 6, 7, 8), None]
    far = 10**12
    later = read_boxes(gt, first=far)
    own = [Box(1, 2, 3, 4), None, Box(5, 6, 7, 8)]
    assert later[:far:far // 4] == [None] * 4 and later[far::2] == [own[0], own[2]]
    assert later[far - 1::2] == [None, None] and len(later[1::3]) == len(range(1, far + 3, 3))
    assert later[::-1][:4] == [own[2], None, own[0], None] and later[far + 5:] == []
    assert later[:far - 2:-1] == [own[2], None, own[0], None]
    assert None in later and Box(5, 6, 7, 8) in later and Box(9, 9, 9, 9) not in later
    assert later.count(None) == far + 1 and later.count(Box(1, 2, 3, 4)) == 1
    assert later.index(Box(5, 6, 7, 8)) == far + 2 and later.index(None) == 0
    assert later.index(None, far) == far + 1 and later.index(None, 5, 9) == 5
    with pytest.raises(ValueError):
        later.index(Box(1, 2, 3, 4), far + 1)
    assert list(zip(reversed(later), range(5), strict=False)) == [
        (own[2], 0), (None, 1), (own[0], 2), (None, 3), (None, 4)]
    folder, whole, _ = david
    short = tmp_path / "short.txt"
    short.write_text("".join(whole.read_text().splitlines(keepends=True)[:5]))
    line = one_error_line(vtrack("run", str(folder), "--gt", str(short), "--start", "12",
                                 "-o", str(tmp_path / "c")))
    assert "the file has boxes for frames 0..4 only" in line, line


def test_a_first_frame_past_the_input_is_refused_from_frame_0_too(
        tmp_path: Path, david: tuple[Path, Path, Path]) -> None:
    """Probe RD: the README says a --gt-first past the input's last frame is refused in one
    line, but only a run with --start was: `vtrack run dav --gt FILE --gt-first 30 --init BOX`
    tracked every frame, scored none and ended 0 with a warning, and without --init it said
    "give --start 30 to track from there", a start the next run refused. Now every run with
    --gt-first opens its input first and refuses it, and so does the library's RunRequest."""
    from vtrack import track
    from vtrack.errors import InputError

    folder, whole, _ = david
    gt = folder / "groundtruth_rect.txt"
    first = whole.read_text().splitlines()[0]
    expected = (f"vtrack: error: --gt-first {FRAMES}: {folder}: has no frame {FRAMES} "
                f"(frames 0..{FRAMES - 1}); the file's first box is of one of its frames")
    for box in (("--init", first), ()):
        line = one_error_line(vtrack("run", str(folder), "--gt", str(gt), "--gt-first",
                                     str(FRAMES), *box, "-c", "s0", "--no-video",
                                     "-o", str(tmp_path / "o")))
        assert line == expected, line
    assert not (tmp_path / "o").exists()
    request = RunRequest(input=str(folder), out_dir=tmp_path / "lib", config=load_config("s0"),
                         gt_path=gt, gt_first=FRAMES, video=False)
    with pytest.raises(InputError, match=f"gt_first={FRAMES}: .* has no frame {FRAMES} "):
        next(iter(track(request)))


def test_a_fifo_waiting_for_its_writer_hears_of_the_ground_truths_mistake_at_once(
        tmp_path: Path) -> None:
    """Probe F8: with --gt-first every run opened its input before reading the ground truth,
    so `vtrack run FIFO --raw 64x48 --fps 30 --gt bad.txt --gt-first 3 --init 1,1,5,5` waited
    for the FIFO's writer for ever instead of naming bad.txt's first line. Only a local file or
    folder states a frame count to check --gt-first against: the others open after the ground
    truth is read (for the CLI and the library's RunRequest)."""
    from vtrack import Box, track
    from vtrack.errors import InputError
    from vtrack.io import RawFormat

    fifo, bad = tmp_path / "ff", tmp_path / "bad.txt"
    os.mkfifo(fifo)
    bad.write_text("1,2,3\n")
    expected = f"{bad} line 1: expected 4 or 8 numbers, got '1,2,3'"
    # (a run that waits for the writer is killed: the bound is a safety net, not a measure)
    done = run_after_start([sys.executable, "-m", "vtrack", "run", str(fifo), "--raw", "64x48",
                            "--fps", "30", "--gt", str(bad), "--gt-first", "3", "--init",
                            "1,1,5,5", "-c", "s0", "--no-video", "-o", str(tmp_path / "o")])
    assert (done.returncode, done.stderr.decode()) == (2, f"vtrack: error: {expected}\n")
    assert not (tmp_path / "o").exists()
    request = RunRequest(input=str(fifo), out_dir=tmp_path / "lib", config=load_config("s0"),
                         raw=RawFormat(64, 48, "gray", 30.0), gt_path=bad, gt_first=3,
                         init_box=Box(1, 1, 5, 5), video=False)
    with pytest.raises(InputError) as refused:
        track(request)  # (at once, before the FIFO is opened)
    assert str(refused.value) == expected
