"""``vtrack batch``'s ``summary.csv`` and ``vtrack report``'s: one writer, one column set."""

from __future__ import annotations

import csv
import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from click.testing import CliRunner, Result

from vtrack.batch import Job, execute
from vtrack.batch.summary import NEVER_STARTED, UNFINISHED, SummaryWriter
from vtrack.cli import main
from vtrack.config import load_config
from vtrack.io.identity import file_identity
from vtrack.io.outdir import (
    BATCH_COLUMNS,
    EARLIER_BATCH_COLUMNS,
    is_batch_folder,
    is_report_folder,
)
from vtrack.report.rows import run_row
from vtrack.report.runs import load_run
from vtrack.request import RunRequest

if TYPE_CHECKING:
    from conftest import ClipFactory

W, H, FRAMES = 160, 120, 60


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def read(path: Path) -> tuple[list[str], dict[tuple[str, str], dict[str, str]]]:
    with path.open(newline="") as handle:
        header = next(csv.reader(handle))
        handle.seek(0)
        return header, {(row["input"], row["config"]): row for row in csv.DictReader(handle)}


def test_a_batch_of_multi_target_runs_has_the_reports_columns_and_numbers(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A batch's summary.csv had other columns, in another order and with other decimals
    (fps 1, scores 4) than the report's of the same runs, and no MOTA or IDF1 column: a batch
    of `-c fixed_camera` over `vtrack scene pedestrians` clips with their .mot.txt wrote
    `ped,fixed_camera,60,571.1,,,,0,0,complete,`. Both now write one column set; a run's row
    is the same in both (its folder named inside the batch in the batch's)."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    for scenario, name in (("pedestrians", "ped"), ("occlusion", "occ")):
        clip = clip_factory(scenario, width=W, height=H, frames=FRAMES)
        shutil.copy(clip.path, inputs / f"{name}.mp4")
        shutil.copy(clip.gt, inputs / f"{name}.gt.txt")
        if clip.mot is not None:
            shutil.copy(clip.mot, inputs / f"{name}.mot.txt")
    out = tmp_path / "results"
    done = vtrack("batch", str(inputs), "-c", "fixed_camera", "-c", "s0", "--no-video",
                  "--out", str(out))
    assert done.exit_code == 0, done.output
    done = vtrack("report", str(out), "--out", str(tmp_path / "report"))
    assert done.exit_code == 0, done.output

    batch_header, batch_rows = read(out / "summary.csv")
    report_header, report_rows = read(tmp_path / "report" / "summary.csv")
    assert batch_header == report_header
    assert set(batch_rows) == set(report_rows) == {
        (name, config) for name in ("ped", "occ") for config in ("fixed_camera", "s0")}
    for key, row in batch_rows.items():
        assert row["run"] == f"{key[0]}/{key[1]}"
        assert Path(report_rows[key]["run"]) == (out / key[0] / key[1]).resolve()
        assert {c: v for c, v in row.items() if c != "run"} == {
            c: v for c, v in report_rows[key].items() if c != "run"}, key
    multi, single = batch_rows[("ped", "fixed_camera")], batch_rows[("occ", "s0")]
    assert float(multi["mota"]) <= 1 and 0 <= float(multi["idf1"]) <= 1
    assert multi["auc"] == multi["frames_lost"] == ""  # one target's columns do not apply
    assert 0 <= float(single["auc"]) <= 1 and single["mota"] == single["idf1"] == ""
    assert len(single["fps"].partition(".")[2]) > 1  # not rounded to 1 decimal any more


def test_a_resumed_multi_target_run_is_printed_with_its_scores(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A resumed multi-target run's line had no MOT scores: 'ped [fixed_camera]: 60 frames, ...
    -> .../ped/fixed_camera (already complete: not run again)' where the first batch printed
    '... mota 0.957, ...' (run.json's summary leaves the scores to its "metrics")."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    clip = clip_factory("pedestrians", width=W, height=H, frames=FRAMES)
    shutil.copy(clip.path, inputs / "ped.mp4")
    shutil.copy(clip.mot, inputs / "ped.mot.txt")
    args = ("batch", str(inputs), "-c", "fixed_camera", "--no-video", "--out",
            str(tmp_path / "results"))
    lines = []
    for _ in range(2):
        done = vtrack(*args)
        assert done.exit_code == 0, done.output
        lines.append(next(line for line in done.output.splitlines()
                          if line.startswith("ped [fixed_camera]")))
    first, again = lines
    assert " mota " in first and " idf1 " in first
    scores = first.partition(" fps, ")[2].partition(" -> ")[0]
    assert scores and scores in again and again.endswith("(already complete: not run again)")


def _batch_of_one(clip_factory: ClipFactory, tmp_path: Path
                  ) -> tuple[Path, Path, dict[tuple[str, str], dict[str, str]]]:
    """A batch of s0 over one occlusion clip: its inputs' folder, its results folder and the
    rows of its summary.csv."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    clip = clip_factory("occlusion", width=W, height=H, frames=FRAMES)
    shutil.copy(clip.path, inputs / "occ.mp4")
    shutil.copy(clip.gt, inputs / "occ.gt.txt")
    out = tmp_path / "results"
    done = vtrack("batch", str(inputs), "-c", "s0", "--no-video", "--out", str(out))
    assert done.exit_code == 0, done.output
    return inputs, out, read(out / "summary.csv")[1]


def test_a_batch_resuming_an_earlier_header_rebuilds_the_rows_it_keeps(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A batch into a folder whose summary.csv has the header of an earlier vtrack kept the
    rows it did not run again (other configs) as they were, in the old layout under the new
    header (no `run`, fps to 1 decimal, scores to 4, every new column empty). Each is now
    rebuilt from its run's folder: the row this vtrack writes for that run."""
    inputs, out, rows = _batch_of_one(clip_factory, tmp_path)
    assert is_batch_folder(out)
    now = rows[("occ", "s0")]
    with (out / "summary.csv").open("w", newline="") as handle:  # as an earlier vtrack wrote it
        writer = csv.writer(handle)
        writer.writerow(EARLIER_BATCH_COLUMNS)
        writer.writerow(["occ", "s0", now["frames"], f"{float(now['fps']):.1f}",
                         f"{float(now['mean_overlap']):.4f}", f"{float(now['auc']):.4f}",
                         f"{float(now['precision20']):.4f}", now["frames_lost"],
                         now["frames_skipped"], "complete", ""])
    assert is_batch_folder(out)
    done = vtrack("batch", str(inputs), "-c", "s1", "--no-video", "--out", str(out))
    assert done.exit_code == 0, done.output
    header, rows = read(out / "summary.csv")
    assert header == list(BATCH_COLUMNS)
    assert set(rows) == {("occ", "s0"), ("occ", "s1")}
    assert rows[("occ", "s0")] == now
    assert rows[("occ", "s1")]["run"] == "occ/s1"


def test_a_resumed_pair_keeps_its_row_while_its_run_json_is_unchanged(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Every resumed pair's row was read again from its run folder (load_run, ~35 us a frame,
    one pair after another in the batch's process: a thousand resumed 3000-frame runs were a
    minute of silence before the first new run). A resumed pair now keeps the row summary.csv
    has for it while its run.json is the very file that row was read from (its size and time,
    recorded beside summary.csv): a track.csv edited in place (same size, so the run still
    counts as complete) does not change it; a run.json touched since does, read again."""
    inputs, out, rows = _batch_of_one(clip_factory, tmp_path)
    first = rows[("occ", "s0")]
    track = out / "occ" / "s0" / "track.csv"
    lines = track.read_text().splitlines(keepends=True)
    for n in range(5, len(lines)):  # every box's x one hundred pixels off, same digits
        cells = lines[n].split(",")
        cells[2] = str((int(cells[2][0]) + 5) % 9 + 1) + cells[2][1:]
        lines[n] = ",".join(cells)
    size = track.stat().st_size
    track.write_text("".join(lines))
    assert track.stat().st_size == size
    done = vtrack("batch", str(inputs), "-c", "s0", "--no-video", "--out", str(out))
    assert done.exit_code == 0, done.output
    assert "not run again" in done.output
    _, rows = read(out / "summary.csv")
    assert rows[("occ", "s0")] == first
    record = out / "occ" / "s0" / "run.json"
    later = record.stat().st_mtime_ns + 2_000_000_000
    os.utime(record, ns=(later, later))
    done = vtrack("batch", str(inputs), "-c", "s0", "--no-video", "--out", str(out))
    assert done.exit_code == 0, done.output
    _, rows = read(out / "summary.csv")
    assert float(rows[("occ", "s0")]["auc"]) < float(first["auc"])
    assert rows[("occ", "s0")]["run"] == "occ/s0"


def test_the_worker_reads_its_runs_row(clip_factory: ClipFactory, tmp_path: Path) -> None:
    """The batch's process read every finished run's row (load_run) one after another; the
    worker that ran the job reads it now, in parallel, and its outcome carries it with the
    identity of the run.json it was read from."""
    clip = clip_factory("occlusion", width=W, height=H, frames=FRAMES)
    folder = tmp_path / "job"
    request = RunRequest(input=str(clip.path), out_dir=folder, config=load_config("s0"),
                         gt_path=clip.gt, video=False)
    outcome = execute(Job("occ", "s0", request))
    assert outcome.status == "complete", outcome.error
    assert outcome.row == run_row(load_run(folder))
    assert outcome.row_source == file_identity(folder / "run.json")


def test_a_batch_resumed_after_a_stopped_force_run_writes_its_scores(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A batch stopped while `--force` ran a pair again wrote that pair's row as interrupted but
    kept its run.json's identity beside it; the next resume (run.json unchanged) took that row
    for the pair's own and wrote `occ,s0,complete,,,,...`: complete with every score empty.
    The identity of a pair without a row is not written, and only a complete row is kept."""
    inputs, out, rows = _batch_of_one(clip_factory, tmp_path)
    first = rows[("occ", "s0")]
    stopped = SummaryWriter(out / "summary.csv", [("occ", "s0")])  # --force, stopped at once
    stopped.write(stopped=True)
    _, rows = read(out / "summary.csv")
    assert rows[("occ", "s0")]["status"] == "interrupted"
    done = vtrack("batch", str(inputs), "-c", "s0", "--no-video", "--out", str(out))
    assert done.exit_code == 0, done.output
    _, rows = read(out / "summary.csv")
    assert rows[("occ", "s0")]["status"] == "complete"
    assert rows[("occ", "s0")]["auc"] == first["auc"] != ""


def test_a_folder_holding_an_earlier_vtracks_report_or_a_fifo_page(tmp_path: Path) -> None:
    """A report written before its page carried the generator line (index.html beside
    summary.md) is a report's folder, not a batch's; an index.html that is no regular file
    (a FIFO) is not opened (is_report_folder blocked on it)."""
    old = tmp_path / "old"
    old.mkdir()
    (old / "index.html").write_text("<html><head><title>vtrack report</title></head></html>")
    (old / "summary.md").write_text("# vtrack report\n")
    (old / "summary.csv").write_text(",".join(BATCH_COLUMNS) + "\n")
    assert is_report_folder(old) and not is_batch_folder(old)
    fifo = tmp_path / "fifo"
    fifo.mkdir()
    os.mkfifo(fifo / "index.html")
    assert not is_report_folder(fifo)


def test_a_failed_row_of_an_input_that_did_not_open_names_its_ground_truth(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A truncated mp4 (no moov box) beside its c7.gt.txt: its `failed` row had an empty
    ground_truth column, though the plan had paired the two (a run's row names its file).
    The row now names it as a run's row does: its real path."""
    clip = clip_factory("smooth", width=W, height=H, frames=FRAMES)
    inputs = tmp_path / "in"
    inputs.mkdir()
    shutil.copy(clip.path, inputs / "a.mp4")
    shutil.copy(clip.gt, inputs / "a.gt.txt")
    (inputs / "c7.mp4").write_bytes(clip.path.read_bytes()[:2000])  # the index is at the end
    shutil.copy(clip.gt, inputs / "c7.gt.txt")
    out = tmp_path / "results"
    result = vtrack("batch", str(inputs), "-c", "s0", "--no-video", "-q", "-o", str(out))
    assert result.exit_code == 1, result.output
    _, rows = read(out / "summary.csv")
    failed, ran = rows["c7", "s0"], rows["a", "s0"]
    assert (failed["status"], failed["run"]) == ("failed", ""), failed
    assert failed["ground_truth"] == os.path.realpath(inputs / "c7.gt.txt")
    assert ran["ground_truth"] == os.path.realpath(inputs / "a.gt.txt")


def test_rows_of_pairs_without_an_outcome_name_their_ground_truth(tmp_path: Path) -> None:
    """The rows of pairs a batch has not finished (unfinished while it runs, never started
    once it stopped) had an empty ground_truth column, while a failed pair's row names its
    file. They name it too now, as a run's row does; a pair without one names none."""
    gt = tmp_path / "in" / "a.gt.txt"
    gt.parent.mkdir()
    gt.write_text("1,2,3,4\n")
    path = tmp_path / "out" / "summary.csv"
    writer = SummaryWriter(path, [("a", "s0"), ("b", "s0")], ground_truth={("a", "s0"): gt})
    for stopped, error in ((False, UNFINISHED), (True, NEVER_STARTED)):
        writer.write(stopped=stopped)
        _, rows = read(path)
        assert [(rows[name, "s0"]["ground_truth"], rows[name, "s0"]["error"])
                for name in "ab"] == [(os.path.realpath(gt), error), ("", error)], rows


@pytest.mark.parametrize(("on_disk", "cell"), [
    (b"c\xff", "c\\xff"),
    (b"c\\xff", "c\\\\xff")])  # (UTF-8 holding the text \xff: its backslash doubled in the cell)
def test_an_input_whose_name_is_not_utf8_is_tracked_and_named_readably(
        clip_factory: ClipFactory, tmp_path: Path, on_disk: bytes, cell: str) -> None:
    """A batch over `c\\xff.mp4` (a name that is not UTF-8) crashed writing summary.csv before
    any run (UnicodeEncodeError: surrogates not allowed, a traceback, exit 1). It is tracked;
    summary.csv and the report's summary.md are UTF-8 and name it `c\\xff`; run again, the
    batch takes its row back (one row, not run again). A UTF-8 name holding that text (a
    backslash, then xff) was read back as the other name: a second row, a report warning."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    name = os.fsdecode(on_disk)
    shutil.copy(clip.path, inputs / f"{name}.mp4")
    shutil.copy(clip.gt, inputs / f"{name}.gt.txt")
    out = tmp_path / "results"
    for _ in range(2):
        result = vtrack("batch", str(inputs), "-c", "s0", "--no-video", "-o", str(out))
        assert result.exit_code == 0, result.output
        rows = (out / "summary.csv").read_bytes().decode("utf-8").splitlines()[1:]
        assert [row.split(",")[:3] for row in rows] == [[cell, "s0", "complete"]]
    assert "not run again" in result.output
    report = vtrack("report", str(out), "--out", str(tmp_path / "report"))
    assert report.exit_code == 0, report.output
    assert "warning" not in report.output  # (its row is the run the report found)
    assert "| c\\xff | s0 | complete |" in (tmp_path / "report" / "summary.md").read_text(
        encoding="utf-8")
