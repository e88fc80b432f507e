"""Issue 21 item 2: `vtrack report` never scores a `track.csv` cut (or edited) after its run
as if it were whole: the run is left out with one warning naming the file."""

from __future__ import annotations

import csv
import errno
import json
import os
import re
from pathlib import Path

import pytest
from test_cli import vtrack

from vtrack.scenes import make_scene, write_groundtruth, write_video

W, H, FRAMES = 64, 48, 40


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("whole")
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    write_video(scene, folder / "clip.mp4")
    write_groundtruth(scene, folder / "clip.gt.txt")
    out = folder / "run"
    result = vtrack("run", str(folder / "clip.mp4"), "--gt", str(folder / "clip.gt.txt"),
                    "-c", "s0", "--no-video", "-o", str(out))
    assert result.returncode == 0, result.stderr.decode()
    return out


def report(run: Path, out: Path) -> tuple[int, str]:
    result = vtrack("report", str(run), "-o", str(out), "-q")
    stderr = result.stderr.decode()
    assert "Traceback" not in stderr, stderr
    return result.returncode, stderr


def test_a_whole_run_is_scored(run_dir: Path, tmp_path: Path) -> None:
    code, stderr = report(run_dir, tmp_path / "rep")
    assert code == 0 and "left out" not in stderr, stderr
    rows = (tmp_path / "rep" / "summary.csv").read_text().splitlines()
    assert len(rows) == 2


@pytest.mark.parametrize("sizes_recorded", [True, False])
def test_a_cut_track_csv_is_left_out_with_a_warning(run_dir: Path, tmp_path: Path,
                                                    sizes_recorded: bool) -> None:
    copy = tmp_path / "run"
    copy.mkdir()
    record = json.loads((run_dir / "run.json").read_text())
    if not sizes_recorded:  # a record from before sizes were recorded: rows against frames
        del record["output_bytes"]
    (copy / "run.json").write_text(json.dumps(record))
    data = (run_dir / "track.csv").read_bytes()
    (copy / "track.csv").write_bytes(data[:1000])
    code, stderr = report(copy, tmp_path / "rep")
    assert code != 0  # the only run is left out: nothing to report
    assert "track.csv" in stderr and "cut or edited" in stderr, stderr
    assert f"{FRAMES} frames" in stderr or "bytes" in stderr, stderr


@pytest.mark.parametrize(("start", "old", "new", "why"), [
    (0, "\n5,", "\n9,", "frame 6 after frame 9: its frame numbers do not increase"),
    (0, f"\n{FRAMES - 1},", f"\n{FRAMES + 3},", f"frame {FRAMES + 3} after the run's last, "
                                                f"{FRAMES - 1}"),
    (5, "\n5,", "\n3,", "frame 3: before the run's first frame, 5"),
])
def test_a_track_csv_whose_frames_do_not_increase_is_left_out(
        run_dir: Path, tmp_path: Path, start: int, old: str, new: str, why: str) -> None:
    """A track.csv whose row of frame 5 was renumbered 9 (same size, same rows) was scored
    with every later row shifted 4 frames off its ground truth (s0's AUC 0.92 read as 0.12),
    its run said to cover frames 0..43 of a 40-frame run. Its last row renumbered past the run's
    last frame was warned of as 'clip.gt.txt has 40 boxes for its 44 frames'; the first row of
    a run from --start 5 renumbered 3 was said to 'not increase'."""
    run = run_dir
    if start:
        run = tmp_path / "from"
        clip = run_dir.parent / "clip"
        assert vtrack("run", f"{clip}.mp4", "--gt", f"{clip}.gt.txt", "-c", "s0", "--start",
                      str(start), "--no-video", "-o", str(run)).returncode == 0
    copy = tmp_path / "run"
    copy.mkdir()
    (copy / "run.json").write_bytes((run / "run.json").read_bytes())
    data = (run / "track.csv").read_text()
    assert old in data
    (copy / "track.csv").write_text(data.replace(old, new, 1))
    code, stderr = report(copy, tmp_path / "rep")
    assert code != 0  # the only run is left out: nothing to report
    assert (f"left out: {copy.resolve() / 'track.csv'}: not a vtrack track.csv ({why})"
            ) in stderr, stderr


@pytest.mark.parametrize("damage", [
    {"config": 5}, {"input": "clip.mp4"}, {"frames": 1e999}, {"timing": []}, {"summary": "x"},
    "[" * 100_000 + "]" * 100_000, [1, 2], {"timing": {"fps": "fast"}},
    {"request": {"gt_origin": 7}}, {"status": "done"}, {"start_frame": -5},
    {"start_frame": "x"}, {"output_bytes": {"track.csv": "123"}},
], ids=["config", "input", "frames", "timing", "summary", "deep", "list", "fps", "origin",
        "status", "start", "start-text", "bytes-text"])
def test_a_hand_damaged_run_json_is_left_out_and_the_other_runs_reported(
        run_dir: Path, tmp_path: Path, damage: dict | str | list) -> None:
    damaged = tmp_path / "damaged"
    damaged.mkdir()
    (damaged / "track.csv").write_bytes((run_dir / "track.csv").read_bytes())
    record = json.loads((run_dir / "run.json").read_text())
    (damaged / "run.json").write_text(
        damage if isinstance(damage, str)
        else json.dumps({**record, **{k: ({**record[k], **v} if isinstance(v, dict) else v)
                                      for k, v in damage.items()}}
                        if isinstance(damage, dict) else damage))
    result = vtrack("report", str(damaged), str(run_dir), "-o", str(tmp_path / "rep"), "-q")
    stderr = result.stderr.decode()
    assert result.returncode == 0 and "Traceback" not in stderr, stderr
    why = " (its 'frames' is not a whole number of 0 or more)" if damage == {
        "frames": 1e999} else ""
    assert stderr.strip() == (f"vtrack: warning: left out: {damaged / 'run.json'}: "
                              f"not a vtrack run record{why}")
    rows = (tmp_path / "rep" / "summary.csv").read_text().splitlines()
    assert len(rows) == 2  # the whole run


def test_a_ground_truth_changed_after_the_run_is_not_used_to_rescore(
        run_dir: Path, tmp_path: Path) -> None:
    """The report rescored the run's boxes against its recorded ground truth file as it is now;
    one edited after the run gave other scores without a word."""
    record = json.loads((run_dir / "run.json").read_text())
    truth = Path(record["request"]["gt"])
    copy = tmp_path / "run"
    copy.mkdir()
    for name in ("run.json", "track.csv"):
        (copy / name).write_bytes((run_dir / name).read_bytes())
    code, stderr = report(copy, tmp_path / "before")
    before = summary_row(tmp_path / "before")
    assert code == 0 and "changed" not in stderr, stderr
    original = truth.read_bytes()
    try:
        lines = original.decode().splitlines()
        shifted = [",".join(str(float(v) + 9 * (i == 0)) for i, v in enumerate(line.split(",")))
                   for line in lines]
        truth.write_text("\n".join(shifted) + "\n")
        code, stderr = report(copy, tmp_path / "after")
    finally:
        truth.write_bytes(original)
    assert code == 0
    assert f"the ground truth {truth} changed after the run" in stderr, stderr
    after = summary_row(tmp_path / "after")  # the recorded overlaps: 4 decimals
    assert float(after["auc"]) == pytest.approx(float(before["auc"]), abs=0.005)
    assert (after["precision20"], after["success50"]) == (before["precision20"],
                                                          before["success50"])


def summary_row(report_dir: Path) -> dict[str, str]:
    with (report_dir / "summary.csv").open(newline="") as handle:
        (row,) = csv.DictReader(handle)
    return row


def test_a_batch_resumes_past_a_hand_damaged_run_json(run_dir: Path, tmp_path: Path) -> None:
    """A ``run.json`` whose summary is not an object stopped the resumed batch with a
    traceback; it is a record of no complete run: the pair is not resumed, one line says why."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    for name in ("clip.mp4", "clip.gt.txt"):
        (inputs / name).write_bytes((run_dir.parent / name).read_bytes())
    args = ("batch", str(inputs), "-c", "s0", "--no-video", "-j", "1", "-o", str(tmp_path / "out"))
    assert vtrack(*args).returncode == 0
    record_path = tmp_path / "out" / "clip" / "s0" / "run.json"
    record = json.loads(record_path.read_text())
    record_path.write_text(json.dumps({**record, "summary": None}))
    again = vtrack(*args)
    stderr = again.stderr.decode()
    assert again.returncode == 1 and "Traceback" not in stderr, stderr
    assert "clip [s0]: failed:" in stderr and "--overwrite" in stderr, stderr
    assert vtrack(*args, "-y").returncode == 0  # replaced when asked
    assert json.loads(record_path.read_text())["summary"]["frames"] == FRAMES


def test_a_fifo_given_as_ground_truth_is_refused_not_waited_on(run_dir: Path,
                                                               tmp_path: Path) -> None:
    """Opening a FIFO waits for a writer: ``report --gt FIFO`` and ``run --gt FIFO`` hung."""
    fifo = tmp_path / "gt.fifo"
    os.mkfifo(fifo)
    for args in (("report", str(run_dir), "--gt", str(fifo), "-o", str(tmp_path / "rep")),
                 ("run", str(run_dir.parent / "clip.mp4"), "--gt", str(fifo), "-c", "s0",
                  "--no-video", "-o", str(tmp_path / "run"))):
        result = vtrack(*args)
        stderr = result.stderr.decode()
        assert result.returncode == 2 and "Traceback" not in stderr, stderr
        assert f"{fifo}: a FIFO, not a file" in stderr, stderr


def test_a_relative_ground_truth_not_found_from_here_is_not_called_changed(
        run_dir: Path, tmp_path: Path) -> None:
    """Reported from another folder, a run's relative ground-truth path was "changed after
    the run"; it is only not found there: the run's recorded overlaps score it."""
    copy = tmp_path / "run"
    copy.mkdir()
    record = json.loads((run_dir / "run.json").read_text())
    record["request"]["gt"] = "elsewhere/clip.gt.txt"
    (copy / "run.json").write_text(json.dumps(record))
    (copy / "track.csv").write_bytes((run_dir / "track.csv").read_bytes())
    code, stderr = report(copy, tmp_path / "rep")
    assert code == 0 and "changed" not in stderr, stderr
    assert float(summary_row(tmp_path / "rep")["auc"]) > 0


def test_a_run_json_link_in_a_loop_is_left_out_with_a_warning(run_dir: Path,
                                                              tmp_path: Path) -> None:
    """A run.json that is a symbolic link to itself (or to a link in a loop, `ln -s loop loop`)
    was passed over without a word: the folder walk took it for missing. It is left out with
    the line other unreadable runs get, found below a folder and given itself."""
    results = tmp_path / "results"
    whole = results / "whole"
    whole.mkdir(parents=True)
    for name in ("run.json", "track.csv"):
        (whole / name).write_bytes((run_dir / name).read_bytes())
    (results / "self").mkdir()
    (results / "self" / "run.json").symlink_to("run.json")
    (results / "loop").mkdir()
    (results / "loop" / "loop").symlink_to("loop")
    (results / "loop" / "run.json").symlink_to("loop")
    code, stderr = report(results, tmp_path / "rep")
    assert code == 0, stderr
    assert [line for line in stderr.splitlines() if "left out" in line] == [
        f"vtrack: warning: left out: {results / name / 'run.json'}: cannot read run record "
        f"({os.strerror(errno.ELOOP)})" for name in ("loop", "self")]
    assert len((tmp_path / "rep" / "summary.csv").read_text().splitlines()) == 2  # the whole
    code, stderr = report(results / "self" / "run.json", tmp_path / "rep2")
    assert code != 0 and stderr == (
        f"vtrack: error: {results / 'self' / 'run.json'}: no run to report; left out: "
        f"{results / 'self' / 'run.json'}: cannot read run record ({os.strerror(errno.ELOOP)})\n")


def test_a_link_to_nothing_or_in_a_loop_given_as_results_is_no_such_folder(
        tmp_path: Path) -> None:
    """`vtrack report dangling` (a symbolic link to nothing) or a link in a loop said
    "not a results folder or run.json", as for a file that is there: it is not there."""
    (tmp_path / "dangling").symlink_to("nowhere")
    (tmp_path / "loop").symlink_to("loop")
    for name, note in (("dangling", " (a symbolic link to nothing)"),
                       ("loop", " (a symbolic link in a loop)"), ("nothing", "")):
        code, stderr = report(tmp_path / name, tmp_path / "rep")
        assert code != 0 and stderr == (
            f"vtrack: error: {tmp_path / name}: no such file or folder{note}\n"), stderr
    assert not (tmp_path / "rep").exists()


def test_a_summary_csv_link_in_a_loop_and_a_linked_run_folder_are_named(
        run_dir: Path, tmp_path: Path) -> None:
    """Below a results folder, a batch's summary.csv that is a symbolic link in a loop was
    passed over without a word (Path.rglob takes it for missing), and so was a run folder that
    is a symbolic link (not followed): the report showed fewer runs and said nothing. Each is
    one warning now; the linked folder given itself is reported. A link into the folders
    walked (`latest -> whole`, as a batch tree's `latest -> batch-2`) was warned of as well,
    in summary.md and index.html too, even when given itself: its runs are reported where it
    leads, and it is no warning now."""
    results = tmp_path / "results"
    whole = results / "whole"
    whole.mkdir(parents=True)
    for name in ("run.json", "track.csv"):
        (whole / name).write_bytes((run_dir / name).read_bytes())
    (results / "linked").symlink_to(run_dir)
    (results / "latest").symlink_to("whole")  # (as a batch tree's latest -> batch-N)
    (results / "batch").mkdir()
    (results / "batch" / "summary.csv").symlink_to("summary.csv")
    code, stderr = report(results, tmp_path / "rep")
    assert code == 0, stderr
    named = ("not followed", "summary.csv: ")  # (not the ground truth others have changed)
    assert [line for line in stderr.splitlines() if any(n in line for n in named)] == [
        f"vtrack: warning: not followed: {results / 'linked'} (a symbolic link to a folder; "
        "give it as RESULTS to report the runs in it)",
        f"vtrack: warning: {results / 'batch' / 'summary.csv'}: cannot read "
        f"({os.strerror(errno.ELOOP)}); the runs without results it lists are not shown"]
    assert len((tmp_path / "rep" / "summary.csv").read_text().splitlines()) == 2  # the whole
    assert "not followed" not in (tmp_path / "rep" / "summary.md").read_text().replace(
        f"not followed: {results / 'linked'} ", "")
    code, stderr = report(results / "linked", tmp_path / "rep2")
    assert code == 0 and "followed" not in stderr, stderr
    assert len((tmp_path / "rep2" / "summary.csv").read_text().splitlines()) == 2
    # a link into what is walked, given too, is no warning either (its run once)
    done = vtrack("report", str(results), str(results / "latest"), "-o",
                  str(tmp_path / "rep3"), "-q")
    assert done.returncode == 0, done.stderr
    assert [line for line in done.stderr.decode().splitlines() if "followed" in line] == [
        f"vtrack: warning: not followed: {results / 'linked'} (a symbolic link to a folder; "
        "give it as RESULTS to report the runs in it)"]
    assert len((tmp_path / "rep3" / "summary.csv").read_text().splitlines()) == 2


def test_a_folder_the_walk_cannot_read_is_named(run_dir: Path, tmp_path: Path) -> None:
    """A folder below RESULTS that cannot be listed (here: too deep, its path past the
    system's limit) was passed over without a word, the runs in it left out; it is one
    warning now, naming it and why, its path cut as other overlong echoes are (it was
    written whole, over 4000 characters)."""
    results = tmp_path / "results"
    whole = results / "whole"
    whole.mkdir(parents=True)
    for name in ("run.json", "track.csv"):
        (whole / name).write_bytes((run_dir / name).read_bytes())
    deep = results / "deep"
    deep.mkdir()
    fd = os.open(deep, os.O_RDONLY)
    try:
        for _ in range(os.pathconf(deep, "PC_PATH_MAX") // 200 + 1):  # (each 200 + 1 long)
            os.mkdir("d" * 200, dir_fd=fd)
            fd, parent = os.open("d" * 200, os.O_RDONLY, dir_fd=fd), fd
            os.close(parent)
    finally:
        os.close(fd)
    code, stderr = report(results, tmp_path / "rep")
    assert code == 0, stderr
    (line,) = [line for line in stderr.splitlines() if "cannot read" in line]
    shown = re.fullmatch(r"vtrack: warning: (.{100})\.\.\.(.{30}) \((\d+) characters\): "
                         r"cannot read .*", line)
    assert shown is not None, line
    assert shown[1] == (str(deep) + f"/{'d' * 200}" * 2)[:100], line
    assert shown[2] == "d" * 30 and int(shown[3]) >= os.pathconf(deep, "PC_PATH_MAX"), line
    assert line.endswith(f": cannot read ({os.strerror(errno.ENAMETOOLONG)}); what is in it "
                         "is not reported"), line
    assert "cannot read" in (tmp_path / "rep" / "summary.md").read_text()
