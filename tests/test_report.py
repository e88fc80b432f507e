"""`vtrack report` on real batch and run output: plots, HTML, tables and OTB numbers."""

from __future__ import annotations

import csv
import json
import os
import re
import shlex
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import av
import cv2
import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line

from vtrack.batch import SUMMARY_COLUMNS
from vtrack.cli import main
from vtrack.evaluate import auc, frame_scores, precision_at, read_boxes
from vtrack.geometry import Box

if TYPE_CHECKING:
    from conftest import Clip, ClipFactory

W, H = 160, 120
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def track_boxes(path: Path) -> list[Box | None]:
    with path.open(newline="") as handle:
        return [None if row["x"] == "" else Box(*(float(row[k]) for k in "xywh"))
                for row in csv.DictReader(handle)]


def html_rows(html: str, table: int) -> tuple[list[str], list[list[str]]]:
    """Header and body cells of the ``table``-th table of the page."""
    body = re.findall(r"<table[^>]*>(.*?)</table>", html, re.S)[table]
    header = re.findall(r"<th[^>]*>(.*?)</th>", body)
    rows = [re.findall(r"<td[^>]*>(.*?)</td>", row)
            for row in re.findall(r"<tr[^>]*>(.*?)</tr>", body)[1:]]
    return header, rows


@pytest.fixture(scope="module")
def batch_out(tmp_path_factory: pytest.TempPathFactory,
              clip_factory: ClipFactory) -> tuple[Path, Path]:
    """Two clips (one with an occlusion) run with two configs by `vtrack batch`: the input
    folder and the batch output folder."""
    folder = tmp_path_factory.mktemp("report-inputs")
    for scenario, frames in (("occlusion", 60), ("smooth", 40)):
        clip = clip_factory(scenario, width=W, height=H, frames=frames)
        shutil.copy(clip.path, folder / f"{scenario}.mp4")
        shutil.copy(clip.gt, folder / f"{scenario}.gt.txt")
    out = tmp_path_factory.mktemp("report-batch")
    result = vtrack("batch", str(folder), "-c", "s0", "-c", "camshift", "--jobs", "2",
                    "--no-video", "--out", str(out))
    assert result.exit_code == 0, result.output
    return folder, out


def test_report_of_a_batch(batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    inputs, batch = batch_out
    report = tmp_path / "report"
    result = vtrack("report", str(batch), "--out", str(report))
    assert result.exit_code == 0, result.output
    html = (report / "index.html").read_text()
    plots = sorted((report / "plots").glob("*.png"))
    # overlap-over-time and success/precision per input, plus the average over inputs; the
    # frames where a tracker lost the target (none is lost on the smooth clip)
    assert {p.name for p in plots} == {"overlap_occlusion.png", "overlap_smooth.png",
                                       "curves_occlusion.png", "curves_smooth.png",
                                       "curves_all.png", "failures_occlusion.png"}
    for plot in plots:
        assert plot.read_bytes().startswith(PNG_SIGNATURE)
        image = cv2.imread(str(plot))
        assert image is not None and image.shape[0] > 100 and image.shape[1] > 100
        assert f'src="plots/{plot.name}"' in html
    assert html.count("<table ") == 2  # averages per config, results per input x config
    assert "lost" in html.split("<footer>")[1]  # the footer states how lost frames count

    header, rows = html_rows(html, 1)
    cells = {(row[0], row[1]): dict(zip(header, row, strict=True)) for row in rows}
    assert set(cells) == {(i, c) for i in ("occlusion", "smooth") for c in ("s0", "camshift")}
    for (name, config), row in cells.items():
        gt = read_boxes(inputs / f"{name}.gt.txt")
        overlaps, errors = frame_scores(track_boxes(batch / name / config / "track.csv"), gt)
        assert row["AUC"] == f"{auc(overlaps):.3f}"
        assert row["Precision@20"] == f"{precision_at(errors):.3f}"
        recorded = json.loads((batch / name / config / "run.json").read_text())["metrics"]
        assert row["AUC"] == f"{recorded['auc']:.3f}"
        recorded_miss = recorded["tracking_miss"]  # honest-state measures, same as run.json
        assert row["Tracking miss"] == ("—" if recorded_miss is None else f"{recorded_miss:.3f}")
        flagged = recorded["miss_flagged"]
        assert row["Miss flagged"] == ("—" if flagged is None else f"{flagged:.3f}")
    assert '<td class=" best">' in html  # best per column highlighted
    markdown = (report / "summary.md").read_text()
    assert "| occlusion | s0 |" in markdown and "plots/curves_all.png" in markdown
    with (report / "summary.csv").open(newline="") as handle:
        assert len(list(csv.DictReader(handle))) == 4


def test_report_scores_a_run_without_ground_truth_with_gt(clip_factory: ClipFactory,
                                                          tmp_path: Path) -> None:
    clip = clip_factory("smooth", width=W, height=H, frames=40)
    first = clip.gt.read_text().splitlines()[0]
    run = tmp_path / "run"
    assert vtrack("run", str(clip.path), "--init", first, "--no-video", "--quiet",
                  "--out", str(run)).exit_code == 0

    bare = vtrack("report", str(run), "--out", str(tmp_path / "bare"))
    assert bare.exit_code == 0 and "no ground truth" in bare.stderr
    # without ground truth: only the state and score over time
    assert [p.name.split("_")[0] for p in (tmp_path / "bare" / "plots").glob("*.png")] == [
        "state"]

    scored = vtrack("report", str(run), "--gt", str(clip.gt), "--out", str(tmp_path / "gt"))
    assert scored.exit_code == 0, scored.output
    overlaps, _ = frame_scores(track_boxes(run / "track.csv"), read_boxes(clip.gt))
    with (tmp_path / "gt" / "summary.csv").open(newline="") as handle:
        (row,) = list(csv.DictReader(handle))
    assert float(row["auc"]) == pytest.approx(auc(overlaps), abs=1e-6)
    assert row["ground_truth"] == str(clip.gt)


def test_gt_for_an_input_given_by_another_path_to_it_scores_its_runs(
        clip_factory: ClipFactory, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack report results --gt footage/a.mp4=a.gt.txt` (--help: INPUT is 'its name as the
    report shows it, or its path') scored nothing, 'no run of input footage/a.mp4 was scored
    with it': a batch records its inputs' absolute paths, and only that text matched. A path
    to the same file now names that input's runs."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    footage = tmp_path / "footage"
    footage.mkdir()
    shutil.copy(clip.path, footage / "a.mp4")
    (footage / "a.init.txt").write_text(clip.gt.read_text().splitlines()[0] + "\n")
    monkeypatch.chdir(tmp_path)
    assert vtrack("batch", "footage", "-c", "s0", "--jobs", "1", "--no-video", "--quiet",
                  "--out", "results").exit_code == 0
    result = vtrack("report", "results", "--gt", f"footage/a.mp4={clip.gt}", "--out", "r")
    assert result.exit_code == 0, result.output
    assert "no run of input" not in result.stderr, result.stderr
    with (tmp_path / "r" / "summary.csv").open(newline="") as handle:
        (row,) = list(csv.DictReader(handle))
    assert row["ground_truth"] == str(clip.gt) and row["frames_evaluated"] == "20", row


def test_gt_for_an_input_whose_runs_have_their_own_says_why_it_went_unused(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """``--gt INPUT=FILE`` for runs that recorded their own ground truth warned only "no run
    of input ... was scored with it"; it now says they were scored with their own."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    run = tmp_path / "run"
    assert vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "--quiet",
                  "--out", str(run)).exit_code == 0
    other = tmp_path / "other.gt.txt"
    other.write_text(clip.gt.read_text())
    name = clip.path.stem
    result = vtrack("report", str(run), "--gt", f"{name}={other}", "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert (f"vtrack: warning: --gt {name}={other}: no run of input {name} was scored with "
            f"it: 1 run of it was already scored with its own ground truth ({clip.gt}), which "
            "--gt does not replace") in result.stderr.splitlines()


def test_gt_naming_the_runs_own_file_another_way_is_not_said_unused(
        clip_factory: ClipFactory, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack run clip.mp4 --gt clip.gt.txt -o run; vtrack report run --gt clip.gt.txt` warned
    "--gt clip.gt.txt: no run was scored with it: 1 run was already scored with its own ground
    truth (/abs/clip.gt.txt)", the very same file (the run records the path it found); so did
    `--gt clip=clip.gt.txt`. The same file, however named, is no warning; a copy still is."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    shutil.copy(clip.path, tmp_path / "clip.mp4")
    shutil.copy(clip.gt, tmp_path / "clip.gt.txt")
    shutil.copy(clip.gt, tmp_path / "copy.gt.txt")
    monkeypatch.chdir(tmp_path)
    assert vtrack("run", "clip.mp4", "--gt", "clip.gt.txt", "--no-video", "--quiet",
                  "--out", "run").exit_code == 0
    for gt in ("clip.gt.txt", "clip=clip.gt.txt", "clip=./clip.gt.txt"):
        result = vtrack("report", "run", "--gt", gt, "--out", "r")
        assert result.exit_code == 0 and "warning" not in result.stderr, (gt, result.stderr)
    result = vtrack("report", "run", "--gt", "copy.gt.txt", "--out", "r")
    assert ("vtrack: warning: --gt copy.gt.txt: no run was scored with it: 1 run was already "
            f"scored with its own ground truth ({tmp_path.resolve() / 'clip.gt.txt'}), which "
            "--gt does not replace") in result.stderr.splitlines(), result.stderr


def test_gt_warnings_are_no_reason_for_a_report_without_runs(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """`vtrack report empty --gt clip.gt.txt` said "empty: no run to report; --gt clip.gt.txt:
    no run was scored with it" (was: "no run.json found"), the --gt warning as its reason; a
    file with a negative-size box gave "2 left out", its note among them; a folder with one
    broken run.json said "2 left out". The --gt files' warnings are given with a report's runs,
    never as why there are none."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    negative = tmp_path / "negative.txt"
    negative.write_text("1,1,5,5\n1,1,-5,5\n")
    (tmp_path / "empty").mkdir()
    (tmp_path / "broken" / "x").mkdir(parents=True)
    (tmp_path / "broken" / "x" / "run.json").write_text("{")
    for gt in (clip.gt, negative):
        assert one_error_line(vtrack("report", str(tmp_path / "empty"), "--gt", str(gt),
                                     "--out", str(tmp_path / "r"))) == (
            f"vtrack: error: {tmp_path / 'empty'}: no run.json found (give vtrack run or vtrack "
            "batch output folders)")
        assert one_error_line(vtrack("report", str(tmp_path / "broken"), "--gt", str(gt),
                                     "--out", str(tmp_path / "r"))) == (
            f"vtrack: error: {tmp_path / 'broken'}: no run to report; left out: "
            f"{tmp_path / 'broken' / 'x' / 'run.json'}: not a vtrack run record")


def test_boxes_of_negative_size_are_warned_of_not_dropped_silently(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A ground-truth line `x,y,-w,h` (a converter's x2 - x1 of swapped corners) was read as
    the target absent, as `0,0,0,0` is: its frame left out of every score (frames_evaluated
    16 of 20 here) without a word. Still absent, now counted in a warning by
    vtrack run (on stderr and in run.json) and vtrack report --gt; `0,0,0,0` and NaN, the
    datasets' marks, are not."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    lines = clip.gt.read_text().splitlines()
    x, y, w, h = lines[7].split(",")
    lines[3], lines[5], lines[7], lines[9] = ("0,0,0,0", "NaN,NaN,NaN,NaN", f"{x},{y},-{w},{h}",
                                              f"{x},{y},{w},-{h}")
    damaged = tmp_path / "damaged.gt.txt"
    damaged.write_text("\n".join(lines) + "\n")
    note = (f"{damaged}: 2 boxes with a negative width or height (the first on line 8) read "
            "as the target absent: their frames are not scored")
    run = tmp_path / "run"
    result = vtrack("run", str(clip.path), "--gt", str(damaged), "--no-video", "--quiet",
                    "--out", str(run))
    assert result.exit_code == 0, result.output
    assert f"vtrack: warning: {note}" in result.stderr.splitlines(), result.stderr
    record = json.loads((run / "run.json").read_text())
    assert note in record["warnings"] and record["metrics"]["frames_evaluated"] == 16
    box = ",".join(f"{v:g}" for v in read_boxes(clip.gt)[0])
    assert vtrack("run", str(clip.path), "--init", box, "--no-video", "--quiet", "--out",
                  str(tmp_path / "bare")).exit_code == 0
    result = vtrack("report", str(tmp_path / "bare"), "--gt", str(damaged), "--out",
                    str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert f"vtrack: warning: {note}" in result.stderr.splitlines(), result.stderr
    result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "--quiet",
                    "--out", str(tmp_path / "clean"))
    assert "negative" not in result.stderr


def _runs_with_their_own_ground_truth(clip_factory: ClipFactory,
                                      tmp_path: Path) -> tuple[Clip, Clip, Path]:
    """A single-target run and a multi-target (s3) run under ``tmp_path/runs``, each scored
    with its clip's own ground truth, and a copy of the single clip's file elsewhere
    (``other.gt.txt``): a --gt the report can be given that no run recorded."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    multi = clip_factory("multi", width=W, height=H, frames=60)
    assert multi.mot is not None
    for name, args in (("single", (str(clip.path), "--gt", str(clip.gt))),
                       ("multi", (str(multi.path), "-c", "s3", "--gt", str(multi.mot)))):
        assert vtrack("run", *args, "--no-video", "--quiet",
                      "--out", str(tmp_path / "runs" / name)).exit_code == 0
    other = tmp_path / "other.gt.txt"
    other.write_text(clip.gt.read_text())
    return clip, multi, other


def test_a_plain_gt_no_run_takes_says_why_it_went_unused(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A plain ``--gt FILE`` given to the report of a run that recorded its own ground truth,
    and of a multi-target run, scored neither (the report showed the run's own file's scores)
    without a word, exit 0: the user who meant to score against FILE read the scores of
    another. Now a warning says no run was scored with it, and why."""
    clip, multi, other = _runs_with_their_own_ground_truth(clip_factory, tmp_path)
    result = vtrack("report", str(tmp_path / "runs"), "--gt", str(other), "--out",
                    str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert (f"vtrack: warning: --gt {other}: no run was scored with it: 1 run was already "
            f"scored with its own ground truth ({clip.gt}), which --gt does not replace; 1 "
            "multi-target run is scored only with the ground truth given to vtrack run --gt"
            ) in result.stderr.splitlines(), result.stderr


def test_gt_for_an_input_by_its_file_name_says_why_it_went_unused(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """`--gt clip.mp4=FILE` (the input by its file name, as --gt INPUT=FILE takes it) for a run
    that recorded its own ground truth, or a multi-target run, warned only "no run of input
    clip.mp4 was scored with it", no reason: the runs of that input were matched by their
    name alone. Now the reason is given, and the run's own file so named is no warning."""
    clip, multi, other = _runs_with_their_own_ground_truth(clip_factory, tmp_path)
    for path, why in ((clip.path, f"1 run of it was already scored with its own ground truth "
                                  f"({clip.gt}), which --gt does not replace"),
                      (multi.path, "1 multi-target run of it is scored only with the ground "
                                   "truth given to vtrack run --gt")):
        result = vtrack("report", str(tmp_path / "runs"), "--gt", f"{path.name}={other}",
                        "--out", str(tmp_path / "r"))
        assert result.exit_code == 0, result.output
        assert (f"vtrack: warning: --gt {path.name}={other}: no run of input {path.name} was "
                f"scored with it: {why}") in result.stderr.splitlines(), result.stderr
    result = vtrack("report", str(tmp_path / "runs" / "single"), "--gt",
                    f"{clip.path.name}={clip.gt}", "--out", str(tmp_path / "r"))
    assert result.exit_code == 0 and "warning" not in result.stderr, result.stderr


def _run_without_ground_truth(clip_factory: ClipFactory,
                              tmp_path: Path) -> tuple[Clip, Path, Path]:
    """A run made without ground truth (``--init`` its clip's first box) at ``tmp_path/run``,
    and a copy of the clip's ground truth elsewhere (``other.gt.txt``)."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    run = tmp_path / "run"
    box = ",".join(f"{v:g}" for v in read_boxes(clip.gt)[0])
    assert vtrack("run", str(clip.path), "--init", box, "--no-video", "--quiet", "--out",
                  str(run)).exit_code == 0
    other = tmp_path / "other.gt.txt"
    other.write_text(clip.gt.read_text())
    return clip, run, other


def test_a_plain_gt_unused_for_an_inputs_own_gt_names_that_one(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A run made without ground truth, `--gt other --gt clip=good`: the run took its input's
    own file, and other was said unused because the run "was already scored with its own
    ground truth (good), which --gt does not replace", though good came from the report's
    own --gt. Now it says the run was scored with --gt clip=good instead."""
    clip, run, other = _run_without_ground_truth(clip_factory, tmp_path)
    name = clip.path.stem
    result = vtrack("report", str(run), "--gt", str(other), "--gt", f"{name}={clip.gt}",
                    "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert [line for line in result.stderr.splitlines() if "--gt" in line] == [
        f"vtrack: warning: --gt {other}: no run was scored with it: 1 run was scored with "
        f"--gt {name}={clip.gt} instead"], result.stderr


def test_a_plain_gt_unused_by_many_runs_names_a_few_of_their_files(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A plain --gt no run took named every run's own ground truth in its one line (a batch of
    100 inputs: 100 paths). Now it names the first 4 and how many more."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    for n in range(6):
        gt = tmp_path / f"gt{n}.txt"
        gt.write_text(clip.gt.read_text())
        assert vtrack("run", str(clip.path), "--gt", str(gt), "--no-video", "--quiet",
                      "--out", str(tmp_path / "runs" / f"r{n}")).exit_code == 0
    other = tmp_path / "other.gt.txt"
    other.write_text(clip.gt.read_text())
    result = vtrack("report", str(tmp_path / "runs"), "--gt", str(other), "--out",
                    str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    files = ", ".join(str(tmp_path / f"gt{n}.txt") for n in range(4))
    assert (f"vtrack: warning: --gt {other}: no run was scored with it: 6 runs were already "
            f"scored with their own ground truth ({files} and 2 more), which --gt does not "
            "replace") in result.stderr.splitlines(), result.stderr


def test_two_gt_files_for_the_same_runs_are_refused_naming_both(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A run made without ground truth, `--gt clip=good --gt clip=other`: the second was said
    unused as 'already scored with its own ground truth (good), which --gt does not replace',
    the file given just before it, not the run's; two plain `--gt good --gt other` scored every
    run with the first and never read the second, exit 0 and not a word. One input named two
    ways (`--gt clip=good --gt clip.mp4=other`, or its path): both match the run, which took
    the first, and the second was said 'no run of input clip.mp4 was scored with it'."""
    clip, run, other = _run_without_ground_truth(clip_factory, tmp_path)
    name = clip.path.stem
    twice = vtrack("report", str(run), "--gt", f"{name}={clip.gt}", "--gt", f"{name}={other}",
                   "--out", str(tmp_path / "r"))
    assert twice.exit_code == 2 and twice.stderr.splitlines() == [
        f"vtrack: error: --gt {name}={other}: input {name} has its ground truth already (--gt "
        f"{name}={clip.gt}); give one file per input"], twice.stderr
    plain = vtrack("report", str(run), "--gt", str(clip.gt), "--gt", str(other), "--out",
                   str(tmp_path / "r"))
    assert plain.exit_code == 2 and plain.stderr.splitlines() == [
        f"vtrack: error: --gt {other}: a second ground truth for every run (--gt {clip.gt} is "
        "the first); give one --gt FILE, or --gt INPUT=FILE for each input"], plain.stderr
    assert not (tmp_path / "r").exists()
    mixed = vtrack("report", str(run), "--gt", str(other), "--gt", f"{name}={clip.gt}", "--out",
                   str(tmp_path / "r"))  # one plain, one per input: the input's own is taken
    assert mixed.exit_code == 0, mixed.stderr
    for second in (clip.path.name, str(clip.path)):
        refused_as_named_twice(run, f"{name}={clip.gt}", second, other, tmp_path / "r2")


def refused_as_named_twice(run: Path, first: str, second: str, other: Path,
                           out: Path) -> None:
    """`vtrack report RUN --gt FIRST --gt SECOND=OTHER`, one input named two ways, is refused
    in one line naming both, and no report is written."""
    both = vtrack("report", str(run), "--gt", first, "--gt", f"{second}={other}", "--out",
                  str(out))
    assert both.exit_code == 2 and both.stderr.splitlines() == [
        f"vtrack: error: --gt {second}={other}: input {second} has its ground truth already "
        f"(--gt {first}); give one file per input"], both.stderr
    assert not out.exists()


def test_one_input_named_two_ways_is_refused_for_runs_that_do_not_take_the_gt(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """`--gt clip=a --gt clip.mp4=b` was refused only for a run without its own ground truth:
    for a run that recorded its own, or a multi-target run, it gave two warnings, the second
    'no run of input clip.mp4 was scored with it', the run named by the --gt's INPUT. README:
    such pairs 'are refused in one line naming both', whatever the run."""
    from vtrack.scenes import make_scene, write_video

    clip = clip_factory("smooth", width=W, height=H, frames=20)
    own = tmp_path / "own"
    assert vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "--quiet",
                  "--out", str(own)).exit_code == 0
    crowd = write_video(make_scene("multi", 0, 160, 120, 60, 30), tmp_path / "crowd.mp4")
    multi = tmp_path / "multi"
    assert vtrack("run", str(crowd), "-c", "s4_multi", "--no-video", "--quiet", "--out",
                  str(multi)).exit_code == 0
    other = tmp_path / "other.gt.txt"
    other.write_text(clip.gt.read_text())
    for run, path in ((own, clip.path), (multi, crowd)):
        refused_as_named_twice(run, f"{path.stem}={clip.gt}", path.name, other, tmp_path / "r")


def test_runs_of_one_input_scored_against_different_ground_truth_are_warned_of(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Two configs of one clip, one run with its ground truth and one with a file whose boxes
    are shifted 15 px, were ranked side by side (the best in bold) without a word; now a
    warning names the input and each file. A byte-identical copy of the ground truth is the
    same truth: no warning."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    shifted = tmp_path / "shifted.gt.txt"
    shifted.write_text("".join(f"{box.x + 15},{box.y},{box.w},{box.h}\n"
                               for box in read_boxes(clip.gt)))
    copy = tmp_path / "copy.gt.txt"
    copy.write_bytes(clip.gt.read_bytes())
    for config, gt in (("robust", clip.gt), ("s0", shifted), ("camshift", copy)):
        assert vtrack("run", str(clip.path), "-c", config, "--gt", str(gt), "--no-video",
                      "--quiet", "--out", str(tmp_path / "runs" / config)).exit_code == 0
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    name = clip.path.stem
    assert [line for line in result.stderr.splitlines() if "different ground truth" in line] == [
        f"vtrack: warning: {name}: its runs were scored against different ground truth "
        f"({' = '.join(sorted([str(copy), str(clip.gt)]))} for camshift, robust; {shifted} "
        "for s0): their scores are not "
        "directly comparable"]
    _warns_no_more_without(tmp_path, "s0", "different ground truth")


def _warns_no_more_without(tmp_path: Path, gone: str, text: str) -> None:
    """The report of ``tmp_path/runs`` without its run folder ``gone`` warns of no ``text``."""
    shutil.rmtree(tmp_path / "runs" / gone)
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "r2"))
    assert result.exit_code == 0, result.output
    assert text not in result.stderr


def test_multi_target_runs_scored_against_different_ground_truth_are_warned_of(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Two s3 runs of one `multi` clip, one against its gt.txt and one against that file's
    first 10 frames (every track box after them a false positive), were ranked side by side
    in the multi-target table, the first's MOTA in bold, without a word, while single-target
    runs of one input are warned of. Now the same warning names the input and each file;
    a byte-identical copy is the same truth: no warning."""
    clip = clip_factory("multi", width=W, height=H, frames=60)
    assert clip.mot is not None
    first = tmp_path / "first.mot.txt"
    first.write_text("".join(line + "\n" for line in clip.mot.read_text().splitlines()
                             if int(line.split(",")[0]) <= 10))
    copy = tmp_path / "copy.mot.txt"
    copy.write_bytes(clip.mot.read_bytes())
    for name, gt in (("whole", clip.mot), ("first", first), ("copy", copy)):
        assert vtrack("run", str(clip.path), "-c", "s3", "--gt", str(gt), "--no-video",
                      "--quiet", "--out", str(tmp_path / "runs" / name)).exit_code == 0
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    labels = {row["run"]: row["config"]
              for row in csv.DictReader((tmp_path / "r" / "summary.csv").open())}
    whole, cut, same = (labels[str(tmp_path / "runs" / n)] for n in ("whole", "first", "copy"))
    assert [line for line in result.stderr.splitlines() if "different ground truth" in line] == [
        f"vtrack: warning: {clip.path.stem}: its runs were scored against different ground "
        f"truth ({' = '.join(sorted([str(copy), str(clip.mot)]))} for "
        f"{', '.join(sorted([same, whole]))}; {first} for {cut}): their scores are not "
        "directly comparable"]
    _warns_no_more_without(tmp_path, "first", "different ground truth")


def test_runs_of_one_input_over_different_frames_are_warned_of(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Probe 52b: two configs of one clip, one run over all 40 frames and one with --start 10
    --frames 20, were ranked side by side (the best in bold) without a word, though they were
    scored on different frames. Now a warning names the input and each run's frames; runs over
    the same frames get none."""
    clip = clip_factory("smooth", width=W, height=H, frames=40)
    for config, span in (("robust", ()), ("s0", ("--start", "10", "--frames", "20")),
                         ("camshift", ())):
        assert vtrack("run", str(clip.path), "-c", config, "--gt", str(clip.gt), *span,
                      "--no-video", "--quiet", "--out",
                      str(tmp_path / "runs" / config)).exit_code == 0
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert [line for line in result.stderr.splitlines() if "different frames" in line] == [
        f"vtrack: warning: {clip.path.stem}: its runs cover different frames (frames 0..39 for "
        "camshift, robust; frames 10..29 for s0): their scores are not directly comparable"]
    _warns_no_more_without(tmp_path, "s0", "different frames")


def test_one_plain_gt_file_scoring_several_inputs_is_warned_of(clip_factory: ClipFactory,
                                                                 tmp_path: Path) -> None:
    """A plain --gt FILE scored every input of its length, another clip's included (AUC 0.02
    for the wrong one), without a word."""
    runs = tmp_path / "runs"
    for scenario in ("smooth", "jump"):
        clip = clip_factory(scenario, width=W, height=H, frames=40)
        first = clip.gt.read_text().splitlines()[0]
        assert vtrack("run", str(clip.path), "--init", first, "--no-video", "--quiet",
                      "--out", str(runs / scenario)).exit_code == 0
    truth = clip_factory("smooth", width=W, height=H, frames=40).gt
    result = vtrack("report", str(runs), "--gt", str(truth), "--out", str(tmp_path / "rep"))
    assert result.exit_code == 0, result.output
    assert f"--gt {truth} scored 2 inputs (jump_" in result.stderr
    assert "each of its length: give --gt INPUT=FILE for each input" in result.stderr
    alone = vtrack("report", str(runs / "smooth"), "--gt", str(truth), "--out",
                   str(tmp_path / "alone"))
    assert alone.exit_code == 0 and "scored" not in alone.stderr


def test_a_run_the_given_gt_does_not_fit_is_not_said_to_lack_ground_truth(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Probe 52b: vtrack report RUN --gt SHORT.txt (30 boxes for a 40-frame run) said why the
    run was not scored, then 'give --gt FILE ... to score them' of that same run, as if no
    --gt had been given. Now the one warning that names the file's misfit is said."""
    clip = clip_factory("smooth", width=W, height=H, frames=40)
    lines = clip.gt.read_text().splitlines()
    run = tmp_path / "run"
    assert vtrack("run", str(clip.path), "--init", lines[0], "-c", "s0", "--no-video",
                  "--quiet", "--out", str(run)).exit_code == 0
    short = tmp_path / "short.txt"
    short.write_text("\n".join(lines[:30]) + "\n")
    result = vtrack("report", str(run), "--gt", str(short), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert result.stderr == (f"vtrack: warning: {run}: input {clip.path.stem} not scored: "
                             f"{short} has 30 boxes for its 40 frames; if its first box "
                             "is of a later frame, give --gt-first 10 (its last box then the "
                             f"last frame's); give --gt {clip.path.stem}=FILE with its own "
                             "ground truth\n")


def test_the_gt_suggested_for_a_run_not_scored_works_pasted(clip_factory: ClipFactory,
                                                           tmp_path: Path) -> None:
    """`vtrack report` of a run of `my clip (1).mp4` given a --gt that does not fit suggested
    `--gt my clip (1)=FILE`, unquoted: pasted into a shell, that is three words and a syntax
    error. The input is quoted as a shell word now, and the suggestion pasted (FILE the clip's
    own ground truth) scores the run."""
    clip = clip_factory("smooth", width=W, height=H, frames=40)
    named = tmp_path / "my clip (1).mp4"
    shutil.copy(clip.path, named)
    lines = clip.gt.read_text().splitlines()
    run = tmp_path / "run"
    assert vtrack("run", str(named), "--init", lines[0], "-c", "s0", "--no-video", "--quiet",
                  "--out", str(run)).exit_code == 0
    short = tmp_path / "short.txt"
    short.write_text("\n".join(lines[:30]) + "\n")
    result = vtrack("report", str(run), "--gt", str(short), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert result.stderr.endswith("; give --gt 'my clip (1)'=FILE with its own ground truth\n")
    suggested = result.stderr.split("; give ")[1].removesuffix(" with its own ground truth\n")
    words = shlex.split(suggested.replace("FILE", shlex.quote(str(clip.gt))))
    scored = vtrack("report", str(run), *words, "--out", str(tmp_path / "r2"))
    assert scored.exit_code == 0 and scored.stderr == "", scored.output
    with (tmp_path / "r2" / "summary.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [(row["input"], row["ground_truth"]) for row in rows] == [("my clip (1)",
                                                                      str(clip.gt))]
    assert rows[0]["auc"] != ""


def test_a_config_without_ground_truth_is_not_said_to_be_scored_on_other_inputs(
        batch_out: tuple[Path, Path], clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A config scored nowhere (no ground truth) made every report say "configurations were
    scored on different inputs"."""
    _, batch = batch_out
    clip = clip_factory("smooth", width=W, height=H, frames=40)
    first = clip.gt.read_text().splitlines()[0]
    unscored = tmp_path / "unscored"
    assert vtrack("run", str(clip.path), "--init", first, "-c", "s2", "--no-video", "--quiet",
                  "--out", str(unscored)).exit_code == 0
    result = vtrack("report", str(batch), str(unscored), "--out", str(tmp_path / "rep"))
    assert result.exit_code == 0 and "no ground truth" in result.stderr
    assert "different inputs" not in result.stderr


def write_multi_target_run(folder: Path, metrics: dict[str, float]) -> None:
    """A multi-target run folder as `vtrack run` leaves it (tracks.csv + run.json)."""
    folder.mkdir(parents=True)
    (folder / "tracks.csv").write_text("frame,id,x,y,w,h,conf,wx,wy,wz,state\n"
                                       "1,1,10,10,5,5,1,-1,-1,-1,confirmed\n")
    record = {"status": "complete", "frames": 1, "input": {"name": "crowd"},
              "config": {"name": folder.name}, "request": {"gt": "gt.txt" if metrics else None},
              "metrics": metrics, "timing": {"fps": 100.0},
              "summary": {"frames_occluded": 0, "frames_lost": 0}}
    (folder / "run.json").write_text(json.dumps(record))


def test_multi_target_runs_get_a_metrics_table(tmp_path: Path) -> None:
    write_multi_target_run(tmp_path / "runs" / "mht",
                           {"mota": 0.5, "motp": 0.75, "idf1": 0.625, "id_switches": 2})
    write_multi_target_run(tmp_path / "runs" / "blobs", {})  # no ground truth: no metrics
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    html = (tmp_path / "report" / "index.html").read_text()
    header, rows = html_rows(html, 0)
    assert header[3:] == ["Frames", "MOTA", "MOTP", "IDF1", "IDs", "FPS"]
    cells = {row[1]: row for row in rows}
    assert cells["mht"][4:8] == ["0.500", "0.750", "0.625", "2"]
    assert cells["blobs"][4:8] == ["—"] * 4
    assert "<img" not in html and not list((tmp_path / "report").rglob("*.png"))
    assert "CLEAR MOT" in html.split("<footer>")[1]


def test_only_the_html_page_says_its_headers_sort_and_hover(tmp_path: Path) -> None:
    """summary.md said "Click a column's header to sort by it; hover it for what it means" and
    "hover a header": a Markdown table does neither."""
    write_multi_target_run(tmp_path / "runs" / "mht", {"mota": 0.5, "id_switches": 2})
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    footer = (tmp_path / "report" / "index.html").read_text().split("<footer>")[1]
    assert "Click a column&#x27;s header to sort by it" in footer and "hover a header" in footer
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert "CLEAR MOT" in markdown and "mark none." in markdown
    assert "click" not in markdown.lower() and "hover" not in markdown.lower()


def test_a_multi_target_report_explains_only_what_it_shows(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """Probe O: `vtrack report` of fixed_camera runs (a MOTA/IDF1 table, no plot) ended with
    the single-target footer: overlap, the success and precision plots, AUC, tracking miss,
    miss flagged and lost frames, none of them on the page. It now explains the multi-target
    table alone; a report with single-target runs too keeps both."""
    write_multi_target_run(tmp_path / "runs" / "mht", {"mota": 0.5, "id_switches": 2})
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    for page in ("index.html", "summary.md"):
        text = (tmp_path / "report" / page).read_text()
        footer = text.split("<footer>")[1] if page == "index.html" else text.split("---")[-1]
        assert "CLEAR MOT" in footer and "in bold" in footer
        for single in ("Overlap is", "Success plot", "AUC", "Tracking miss", "Miss flagged",
                       "Lost frames"):
            assert single not in footer, (page, single)
    mixed = tmp_path / "mixed"
    shutil.copytree(tmp_path / "runs" / "mht", mixed / "mht")
    shutil.copytree(batch_out[1] / "smooth", mixed / "smooth")
    result = vtrack("report", str(mixed), "--out", str(tmp_path / "report2"))
    assert result.exit_code == 0, result.output
    footer = (tmp_path / "report2" / "index.html").read_text().split("<footer>")[1]
    assert "Overlap is" in footer and "Tracking miss" in footer and "CLEAR MOT" in footer


def test_the_multi_target_table_ranks_each_metric_its_own_way(tmp_path: Path) -> None:
    """Issue 22: every MOT metric was marked best when highest (mostly lost, track ids) and
    the table repeated the frame count and derivable box counts, too wide for the page."""
    common = {"frames": 1, "gt_boxes": 10, "gt_ids": 2, "matches": 8, "partially_tracked": 0}
    write_multi_target_run(tmp_path / "runs" / "good", {
        **common, "mota": 0.8, "misses": 2, "mostly_lost": 0, "mostly_tracked": 2,
        "track_ids": 2, "track_boxes": 8})
    write_multi_target_run(tmp_path / "runs" / "bad", {
        **common, "mota": 0.1, "misses": 9, "mostly_lost": 2, "mostly_tracked": 0,
        "track_ids": 7, "track_boxes": 15})
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    html = (tmp_path / "report" / "index.html").read_text()
    header = html_rows(html, 0)[0]
    assert header[3:] == ["Frames", "MOTA", "FN", "MT", "PT", "ML", "GT ids", "Tracks", "FPS"]
    body = re.findall(r"<table[^>]*>(.*?)</table>", html, re.S)[0]
    rows = {re.findall(r"<td[^>]*>(.*?)</td>", row)[1]: re.findall(r"<td([^>]*)>", row)
            for row in re.findall(r"<tr[^>]*>(.*?)</tr>", body)[1:]}
    best = {config: {header[n] for n, attrs in enumerate(cells) if "best" in attrs}
            for config, cells in rows.items()}
    assert best["good"] == {"MOTA", "FN", "MT", "ML"}  # fewer misses, fewer mostly lost
    assert best["bad"] == set()  # more track ids is not better; equal FPS marks nothing
    summary = (tmp_path / "report" / "summary.csv").read_text().splitlines()[0]
    assert {"gt_boxes", "track_boxes", "matches"} <= set(summary.split(","))  # kept there


def test_report_errors_are_one_line(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    assert "no run.json" in one_error_line(vtrack("report", str(tmp_path / "empty")))
    assert "missing" in one_error_line(vtrack("report", str(tmp_path / "missing")))


def test_when_every_run_is_left_out_the_error_names_every_reason(tmp_path: Path) -> None:
    """Four damaged run folders: the one error line named only the first."""
    for name in ("a", "b", "c"):
        (tmp_path / "runs" / name).mkdir(parents=True)
        (tmp_path / "runs" / name / "run.json").write_text("{not json" + name)
    write_multi_target_run(tmp_path / "runs" / "d", {})
    (tmp_path / "runs" / "d" / "tracks.csv").unlink()
    line = one_error_line(vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "r")))
    assert "no run to report, 4 left out: " in line
    for name in "abcd":
        assert str(tmp_path / "runs" / name) in line, line


def test_rows_without_results_of_two_batches_name_their_batch(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """`vtrack report batch-a batch-b`, batch-b stopped before it ran smooth [s0]: the list
    of runs without results said 'smooth [s0] interrupted: never ran' beside batch-a's
    complete smooth [s0], as if that run had not run; and each batch's row of an input that
    never ran anywhere was listed twice alike. Each such row now names its batch."""
    _, original = batch_out
    batches = {name: tmp_path / name for name in ("batch-a", "batch-b")}
    for batch in batches.values():
        shutil.copytree(original, batch)
        with (batch / "summary.csv").open("a", newline="") as handle:
            csv.DictWriter(handle, fieldnames=SUMMARY_COLUMNS).writerow(
                {"input": "never", "config": "s0", "status": "interrupted"})
    stopped = batches["batch-b"]
    shutil.rmtree(stopped / "smooth" / "s0")
    with (stopped / "summary.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        if (row["input"], row["config"]) == ("smooth", "s0"):
            row.update({column: "" for column in SUMMARY_COLUMNS[2:]}, status="interrupted")
    with (stopped / "summary.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=SUMMARY_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    report = tmp_path / "report"
    result = vtrack("report", *map(str, batches.values()), "--out", str(report))
    assert result.exit_code == 0, result.output
    markdown = (report / "summary.md").read_text()
    listed = sorted(line for line in markdown.splitlines() if line.startswith("- **"))
    assert listed == [  # (each batch's s0 one label: both ran occlusion [s0])
        f"- **{name}** [s0 ({batch})] interrupted: never ran (the batch stopped first)"
        for name, batch in (("never (batch-a)", "batch-a"), ("never (batch-b)", "batch-b"),
                            ("smooth (batch-b)", "batch-b"))]
    with (report / "summary.csv").open(newline="") as handle:
        statuses = {(row["input"], row["config"]): row["status"]
                    for row in csv.DictReader(handle)}
    assert statuses[("smooth", "s0 (batch-a)")] == "complete"  # batch-a's run, the only one
    assert statuses[("smooth (batch-b)", "s0 (batch-b)")] == "interrupted"


def test_rows_without_results_are_listed_and_failed_runs_not_averaged(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """A run that failed part way (1 frame tracked) was averaged as if whole, and a batch row
    the batch never ran (stopped first) appeared nowhere in the report."""
    _, original = batch_out
    batch = tmp_path / "batch"
    shutil.copytree(original, batch)
    record_path = batch / "smooth" / "s0" / "run.json"
    record = json.loads(record_path.read_text())
    record.update(status="failed", error="smooth.mp4: a broken frame")
    record_path.write_text(json.dumps(record))
    with (batch / "summary.csv").open("a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=SUMMARY_COLUMNS)
        writer.writerow({"input": "never", "config": "s0", "status": "interrupted"})
    report = tmp_path / "report"
    result = vtrack("report", str(batch), "--out", str(report))
    assert result.exit_code == 0, result.output
    html = (report / "index.html").read_text()
    header, averages = html_rows(html, 0)
    by_config = {row[0]: dict(zip(header, row, strict=True)) for row in averages}
    _, results = html_rows(html, 1)
    occlusion_s0 = next(row for row in results if row[:2] == ["occlusion", "s0"])
    assert by_config["s0"]["Inputs"] == "1"  # the failed run is not averaged
    # (over occlusion only, camshift's over both: not ranked against it, and says so)
    assert by_config["s0"]["AUC"].removesuffix(" (on 1 of 2 inputs)") in occlusion_s0
    assert by_config["s0"]["AUC"].endswith(" (on 1 of 2 inputs)")
    assert by_config["camshift"]["Inputs"] == "2"
    assert "1 single-target run failed part way" in html
    markdown = (report / "summary.md").read_text()
    assert "- **never** [s0] interrupted: never ran (the batch stopped first)" in markdown
    with (report / "summary.csv").open(newline="") as handle:
        rows = {(row["input"], row["config"]): row for row in csv.DictReader(handle)}
    assert rows[("never", "s0")]["status"] == "interrupted"
    assert rows[("smooth", "s0")]["error"] == "smooth.mp4: a broken frame"
    assert len(rows) == 5


def test_a_run_that_did_not_complete_is_never_marked_best_and_says_how_far_it_got(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """A failed run scored on the frames it reached was bolded as the input's best AUC, its
    status only "failed"."""
    _, original = batch_out
    batch = tmp_path / "batch"
    shutil.copytree(original, batch)
    scores = {}
    for config in ("s0", "camshift"):
        scores[config] = json.loads((batch / "occlusion" / config / "run.json").read_text())[
            "metrics"]["auc"]
    better, worse = sorted(scores, key=scores.get, reverse=True)
    record_path = batch / "occlusion" / better / "run.json"
    record = json.loads(record_path.read_text())
    record.update(status="failed", error="occlusion.mp4: a broken frame")
    record_path.write_text(json.dumps(record))
    report = tmp_path / "report"
    assert vtrack("report", str(batch), "--out", str(report)).exit_code == 0
    html = (report / "index.html").read_text()
    body = re.findall(r"<table[^>]*>(.*?)</table>", html, re.S)[1]
    rows = {tuple(re.findall(r"<td[^>]*>(.*?)</td>", row)[:2]): row
            for row in re.findall(r"<tr[^>]*>(.*?)</tr>", body)[1:]}
    assert "best" not in rows[("occlusion", better)]  # (one complete run left: none is best)
    assert "best" not in rows[("occlusion", worse)]
    frames = record["input"]["frame_count"]
    assert f"failed: {record['frames']} of {frames} frames" in rows[("occlusion", better)]


def test_a_partial_run_whose_name_was_told_apart_is_not_listed_without_results(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """`a.mp4` and a cut `a.ts`: the partial a.ts had results, yet was also listed under
    "Runs without results" (its batch row was matched by name, told apart since)."""
    folder = tmp_path / "in"
    folder.mkdir()
    clip = clip_factory("smooth", width=W, height=H, frames=40)
    shutil.copy(clip.path, folder / "a.mp4")
    shutil.copy(clip.gt, folder / "a.gt.txt")
    with av.open(str(clip.path)) as source, av.open(str(tmp_path / "a.ts"), "w") as ts:
        stream = ts.add_stream_from_template(source.streams.video[0])
        for packet in source.demux(video=0):
            if packet.dts is not None:
                packet.stream = stream
                ts.mux(packet)
    data = (tmp_path / "a.ts").read_bytes()
    (folder / "a.ts").write_bytes(data[: len(data) * 2 // 3])
    out = tmp_path / "out"
    assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "--out", str(out)
                  ).exit_code == 1  # the cut one is partial
    report = tmp_path / "report"
    assert vtrack("report", str(out), "--out", str(report)).exit_code == 0
    markdown = (report / "summary.md").read_text()
    assert "partial" in markdown and "Runs without results" not in markdown


def test_a_report_of_single_and_multi_target_runs_has_distinct_columns(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    _, batch = batch_out
    write_multi_target_run(tmp_path / "runs" / "mht", {"frames": 1, "mota": 0.5, "idf1": 0.6})
    shutil.copytree(batch / "smooth", tmp_path / "runs" / "smooth")
    result = vtrack("report", str(tmp_path / "runs"), "--out", str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        header = next(csv.reader(handle))
        handle.seek(0)
        rows = list(csv.DictReader(handle))
    assert len(header) == len(set(header)) and "mota" in header
    assert all(row["frames"] for row in rows) and len(rows) == 3


def test_inputs_of_one_name_in_two_containers_are_two_inputs(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    for name in ("a.mp4", "a.mkv"):  # FFmpeg reads the container the bytes hold
        shutil.copy(clip.path, folder / name)
    shutil.copy(clip.gt, folder / "a.gt.txt")
    out = tmp_path / "out"
    assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "--out", str(out)
                  ).exit_code == 0
    result = vtrack("report", str(out), "--out", str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert "2 runs of 2 inputs with 1 configuration;" in markdown
    assert "| a.mkv | s0 |" in markdown and "| a.mp4 | s0 |" in markdown
    assert "different inputs" not in markdown


def test_an_input_named_all_keeps_its_own_plots(clip_factory: ClipFactory,
                                                tmp_path: Path) -> None:
    """The plots over all inputs are ``curves_all.png``: an input named ``all`` showed those
    under its own heading, its own curves written over by them."""
    folder = tmp_path / "in"
    folder.mkdir()
    for name, scenario in (("all", "smooth"), ("b", "jump")):
        clip = clip_factory(scenario, width=W, height=H, frames=20)
        shutil.copy(clip.path, folder / f"{name}.mp4")
        shutil.copy(clip.gt, folder / f"{name}.gt.txt")
    out = tmp_path / "out"
    assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "--out", str(out)
                  ).exit_code == 0
    report = tmp_path / "report"
    assert vtrack("report", str(out), "--out", str(report)).exit_code == 0
    markdown = (report / "summary.md").read_text()
    under_all = markdown.split("\n## all\n", 1)[1].split("\n## ", 1)[0]
    assert re.findall(r"plots/(curves_[^)]+)\)", under_all) == ["curves_all-2.png"]
    everything = markdown.split("## All inputs", 1)[1].split("\n## ", 1)[0]
    assert re.findall(r"plots/(curves_[^)]+)\)", everything) == ["curves_all.png"]
    assert (report / "plots" / "curves_all-2.png").read_bytes() != (
        report / "plots" / "curves_all.png").read_bytes()


def _table_labels(markdown: str) -> set[tuple[str, str]]:
    """(input, config) of every row of the results table in summary.md."""
    rows = markdown.split("## Results per input and configuration", 1)[1].split("\n## ", 1)[0]
    return {tuple(c.strip() for c in line.strip("|").split("|")[:2])
            for line in rows.splitlines()[4:] if line.startswith("|")}


def test_one_file_name_in_two_folders_is_two_inputs(clip_factory: ClipFactory,
                                                    tmp_path: Path) -> None:
    """Two different clip.mp4 were one input (their runs two configs, "s0 (bx)" and "s0 (by)"),
    and one's boxes were drawn on the other's frames."""
    for name, scenario in (("x", "smooth"), ("y", "jump")):
        folder = tmp_path / f"d{name}"
        folder.mkdir()
        clip = clip_factory(scenario, width=W, height=H, frames=40)
        shutil.copy(clip.path, folder / "clip.mp4")
        shutil.copy(clip.gt, folder / "clip.gt.txt")
        assert vtrack("batch", str(folder), "-c", "s0", "--no-video", "--out",
                      str(tmp_path / f"b{name}")).exit_code == 0
    result = vtrack("report", str(tmp_path / "bx"), str(tmp_path / "by"), "--out",
                    str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert _table_labels(markdown) == {("clip (bx)", "s0"), ("clip (by)", "s0")}


def test_a_sequence_run_from_inside_its_img_folder_is_the_same_input(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack run .` from inside SEQ/img and `vtrack run SEQ` from its parent were two inputs
    ("seq (runs-in)", "seq (runs-out)"): the report found the sequence of `.` from its own
    folder. Now an image sequence is the one the run recorded."""
    from vtrack.scenes import make_scene, write_image_sequence

    write_image_sequence(make_scene("smooth", 0, 96, 72, 10, 30), tmp_path / "seq")
    monkeypatch.chdir(tmp_path / "seq" / "img")
    assert vtrack("run", ".", "--gt", "../groundtruth_rect.txt", "-c", "s0", "--no-video",
                  "--quiet", "--out", str(tmp_path / "runs-in")).exit_code == 0
    monkeypatch.chdir(tmp_path)
    assert vtrack("run", "seq", "--gt", "seq/groundtruth_rect.txt", "-c", "camshift",
                  "--no-video", "--quiet", "--out", "runs-out").exit_code == 0
    result = vtrack("report", "runs-in", "runs-out", "--out", "report")
    assert result.exit_code == 0, result.output
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert "2 runs of 1 input with 2 configurations;" in markdown, markdown
    assert _table_labels(markdown) == {("seq", "s0"), ("seq", "camshift")}


def _two_datasets_runs(tmp_path: Path, ext: str) -> None:
    """d1/Car and d2/Car, two sequences of ``ext`` images (other pixels, one name, frame count
    and frame size), and from ``tmp_path`` (the working folder) runs/a of d1/Car/img (s0),
    runs/b of d2/Car/img (s0) and runs/c of d2/Car (camshift)."""
    from vtrack.scenes import make_scene, write_image_sequence

    for dataset, scenario in (("d1", "smooth"), ("d2", "jump")):
        car = write_image_sequence(make_scene(scenario, 0, 96, 72, 10, 30), tmp_path / dataset
                                   / "Car")
        for jpg in sorted((car / "img").glob("*.jpg")) if ext != "jpg" else []:
            assert cv2.imwrite(str(jpg.with_suffix(f".{ext}")), cv2.imread(str(jpg)))
            jpg.unlink()
    sizes = {p.stat().st_size for p in tmp_path.glob(f"d?/Car/img/*.{ext}")}
    assert (len(sizes) == 1) if ext == "bmp" else (len(sizes) > 1), sizes  # bmp: one size
    for given, config, out in (("d1/Car/img", "s0", "a"), ("d2/Car/img", "s0", "b"),
                               ("d2/Car", "camshift", "c")):
        gt = f"{given.removesuffix('/img')}/groundtruth_rect.txt"
        assert vtrack("run", given, "--gt", gt, "-c", config, "--no-video", "--quiet",
                      "--out", f"runs/{out}").exit_code == 0


def _as_older(record: Path, image_bytes: int | None = None) -> None:
    """``record`` (a run.json) as a vtrack before ``input.image_identity`` wrote it (with
    ``image_bytes``, one that recorded the images' total size instead)."""
    data = json.loads(record.read_text())
    del data["input"]["image_identity"]
    if image_bytes is not None:
        data["input"]["image_bytes"] = image_bytes
    record.write_text(json.dumps(data))


@pytest.mark.parametrize("ext", ["jpg", "bmp"])
def test_two_datasets_sequences_of_one_name_count_and_size_are_two_inputs(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ext: str) -> None:
    """d1/Car/img and d2/Car/img, other pixels but one name, frame count and frame size, were
    one input "Car" (their runs two configs, "s0 (a)" and "s0 (b)"): the key left sizes out so
    that runs of SEQ and SEQ/img join. The images' total size told JPEG sequences apart but not
    uncompressed ones (BMP: every image of both of one size); run.json records a fingerprint
    of the images now (their total size, the first and last images' bytes), which tells both
    apart, while d2/Car and d2/Car/img stay one input; records without it join as before."""
    monkeypatch.chdir(tmp_path)
    _two_datasets_runs(tmp_path, ext)
    assert vtrack("report", "runs", "--out", "report").exit_code == 0
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert "3 runs of 2 inputs with 2 configurations;" in markdown, markdown
    labels = _table_labels(markdown)
    inputs = {config: {i for i, c in labels if c == config} for config in ("s0", "camshift")}
    assert len(inputs["s0"]) == 2 and len(inputs["camshift"]) == 1, labels
    assert inputs["camshift"] < inputs["s0"], labels  # d2/Car is d2/Car/img
    for out in "abc":  # records from before image_identity
        _as_older(tmp_path / "runs" / out / "run.json")
    assert vtrack("report", "runs", "--out", "older").exit_code == 0
    assert _table_labels((tmp_path / "older" / "summary.md").read_text()) == {
        ("Car", "s0 (a)"), ("Car", "s0 (b)"), ("Car", "camshift")}


def test_an_older_record_joins_the_one_input_of_its_key_that_has_a_fingerprint(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A run.json without input.image_identity (an older vtrack's) beside runs that have one:
    it joins the one input of its name, frame count and frame size that has one (d2/Car's
    camshift run beside d2/Car/img's s0 run: one input "Car"), and stays apart when two such
    inputs could be its (d1's and d2's), rather than being averaged with the wrong one."""
    monkeypatch.chdir(tmp_path)
    _two_datasets_runs(tmp_path, "jpg")
    _as_older(tmp_path / "runs" / "c" / "run.json")
    assert vtrack("report", "runs/b", "runs/c", "--out", "joined").exit_code == 0
    markdown = (tmp_path / "joined" / "summary.md").read_text()
    assert "2 runs of 1 input with 2 configurations;" in markdown, markdown
    assert _table_labels(markdown) == {("Car", "s0"), ("Car", "camshift")}
    assert vtrack("report", "runs", "--out", "apart").exit_code == 0
    markdown = (tmp_path / "apart" / "summary.md").read_text()
    assert "3 runs of 3 inputs with 2 configurations;" in markdown, markdown


def test_older_records_of_other_image_totals_stay_two_inputs(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Records a vtrack wrote with input.image_bytes (the images' total size) and no
    image_identity: d1/Car/img's and d2/Car/img's, other totals, were kept apart by it once,
    and joined as one input "Car" since the report keyed on image_identity alone. They are
    two inputs again, d2/Car's run one with d2/Car/img's (one total)."""
    monkeypatch.chdir(tmp_path)
    _two_datasets_runs(tmp_path, "jpg")
    for out, dataset in (("a", "d1"), ("b", "d2"), ("c", "d2")):
        total = sum(p.stat().st_size for p in (tmp_path / dataset / "Car" / "img").iterdir())
        _as_older(tmp_path / "runs" / out / "run.json", total)
    assert vtrack("report", "runs", "--out", "older").exit_code == 0
    markdown = (tmp_path / "older" / "summary.md").read_text()
    assert "3 runs of 2 inputs with 2 configurations;" in markdown, markdown
    labels = _table_labels(markdown)
    inputs = {config: {i for i, c in labels if c == config} for config in ("s0", "camshift")}
    assert len(inputs["s0"]) == 2 and inputs["camshift"] < inputs["s0"], labels


def test_an_older_record_without_a_total_joins_the_one_other_input_of_its_key(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Three runs of d2/Car/img: one recorded with image_identity, one with input.image_bytes
    only, one with neither (the oldest vtrack's). The report said "3 runs of 3 inputs": the
    total told the second from the first, which has none, and the third stayed apart from
    both. A total tells runs apart only from another total: they are one input "Car", and so
    are the two older runs alone."""
    monkeypatch.chdir(tmp_path)
    _two_datasets_runs(tmp_path, "jpg")
    assert vtrack("run", "d2/Car/img", "--gt", "d2/Car/groundtruth_rect.txt", "-c", "s1",
                  "--no-video", "--quiet", "--out", "runs/d").exit_code == 0
    total = sum(p.stat().st_size for p in (tmp_path / "d2" / "Car" / "img").iterdir())
    _as_older(tmp_path / "runs" / "c" / "run.json", total)
    _as_older(tmp_path / "runs" / "d" / "run.json")
    assert vtrack("report", "runs/b", "runs/c", "runs/d", "--out", "one").exit_code == 0
    markdown = (tmp_path / "one" / "summary.md").read_text()
    assert "3 runs of 1 input with 3 configurations;" in markdown, markdown
    assert _table_labels(markdown) == {("Car", "s0"), ("Car", "camshift"), ("Car", "s1")}
    assert vtrack("report", "runs/c", "runs/d", "--out", "older").exit_code == 0
    markdown = (tmp_path / "older" / "summary.md").read_text()
    assert "2 runs of 1 input with 2 configurations;" in markdown, markdown


def test_configs_of_one_name_but_other_chains_are_told_apart_over_every_input(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Two TOML files both named "mine": run on different inputs they were averaged as one
    config; run on overlapping inputs one batch's config got two labels."""
    shipped = (Path(__file__).parents[1] / "vtrack" / "configs" / "s0.toml").read_text()
    configs = {}
    for name, iterations in (("A", 1), ("B", 10)):
        (tmp_path / name).mkdir()
        configs[name] = tmp_path / name / "mine.toml"
        configs[name].write_text(shipped.replace('name = "s0"', 'name = "mine"', 1).replace(
            "\niterations = 1\n", f"\niterations = {iterations}\n", 1))
    inputs = tmp_path / "in"
    inputs.mkdir()
    for scenario in ("smooth", "jump"):
        clip = clip_factory(scenario, width=W, height=H, frames=40)
        shutil.copy(clip.path, inputs / f"{scenario}.mp4")
        shutil.copy(clip.gt, inputs / f"{scenario}.gt.txt")
    assert vtrack("batch", str(inputs), "-c", str(configs["A"]), "--no-video", "--out",
                  str(tmp_path / "bA")).exit_code == 0
    only_smooth = tmp_path / "in-smooth"
    only_smooth.mkdir()
    for name in ("smooth.mp4", "smooth.gt.txt"):
        shutil.copy(inputs / name, only_smooth / name)
    assert vtrack("batch", str(only_smooth), "-c", str(configs["B"]), "--no-video", "--out",
                  str(tmp_path / "bB")).exit_code == 0
    result = vtrack("report", str(tmp_path / "bA"), str(tmp_path / "bB"), "--out",
                    str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert _table_labels(markdown) == {("jump", "mine (meanshift.iterations=1)"),
                                       ("smooth", "mine (meanshift.iterations=1)"),
                                       ("smooth", "mine (meanshift.iterations=10)")}


def test_a_batch_s_config_keeps_one_label_beside_a_run_of_one_of_its_inputs(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """`vtrack report batch byhand`, byhand a `vtrack run` of one of the batch's inputs with one
    of its configs: that input's batch run was labelled "s0 (batch)" and the batch's other runs
    "s0", so the All inputs table averaged the batch's s0 as two configurations (one input
    each), neither the batch's mean; its row without results stayed "s0"."""
    inputs, original = batch_out
    batch = tmp_path / "batch"
    shutil.copytree(original, batch)
    with (batch / "summary.csv").open("a", newline="") as handle:
        csv.DictWriter(handle, fieldnames=SUMMARY_COLUMNS).writerow(
            {"input": "never", "config": "s0", "status": "interrupted"})
    byhand = tmp_path / "byhand"
    ran = vtrack("run", str(inputs / "smooth.mp4"), "-c", "s0", "--gt",
                 str(inputs / "smooth.gt.txt"), "--no-video", "--out", str(byhand))
    assert ran.exit_code == 0, ran.output
    report = tmp_path / "report"
    result = vtrack("report", str(batch), str(byhand), "--out", str(report))
    assert result.exit_code == 0, result.output
    markdown = (report / "summary.md").read_text()
    assert _table_labels(markdown) == {
        ("occlusion", "s0 (batch)"), ("smooth", "s0 (batch)"), ("smooth", "s0 (byhand)"),
        ("occlusion", "camshift"), ("smooth", "camshift")}
    header, averages = html_rows((report / "index.html").read_text(), 0)
    inputs_of = {row[0]: row[header.index("Inputs")] for row in averages}
    assert inputs_of == {"s0 (batch)": "2", "s0 (byhand)": "1", "camshift": "2"}
    assert "- **never** [s0 (batch)] interrupted" in markdown


@pytest.mark.parametrize("arguments", [["runs"], ["runs/smooth", "runs/occlusion"]])
def test_the_vtrack_runs_under_one_results_argument_keep_one_label(
        batch_out: tuple[Path, Path], tmp_path: Path, arguments: list[str]) -> None:
    """`vtrack report batch runs`, runs/<input> a `vtrack run -o runs/<input>` of each of the
    batch's inputs with one of its configs: each was labelled by its own folder ("s0
    (runs/smooth)", "s0 (runs/occlusion)"), one input each in All inputs, with a warning that
    the configurations were scored on different inputs. The runs found under one argument, of
    one config with the same values, are one label: "s0 (runs)", averaged over both inputs.
    So are they given as one argument each (`vtrack report batch runs/*`, the shell's glob:
    they were labelled by their own arguments, with the warning): `vtrack run` results of
    different inputs are one label, whichever argument each came from."""
    inputs, original = batch_out
    batch = tmp_path / "batch"
    shutil.copytree(original, batch)
    runs = tmp_path / "runs"
    for name in ("smooth", "occlusion"):
        ran = vtrack("run", str(inputs / f"{name}.mp4"), "-c", "s0", "--gt",
                     str(inputs / f"{name}.gt.txt"), "--no-video", "--out", str(runs / name))
        assert ran.exit_code == 0, ran.output
    report = tmp_path / "report"
    result = vtrack("report", str(batch), *(str(tmp_path / a) for a in arguments), "--out",
                    str(report))
    assert result.exit_code == 0, result.output
    markdown = (report / "summary.md").read_text()
    assert _table_labels(markdown) == {
        (name, config) for name in ("smooth", "occlusion")
        for config in ("s0 (batch)", "s0 (runs)", "camshift")}
    header, averages = html_rows((report / "index.html").read_text(), 0)
    inputs_of = {row[0]: row[header.index("Inputs")] for row in averages}
    assert inputs_of == {"s0 (batch)": "2", "s0 (runs)": "2", "camshift": "2"}
    assert "scored on different inputs" not in result.output


def test_a_motchallenge_gt_given_to_report_says_what_report_scores(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """It said to use a multi-target config (--config s3): report has no --config."""
    _, batch = batch_out
    mot = tmp_path / "gt.txt"
    mot.write_text("1,1,10,10,20,40,1,-1,-1,-1\n2,1,12,10,20,40,1,-1,-1,-1\n")
    result = vtrack("report", str(batch), "--gt", str(mot), "--out", str(tmp_path / "rep"))
    assert result.exit_code == 2
    assert result.output.strip() == (
        f"vtrack: error: --gt {mot}: MOTChallenge ground truth (many targets); the report's "
        "--gt scores single-target runs: a multi-target run is scored with the ground truth "
        "given to vtrack run --gt")


def test_a_report_made_from_another_folder_reads_the_runs_relative_input_and_ground_truth(
        clip_factory: ClipFactory, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A report made from another folder reads a run's relative input and ground truth from
    the folder the run was started in. The one ground truth a run named relatively (`--gt
    clip.gt.txt`) and another by its absolute path (as `vtrack batch` records it) was called
    two: "scored against different ground truth (.../clip.gt.txt for camshift; clip.gt.txt
    for s0)", and summary.csv named clip.gt.txt, not there from the report's folder."""
    clip = clip_factory("occlusion", width=W, height=H, frames=60)
    started = tmp_path / "project"
    started.mkdir()
    shutil.copy(clip.path, started / "clip.mp4")
    shutil.copy(clip.gt, started / "clip.gt.txt")
    monkeypatch.chdir(started)
    for config, gt, out in (("s0", "clip.gt.txt", "runs"),
                            ("camshift", str(started / "clip.gt.txt"), "runs-abs")):
        assert vtrack("run", "clip.mp4", "--gt", gt, "-c", config, "--no-video",
                      "--quiet", "--out", out).exit_code == 0
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)

    # the failure thumbnails need the input's frames and the ground truth's boxes
    found = vtrack("report", str(started / "runs"), str(started / "runs-abs"), "--out", "found")
    assert found.exit_code == 0 and "left out" not in found.stderr, found.output
    assert "different ground truth" not in found.stderr
    assert (elsewhere / "found" / "plots" / "failures_clip.png").is_file()
    with (elsewhere / "found" / "summary.csv").open(newline="") as handle:
        truths = {row["config"]: row["ground_truth"] for row in csv.DictReader(handle)}
    assert truths == {"s0": str(started / "clip.gt.txt"),
                      "camshift": str(started / "clip.gt.txt")}

    # a ground truth no longer there: scored as the run recorded, the thumbnails left out
    # with a word (not silently)
    (started / "clip.gt.txt").rename(started / "other.txt")
    gone = vtrack("report", str(started / "runs"), "--out", "gone")
    assert gone.exit_code == 0
    assert "failure frames of clip left out: the ground truth clip.gt.txt" in gone.stderr
    assert not (elsewhere / "gone" / "plots" / "failures_clip.png").exists()
    assert (elsewhere / "gone" / "plots" / "overlap_clip.png").is_file()


def test_a_tracker_that_gives_no_score_is_said_so_not_plotted_blank(clip_factory: ClipFactory,
                                                                     tmp_path: Path) -> None:
    """Probe 48 item 4: s4 (its document defines no confidence) leaves ``score`` empty on every
    row, and the report drew a blank score plot. The page now says it has none, and the panel
    does too; s0's score is plotted as before."""
    clip = clip_factory("bounce", width=W, height=H, frames=60)
    box = clip.gt.read_text().splitlines()[0]
    for config, init in (("s4", []), ("s0", ["--init", box])):
        result = vtrack("run", str(clip.path), "-c", config, *init, "--no-video", "-q", "-o",
                        str(tmp_path / config))
        assert result.exit_code == 0, result.output
    with (tmp_path / "s4" / "track.csv").open(newline="") as handle:
        assert {row["score"] for row in csv.DictReader(handle)} == {""}
    assert vtrack("report", str(tmp_path / "s4"), str(tmp_path / "s0"), "-q", "-o",
                  str(tmp_path / "report")).exit_code == 0
    page = (tmp_path / "report" / "index.html").read_text()
    notes = re.findall(r"Warning: ([^<]*no score[^<]*)</p>", page)
    assert len(notes) == 1 and "[s4]: no score: this tracker gives none" in notes[0], notes
    assert len(list((tmp_path / "report" / "plots").glob("state_*.png"))) == 1


def test_no_input_s_plots_take_the_name_of_the_plots_over_all_inputs_in_any_case() -> None:
    """``curves_All.png`` is ``curves_all.png`` on a file system blind to case (macOS,
    Windows): an input named All, ALL or all gets another slug."""
    from vtrack.report import ALL_INPUTS, _slugs

    slugs = _slugs(["All", "ALL", "all", "alley"])
    assert all(slug.lower() != ALL_INPUTS for slug in slugs.values()), slugs
    assert slugs["alley"] == "alley"


def test_a_report_of_a_batch_whose_every_run_failed_counts_those_runs(tmp_path: Path) -> None:
    """Every run of the batch failed (an input that is no video): the report's heading read
    "0 runs of 0 inputs with 0 configurations" above its list of those runs. Now it counts
    them, their inputs and configurations."""
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "notvideo.mp4").write_text("this is not a video\n")
    (folder / "notvideo.gt.txt").write_text("1,1,10,10\n")
    out, report = tmp_path / "out", tmp_path / "report"
    ran = vtrack("batch", str(folder), "-c", "s0", "-c", "camshift", "--no-video", "-j", "1",
                 "--out", str(out))
    assert ran.exit_code == 1, ran.output
    result = vtrack("report", str(out), "--out", str(report))
    assert result.exit_code == 0, result.output
    markdown = (report / "summary.md").read_text()
    assert "2 runs without results of 1 input with 2 configurations;" in markdown, markdown
    assert "0 runs" not in markdown


def test_runs_of_vtrack_run_only_keep_their_labels_and_a_run_inside_a_batch_is_named(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """Telling a batch's runs apart from a `vtrack run` of one of its inputs relabelled runs
    of `vtrack run` only too: each run folder its own origin, so the only run of another input
    became "s0 (b/s0)" (it is "s0", and those of one input "s0 (s0)" / "s0 (s0-again)"); and a
    `vtrack run` folder inside the batch's folder made the batch's label "s0 (.)"."""
    inputs, original = batch_out
    runs = tmp_path / "runs"
    for name, out in (("smooth", "smooth/s0"), ("smooth", "smooth/s0-again"),
                      ("occlusion", "occlusion/s0")):
        ran = vtrack("run", str(inputs / f"{name}.mp4"), "-c", "s0", "--gt",
                     str(inputs / f"{name}.gt.txt"), "--no-video", "--out", str(runs / out))
        assert ran.exit_code == 0, ran.output
    result = vtrack("report", str(runs), "--out", str(tmp_path / "r1"))
    assert result.exit_code == 0, result.output
    assert _table_labels((tmp_path / "r1" / "summary.md").read_text()) == {
        ("smooth", "s0 (s0)"), ("smooth", "s0 (s0-again)"), ("occlusion", "s0")}
    batch = tmp_path / "batch"
    shutil.copytree(original, batch)
    ran = vtrack("run", str(inputs / "smooth.mp4"), "-c", "s0", "--gt",
                 str(inputs / "smooth.gt.txt"), "--no-video", "--out", str(batch / "extra"))
    assert ran.exit_code == 0, ran.output
    result = vtrack("report", str(batch), "--out", str(tmp_path / "r2"))
    assert result.exit_code == 0, result.output
    labels = _table_labels((tmp_path / "r2" / "summary.md").read_text())
    assert ("smooth", "s0 (batch)") in labels and ("smooth", "s0 (batch/extra)") in labels, labels
    assert not any("(.)" in label for _, label in labels), labels


def test_one_ground_truth_is_one_path_in_the_summary_also_through_dot_dot(
        batch_out: tuple[Path, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A run given `--gt ../clips/b.gt.txt` was listed with `/.../sub/../clips/b.gt.txt` beside
    the batch's `/.../clips/b.gt.txt`."""
    inputs, batch = batch_out
    sub = tmp_path / "sub"
    sub.mkdir()
    monkeypatch.chdir(sub)
    relative = os.path.relpath(inputs / "smooth.gt.txt", sub)
    ran = vtrack("run", str(inputs / "smooth.mp4"), "-c", "camshift", "--gt", relative,
                 "--no-video", "--out", str(tmp_path / "byhand"))
    assert ran.exit_code == 0, ran.output
    monkeypatch.chdir(tmp_path)
    result = vtrack("report", str(batch), str(tmp_path / "byhand"), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    with (tmp_path / "r" / "summary.csv").open(newline="") as handle:
        truths = {row["ground_truth"] for row in csv.DictReader(handle)
                  if row["input"] == "smooth"}
    assert truths == {str((inputs / "smooth.gt.txt").resolve())}, truths


def test_a_multi_target_runs_ground_truth_is_named_where_it_is_found(
        clip_factory: ClipFactory, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A multi-target run's ground truth was listed as typed (`m.mot.txt`), a path that does
    not exist from the report's folder; a single target's is the file found from the run's."""
    clip = clip_factory("multi", frames=60)
    work = tmp_path / "work"
    work.mkdir()
    shutil.copy(clip.path, work / "m.mp4")
    shutil.copy(clip.mot, work / "m.mot.txt")
    monkeypatch.chdir(work)
    ran = vtrack("run", "m.mp4", "-c", "s3", "--gt", "m.mot.txt", "--no-video", "--out", "run")
    assert ran.exit_code == 0, ran.output
    monkeypatch.chdir(tmp_path)
    result = vtrack("report", str(work / "run"), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    with (tmp_path / "r" / "summary.csv").open(newline="") as handle:
        (row,) = list(csv.DictReader(handle))
    assert row["ground_truth"] == str(work / "m.mot.txt")


def test_a_ground_truth_reached_through_a_link_and_dot_dot_is_the_file_the_run_read(
        batch_out: tuple[Path, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`--gt link/../clips/smooth.gt.txt`, link a symbolic link to a folder elsewhere: the
    report named the path with `link/..` removed as text, another file (here another clip's
    truth), and warned that the ground truth had changed since the run."""
    inputs, _ = batch_out
    elsewhere = tmp_path / "elsewhere"
    (elsewhere / "deep").mkdir(parents=True)
    shutil.copytree(inputs, elsewhere / "clips")
    work = tmp_path / "work"
    (work / "clips").mkdir(parents=True)
    shutil.copy(inputs / "occlusion.gt.txt", work / "clips" / "smooth.gt.txt")  # another's
    (work / "link").symlink_to(elsewhere / "deep")
    monkeypatch.chdir(work)
    ran = vtrack("run", str(elsewhere / "clips" / "smooth.mp4"), "-c", "s0", "--gt",
                 "link/../clips/smooth.gt.txt", "--no-video", "--out", str(tmp_path / "run"))
    assert ran.exit_code == 0, ran.output
    monkeypatch.chdir(tmp_path)
    result = vtrack("report", str(tmp_path / "run"), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    assert "Warning" not in result.output and "changed" not in result.output, result.output
    with (tmp_path / "r" / "summary.csv").open(newline="") as handle:
        (row,) = list(csv.DictReader(handle))
    assert row["ground_truth"] == str((elsewhere / "clips" / "smooth.gt.txt").resolve())


def test_the_definitions_say_the_all_inputs_lost_frames_are_a_total(
        batch_out: tuple[Path, Path], tmp_path: Path) -> None:
    """The All inputs row adds the inputs' lost frames up but averages every other column,
    while the page said only that averages over inputs are means."""
    _, batch = batch_out
    result = vtrack("report", str(batch), "--out", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    for page in ("index.html", "summary.md"):
        text = (tmp_path / "r" / page).read_text()
        assert "means of the per-input curves and scores (lost frames: their total)" in text


def test_mean_center_error_leaves_lost_frames_out_and_the_docs_say_so(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A run lost in frames where the target is in view (scored: overlap 0) has a
    mean_center_error over its other frames only (run.json, summary.csv), and nothing said so:
    the report's notes said a lost frame counts as an infinite centre error, and a run lost
    most of the time showed a small mean error. The notes and the README now say it."""
    clip = clip_factory("leave_return", width=W, height=H, frames=90)
    out = tmp_path / "run"
    ran = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "--out", str(out))
    assert ran.exit_code == 0, ran.output
    with (out / "track.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert any(r["state"] == "lost" and r["overlap"] != "" for r in rows)  # lost and scored
    errors = [float(r["center_error"]) for r in rows if r["center_error"] != ""]
    recorded = json.loads((out / "run.json").read_text())["metrics"]["mean_center_error"]
    assert recorded == pytest.approx(sum(errors) / len(errors), abs=1e-3)
    result = vtrack("report", str(out), "--out", str(tmp_path / "report"))
    assert result.exit_code == 0, result.output
    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        (row,) = csv.DictReader(handle)
    assert float(row["mean_center_error"]) == pytest.approx(recorded, abs=1e-6)
    said = ("mean_center_error is the mean over the evaluated frames where the tracker claims "
            "a box, lost frames left out")
    assert said in (tmp_path / "report" / "summary.md").read_text()
    assert said in (tmp_path / "report" / "index.html").read_text()
    readme = " ".join((Path(__file__).parents[1] / "README.md").read_text().split())
    assert ("`mean_center_error` is the mean centre error in px over the evaluated frames "
            "where the tracker claims a box: its `lost` frames") in readme
    assert "`mean_center_error` leaves the `lost` frames out" in readme
