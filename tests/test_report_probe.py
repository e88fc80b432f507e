"""`vtrack report` against what a hostile tester did to it (probe 48): plots that cannot be
written, hand-edited records and batch summaries, many runs of one input, a report written over
an earlier one, an input replaced after its run. Every input is made here: generated clips run
by `vtrack run`."""

from __future__ import annotations

import json
import re
import resource
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from vtrack.scenes import make_scene, write_groundtruth, write_video

W, H = 160, 120


def vtrack(*args: str, fsize: int | None = None, cwd: Path | None = None
           ) -> subprocess.CompletedProcess:
    """``python -m vtrack ARGS`` as a user runs it (a whole process: tracebacks, exit codes);
    ``fsize`` limits the size of every file it writes (``prlimit --fsize``)."""

    def limit() -> None:
        if fsize is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))

    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, timeout=300, check=False, preexec_fn=limit, cwd=cwd)


def error_line(done: subprocess.CompletedProcess) -> str:
    """The one ``vtrack: error:`` line of a failed command (and nothing else on stderr)."""
    assert done.returncode != 0, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip()
             and not line.startswith("vtrack: warning: ")]
    assert len(lines) == 1 and lines[0].startswith("vtrack: error: "), done.stderr
    return lines[0]


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A 60-frame occlusion clip and its ground truth."""
    folder = tmp_path_factory.mktemp("probe-clip")
    scene = make_scene("occlusion", seed=0, width=W, height=H, frames=60, fps=30)
    return (write_video(scene, folder / "occlusion.mp4"),
            write_groundtruth(scene, folder / "occlusion.gt.txt"))


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory, clip: tuple[Path, Path]) -> Path:
    """Two runs of the clip with its ground truth (s0 and camshift): results/<config>/."""
    video, gt = clip
    out = tmp_path_factory.mktemp("probe-results")
    for config in ("s0", "camshift"):
        done = vtrack("run", str(video), "-c", config, "--gt", str(gt), "--no-video", "-q",
                      "-o", str(out / config))
        assert done.returncode == 0, done.stderr
    return out


def test_a_plot_that_cannot_be_written_is_one_error_line_and_no_page(results: Path,
                                                                     tmp_path: Path) -> None:
    """A file size limit made savefig raise: a traceback, exit 1, and a report folder holding
    some plots. Now one line naming the plot and the reason, and nothing that looks like a
    report; an earlier report in that folder stays whole."""
    report = tmp_path / "report"
    line = error_line(vtrack("report", str(results), "-o", str(report), fsize=20_000))
    assert str(report / "plots") in line and ".png: cannot write (File too large)" in line
    assert not [p for p in report.rglob("*") if p.is_file()]  # no page, no plot, no temp file

    assert vtrack("report", str(results), "-o", str(report)).returncode == 0
    earlier = {p: p.read_bytes() for p in report.rglob("*") if p.is_file()}
    error_line(vtrack("report", str(results), "-o", str(report), "--title", "again",
                      fsize=20_000))
    assert {p: p.read_bytes() for p in report.rglob("*") if p.is_file()} == earlier


def test_a_folder_in_the_place_of_a_plot_or_of_plots_is_named(results: Path,
                                                             tmp_path: Path) -> None:
    (tmp_path / "a" / "plots" / "curves_all.png").mkdir(parents=True)
    line = error_line(vtrack("report", str(results), "-o", str(tmp_path / "a")))
    assert f"{tmp_path / 'a' / 'plots' / 'curves_all.png'}: cannot write" in line
    assert not (tmp_path / "a" / "index.html").exists()
    assert [p.name for p in (tmp_path / "a" / "plots").iterdir()] == ["curves_all.png"]

    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "plots").touch()  # the folder was named, as if it were the file
    line = error_line(vtrack("report", str(results), "-o", str(tmp_path / "b")))
    assert line.startswith(f"vtrack: error: {tmp_path / 'b' / 'plots'}: "), line


@pytest.fixture(scope="module")
def multi_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A multi-target run (s3) of the generated multi scene with its MOTChallenge ground
    truth: its run.json records MOTA, IDF1, false positives ..."""
    folder = tmp_path_factory.mktemp("probe-multi")
    done = vtrack("scene", "multi", str(folder / "multi.mp4"), "--frames", "60",
                  "--size", f"{W}x{H}")
    assert done.returncode == 0, done.stderr
    done = vtrack("run", str(folder / "multi.mp4"), "-c", "s3", "--gt",
                  str(folder / "multi.mot.txt"), "--no-video", "-q", "-o", str(folder / "s3"))
    assert done.returncode == 0, done.stderr
    return folder / "s3"


@pytest.mark.parametrize("edit", [{"mota": "0.9"}, {"false_positives": "many"}, {"idf1": [1]},
                                  {"mota": 10**400}, {"mota": True}, {"motp": {"a": 1}}])
def test_a_multi_target_record_with_metrics_of_the_wrong_kind_is_left_out(
        multi_run: Path, tmp_path: Path, edit: dict[str, object]) -> None:
    """A hand-edited multi-target run.json gave a traceback (TypeError in tables._finite,
    OverflowError for 10**400); now it is left out like a single-target record of the wrong
    kind, and the other runs are reported."""
    shutil.copytree(multi_run, tmp_path / "runs" / "good")
    shutil.copytree(multi_run, tmp_path / "runs" / "edited")
    record_path = tmp_path / "runs" / "edited" / "run.json"
    record = json.loads(record_path.read_text())
    record["metrics"].update(edit)
    record_path.write_text(json.dumps(record))
    done = vtrack("report", str(tmp_path / "runs"), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    assert (f"vtrack: warning: left out: {record_path}: not a vtrack run record"
            in done.stderr.splitlines())
    assert "Traceback" not in done.stderr
    html = (tmp_path / "report" / "index.html").read_text()
    assert html.count("<td class=\"label\">s3") == 1  # the good run only


@pytest.mark.parametrize(("text", "missing"), [('{"a": 1}', "'status' or 'frames'"),
                                               ('{"status": "complete"}', "'frames'")])
def test_a_record_without_a_runs_keys_is_left_out_as_no_run_record(
        results: Path, tmp_path: Path, text: str, missing: str) -> None:
    """A run.json replaced by `{"a":1}` was read as a run of 0 frames: the report blamed its
    track.csv ('holds 60 rows, run.json records 0 frames (cut or edited after the run)'). It
    is now left out as what it is, no run's record, naming the keys it lacks."""
    shutil.copytree(results, tmp_path / "runs")
    record_path = tmp_path / "runs" / "s0" / "run.json"
    record_path.write_text(text)
    done = vtrack("report", str(tmp_path / "runs"), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    assert [line for line in done.stderr.splitlines() if "left out" in line] == [
        f"vtrack: warning: left out: {record_path}: not a vtrack run record (it has no "
        f"{missing})"]


@pytest.mark.parametrize("frames", ["null", "true", "-1", "2.5", '"60"'])
def test_a_record_whose_frames_is_no_whole_number_is_left_out_as_no_run_record(
        results: Path, tmp_path: Path, frames: str) -> None:
    """`{"status": "complete", "frames": null}` (or `true`) passed as a run's record: null was
    read as 0 frames (the report blamed the track.csv for holding 60 rows), true as 1. A
    record's frames is a whole number of 0 or more, else it is left out as no run's record,
    saying so."""
    shutil.copytree(results, tmp_path / "runs")
    record_path = tmp_path / "runs" / "s0" / "run.json"
    record = json.loads(record_path.read_text())
    record_path.write_text(json.dumps(record).replace(f'"frames": {record["frames"]}',
                                                      f'"frames": {frames}', 1))
    assert json.loads(record_path.read_text())["frames"] == json.loads(frames)
    done = vtrack("report", str(tmp_path / "runs"), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    assert [line for line in done.stderr.splitlines() if "left out" in line] == [
        f"vtrack: warning: left out: {record_path}: not a vtrack run record (its 'frames' is "
        "not a whole number of 0 or more)"]


def test_a_dash_for_a_measure_of_a_run_with_ground_truth_is_explained(
        multi_run: Path, tmp_path: Path) -> None:
    """Probe 52b: a multi-target run whose track boxes matched no ground-truth box showed MOTP
    as a dash, and the page said 'a dash means the run had no ground truth', though it had
    (its MOTA, FN ... beside it). Now the page says why such a measure has none."""
    video = multi_run.parent / "multi.mp4"
    far = tmp_path / "far.txt"  # a 1x1 box in a corner: no track box overlaps it by half
    far.write_text("".join(f"{frame},1,0,0,1,1,1,1,1\n" for frame in range(1, 61)))
    done = vtrack("run", str(video), "-c", "s3", "--gt", str(far), "--no-video", "-q", "-o",
                  str(tmp_path / "runs" / "far"))
    assert done.returncode == 0, done.stderr
    metrics = json.loads((tmp_path / "runs" / "far" / "run.json").read_text())["metrics"]
    assert metrics["motp"] is None and metrics["misses"] == 60
    shutil.copytree(multi_run, tmp_path / "runs" / "given")  # one with a MOTP: the column
    done = vtrack("report", str(tmp_path / "runs"), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    markdown = (tmp_path / "report" / "summary.md").read_text()
    header, *rows = [line.split(" | ") for line in markdown.splitlines()
                     if line.startswith(("| Input |", "| multi |"))]
    motp = {row[1]: row[header.index("MOTP")] for row in rows}
    assert motp["s3 (far)"] == "—" and motp["s3 (given)"] != "—", motp
    assert "MOTP: no track box matched" in markdown.split("---")[-1]


def test_many_runs_of_one_input_draw_a_bounded_figure_and_say_what_is_left_out(
        results: Path, tmp_path: Path) -> None:
    """100 runs of one input drew 100 overlap panels (a 1000 x 17090 px image, 34 s) and as
    many failure-frame columns; the success plot's legend ran off the figure. Now at most
    MAX_RUNS_DRAWN panels and columns, the page names the runs not drawn, and the legend names
    the best MAX_LEGEND configurations and counts the others."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from vtrack.report import plots

    copies, drawn = 14, 6  # plots.MAX_RUNS_DRAWN
    for n in range(copies):
        shutil.copytree(results / "s0", tmp_path / "runs" / f"r{n:02d}" / "s0")
    done = vtrack("report", str(tmp_path / "runs"), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    overlap = (tmp_path / "report" / "plots" / "overlap_occlusion.png").read_bytes()
    width, height = (int.from_bytes(overlap[16 + 4 * i:20 + 4 * i], "big") for i in (0, 1))
    assert width == 1000 and height <= (0.9 + 1.7 * drawn) * 100 + 1  # 6 panels at 100 dpi
    html = (tmp_path / "report" / "index.html").read_text()
    left_out = copies - drawn
    (note,) = re.findall(r'<p class="note">([^<]*)</p>', html)
    assert note.startswith(f"Of the {copies} scored runs of this input, {drawn} are drawn")
    # one AUC for all (copies of one run): the best and the worst by configuration name
    assert "; and s0 (r11) " in note and "Not drawn: s0 (r03) " in note
    assert f" and {left_out - 5} more" in note
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert f"Of the {copies} scored runs" in markdown
    assert html.count('<td class="label">s0 (r') == 2 * copies  # every run in both tables
    assert drawn == plots.MAX_RUNS_DRAWN

    curves = {f"c{n:03d}": plots.OVERLAP_THRESHOLDS * 0 + n / 100 for n in range(40)}
    precision = {c: plots.ERROR_THRESHOLDS * 0 + v[0] for c, v in curves.items()}
    figure = plots.curves_figure("many", curves, precision, plots.colours(list(curves)))
    renderer = FigureCanvasAgg(figure).get_renderer()
    figure.draw(renderer)
    whole = figure.bbox
    for axis in figure.axes:
        legend = axis.get_legend()
        texts = [t.get_text() for t in legend.get_texts()]
        assert texts[0].startswith("c039 [0.390]") and len(texts) == plots.MAX_LEGEND + 1
        assert texts[-1].startswith(f"{40 - plots.MAX_LEGEND} more")
        box = legend.get_window_extent(renderer)
        assert whole.x0 <= box.x0 <= box.x1 <= whole.x1
        assert whole.y0 <= box.y0 <= box.y1 <= whole.y1


def batch_with_summary(results: Path, folder: Path, text: str) -> Path:
    """A batch folder: the s0 run as <input>/<config>/ and ``text`` as its summary.csv."""
    shutil.copytree(results / "s0", folder / "occlusion" / "s0")
    (folder / "summary.csv").write_text(text)
    return folder


HEADER = ("input,config,frames,fps,mean_overlap,auc,precision20,frames_lost,frames_skipped,"
          "status,error\n")
COMPLETE = "occlusion,s0,60,500.0,0.8,0.8,1.0,0,0,complete,\n"
FAILED = "broken.mp4,s0,,,,,,,,failed,broken.mp4: a broken link\n"


def test_a_batch_summary_with_empty_and_repeated_rows_lists_each_failure_once(
        results: Path, tmp_path: Path) -> None:
    """An all-empty row was listed as a run with empty input, config and status, and a row
    repeated was listed twice."""
    batch = batch_with_summary(results, tmp_path / "batch",
                               HEADER + ",,,,,,,,,,\n" + FAILED + COMPLETE + FAILED + "\n")
    done = vtrack("report", str(batch), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    assert "summary.csv" not in done.stderr  # nothing wrong with it
    html = (tmp_path / "report" / "index.html").read_text()
    assert re.findall(r"<li>(.*?)</li>", html) == [
        "<b>broken.mp4</b> [s0] failed: broken.mp4: a broken link"]
    rows = (tmp_path / "report" / "summary.csv").read_text().splitlines()
    assert [row.split(",")[:3] for row in rows[1:]] == [["occlusion", "s0", "complete"],
                                                       ["broken.mp4", "s0", "failed"]]


@pytest.mark.parametrize(("text", "problem"), [
    (HEADER.replace("input,", "name,") + FAILED, "not a vtrack batch summary"),
    (HEADER + FAILED.replace(",failed,", ",failed,X,") + COMPLETE, "line 2 not read"),
    (HEADER + COMPLETE + FAILED.replace("failed", "exploded"), "line 3 not read"),
    (HEADER + FAILED.replace(",broken.mp4:", ',"broken.mp4:') + FAILED.replace("s0", "s1"),
     "lines 2-3 not read"),
], ids=["header", "extra-column", "unknown-status", "broken-quote"])
def test_batch_rows_that_cannot_be_read_are_a_warning_naming_the_summary(
        results: Path, tmp_path: Path, text: str, problem: str) -> None:
    """A summary.csv of another layout (a changed header, an extra column, a broken quote)
    lost its failed rows from the report without a word."""
    batch = batch_with_summary(results, tmp_path / "batch", text)
    done = vtrack("report", str(batch), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    warning = f"vtrack: warning: {batch / 'summary.csv'}: {problem}"
    assert [line for line in done.stderr.splitlines() if line.startswith(warning)], done.stderr
    assert "<li>" not in (tmp_path / "report" / "index.html").read_text()


def test_a_multi_target_run_without_its_tracks_csv_is_named_by_that_file(
        multi_run: Path, tmp_path: Path) -> None:
    """The warning named .../track.csv, a file a multi-target run never writes."""
    shutil.copytree(multi_run, tmp_path / "runs" / "good")
    shutil.copytree(multi_run, tmp_path / "runs" / "cut")
    (tmp_path / "runs" / "cut" / "tracks.csv").unlink()
    done = vtrack("report", str(tmp_path / "runs"), "-o", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    assert (f"vtrack: warning: left out: {tmp_path / 'runs' / 'cut' / 'tracks.csv'}: is missing"
            in done.stderr), done.stderr
    assert "track.csv" not in done.stderr


def test_a_report_over_an_earlier_one_removes_that_reports_plots_only(
        results: Path, tmp_path: Path) -> None:
    """A report written into an earlier report's folder kept the earlier plots (240 stale of
    244). Now the plots named as a report names them and not written this time go; the
    user's other files stay."""
    report = tmp_path / "report"
    assert vtrack("report", str(results), "-o", str(report)).returncode == 0
    plots_dir = report / "plots"
    ours = sorted(p.name for p in plots_dir.iterdir())
    png = (plots_dir / "curves_all.png").read_bytes()
    for name in ("overlap_gone.png", "curves_gone.png", "failures_gone.png", "state_gone.png"):
        (plots_dir / name).write_bytes(png)  # as an earlier report of input "gone" left them
    (plots_dir / "mine.png").write_bytes(png)
    (plots_dir / "overlap_notes.txt").write_text("the user's")
    (plots_dir / "state_folder.png").mkdir()
    assert vtrack("report", str(results), "-o", str(report)).returncode == 0
    assert sorted(p.name for p in plots_dir.iterdir()) == sorted(
        [*ours, "mine.png", "overlap_notes.txt", "state_folder.png"])


def test_failure_frames_are_not_drawn_from_an_input_replaced_after_the_run(
        clip: tuple[Path, Path], tmp_path: Path) -> None:
    """The thumbnails were drawn from whatever video now had the input's name; run.json
    records the input's size and modification time, so the replaced one is told apart and the
    thumbnails are left out with a warning, as they are when the input is missing."""
    video, gt = clip
    shutil.copy(video, tmp_path / "clip.mp4")
    done = vtrack("run", str(tmp_path / "clip.mp4"), "-c", "s0", "--gt", str(gt),
                  "--no-video", "-q", "-o", str(tmp_path / "run"))
    assert done.returncode == 0, done.stderr
    assert vtrack("report", str(tmp_path / "run"), "-o", str(tmp_path / "before")).returncode == 0
    assert (tmp_path / "before" / "plots" / "failures_clip.png").is_file()

    other = make_scene("smooth", seed=3, width=W, height=H, frames=60, fps=30)
    write_video(other, tmp_path / "clip.mp4")  # another video under the run's input name
    done = vtrack("report", str(tmp_path / "run"), "-o", str(tmp_path / "after"))
    assert done.returncode == 0, done.stderr
    assert (f"vtrack: warning: failure frames of clip left out: the input "
            f"{tmp_path / 'clip.mp4'} changed since the run" in done.stderr), done.stderr
    assert not (tmp_path / "after" / "plots" / "failures_clip.png").exists()
    assert (tmp_path / "after" / "plots" / "overlap_clip.png").is_file()  # the rest is there


@pytest.mark.parametrize("configs", [["s0"], ["s0", "camshift"]])
def test_the_failure_frames_title_fits_its_figure(results: Path, configs: list[str]) -> None:
    """The title was one line wider than the figure: at 672 px it read '... said occluded or
    lo', with one config only its middle showed. Now it is wrapped to the figure's width."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from vtrack.report import failures, plots
    from vtrack.report.runs import load_run

    runs = [load_run(results / config) for config in configs]
    assert all(failures.failure_frames(run) for run in runs), "the clip should make them miss"
    figure = failures.failure_figure("occlusion", runs, plots.colours(configs))
    renderer = FigureCanvasAgg(figure).get_renderer()
    figure.draw(renderer)
    title = figure.get_suptitle()
    assert title.replace("\n", " ").endswith("dashed: the tracker said occluded or lost)")
    box, whole = figure._suptitle.get_window_extent(renderer), figure.bbox
    assert whole.x0 <= box.x0 <= box.x1 <= whole.x1 and box.y1 <= whole.y1, (box, whole)
