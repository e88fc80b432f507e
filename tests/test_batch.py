"""`vtrack batch` end to end on small generated clips: discovery, failures, resume, worker death,
Dask, and the one-line errors."""

from __future__ import annotations

import csv
import itertools
import json
import multiprocessing
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import av
import cv2
import numpy as np
import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line

from vtrack.batch import (
    SUMMARY_COLUMNS,
    LocalExecutor,
    Outcome,
    SummaryWriter,
    find_inputs,
    nested_inputs,
    plan,
)
from vtrack.batch.discover import NESTED_LOOKS
from vtrack.batch.summary import NEVER_STARTED, WRITE_SPACING
from vtrack.cli import main
from vtrack.config import DEFAULT_CONFIG, load_config
from vtrack.errors import ConfigError
from vtrack.io.videowriter import VideoTooSmallError
from vtrack.request import RunRequest
from vtrack.run import run
from vtrack.scenes import make_scene, write_groundtruth

if TYPE_CHECKING:
    from conftest import ClipFactory

W, H, FRAMES = 160, 120, 48
CONFIGS = ("s0", "camshift")


def batch(*args: str) -> Result:
    return CliRunner().invoke(main, ["batch", *args], catch_exceptions=False)


def summary(out: Path) -> dict[tuple[str, str], dict[str, str]]:
    with (out / "summary.csv").open(newline="") as handle:
        reader = csv.DictReader(handle)
        assert tuple(reader.fieldnames or ()) == SUMMARY_COLUMNS
        rows = list(reader)
    keyed = {(row["input"], row["config"]): row for row in rows}
    assert len(keyed) == len(rows), "one row per input x config"
    return keyed


def write_faststart_mp4(path: Path, frames: int) -> None:
    """An H.264 mp4 with its index first (movflags=faststart): cut short, it still opens."""
    scene = make_scene("smooth", 1, W, H, frames, 30)
    with av.open(str(path), "w", options={"movflags": "faststart"}) as container:
        stream = container.add_stream("libx264", rate=30, options={"preset": "ultrafast"})
        stream.width, stream.height, stream.pix_fmt = W, H, "yuv420p"
        for index, bgr in enumerate(scene.frames()):
            frame = av.VideoFrame.from_ndarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2YUV_I420),
                                               format="yuv420p")
            frame.pts = index
            container.mux(stream.encode(frame))
        container.mux(stream.encode(None))
    write_groundtruth(scene, path.with_suffix(".gt.txt"))


def add_clip(folder: Path, clip_factory: ClipFactory, scenario: str, name: str,
             fmt: str = "mp4") -> None:
    clip = clip_factory(scenario, width=W, height=H, frames=FRAMES, fmt=fmt)
    if fmt == "images":
        shutil.copytree(clip.path, folder / name)
    else:
        shutil.copy(clip.path, folder / f"{name}.mp4")
        shutil.copy(clip.gt, folder / f"{name}.gt.txt")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory, clip_factory: ClipFactory) -> Path:
    """Good clips (video + gt, OTB folder, video with only an init box), a truncated mp4 and a
    text file named .mp4."""
    folder = tmp_path_factory.mktemp("inputs")
    add_clip(folder, clip_factory, "smooth", "smooth")
    add_clip(folder, clip_factory, "jump", "jump")
    add_clip(folder, clip_factory, "smooth", "seq", fmt="images")
    add_clip(folder, clip_factory, "distractor", "nogt")
    gt = folder / "nogt.gt.txt"
    (folder / "nogt.init.txt").write_text(gt.read_text().splitlines()[0] + "\n")
    gt.unlink()
    write_faststart_mp4(folder / "truncated.mp4", FRAMES)
    data = (folder / "truncated.mp4").read_bytes()
    (folder / "truncated.mp4").write_bytes(data[: len(data) * 6 // 10])
    (folder / "notvideo.mp4").write_text("this is not a video\n")
    shutil.copy(folder / "smooth.gt.txt", folder / "notvideo.gt.txt")
    (folder / "README.txt").write_text("not an input\n")
    return folder


def test_find_inputs_pairs_ground_truth_and_origin(inputs: Path) -> None:
    found = {item.name: item for item in find_inputs(inputs)}
    assert sorted(found) == ["jump", "nogt", "notvideo", "seq", "smooth", "truncated"]
    assert found["smooth"].groundtruth == inputs / "smooth.gt.txt"
    assert found["smooth"].gt_origin == 0
    assert found["seq"].groundtruth == inputs / "seq" / "groundtruth_rect.txt"
    assert found["seq"].gt_origin == 1  # OTB: 1-based boxes inside sequence folders
    assert found["nogt"].groundtruth is None
    assert found["nogt"].init == inputs / "nogt.init.txt"
    assert {i.gt_origin for i in find_inputs(inputs, gt_origin=0)} == {0}


def test_batch_records_failures_resumes_and_forces(inputs: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = [str(inputs), "-c", CONFIGS[0], "-c", CONFIGS[1], "--jobs", "2", "--no-video",
            "--out", str(out)]
    first = batch(*args)
    assert first.exit_code == 1, first.output
    rows = summary(out)
    names = ("jump", "nogt", "notvideo", "seq", "smooth", "truncated")
    assert set(rows) == {(n, c) for n in names for c in CONFIGS}
    good = [(n, c) for n in ("jump", "nogt", "seq", "smooth") for c in CONFIGS]
    for key in good:
        assert rows[key]["status"] == "complete", rows[key]
        assert (out / key[0] / key[1] / "track.csv").is_file()
        assert not (out / key[0] / key[1] / "annotated.mp4").exists()
    assert rows[("smooth", "s0")]["auc"] != ""
    assert rows[("nogt", "s0")]["auc"] == "" and rows[("nogt", "s0")]["frames"] == str(FRAMES)
    for config in CONFIGS:
        assert rows[("notvideo", config)]["status"] == "failed"
        assert "notvideo.mp4" in rows[("notvideo", config)]["error"]
        assert rows[("truncated", config)]["status"] == "partial"
        assert "truncated.mp4" in rows[("truncated", config)]["error"]
    assert "notvideo" in first.stderr and "Traceback" not in first.stderr

    stamps = {key: (out / key[0] / key[1] / "run.json").stat().st_mtime_ns for key in good}
    first_rows = rows
    second = batch(*args)
    assert second.exit_code == 1
    rows = summary(out)
    for key in good:
        assert rows[key]["status"] == "complete"
        assert rows[key]["auc"] == first_rows[key]["auc"]
        assert (out / key[0] / key[1] / "run.json").stat().st_mtime_ns == stamps[key]
    assert rows[("truncated", "s0")]["status"] == "partial"  # not complete: run again

    third = batch(*args, "--force")
    rows = summary(out)
    for key in good:
        assert rows[key]["status"] == "complete"
        assert (out / key[0] / key[1] / "run.json").stat().st_mtime_ns != stamps[key]
    assert third.exit_code == 1


CRASHING_LAUNCHER = """
import os
import sys

import vtrack.batch.worker

_execute = vtrack.batch.worker.execute


def execute(job, *args):
    if job.input == "smooth" and job.attempt == 1:
        os._exit(3)  # the worker process dies mid-batch
    return _execute(job, *args)


vtrack.batch.worker.execute = execute  # what the worker loop (_serve) calls

if __name__ == "__main__":
    from vtrack.cli import main

    sys.exit(main())
"""


def test_a_killed_worker_is_retried_without_duplicates(inputs: Path, tmp_path: Path) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("smooth", "jump"):
        shutil.copy(inputs / f"{name}.mp4", folder)
        shutil.copy(inputs / f"{name}.gt.txt", folder)
    out = tmp_path / "out"
    # The batch runs from a launcher whose worker processes die (a real os._exit) on their
    # first attempt at "smooth": worker processes import the launcher as their main module.
    launcher = tmp_path / "launcher.py"
    launcher.write_text(CRASHING_LAUNCHER)
    result = subprocess.run(
        [sys.executable, str(launcher), "batch", str(folder), "--jobs", "2", "--no-video",
         "--out", str(out)], capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    rows = summary(out)
    assert set(rows) == {("smooth", DEFAULT_CONFIG), ("jump", DEFAULT_CONFIG)}
    assert all(row["status"] == "complete" for row in rows.values())
    assert "attempt 2" in result.stdout  # the crash hook did kill the first attempt


def test_dask_gives_the_same_tracks_as_the_local_pool(inputs: Path, tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("smooth", "jump"):
        shutil.copy(inputs / f"{name}.mp4", folder)
        shutil.copy(inputs / f"{name}.gt.txt", folder)
    shutil.copytree(inputs / "seq", folder / "seq")
    local = batch(str(folder), "--jobs", "2", "--no-video", "--out", str(tmp_path / "local"))
    assert local.exit_code == 0, local.output
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        remote = batch(str(folder), "--scheduler", cluster.scheduler_address, "--no-video",
                       "--out", str(tmp_path / "dask"))
    assert remote.exit_code == 0, remote.output
    assert summary(tmp_path / "dask").keys() == summary(tmp_path / "local").keys()
    for name in ("smooth", "jump", "seq"):
        tracks = [(tmp_path / side / name / DEFAULT_CONFIG / "track.csv").read_text()
                  for side in ("local", "dask")]
        assert tracks[0] == tracks[1]


def test_a_folder_without_inputs_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("nothing to track\n")
    line = one_error_line(batch(str(tmp_path)))
    assert str(tmp_path) in line and "no inputs" in line


def test_an_unreachable_scheduler_is_one_line(inputs: Path, tmp_path: Path) -> None:
    line = one_error_line(batch(str(inputs), "--scheduler", "tcp://127.0.0.1:9",
                                "--scheduler-timeout", "1", "--out", str(tmp_path)))
    assert "tcp://127.0.0.1:9" in line and "cannot reach" in line


@pytest.mark.parametrize(("address", "problem"), [
    ("", "no address"),  # ran the batch locally
    ("tcp://127.0.0.1", "no port"),
    ("tcp://127.0.0.1:99999", "not a number from 1 to 65535"),
    ("ucx://", "does not connect with ucx://"),
    ("tls://", "does not connect with tls://"),
    ("inproc://", "does not connect with inproc://"),
])
def test_a_scheduler_address_that_cannot_be_one_says_what_is_wrong(
        inputs: Path, tmp_path: Path, address: str, problem: str) -> None:
    """These said "not a Dask scheduler" (an empty one ran the batch locally, exit 0)."""
    out = tmp_path / "out"
    line = one_error_line(batch(str(inputs), "--scheduler", address, "--no-video",
                                "--out", str(out)))
    assert problem in line and "not a Dask scheduler" not in line
    assert not (out / "summary.csv").exists()


@pytest.mark.parametrize("option", ["--scheduler-timeout", "--worker-timeout"])
def test_dask_options_without_a_scheduler_are_refused(inputs: Path, tmp_path: Path,
                                                      option: str) -> None:
    """They were accepted and ignored: the batch ran locally."""
    out = tmp_path / "out"
    line = one_error_line(batch(str(inputs), option, "5", "--no-video", "--out", str(out)))
    assert option in line and "--scheduler" in line.replace(option, "")
    assert not (out / "summary.csv").exists()


def test_a_set_for_a_stage_one_config_lacks_names_that_config(inputs: Path,
                                                               tmp_path: Path) -> None:
    """The message showed s0's chain but not which --config it was."""
    line = one_error_line(batch(str(inputs), "-c", "s0", "-c", "s1", "--set",
                                "particle.particles=16", "--out", str(tmp_path / "out")))
    assert "--config s0:" in line and "'particle' is not in the chain" in line
    assert "every --config" in line


def test_scheduler_without_dask_says_how_to_install(inputs: Path, tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    line = one_error_line(batch(str(inputs), "--scheduler", "tcp://127.0.0.1:8786",
                                "--out", str(tmp_path)))
    assert "pip install 'vtrack[dask]'" in line


LAUNCHER = """
import sys

from vtrack.cli import main

if __name__ == "__main__":
    sys.exit(main())
"""


@pytest.mark.parametrize("shadow", ["namespace", "package"])
def test_batch_from_a_folder_holding_a_vtrack_folder(inputs: Path, tmp_path: Path,
                                                     shadow: str) -> None:
    """Run as the installed ``vtrack`` script is (its folder first on sys.path, not the current
    folder) from a folder holding a ``vtrack/`` folder: workers import the installed package."""
    here = tmp_path / "clone-parent"
    (here / "vtrack").mkdir(parents=True)
    if shadow == "package":  # imports cleanly, but is not vtrack (no __version__, no cli)
        (here / "vtrack" / "__init__.py").write_text("SHADOW = True\n")
    (here / "in").mkdir()
    for name in ("smooth", "jump"):
        shutil.copy(inputs / f"{name}.mp4", here / "in")
        shutil.copy(inputs / f"{name}.gt.txt", here / "in")
    launcher = tmp_path / "bin" / "vtrack-launcher.py"
    launcher.parent.mkdir()
    launcher.write_text(LAUNCHER)
    result = subprocess.run(
        [sys.executable, str(launcher), "batch", "in", "--jobs", "2", "--no-video",
         "--out", "out"], cwd=here, capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    assert "ImportError" not in result.stderr and "Traceback" not in result.stderr
    rows = summary(here / "out")
    assert set(rows) == {("smooth", DEFAULT_CONFIG), ("jump", DEFAULT_CONFIG)}
    assert all(row["status"] == "complete" for row in rows.values())


def clips_folder(tmp_path: Path, clip_factory: ClipFactory, *names: str) -> Path:
    """A folder ``tmp_path/in`` holding a smooth clip and its ground truth under each name."""
    folder = tmp_path / "in"
    folder.mkdir()
    for name in names:
        add_clip(folder, clip_factory, "smooth", name)
    return folder


def test_inputs_whose_results_folders_would_be_one_are_refused(tmp_path: Path,
                                                               clip_factory: ClipFactory) -> None:
    """`x y.mp4` and `x_y.mp4` were both written to `x_y/` (the second overwrote the first)."""
    folder = clips_folder(tmp_path, clip_factory, "x y", "x_y")
    result = batch(str(folder), "-c", "s0", "--no-video", "--out", str(tmp_path / "out"))
    assert result.exit_code != 0
    assert result.output.count("\n") == 1 and "Traceback" not in result.output
    assert "'x y.mp4' and 'x_y.mp4' would share the results folder 'x_y.mp4'" in result.output
    assert not (tmp_path / "out" / "summary.csv").exists()


def test_inputs_whose_names_differ_only_in_case_get_folders_of_their_own(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """`a.mp4` and `A.mp4` in one folder ran into out/a/ and out/A/: one folder on a
    case-insensitive disk (macOS, Windows), where the second run replaced the first's files.
    Stems that differ only in case now clash as any two of one folder do (`a.mp4` and `A.avi`
    keep their full names); full names that differ only in case are refused, as configs are."""
    folder = clips_folder(tmp_path, clip_factory, "a", "A")
    out = tmp_path / "out"
    line = one_error_line(batch(str(folder), "-c", "s0", "--no-video", "--out", str(out)))
    assert line == (f"vtrack: error: {folder}: the results folders of 'A.mp4' and of 'a.mp4' "
                    "differ only in case, one folder on a case-insensitive disk (macOS, "
                    "Windows): rename one")
    assert not out.exists()
    (folder / "A.mp4").rename(folder / "A.avi")
    assert [item.name for item in find_inputs(folder)] == ["A.avi", "a.mp4"]


def test_an_input_named_like_the_batch_summary_gets_its_own_folder(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """``summary.csv.mp4``'s results folder was ``summary.csv``, the batch's own file: the
    input could never run."""
    folder = clips_folder(tmp_path, clip_factory, "summary.csv")
    (folder / "summary.csv").mkdir()  # a sequence folder of that name cannot be renamed
    shutil.copytree(clip_factory("smooth", width=W, height=H, frames=FRAMES,
                                 fmt="images").path / "img", folder / "summary.csv" / "img")
    refused = batch(str(folder), "-c", "s0", "--no-video", "--out", str(tmp_path / "no"))
    assert refused.exit_code != 0 and "'summary.csv' would have the results folder" in \
        refused.output
    shutil.rmtree(folder / "summary.csv")
    out = tmp_path / "out"
    result = batch(str(folder), "-c", "s0", "--no-video", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert summary(out)[("summary.csv.mp4", "s0")]["status"] == "complete"
    assert (out / "summary.csv.mp4" / "s0" / "track.csv").is_file()


def test_names_with_control_characters_keep_one_line_in_messages_and_the_report(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """An input named with a newline split its summary line, its Markdown table row and its
    heading in two; one with a tab made matplotlib warn of a missing glyph."""
    folder = clips_folder(tmp_path, clip_factory, "new\nline", "tab\tx")
    out, report = tmp_path / "out", tmp_path / "report"
    done = subprocess.run([sys.executable, "-W", "error::UserWarning", "-m", "vtrack", "batch",
                           str(folder), "-c", "s0", "--no-video", "-o", str(out)],
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines() + done.stdout.splitlines()
    assert any(line.startswith("new\\nline [s0]: ") for line in lines), lines
    assert any(line.startswith("tab\\tx [s0]: ") for line in lines), lines
    shown = subprocess.run([sys.executable, "-W", "error::UserWarning", "-m", "vtrack",
                            "report", str(out), "-q", "-o", str(report)],
                           capture_output=True, text=True, timeout=300, check=False)
    assert shown.returncode == 0 and shown.stderr == "", shown.stderr
    markdown = (report / "summary.md").read_text().splitlines()
    assert "## new\\nline" in markdown and "## tab\\tx" in markdown
    assert sum(line.startswith(("| new\\nline | s0 |", "| tab\\tx | s0 |"))
               for line in markdown) == 2


def test_warnings_and_errors_naming_a_newline_are_one_line_in_every_command(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """`vtrack batch` wrote a failed run's error and a run's warning (a ground truth shorter
    than the clip) as 'vtrack: error: new' then 'line [s0]: failed: ...' on the next line,
    when the input's name held a newline; `vtrack run` and `vtrack report` their warnings
    alike. Every such line now writes the newline as '\\n' (vtrack.cli._messages)."""
    folder = clips_folder(tmp_path, clip_factory, "new\nline", "no\ntruth")
    (folder / "no\ntruth.gt.txt").unlink()  # s0 has no first box: the run fails
    short = folder / "new\nline.gt.txt"  # fewer boxes than frames: a warning
    short.write_text("".join(short.read_text().splitlines(keepends=True)[:5]))
    runner = CliRunner()
    out = tmp_path / "out"
    done = runner.invoke(main, ["batch", str(folder), "-c", "s0", "--no-video", "-o", str(out),
                                "-j", "1"])
    assert done.exit_code == 1, done.output
    rest = [line for line in done.stderr.splitlines() if not line.startswith("vtrack: ")]
    assert rest == [], done.stderr
    assert "vtrack: error: no\\ntruth [s0]: failed: " in done.stderr
    assert "vtrack: warning: new\\nline [s0]: " in done.stderr
    assert all(line.startswith(("new\\nline [s0]: ", "no\\ntruth [s0]: ", "2 runs "))
               for line in done.stdout.splitlines()), done.stdout
    ran = runner.invoke(main, ["run", str(folder / "new\nline.mp4"), "-c", "s0", "--no-video",
                               "--gt", str(short), "-o", str(tmp_path / "run"), "-q"])
    assert ran.exit_code == 0, ran.output
    assert ran.stderr.count("\n") == 1 and "new\\nline.gt.txt: ground truth has 5 boxes" in \
        ran.stderr, ran.stderr
    other = tmp_path / "other.gt.txt"  # for an input the report has no run of: a warning
    other.write_text(short.read_text())
    shown = runner.invoke(main, ["report", str(tmp_path / "run"), "-q", "-o",
                                 str(tmp_path / "report"), "--gt", f"x\ny={other}"])
    assert shown.exit_code == 0, shown.output
    assert "vtrack: warning: --gt x\\ny=" in shown.stderr
    assert all(line.startswith("vtrack: warning: ") for line in shown.stderr.splitlines()), \
        shown.stderr


def test_a_broken_link_and_a_fifo_are_failed_rows(tmp_path: Path,
                                                  clip_factory: ClipFactory) -> None:
    folder = clips_folder(tmp_path, clip_factory, "good")
    (folder / "gone.mp4").symlink_to(tmp_path / "nowhere.mp4")
    shutil.copy(folder / "good.gt.txt", folder / "gone.gt.txt")
    os.mkfifo(folder / "pipe.mp4")
    shutil.copy(folder / "good.gt.txt", folder / "pipe.gt.txt")
    (folder / "loop.mp4").symlink_to("loop.mp4")  # said "to loop.mp4, which does not exist"
    out = tmp_path / "out"
    result = batch(str(folder), "-c", "s0", "--no-video", "--out", str(out))
    assert result.exit_code == 1, result.output
    rows = summary(out)
    assert rows[("good", "s0")]["status"] == "complete"
    assert rows[("gone.mp4", "s0")]["status"] == "failed"
    assert "a broken link" in rows[("gone.mp4", "s0")]["error"]
    assert rows[("loop.mp4", "s0")]["status"] == "failed"
    assert "a link in a loop (to loop.mp4" in rows[("loop.mp4", "s0")]["error"]
    assert rows[("pipe.mp4", "s0")]["status"] == "failed"
    assert "not a regular file" in rows[("pipe.mp4", "s0")]["error"]


def test_the_library_plan_refuses_configs_of_one_results_folder(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """`plan(inputs, {"s0": s0, "S0": s0}, out, settings)` planned both, into out/a/s0/ and
    out/a/S0/ (one folder on a case-insensitive disk), and `{"x y": ..., "x_y": ...}` two jobs
    into the one folder out/a/x_y/: only `vtrack batch` checked its configs. plan() refuses
    them itself now, worded as `vtrack batch` is, before anything is planned."""
    folder = clips_folder(tmp_path, clip_factory, "a")
    config = load_config("s0")
    out = tmp_path / "out"
    request = RunRequest(input=str(folder), out_dir=out, config=config, video=False)
    with pytest.raises(ConfigError) as case:
        plan(find_inputs(folder), {"s0": config, "S0": config}, out, request)
    assert str(case.value) == ("the results folders of 'S0' and of 's0' (s0) differ only in "
                               "case, one folder on a case-insensitive disk (macOS, Windows): "
                               "rename one")
    with pytest.raises(ConfigError) as same:
        plan(find_inputs(folder), {"x y": config, "x_y": config}, out, request)
    assert str(same.value) == ("another config has the results folder of 'x_y' (s0); results "
                               "are kept per name, rename one")
    assert not out.exists()
    assert len(plan(find_inputs(folder), {"s0": config, "t0": config}, out, request).jobs) == 2


def test_a_picture_too_small_for_the_video_names_no_video_in_its_row(tmp_path: Path) -> None:
    """A batch's run of a sequence of 1x1 pictures failed with 'cannot encode a 1x1 video (H.264
    in yuv420p needs at least 2x2 pixels)' and no way out, where `vtrack run` names --no-video:
    its row and its error line name --no-video now (the library's run() names video=False),
    and --no-video tracks it."""
    images = tmp_path / "in" / "seq" / "img"
    images.mkdir(parents=True)
    for n in range(1, 6):
        cv2.imwrite(str(images / f"{n:04d}.png"), np.zeros((1, 1, 3), np.uint8))
    out = tmp_path / "out"
    result = batch(str(tmp_path / "in"), "-c", "s4", "-j", "1", "--out", str(out))
    assert result.exit_code == 1
    error = summary(out)[("seq", "s4")]["error"]
    assert error == (f"{out / 'seq' / 's4' / 'annotated.mp4'}: cannot encode a 1x1 video "
                     "(H.264 in yuv420p needs at least 2x2 pixels); give --no-video to track "
                     "it without the video")
    assert f"vtrack: error: seq [s4]: failed: {error}" in result.output
    with pytest.raises(VideoTooSmallError, match=r"; give video=False to track it without"):
        run(RunRequest(input=str(images.parent), out_dir=tmp_path / "lib",
                       config=load_config("s4")))
    done = batch(str(tmp_path / "in"), "-c", "s4", "-j", "1", "--no-video", "--out",
                 str(tmp_path / "out2"))
    assert done.exit_code == 0, done.output
    assert summary(tmp_path / "out2")[("seq", "s4")]["status"] == "complete"


def test_more_jobs_than_runs_start_a_worker_per_run(tmp_path: Path,
                                                    clip_factory: ClipFactory) -> None:
    """`--jobs 1000` on four runs started a worker process per job slot and hung."""
    folder = clips_folder(tmp_path, clip_factory, "a", "b")
    config = load_config("s0")
    request = RunRequest(input=str(folder), out_dir=tmp_path / "out", config=config, video=False)
    batch_plan = plan(find_inputs(folder), {"s0": config}, tmp_path / "out", request)
    executor = LocalExecutor(workers=64)
    most = 0
    outcomes = []
    for outcome in executor.run(batch_plan.jobs):
        most = max(most, len(multiprocessing.active_children()))
        outcomes.append(outcome)
    assert [o.status for o in outcomes] == ["complete", "complete"]
    assert 1 <= most <= len(batch_plan.jobs)
    too_many = batch(str(folder), "--jobs", "513", "--out", str(tmp_path / "o2"))
    assert too_many.exit_code == 2 and "1<=x<=512" in too_many.output


MOT_CONFIG = """
[[stage]]
name = "mot_detections"
path = "det.txt"
[[stage]]
name = "byte_tracks"
"""


def detections_setup(tmp_path: Path, clip_factory: ClipFactory) -> tuple[Path, Path]:
    """An input folder with a multi-target clip, and a working folder holding ``mot.toml``
    (``path = "det.txt"``, relative) and ``det.txt`` (the clip's ground truth as detections)."""
    clip = clip_factory("multi", width=W, height=H, frames=60)
    assert clip.mot is not None
    folder, work = tmp_path / "in", tmp_path / "work"
    folder.mkdir()
    work.mkdir()
    shutil.copy(clip.path, folder / "multi.mp4")
    shutil.copy(clip.mot, folder / "multi.mot.txt")
    rows = [line.split(",")[:6] for line in clip.mot.read_text().splitlines() if line.strip()]
    (work / "det.txt").write_text("".join(",".join(row) + ",1,-1,-1,-1\n" for row in rows))
    (work / "mot.toml").write_text(MOT_CONFIG)
    return folder, work


def test_a_relative_detections_path_is_the_batch_folders_on_dask(
        tmp_path: Path, clip_factory: ClipFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """``path = "det.txt"`` was read in the Dask worker's working folder (here one without a
    det.txt: every run failed; with another det.txt there it scored against that one)."""
    distributed = pytest.importorskip("distributed")
    folder, work = detections_setup(tmp_path, clip_factory)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # the worker processes start here
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        monkeypatch.chdir(work)  # the batch runs from here, where det.txt is
        result = batch(str(folder), "-c", "mot.toml", "--scheduler", cluster.scheduler_address,
                       "--no-video", "--out", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert summary(tmp_path / "out")[("multi", "mot")]["status"] == "complete"
    tracks = (tmp_path / "out" / "multi" / "mot" / "tracks.csv").read_text().splitlines()
    assert len(tracks) > 60  # the clip's people were tracked from the detections


def test_a_replaced_detections_file_runs_again(tmp_path: Path, clip_factory: ClipFactory,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """After det.txt was replaced, the batch said "complete before, not run again" and kept
    the results of the old detections."""
    folder, work = detections_setup(tmp_path, clip_factory)
    monkeypatch.chdir(work)
    out = tmp_path / "out"
    first = batch(str(folder), "-c", "mot.toml", "--jobs", "1", "--no-video", "--out", str(out))
    assert first.exit_code == 0, first.output
    tracks = out / "multi" / "mot" / "tracks.csv"
    before = tracks.read_text()
    again = batch(str(folder), "-c", "mot.toml", "--jobs", "1", "--no-video", "--out", str(out))
    assert "not run again" in again.output  # unchanged: reused
    det = work / "det.txt"
    det.write_text("".join(det.read_text().splitlines(keepends=True)[:3]))  # another detector
    replaced = batch(str(folder), "-c", "mot.toml", "--jobs", "1", "--no-video",
                     "--out", str(out))
    assert replaced.exit_code == 0, replaced.output
    assert "not run again" not in replaced.output
    assert tracks.read_text() != before


def test_the_same_config_file_named_another_way_resumes(
        tmp_path: Path, clip_factory: ClipFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack batch IN -c mot.toml -o OUT`, then `-c /abs/work/mot.toml` (or from a folder
    below, `-c ../mot.toml`) said "not run: OUT/multi/mot: holds the results of an earlier run
    ...; give --overwrite ... (made with other settings: the config (its file or a --set))":
    run.json records the config's source as typed. The same file is now the same run; another
    file of that name with other values, or a --set, still is not. (det.txt is named whole:
    a relative one is read from the folder the batch runs in, another file from below.)"""
    folder, work = detections_setup(tmp_path, clip_factory)
    config = MOT_CONFIG.replace('path = "det.txt"', f'path = "{work / "det.txt"}"')
    (work / "mot.toml").write_text(config)
    monkeypatch.chdir(work)
    out = tmp_path / "out"
    first = batch(str(folder), "-c", "mot.toml", "-j", "1", "--no-video", "-o", str(out))
    assert first.exit_code == 0, first.output
    below = work / "below"
    below.mkdir()
    for where, spec in ((work, str(work / "mot.toml")), (below, "../mot.toml")):
        monkeypatch.chdir(where)
        again = batch(str(folder), "-c", spec, "-j", "1", "--no-video", "-o", str(out))
        assert again.exit_code == 0, again.output
        assert "not run again" in again.output and "other settings" not in again.output
    other = tmp_path / "other"
    other.mkdir()
    (other / "mot.toml").write_text(config + "q = 2.0\n")
    for args in (["-c", str(other / "mot.toml")],
                 ["-c", str(work / "mot.toml"), "--set", "byte_tracks.q=2"]):
        changed = batch(str(folder), *args, "-j", "1", "--no-video", "-o", str(out))
        assert changed.exit_code != 0
        assert "made with other settings: the config (its file or a --set)" in changed.output


def mot_sequence(seq: Path, clip_factory: ClipFactory) -> Path:
    """A MOTChallenge sequence folder ``seq`` (img1/000001.jpg ..., gt/gt.txt) of 60 frames of
    the generated ``multi`` scene."""
    clip = clip_factory("multi", frames=60, fmt="images")
    shutil.copytree(clip.path / "img", seq / "img1")
    (seq / "gt").mkdir()
    shutil.copy(clip.mot, seq / "gt" / "gt.txt")
    return seq


def test_a_motchallenge_sequence_folder_is_an_input(tmp_path: Path,
                                                    clip_factory: ClipFactory) -> None:
    """Probe 51c: a MOTChallenge sequence (SEQ/img1/000001.jpg, SEQ/gt/gt.txt) was no input:
    `vtrack batch` of a folder of them said 'no inputs (... sequence folders with an img/
    folder)' though its --help names gt/gt.txt, and `vtrack run SEQ` 'no images in the folder
    or its img/'. img1/ is now a sequence's image folder as img/ is, and SEQ/img1 is SEQ."""
    seq = mot_sequence(tmp_path / "MOT" / "SEQ-01", clip_factory)
    out = tmp_path / "out"
    result = batch(str(seq.parent), "-c", "s3", "--no-video", "-j", "1", "-o", str(out), "-q")
    assert result.exit_code == 0, result.output
    assert summary(out)[("SEQ-01", "s3")]["status"] == "complete"
    record = json.loads((out / "SEQ-01" / "s3" / "run.json").read_text())
    assert record["request"]["gt"] == str(seq / "gt" / "gt.txt")
    assert record["metrics"]["gt_boxes"] > 100 and record["metrics"]["mota"] > 0.5
    for given in (seq, seq / "img1"):
        ran = CliRunner().invoke(main, ["run", str(given), "-c", "s3", "--no-video", "-q",
                                        "-o", str(tmp_path / given.name)])
        assert ran.exit_code == 0, ran.output
        record = json.loads((tmp_path / given.name / "run.json").read_text())
        assert record["input"]["name"] == "SEQ-01" and record["frames"] == 60


def test_a_motchallenge_sequence_plays_at_its_seqinfo_frame_rate(
        tmp_path: Path, clip_factory: ClipFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """Probe 51c: a MOTChallenge sequence's frame rate is in its seqinfo.ini (frameRate=25);
    its frames were timed at 30 fps whatever it said (time_s, the annotated video's rate, a
    --frames 2s span). It is read now, --fps still wins, and a frameRate that is no rate is
    one line naming the file. ``vtrack run .`` inside img1/ looked for ./seqinfo.ini (30 fps)
    though it named the run after the sequence."""
    clip = clip_factory("multi", frames=60, fmt="images")
    seq = tmp_path / "SEQ-02"
    shutil.copytree(clip.path / "img", seq / "img1")
    info = seq / "seqinfo.ini"
    info.write_text("[Sequence]\nname=SEQ-02\nimDir=img1\nframeRate=25\nseqLength=60\n")

    def run(*args: str) -> Result:
        return CliRunner().invoke(main, ["run", *args, "-c", "s3", "--no-video", "-q", "-y",
                                         "-o", str(tmp_path / "out")])

    for given, extra, fps in ((seq, (), 25.0), (seq / "img1", (), 25.0),
                              (seq, ("--fps", "10"), 10.0)):
        result = run(str(given), *extra)
        assert result.exit_code == 0, result.output
        record = json.loads((tmp_path / "out" / "run.json").read_text())
        assert record["input"]["fps"] == fps and record["input"]["duration_s"] == 60 / fps
    monkeypatch.chdir(seq / "img1")
    assert run(".").exit_code == 0
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert (record["input"]["fps"], record["input"]["name"]) == (25.0, "SEQ-02")
    result = batch(str(tmp_path), "-c", "s3", "--no-video", "-j", "1", "-o", str(tmp_path / "b"),
                   "-q")
    assert result.exit_code == 0, result.output
    assert json.loads((tmp_path / "b" / "SEQ-02" / "s3" / "run.json").read_text()
                      )["input"]["fps"] == 25.0
    info.write_text("[Sequence]\nframeRate=fast\n")
    assert one_error_line(run(str(seq))) == (
        f"vtrack: error: {info}: frameRate must be a frame rate from 0.01 to 10000 frames per "
        "second, got 'fast' (--fps N gives the sequence's frame rate instead)")


@pytest.mark.parametrize("rate", ["1e13", "1e-300", "20000"])
def test_a_seqinfo_frame_rate_past_what_fps_takes_is_one_line(
        rate: str, tmp_path: Path, clip_factory: ClipFactory) -> None:
    """A MOTChallenge sequence whose seqinfo.ini says frameRate=1e13 (or 1e-300, or 20000)
    was taken though --fps refuses such a rate: `vtrack run SEQ -c fixed_camera` ended in an
    OverflowError traceback from PyAV's add_stream (1e13), in `annotated.mp4: cannot write
    video (Python int too large to convert to C long)` after tracking, exit 1 (1e-300), or
    wrote a video at 90000 fps, not 20000. It is one line naming the file and the range --fps
    takes now, exit 2, nothing written; --fps still wins over the file."""
    clip = clip_factory("multi", frames=60, fmt="images")
    seq = tmp_path / "SEQ-03"
    shutil.copytree(clip.path / "img", seq / "img1")
    info = seq / "seqinfo.ini"
    info.write_text(f"[Sequence]\nname=SEQ-03\nimDir=img1\nframeRate={rate}\nseqLength=60\n")
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["run", str(seq), "-c", "fixed_camera", "-q", "-o",
                                       str(out)])
    assert one_error_line(result) == (
        f"vtrack: error: {info}: frameRate must be a frame rate from 0.01 to 10000 frames per "
        f"second, got '{rate}' (--fps N gives the sequence's frame rate instead)")
    assert result.exit_code == 2 and not out.exists()
    given = CliRunner().invoke(main, ["run", str(seq), "-c", "fixed_camera", "-q", "--fps", "25",
                                      "-o", str(out)])
    assert given.exit_code == 0, given.output
    assert json.loads((out / "run.json").read_text())["input"]["fps"] == 25.0


def test_videos_in_sub_folders_are_counted_in_one_warning(tmp_path: Path,
                                                          clip_factory: ClipFactory) -> None:
    """`in/nested/c.mp4` is no input, and the batch said nothing of it. Now one warning line
    counts the video files in sub-folders (at any depth) and names the first; a sequence
    folder's images and a results folder's annotated.mp4 are not counted."""
    folder = clips_folder(tmp_path, clip_factory, "a")
    add_clip(folder, clip_factory, "smooth", "seq", fmt="images")
    for name in ("nested/c.mp4", "nested/deeper/d.mkv", "old/a/s0/annotated.mp4"):
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(folder / "a.mp4", folder / name)
    (folder / "old" / "a" / "s0" / "run.json").write_text("{}\n")
    shutil.copy(folder / "a.gt.txt", folder / "nested" / "c.gt.txt")
    result = batch(str(folder), "-c", "s0", "--no-video", "--out", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert set(summary(tmp_path / "out")) == {("a", "s0"), ("seq", "s0")}
    # (a progress line may come too on a slow machine: stderr is no terminal here)
    warnings = [line for line in result.stderr.splitlines() if line.startswith("vtrack: warn")]
    assert len(warnings) == 1 and warnings[0].startswith(f"vtrack: warning: {folder}: "), warnings
    assert "2 video files in sub-folders are not inputs" in warnings[0]
    assert f"({folder / 'nested' / 'c.mp4'} and 1 more)" in warnings[0]
    alone = batch(str(folder / "nested"), "-c", "s0", "--no-video", "--out",
                  str(tmp_path / "out2"))
    assert alone.exit_code == 0 and "1 video file in sub-folders is not an input" in alone.stderr


def test_inputs_one_folder_deeper_are_named_with_the_batch_that_tracks_them(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """`IN/group/seq/img/...` (a sequence folder in a sub-folder) was passed over without a
    word, and `vtrack batch IN` with `IN/group/clip.mp4` only said `IN: no inputs (...)`. Now
    the sequence folders there are counted with the videos, and the line names the first and
    the `vtrack batch IN/group` that tracks them: a warning when the batch has inputs, else
    the no-inputs error's end."""
    folder = tmp_path / "in"
    (folder / "group").mkdir(parents=True)
    add_clip(folder / "group", clip_factory, "smooth", "seq", fmt="images")
    nothing = batch(str(folder), "-c", "s0", "--no-video", "--out", str(tmp_path / "o1"))
    assert one_error_line(nothing) == (
        f"vtrack: error: {folder}: no inputs (video files or sequence folders: images in img/ "
        "or img1/, or in color/ or the folder itself beside their groundtruth.txt, "
        "groundtruth_rect.txt or init.txt); 1 sequence folder in sub-folders is not an input "
        f"({folder / 'group' / 'seq'}): a batch takes the videos directly in the folder and "
        "its sequence folders (img/, img1/, color/); to track it, vtrack batch "
        f"{folder / 'group'}")
    add_clip(folder / "group", clip_factory, "smooth", "clip")
    add_clip(folder, clip_factory, "smooth", "a")
    result = batch(str(folder), "-c", "s0", "--no-video", "--out", str(tmp_path / "o2"))
    assert result.exit_code == 0, result.output
    assert set(summary(tmp_path / "o2")) == {("a", "s0")}
    warnings = [line for line in result.stderr.splitlines() if line.startswith("vtrack: warn")]
    assert warnings == [
        f"vtrack: warning: {folder}: 1 video file and 1 sequence folder in sub-folders are not "
        f"inputs ({folder / 'group' / 'clip.mp4'} and 1 more): a batch takes the videos "
        "directly in the folder and its sequence folders (img/, img1/, color/); to track them, "
        f"vtrack batch {folder / 'group'}"]
    alone = batch(str(folder / "group"), "-c", "s0", "--no-video", "--out", str(tmp_path / "o3"))
    assert alone.exit_code == 0 and "vtrack: warning" not in alone.stderr, alone.output
    assert set(summary(tmp_path / "o3")) == {("clip", "s0"), ("seq", "s0")}


def test_the_nested_walk_is_bounded_names_the_nearest_and_quotes_its_folder(
        tmp_path: Path) -> None:
    """The walk for inputs in sub-folders went through the whole tree before a batch began or
    said 'no inputs' (`vtrack batch /usr`: seconds), named the first by path (a file 5
    folders deep), and gave `vtrack batch IN/my group`, which breaks when pasted. Now it looks
    at NESTED_LOOKS folders at most, breadth first, says so ("at least", "e.g."), names the
    nearest find, and quotes the folder."""
    folder = tmp_path / "in"
    for name in ("a/b/c/deep.mp4", "my group/near.mp4"):
        (folder / name).parent.mkdir(parents=True)
        (folder / name).write_bytes(b"not read")
    for number in range(NESTED_LOOKS):  # more folders than the walk looks at
        (folder / "zz" / f"d{number:03d}").mkdir(parents=True)
    nothing = batch(str(folder), "-c", "s0", "--no-video", "--out", str(tmp_path / "o"))
    assert one_error_line(nothing).endswith(
        "; at least 1 video file in sub-folders is not an input "
        f"({folder / 'my group' / 'near.mp4'}, in the first {NESTED_LOOKS} folders looked "
        "at): a batch takes the videos directly in the folder and its sequence folders "
        "(img/, img1/, color/); to track them, e.g. "
        f"vtrack batch '{folder / 'my group'}'"), nothing.output
    shutil.rmtree(folder / "zz")  # every folder looked at: all counted, the nearest first
    assert nested_inputs(folder) == ([folder / "my group" / "near.mp4",
                                      folder / "a" / "b" / "c" / "deep.mp4"], True)


def test_the_nested_walk_counts_a_folder_as_it_lists_it(tmp_path: Path) -> None:
    """The walk counted the folders at the top before listing them: with more than
    NESTED_LOOKS of them it stopped at once, found nothing and said nothing (`vtrack batch big`
    with 521 folders and big/g000/sub/c.mp4: a bare 'no inputs'). Now a folder counts when it
    is listed: the first listings' finds are kept, and a walk cut short with nothing found
    says so."""
    folder = tmp_path / "big"
    for number in range(5):
        (folder / f"g{number}" / "sub").mkdir(parents=True)
    (folder / "g0" / "sub" / "c.mp4").write_bytes(b"not read")
    # 5 listings at the top, the 6th is g0/sub
    assert nested_inputs(folder, looks=6) == ([folder / "g0" / "sub" / "c.mp4"], False)
    assert nested_inputs(folder, looks=5) == ([], False)
    assert nested_inputs(folder, looks=10) == ([folder / "g0" / "sub" / "c.mp4"], True)
    empty = tmp_path / "empty"
    for number in range(NESTED_LOOKS + 1):
        (empty / f"g{number:03d}").mkdir(parents=True)
    nothing = batch(str(empty), "-c", "s0", "--no-video", "--out", str(tmp_path / "o"))
    assert one_error_line(nothing).endswith(
        "init.txt); none in sub-folders either, in the first "
        f"{NESTED_LOOKS} folders looked at"), nothing.output


def test_summary_writes_are_spaced_by_their_own_time(tmp_path: Path) -> None:
    """Each end wrote every row: 30,000 pairs (227 ms a write) spent 1.9 hours writing 100 GB.
    Now a write comes at an end once WRITE_SPACING times the last write's time has passed; a
    clock that reads one second later each time makes every write take a second."""
    ticks = itertools.count()
    path = tmp_path / "summary.csv"
    writer = SummaryWriter(path, [(f"in{n:03d}", "s0") for n in range(100)],
                           clock=lambda: float(next(ticks)))

    def failed() -> int:
        with open(path, newline="") as handle:
            return sum(row["status"] == "failed" for row in csv.DictReader(handle))

    shown = []
    for n in range(100):
        writer.add(Outcome(f"in{n:03d}", "s0", "failed", error="broken"))
        shown.append(failed())
    assert shown[0] == 1  # the first end is written at once
    assert len(set(shown)) <= 1 + 100 / WRITE_SPACING  # not every end: about one in 20
    writer.flush()
    assert failed() == 100


def test_a_batch_run_whose_first_frame_is_absent_names_the_options_as_vtrack_run_does(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """A batch's runs share vtrack run's options (--start, --set; a first box as --init gives
    it): its messages name those, not the library's init_box=(x, y, w, h)."""
    folder = tmp_path / "in"
    folder.mkdir()
    clip = clip_factory("smooth", width=W, height=H, frames=FRAMES)
    shutil.copy(clip.path, folder / "a.mp4")
    lines = clip.gt.read_text().splitlines()
    lines[10] = "0,0,0,0"  # the target absent on the frame the batch starts at
    (folder / "a.gt.txt").write_text("\n".join(lines) + "\n")
    result = batch(str(folder), "-c", "s0", "--out", str(tmp_path / "out"), "--no-video",
                   "--start", "10")
    assert result.exit_code != 0
    assert "give --init x,y,w,h" in result.output, result.output
    assert "init_box" not in result.output


def test_a_single_target_config_on_a_motchallenge_sequence_names_its_ground_truth(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """Probe R: `vtrack batch MOT/ -c robust` over a MOTChallenge sequence (SEQ/img1,
    SEQ/gt/gt.txt) failed its row with 'there is no ground truth or initial box
    (groundtruth_rect.txt, groundtruth.txt, init.txt)', as if the folder had none: it has
    gt/gt.txt, which only a multi-target config reads. The row now names that file and the
    configs that read it."""
    seq = mot_sequence(tmp_path / "MOT" / "SEQ-01", clip_factory)
    out = tmp_path / "out"
    result = batch(str(seq.parent), "-c", "robust", "--no-video", "-j", "1", "-o", str(out),
                   "-q")
    assert result.exit_code == 1, result.output
    error = summary(out)[("SEQ-01", "robust")]["error"]
    assert "SEQ-01/gt/gt.txt is MOTChallenge ground truth" in error, error
    assert "--config fixed_camera, s3 or s4_multi" in error, error
    assert f"vtrack: error: SEQ-01 [robust]: failed: {error}" in result.stderr.splitlines()


def test_a_batch_says_its_runs_warnings(tmp_path: Path, clip_factory: ClipFactory) -> None:
    """Probe R: a sequence whose groundtruth_rect.txt has 100 boxes for 120 frames gets from
    `vtrack run` 'vtrack: warning: ...: ground truth has 100 boxes for 120 frames (fewer);
    overlap is empty from frame 100 on', but `vtrack batch` of its folder said nothing (the
    warning was only in run.json): its last 20 frames went unscored without a word. The batch
    now says each run's warnings after it, named by input and config (with -q too, as
    vtrack run does), and not again for a run complete before."""
    clip = clip_factory("smooth", frames=30, fmt="images")
    folder = tmp_path / "in"
    shutil.copytree(clip.path, folder / "seq")
    truth = folder / "seq" / "groundtruth_rect.txt"
    truth.write_text("".join(truth.read_text().splitlines(keepends=True)[:20]))
    out = tmp_path / "out"
    for quiet in ((), ("-q",)):
        result = batch(str(folder), "-c", "s0", "--no-video", "-j", "1", "-o", str(out), "-y",
                       "--force", *quiet)
        assert result.exit_code == 0, result.output
        recorded = json.loads((out / "seq" / "s0" / "run.json").read_text())["warnings"]
        assert len(recorded) == 1 and "20 boxes for 30 frames" in recorded[0], recorded
        said = [line for line in result.stderr.splitlines() if "warning" in line]
        assert said == [f"vtrack: warning: seq [s0]: {recorded[0]}"]
    again = batch(str(folder), "-c", "s0", "--no-video", "-j", "1", "-o", str(out))
    assert "already complete: not run again" in again.output
    assert "warning" not in again.stderr


def test_vot_layouts_are_batch_inputs_and_their_ground_truth_is_read_as_vot_writes_it(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """VOT's layouts were no batch inputs: images directly in the sequence folder beside
    groundtruth.txt, or VOT2017+'s color/, gave 'vot: no inputs ...' (vtrack run read the
    first, not the second). VOT's boxes are 0-based (the VOT toolkit's pixel 0 is the image's
    first): both VOT layouts read them so, as batch inputs and with vtrack run; groundtruth.txt
    beside img/ (UAV123's, LaSOT's layout, MATLAB toolkits) stays 1-based."""
    from vtrack.evaluate import read_boxes

    clip = clip_factory("smooth", width=160, height=120, frames=20, fmt="images")
    truth = read_boxes(clip.gt, origin=1)  # (vtrack scene writes OTB's 1-based boxes)
    vot = "".join(f"{b.x},{b.y},{b.w},{b.h}\n" for b in truth)  # VOT's: 0-based
    folder = tmp_path / "vot"
    one_based = "".join(f"{b.x + 1},{b.y + 1},{b.w},{b.h}\n" for b in truth)
    for name, images in (("flat", "."), ("vot17", "color"), ("uav", "img")):
        shutil.copytree(clip.path / "img", folder / name / images, dirs_exist_ok=True)
        (folder / name / "groundtruth.txt").write_text(one_based if images == "img" else vot)
    (folder / "plots").mkdir()  # images without ground truth: no input
    shutil.copy(next((clip.path / "img").iterdir()), folder / "plots" / "curves_all.jpg")
    result = batch(str(folder), "-c", "s0", "--no-video", "-j", "1", "-o", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    with (tmp_path / "out" / "summary.csv").open(newline="") as handle:
        rows = {row["input"]: row for row in csv.DictReader(handle)}
    assert sorted(rows) == ["flat", "uav", "vot17"], rows
    first = [truth[0].x, truth[0].y, truth[0].w, truth[0].h]
    for name in rows:
        assert rows[name]["status"] == "complete" and rows[name]["frames"] == "20", rows[name]
        record = json.loads((tmp_path / "out" / name / "s0" / "run.json").read_text())
        assert record["init"] == pytest.approx(first), name
    for name in ("flat", "vot17"):
        ran = CliRunner().invoke(main, [
            "run", str(folder / name), "-c", "s0", "--gt", str(folder / name / "groundtruth.txt"),
            "--no-video", "-o", str(tmp_path / f"run-{name}")], catch_exceptions=False)
        assert ran.exit_code == 0, ran.output
        record = json.loads((tmp_path / f"run-{name}" / "run.json").read_text())
        assert record["init"] == pytest.approx(first), name


def otb_two_targets(clip_factory: ClipFactory, folder: Path) -> tuple[Path, list[list[float]]]:
    """An OTB sequence of two targets, ``folder/Jogging`` (``img/``,
    ``groundtruth_rect.1.txt`` and ``groundtruth_rect.2.txt``, OTB's 1-based boxes, target 2
    3 pixels right of target 1), and a plain one, ``folder/Plain``; each target's 0-based
    boxes."""
    from vtrack.evaluate import read_boxes

    clip = clip_factory("smooth", width=160, height=120, frames=20, fmt="images")
    sequence = folder / "Jogging"
    shutil.copytree(clip.path / "img", sequence / "img")
    shutil.copytree(clip.path, folder / "Plain")
    truth = read_boxes(clip.gt, origin=1)
    boxes = []
    for n, dx in ((1, 0), (2, 3)):
        rows = [[b.x + dx, b.y, b.w, b.h] for b in truth]
        (sequence / f"groundtruth_rect.{n}.txt").write_text(
            "".join(f"{x + 1},{y + 1},{w},{h}\n" for x, y, w, h in rows))
        boxes.append(rows)
    return sequence, boxes


@pytest.mark.parametrize("start", [None, "5"])
def test_each_target_of_an_otb_sequence_is_an_input_of_its_own(
        clip_factory: ClipFactory, tmp_path: Path, start: str | None) -> None:
    """OTB's two-target sequences (img/ and groundtruth_rect.1.txt, groundtruth_rect.2.txt:
    Jogging, Skating2, Human4) were one failed row in a batch ('config 's0' tracks one given
    target, and the sequence has 2 targets' ground truth (...), none of which a batch takes by
    itself: track each with vtrack run, e.g. vtrack run .../Jogging -c s0 --gt
    .../groundtruth_rect.1.txt'), so a batch over OTB100 gave no result for them. Each target
    is now an input, named as OTB names it (Jogging-1, Jogging-2), tracked from its own boxes
    (at --start 5 too), with its results folder, its row and a run.json recording the
    sequence folder and the target; a second batch resumes them, an older run.json without a
    target resumes too, and the report lists Jogging-1, Jogging-2 and Plain."""
    sequence, boxes = otb_two_targets(clip_factory, tmp_path / "in")
    starts = [] if start is None else ["--start", start]
    out = tmp_path / "out"
    result = batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-j", "1", "-o", str(out),
                   *starts)
    assert result.exit_code == 0, result.output
    rows = summary(out)
    assert sorted(rows) == [("Jogging-1", "s0"), ("Jogging-2", "s0"), ("Plain", "s0")]
    assert all(row["status"] == "complete" for row in rows.values()), rows
    first = int(start or 0)
    for n in (1, 2):
        record = json.loads((out / f"Jogging-{n}" / "s0" / "run.json").read_text())
        assert record["status"] == "complete"
        assert record["request"]["input"] == str(sequence)
        assert record["request"]["gt"] == str(sequence / f"groundtruth_rect.{n}.txt")
        assert record["request"]["target"] == n
        assert record["init"] == pytest.approx(boxes[n - 1][first]), n
    plain = out / "Plain" / "s0" / "run.json"
    older = json.loads(plain.read_text())
    assert older["request"].pop("target") is None
    plain.write_text(json.dumps(older))  # a run.json of before targets were recorded
    again = batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-j", "1", "-o", str(out),
                  *starts)
    assert again.exit_code == 0, again.output
    assert again.output.count("already complete: not run again") == 3, again.output
    shown = CliRunner().invoke(main, ["report", str(out), "-q", "-o", str(tmp_path / "report")],
                               catch_exceptions=False)
    assert shown.exit_code == 0, shown.output
    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        assert sorted(row["input"] for row in csv.DictReader(handle)) == [
            "Jogging-1", "Jogging-2", "Plain"]


def test_a_multi_target_config_runs_once_on_an_otb_sequence_of_several_targets(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A multi-target config (s3) ran an OTB sequence of two targets once per target:
    Jogging-1 [s3] and Jogging-2 [s3], the same run twice, the report counting the sequence
    twice. Targets are inputs of single-target configs only: s3 runs once, on Jogging (as
    vtrack run Jogging -c s3 names it), s0 on each target; the plain sequence gets both."""
    sequence, _ = otb_two_targets(clip_factory, tmp_path / "in")
    out = tmp_path / "out"
    result = batch(str(tmp_path / "in"), "-c", "s0", "-c", "s3", "--no-video", "-j", "1",
                   "-o", str(out))
    assert result.exit_code == 0, result.output
    rows = summary(out)
    assert list(rows) == [("Jogging", "s3"), ("Jogging-1", "s0"), ("Jogging-2", "s0"),
                          ("Plain", "s0"), ("Plain", "s3")], rows
    assert all(row["status"] == "complete" for row in rows.values()), rows
    assert "5 runs (5 complete)" in result.output, result.output
    assert not (out / "Jogging-1" / "s3").exists() and not (out / "Jogging" / "s0").exists()
    record = json.loads((out / "Jogging" / "s3" / "run.json").read_text())
    assert record["request"]["input"] == str(sequence)
    assert record["request"]["target"] is None and record["request"]["gt"] is None


def test_a_run_of_one_target_of_an_otb_sequence_is_named_after_it(
        clip_factory: ClipFactory, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """vtrack run Jogging --gt Jogging/groundtruth_rect.2.txt wrote vtrack-out/Jogging/s0, the
    folder of target 1's run too, and the report named it Jogging: joined with a batch's
    Jogging-2 it was another input. It now writes vtrack-out/Jogging-2/s0, records target 2,
    and the report joins it with the batch's Jogging-2 (two results of one input)."""
    sequence, _ = otb_two_targets(clip_factory, tmp_path / "in")
    monkeypatch.chdir(tmp_path)
    ran = CliRunner().invoke(main, ["run", str(sequence), "-c", "s0", "--no-video", "--gt",
                                    str(sequence / "groundtruth_rect.2.txt")],
                             catch_exceptions=False)
    assert ran.exit_code == 0, ran.output
    record = json.loads((tmp_path / "vtrack-out" / "Jogging-2" / "s0" / "run.json").read_text())
    assert record["request"]["target"] == 2
    assert batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-j", "1", "-o",
                 str(tmp_path / "out")).exit_code == 0
    shown = CliRunner().invoke(main, ["report", str(tmp_path / "out"), "vtrack-out", "-q",
                                      "-o", str(tmp_path / "report")], catch_exceptions=False)
    assert shown.exit_code == 0, shown.output
    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        inputs = sorted(row["input"] for row in csv.DictReader(handle))
    assert inputs == ["Jogging-1", "Jogging-2", "Jogging-2", "Plain"], inputs


def test_a_run_of_a_target_from_its_images_folder_is_joined_with_the_batchs_target(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """vtrack run Jogging/img --gt Jogging/groundtruth_rect.1.txt beside a batch over a folder
    whose Jogging also holds groundtruth_rect.txt: the report keyed an input by the path the
    run was given (img, 20 files; the batch's Jogging, 23) and relabelled the two by their file
    names, so its headings were Jogging (the batch's Jogging and its target 1 under one name),
    Jogging-2 and img, no Jogging-1. An image sequence is now keyed by its sequence folder and
    target: the run and the batch's target 1 are two results of Jogging-1."""
    sequence, _ = otb_two_targets(clip_factory, tmp_path / "in")
    shutil.copy(sequence / "groundtruth_rect.1.txt", sequence / "groundtruth_rect.txt")
    ran = CliRunner().invoke(main, ["run", str(sequence / "img"), "-c", "s0", "--no-video",
                                    "--gt", str(sequence / "groundtruth_rect.1.txt"),
                                    "-o", str(tmp_path / "v10" / "x")], catch_exceptions=False)
    assert ran.exit_code == 0, ran.output
    assert batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-j", "1", "-o",
                 str(tmp_path / "o10")).exit_code == 0
    shown = CliRunner().invoke(main, ["report", str(tmp_path / "o10"), str(tmp_path / "v10"),
                                      "-q", "-o", str(tmp_path / "report")],
                               catch_exceptions=False)
    assert shown.exit_code == 0, shown.output
    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        rows = sorted((row["input"], row["config"]) for row in csv.DictReader(handle))
    assert rows == [("Jogging", "s0 (o10)"), ("Jogging-1", "s0 (o10)"), ("Jogging-1", "s0 (v10)"),
                    ("Jogging-2", "s0 (o10)"), ("Plain", "s0 (o10)")], rows


def test_a_batch_over_an_older_batchs_failed_sequence_drops_its_row(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A vtrack before each target was an input failed a two-target sequence as one row,
    Jogging [s0]. A batch into that folder kept the row beside Jogging-1 and Jogging-2 (the
    report listed its old advice under "Runs without results"). That refusal is dropped when
    the sequence's targets are planned; other rows are kept, of the sequence itself too: a
    multi-target config's row a stopped batch never ran (no run in its folder either) was
    dropped with it."""
    sequence, _ = otb_two_targets(clip_factory, tmp_path / "in")
    out = tmp_path / "out"
    out.mkdir()
    blank = [""] * (len(SUMMARY_COLUMNS) - 5)
    lines = [",".join(SUMMARY_COLUMNS)]
    lines += [",".join(["Jogging", "s0", "failed", *blank, "", f'"{sequence}: config \'s0\' '
                        'tracks one given target, and the sequence has 2 targets\' ground '
                        'truth: track each with vtrack run"'])]
    lines += [",".join(["Jogging", "s3", "interrupted", *blank, "", f'"{NEVER_STARTED}"'])]
    lines += [",".join(["Gone", "s0", "failed", *blank, "", "an input since removed"])]
    (out / "summary.csv").write_text("\n".join(lines) + "\n")
    assert [key for key in summary(out)] == [("Jogging", "s0"), ("Jogging", "s3"),
                                             ("Gone", "s0")]
    result = batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-j", "1", "-o", str(out))
    assert result.exit_code == 0, result.output
    rows = summary(out)
    assert sorted(rows) == [("Gone", "s0"), ("Jogging", "s3"), ("Jogging-1", "s0"),
                            ("Jogging-2", "s0"), ("Plain", "s0")]
    assert rows["Jogging", "s3"]["error"] == NEVER_STARTED
    shown = CliRunner().invoke(main, ["report", str(out), "-q", "-o", str(tmp_path / "report")],
                               catch_exceptions=False)
    assert shown.exit_code == 0, shown.output
    assert "targets' ground truth" not in (tmp_path / "report" / "summary.md").read_text()


def test_a_multi_target_config_on_a_sequence_of_targets_only_warns_it_is_not_scored(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """'vtrack batch in/Jogging -c s3' (groundtruth_rect.1.txt and .2.txt, no MOTChallenge
    ground truth) said nothing of s3's run being not scored once each target was an input: the
    folder's ground truth was no longer counted. The warning names the folder and its files."""
    sequence, _ = otb_two_targets(clip_factory, tmp_path / "in")
    result = batch(str(sequence), "-c", "s3", "--no-video", "-j", "1", "-o",
                   str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert set(summary(tmp_path / "out")) == {("Jogging", "s3")}
    warnings = [line for line in result.stderr.splitlines() if line.startswith("vtrack: warn")]
    assert warnings == [
        f"vtrack: warning: {sequence}: one target's ground truth per file "
        "(groundtruth_rect.1.txt, groundtruth_rect.2.txt); config 's3' tracks several targets "
        "and reads MOTChallenge ground truth (groundtruth_mot.txt or gt.txt or gt/gt.txt in "
        "Jogging/): its run is not scored"], result.stderr


def test_a_folder_named_like_a_target_of_a_sequence_beside_it_stops_the_batch(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A sequence folder Jogging-1 beside Jogging (groundtruth_rect.1.txt) would write the
    results folder of Jogging's target 1: the batch stops before it starts, naming both."""
    _, _ = otb_two_targets(clip_factory, tmp_path / "in")
    shutil.copytree(tmp_path / "in" / "Plain", tmp_path / "in" / "Jogging-1")
    result = CliRunner().invoke(main, ["batch", str(tmp_path / "in"), "-c", "s0",
                                       "-o", str(tmp_path / "out")])
    assert one_error_line(result).endswith(
        "'Jogging/groundtruth_rect.1.txt' and 'Jogging-1' would share the results folder "
        "'Jogging-1' (both are named 'Jogging-1'): rename one"), result.stderr
    assert not (tmp_path / "out").exists()


def test_a_video_beside_a_sequence_of_targets_only_keeps_its_name_unless_the_sequence_runs(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """in/Jogging.mp4 beside in/Jogging/ (groundtruth_rect.1.txt and .2.txt only): 'vtrack batch
    in -c s0' named the video 'Jogging.mp4', as if the folder Jogging were an input, which no
    single-target config runs on (its targets are). The video is Jogging unless a multi-target
    config runs on the folder (then both keep folders of their own)."""
    _, _ = otb_two_targets(clip_factory, tmp_path / "in")
    add_clip(tmp_path / "in", clip_factory, "smooth", "Jogging")
    result = batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-j", "1", "-o",
                   str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    rows = summary(tmp_path / "out")
    assert sorted(rows) == [("Jogging", "s0"), ("Jogging-1", "s0"), ("Jogging-2", "s0"),
                            ("Plain", "s0")], result.output
    assert rows["Jogging", "s0"]["ground_truth"].endswith("Jogging.gt.txt")
    both = batch(str(tmp_path / "in"), "-c", "s0", "-c", "s3", "--no-video", "-j", "1", "-o",
                 str(tmp_path / "out-both"))
    assert both.exit_code == 0, both.output
    assert {key for key in summary(tmp_path / "out-both") if key[0].startswith("Jogging")} == {
        ("Jogging", "s3"), ("Jogging.mp4", "s0"), ("Jogging.mp4", "s3"), ("Jogging-1", "s0"),
        ("Jogging-2", "s0")}


def test_only_folders_of_a_sequences_images_are_sequences_and_results_are_no_inputs(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Any folder holding a color/ folder was a sequence, images in it or not: in5/ with a.mp4,
    a.gt.txt and color/graded.mp4 (a colourist's output) failed as one input 'in5' ('no ground
    truth or initial box') and a.mp4 was not run; a batch whose --out was in7/res took res
    (its color/ results) as an input the second time; and in6/ with clip.mp4, clip.gt.txt,
    one thumbnail.jpg and a groundtruth.txt ran as one sequence of 1 frame, clip not run."""
    clips = clips_folder(tmp_path, clip_factory, "a")
    image = next((clip_factory("smooth", width=W, height=H, frames=FRAMES,
                               fmt="images").path / "img").iterdir())
    in5, in6, in7 = (tmp_path / n for n in ("in5", "in6", "in7"))
    (in5 / "color").mkdir(parents=True)
    for name in ("a.mp4", "a.gt.txt"):
        shutil.copy(clips / name, in5 / name)
    shutil.copy(clips / "a.mp4", in5 / "color" / "graded.mp4")
    in6.mkdir()
    shutil.copy(clips / "a.mp4", in6 / "clip.mp4")
    shutil.copy(clips / "a.gt.txt", in6 / "clip.gt.txt")
    shutil.copy(clips / "a.gt.txt", in6 / "groundtruth.txt")
    shutil.copy(image, in6 / "thumbnail.jpg")
    in7.mkdir()
    shutil.copy(clips / "a.mp4", in7 / "color.mp4")
    shutil.copy(clips / "a.gt.txt", in7 / "color.gt.txt")
    for folder, name in ((in5, "a"), (in6, "clip"), (in7, "color"), (in7, "color")):
        out = in7 / "res" if folder == in7 else tmp_path / f"out-{folder.name}"
        result = batch(str(folder), "-c", "s0", "--no-video", "-j", "1", "-o", str(out))
        assert result.exit_code == 0, result.output
        assert set(summary(out)) == {(name, "s0")}, result.output
        assert summary(out)[name, "s0"]["status"] == "complete"
    assert "1 video file in sub-folders is not an input" in batch(
        str(in5), "-c", "s0", "--no-video", "-o", str(tmp_path / "out-in5")).stderr


def test_a_sequence_whose_img_folder_holds_no_image_is_a_failed_row_not_passed_over(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """An OTB sequence whose img/ holds no image (a download that failed; or its images one
    folder deeper) beside a video: the batch passed over it without a word (exit 0, one row),
    where it used to fail its row saying so. img/ and img1/ are names only sequences use: the
    folder is a sequence, and its row says it has no images."""
    clips = clips_folder(tmp_path, clip_factory, "a")
    folder = tmp_path / "in-seq"
    (folder / "seq" / "img" / "sub").mkdir(parents=True)
    shutil.copy(clips / "a.mp4", folder / "a.mp4")
    shutil.copy(clips / "a.gt.txt", folder / "a.gt.txt")
    shutil.copy(clips / "a.gt.txt", folder / "seq" / "groundtruth_rect.txt")
    result = batch(str(folder), "-c", "s0", "--no-video", "-j", "1", "-o", str(tmp_path / "o"))
    rows = summary(tmp_path / "o")
    assert set(rows) == {("a", "s0"), ("seq", "s0")}, result.output
    assert rows["seq", "s0"]["status"] == "failed"
    assert "no images" in result.stderr, result.stderr


def test_a_flat_sequence_is_one_input_by_one_rule_with_otbs_boxes_and_an_init_box(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Discovery and --gt-origin auto each had a rule of what a sequence folder is: images
    directly beside groundtruth_rect.txt were a batch input whose OTB boxes were read 0-based
    (one pixel off), and images beside the init.txt of vtrack select (which vtrack run reads)
    were none: 'no inputs'. One rule (is_sequence_folder) now decides for both."""
    from vtrack.evaluate import read_boxes

    clip = clip_factory("smooth", width=W, height=H, frames=20, fmt="images")
    first = read_boxes(clip.gt, origin=1)[0]  # vtrack scene writes OTB's 1-based boxes
    for name, box_file in (("otb", "groundtruth_rect.txt"), ("picked", "init.txt")):
        shutil.copytree(clip.path / "img", tmp_path / name / "seq")
        shutil.copy(clip.gt, tmp_path / name / "seq" / box_file)
    (tmp_path / "picked" / "seq" / "init.txt").write_text(first.text() + "\n")
    for name in ("otb", "picked"):
        out = tmp_path / f"out-{name}"
        result = batch(str(tmp_path / name), "-c", "s0", "--no-video", "-o", str(out))
        assert result.exit_code == 0, result.output
        record = json.loads((out / "seq" / "s0" / "run.json").read_text())
        assert record["init"] == pytest.approx([first.x, first.y, first.w, first.h]), name


def test_an_empty_img_folder_beside_flat_images_does_not_hide_them(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A sequence of images directly in its folder beside its groundtruth_rect.txt and an
    empty img/ was refused: `vtrack run seq` said 'seq: no images (...) in the folder or its
    img/ (img1/, color/)' and `vtrack batch` 'no inputs', as the first of img/, img1/, color/
    that existed was taken, empty or not. The first that holds images is taken now."""
    from vtrack.evaluate import read_boxes

    clip = clip_factory("smooth", width=W, height=H, frames=20, fmt="images")
    first = read_boxes(clip.gt, origin=1)[0]
    sequence = tmp_path / "in" / "seq"
    shutil.copytree(clip.path / "img", sequence)
    shutil.copy(clip.gt, sequence / "groundtruth_rect.txt")
    (sequence / "img").mkdir()
    result = batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-o", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    record = json.loads((tmp_path / "out" / "seq" / "s0" / "run.json").read_text())
    assert record["summary"]["frames"] == 20
    assert record["init"] == pytest.approx([first.x, first.y, first.w, first.h])
    ran = CliRunner().invoke(main, ["run", str(sequence), "-c", "s0", "--no-video", "--gt",
                                    str(sequence / "groundtruth_rect.txt"), "-o",
                                    str(tmp_path / "run")], catch_exceptions=False)
    assert ran.exit_code == 0, ran.output
    assert json.loads((tmp_path / "run" / "run.json").read_text())["summary"]["frames"] == 20


def test_a_batch_run_from_an_init_box_records_the_origin_vtrack_run_does(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """A sequence folder without ground truth (its first box from init.txt, 0-based whatever
    the origin) was found with gt_origin 1, which its run.json recorded ('gt_origin': 1 for a
    run with no ground truth) where `vtrack run` of the same folder records 0."""
    from vtrack.evaluate import read_boxes

    clip = clip_factory("smooth", width=W, height=H, frames=20, fmt="images")
    first = read_boxes(clip.gt, origin=1)[0]
    sequence = tmp_path / "in" / "seq"
    shutil.copytree(clip.path / "img", sequence / "img")
    (sequence / "init.txt").write_text(first.text() + "\n")
    result = batch(str(tmp_path / "in"), "-c", "s0", "--no-video", "-o", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    ran = CliRunner().invoke(main, ["run", str(sequence), "-c", "s0", "--no-video", "-o",
                                    str(tmp_path / "run")], catch_exceptions=False)
    assert ran.exit_code == 0, ran.output
    records = [json.loads((out / "run.json").read_text())["request"]
               for out in (tmp_path / "out" / "seq" / "s0", tmp_path / "run")]
    assert [r["gt_origin"] for r in records] == [0, 0]
    assert records[0]["init"] == pytest.approx(list(first))


def test_jobs_beyond_what_the_memory_holds_start_fewer_workers_saying_so(
        tmp_path: Path, clip_factory: ClipFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack batch --jobs 512` started a worker per run to do, whatever the memory: 500 runs
    of ~75 MB workers wanted ~37 GB, and the OOM killer ended the batch. The workers are bounded
    by what the memory available holds (here 2 of WORKER_MEMORY), in one warning line that
    counts the runs to do when they are fewer than --jobs, and says when the memory holds not
    even one worker (one starts); a batch that needs no more than that says nothing."""
    from vtrack.cli import batch as batch_command
    WORKER_MEMORY = 100 * 2**20  # (vtrack.machine.WORKER_MEMORY)

    started: list[int] = []

    class Counted(LocalExecutor):
        def __init__(self, workers: int, **kwargs: object) -> None:
            started.append(workers)
            super().__init__(workers, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr("vtrack.batch.LocalExecutor", Counted)
    monkeypatch.setattr(batch_command, "available_memory", lambda: WORKER_MEMORY * 5 // 2,
                        raising=False)
    folder = tmp_path / "in"
    folder.mkdir()
    for n, scenario in enumerate(("smooth", "jump", "bounce")):
        add_clip(folder, clip_factory, scenario, f"c{n}")
    result = batch(str(folder), "-c", "s0", "--no-video", "-q", "--jobs", "512", "-o",
                   str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert started == [2]
    assert result.stderr.splitlines() == [  # (it said "not 512" of 3 runs to do)
        "vtrack: warning: --jobs 512: starting 2 workers, not 3 (one per run to do): the "
        "memory available (0.2 GiB) holds about 2 of 100 MiB each"]
    assert {row["status"] for row in summary(tmp_path / "out").values()} == {"complete"}
    (folder / "c2.mp4").unlink()  # two runs to do: the two workers it holds, no warning
    again = batch(str(folder), "-c", "s0", "--no-video", "-q", "--jobs", "512", "--force",
                  "-o", str(tmp_path / "again"))
    assert again.exit_code == 0 and again.stderr == "", again.output
    # less than one worker's memory: one starts (it said "holds about 1" of 0.0 GiB)
    monkeypatch.setattr(batch_command, "available_memory", lambda: 60 * 2**20)
    scarce = batch(str(folder), "-c", "s0", "--no-video", "-q", "--jobs", "2", "--force",
                   "-o", str(tmp_path / "again"))
    assert scarce.exit_code == 0, scarce.output
    assert started == [2, 2, 1]
    assert scarce.stderr.splitlines() == [
        "vtrack: warning: --jobs 2: too little memory for one worker of 100 MiB (the memory "
        "available: 60 MiB): starting 1, not 2"]


def test_a_local_batch_shares_the_cores_among_the_workers_it_starts(
        tmp_path: Path, clip_factory: ClipFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack batch in/ -c s0 --jobs 4` of one input started one worker (one per run to do)
    yet gave its run the cores over 4 OpenCV threads (on 2 cores: 1, one core idle; with the
    default --jobs, the cores over the cores: 1). The cores are now shared among the workers
    that start: one run takes them all, two runs half each (run.json's
    timing.opencv_threads). The batch takes this machine as 8 cores (the batch reads
    vtrack.batch's cpu_count when it starts its workers), so the shares differ from one
    worker's on any machine, 1 core too."""
    import vtrack.batch
    from vtrack.cli import batch as batch_command

    cores = 8
    monkeypatch.setattr(vtrack.batch, "cpu_count", lambda: cores)
    monkeypatch.setattr(batch_command, "available_memory", lambda: None)  # (not a bound)
    folder = tmp_path / "in"
    folder.mkdir()
    add_clip(folder, clip_factory, "smooth", "c0")

    def threads(out: Path, name: str = "c0") -> int:
        record = json.loads((out / name / "s0" / "run.json").read_text())
        return record["timing"]["opencv_threads"]

    for name, jobs, workers in (("four", ("--jobs", "4"), 4), ("default", (), cores)):
        done = batch(str(folder), "-c", "s0", *jobs, "--no-video", "-q", "-o",
                     str(tmp_path / name))
        assert done.exit_code == 0, done.output
        runs = 1
        assert threads(tmp_path / name) == cores // min(workers, runs), name  # 8, not 2 or 1
    add_clip(folder, clip_factory, "jump", "c1")
    two = batch(str(folder), "-c", "s0", "--jobs", "4", "--no-video", "-q", "-o",
                str(tmp_path / "two"))
    assert two.exit_code == 0, two.output
    assert [threads(tmp_path / "two", name) for name in ("c0", "c1")] == \
        [cores // min(4, 2)] * 2  # 4 each, not 8 // 4 = 2


def test_a_dask_jobs_thread_guess_never_fails_the_job(
        caplog: pytest.LogCaptureFixture) -> None:
    """A Dask job's OpenCV threads are its worker's cores over the tasks the workers at its
    host run at once, as the scheduler lists them. An error there other than OSError,
    KeyError or ValueError (an entry whose nthreads is None: TypeError; anything the client
    raises) failed every job of the batch, though it only spoils that guess: the count is now
    the worker's own tasks, with a warning and its traceback in the worker's log."""
    from vtrack.batch.worker import tasks_at_host

    here, there = "tcp://10.0.0.5:4001", "tcp://10.0.0.6:4001"
    workers = {here: {"host": "10.0.0.5", "nthreads": 1},
               "tcp://10.0.0.5:4002": {"host": "10.0.0.5", "nthreads": 2},
               there: {"host": "10.0.0.6", "nthreads": 4}}
    assert tasks_at_host(here, 1, lambda: workers) == 3
    assert tasks_at_host(there, 4, lambda: workers) == 4
    assert caplog.records == []

    def closing() -> dict:
        raise RuntimeError("the client is closing")

    broken = {here: {"host": "10.0.0.5", "nthreads": None}}
    for listed, error in ((closing, RuntimeError), (lambda: broken, TypeError),
                          (lambda: {}, KeyError)):
        caplog.clear()
        with caplog.at_level("WARNING", logger="distributed.worker"):
            assert tasks_at_host(here, 2, listed) == 2
        [record] = caplog.records
        assert record.name == "distributed.worker" and record.levelname == "WARNING"
        assert "this worker's 2 tasks" in record.getMessage()
        assert record.exc_info is not None and record.exc_info[0] is error


def test_a_jobs_opencv_threads_come_from_the_machine_that_runs_it(
        tmp_path: Path, clip_factory: ClipFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack batch in/ --scheduler ADDRESS` read this machine's free memory to cap
    `workers`, which set the jobs' OpenCV threads (cpu_count() // workers), and the Dask
    executor then gave every job 1 thread whatever the worker's machine: a worker of 1 task on
    a 2-core machine ran with 1. The local pool keeps its memory cap (its threads: the cores
    over its workers); with a scheduler the local memory is not read, and each job's threads
    are its worker's machine's cores over the tasks its workers there run at once
    (run.json's timing.opencv_threads says how many it had): 2 workers of 1 task, the cores
    over 2."""
    distributed = pytest.importorskip("distributed")
    from vtrack.cli import batch as batch_command
    from vtrack.machine import cpu_count

    if cpu_count() < 2:  # (the workers' own cores: a worker process cannot be patched here)
        pytest.skip("1 core: the cores over 2 workers is 1, as a worker taking them all")
    asked: list[str] = []

    def scarce() -> int:  # room for one local worker of 100 MiB
        asked.append("memory")
        return 60 * 2**20

    monkeypatch.setattr(batch_command, "available_memory", scarce)
    folder = tmp_path / "in"
    folder.mkdir()
    add_clip(folder, clip_factory, "smooth", "c0")

    def threads(out: Path) -> int:
        record = json.loads((out / "c0" / "s0" / "run.json").read_text())
        return record["timing"]["opencv_threads"]

    # two workers of one task on this machine: whichever runs the job shares its cores with
    # the other (a worker counting only its own task would take them all)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        remote = batch(str(folder), "-c", "s0", "--scheduler", cluster.scheduler_address,
                       "--no-video", "-q", "-o", str(tmp_path / "dask"))
    assert remote.exit_code == 0, remote.output
    assert asked == []  # this machine's memory is not read for the cluster's workers
    assert threads(tmp_path / "dask") == max(1, cpu_count() // 2)
    local = batch(str(folder), "-c", "s0", "--no-video", "-q", "--jobs", "2", "-o",
                  str(tmp_path / "local"))
    assert local.exit_code == 0, local.output
    assert asked == ["memory"] and threads(tmp_path / "local") == cpu_count()  # 1 worker
