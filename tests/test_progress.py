"""Progress you can read (issue 12 item 3): the bars as a user sees them in a terminal.

Each command runs as a real subprocess whose stderr is a pseudo-terminal (``pty``), so tqdm
draws exactly what it draws for a user; the captured text is checked for the total, the
percentage and the ETA, and for the absence of any bar before an input error.
"""

from __future__ import annotations

import fcntl
import json
import os
import pty
import re
import struct
import subprocess
import sys
import termios
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from vtrack.configs import DEFAULT_CONFIG
from vtrack.scenes import make_scene, write_groundtruth, write_video

if TYPE_CHECKING:
    from conftest import ClipFactory

FRAMES = 24


def in_terminal(*args: str, cwd: Path) -> tuple[int, str]:
    """Run ``vtrack ARGS`` with stderr on a 120x40 pseudo-terminal; its exit code and what the
    terminal received."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    process = subprocess.Popen([sys.executable, "-m", "vtrack", *args], cwd=cwd,
                               stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                               stderr=slave)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # EIO: the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    return process.wait(timeout=60), b"".join(chunks).decode(errors="replace")


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("progress")
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=FRAMES, fps=30)
    path = write_video(scene, folder / "walk.mp4")
    write_groundtruth(scene, folder / "walk.gt.txt")
    return path


def test_run_bar_shows_total_percent_rate_and_eta(clip: Path, tmp_path: Path) -> None:
    code, screen = in_terminal("run", str(clip), "--gt", str(clip.with_suffix(".gt.txt")),
                               "--no-video", "--out", "out", cwd=tmp_path)
    assert code == 0, screen
    assert f"{FRAMES}/{FRAMES}" in screen and "100%" in screen
    # tqdm's "[elapsed<remaining, rate]": the ETA and the rate are there
    assert re.search(r"\[\d\d:\d\d<\d\d:\d\d, +[\d.]+ ?frame/s\]", screen), screen
    assert re.search(rf"{re.escape(str(clip))}: +\d+%\|", screen), screen  # as given


def test_run_bar_total_is_capped_by_frames(clip: Path, tmp_path: Path) -> None:
    code, screen = in_terminal("run", str(clip), "--gt", str(clip.with_suffix(".gt.txt")),
                               "--no-video", "--frames", "10", "--out", "out", cwd=tmp_path)
    assert code == 0, screen
    assert "10/10" in screen and f"/{FRAMES}" not in screen


def test_an_input_error_prints_no_bar(tmp_path: Path) -> None:
    code, screen = in_terminal("run", "missing.mp4", "--init", "1,1,5,5", cwd=tmp_path)
    assert code == 2
    assert screen.strip() == "vtrack: error: missing.mp4: no such file"


def test_a_box_outside_the_frame_prints_no_bar(clip: Path, tmp_path: Path) -> None:
    code, screen = in_terminal("run", str(clip), "--init", "500,500,10,10", cwd=tmp_path)
    assert code == 2
    assert "frame/s" not in screen and "%|" not in screen and "0frame" not in screen
    assert screen.strip().startswith("vtrack: error: --init")


def test_batch_bar_counts_frames_of_all_runs_with_eta(clip: Path, tmp_path: Path) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("a", "b"):
        (folder / f"{name}.mp4").write_bytes(clip.read_bytes())
        (folder / f"{name}.gt.txt").write_bytes(clip.with_suffix(".gt.txt").read_bytes())
    args = ("batch", str(folder), "--no-video", "--jobs", "1", "--out", "res")
    code, screen = in_terminal(*args, cwd=tmp_path)
    assert code == 0, screen
    assert f"{2 * FRAMES}/{2 * FRAMES}" in screen and "100%" in screen and "2/2 runs" in screen
    assert re.search(r"\[\d\d:\d\d<\d\d:\d\d", screen), screen
    # runs complete before (resume) are not counted: the bar is the runs to do
    code, screen = in_terminal(*args, "--config", DEFAULT_CONFIG, "--config", "s2",
                               cwd=tmp_path)
    assert code == 0, screen
    assert f"{2 * FRAMES}/{2 * FRAMES}" in screen and "2/2 runs" in screen, screen


def test_a_tracker_that_cannot_start_prints_no_bar(clip: Path, tmp_path: Path) -> None:
    """S0 refuses a box with no colour on the first frame: the error comes alone."""
    grey = tmp_path / "grey.mp4"
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=12, fps=30)
    write_video(scene, grey)
    code, screen = in_terminal("run", str(grey), "-c", "s0", "--init", "0,0,12,12", "--no-video",
                               cwd=tmp_path)
    assert code != 0, "the grey background corner should have no colour for S0"
    assert "%|" not in screen and "frame/s" not in screen, screen
    assert screen.strip().startswith("vtrack: error:")


def test_report_shows_its_progress_through_the_inputs(clip: Path, tmp_path: Path) -> None:
    """`vtrack report` of a large batch drew its plots for minutes without a word (~1.4 s an
    input); now a bar counts the inputs in a terminal, lines do in a log, --quiet is silent."""
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("a", "b", "c"):
        (folder / f"{name}.mp4").write_bytes(clip.read_bytes())
        (folder / f"{name}.gt.txt").write_bytes(clip.with_suffix(".gt.txt").read_bytes())
    batch = subprocess.run([sys.executable, "-m", "vtrack", "batch", str(folder), "-c", "s0",
                            "--no-video", "--jobs", "2", "-q", "--out", "res"], cwd=tmp_path,
                           capture_output=True, timeout=300, check=False)
    assert batch.returncode == 0, batch.stderr
    code, screen = in_terminal("report", "res", "--out", "rep", cwd=tmp_path)
    assert code == 0, screen
    assert "3/3" in screen and "100%" in screen and re.search(r"report: +\d+%\|", screen)
    logged = subprocess.run([sys.executable, "-m", "vtrack", "report", "res", "--out", "rep2",
                             "--stats-period", "0"], cwd=tmp_path, capture_output=True,
                            timeout=300, check=False, text=True)
    assert logged.returncode == 0, logged.stderr
    lines = [line for line in logged.stderr.splitlines() if line.startswith("report: ")]
    assert [line.split(" inputs")[0] for line in lines] == [
        "report: 1/3", "report: 2/3", "report: 3/3"]
    assert all(re.search(r"[\d.]+ inputs/s", line) for line in lines), lines
    quiet = subprocess.run([sys.executable, "-m", "vtrack", "report", "res", "--out", "rep3",
                            "--stats-period", "0", "-q"], cwd=tmp_path, capture_output=True,
                           timeout=300, check=False, text=True)
    assert quiet.returncode == 0 and quiet.stderr == "" and quiet.stdout == ""


def test_a_progress_line_counts_the_first_frames_time_in_its_rate(
        clip_factory: ClipFactory, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`--stats-period 0` printed '1/N frames, 306184.7 fps' after the first frame: the rate's
    clock started once that frame was done. A line's rate is now the run's frames over its
    seconds as ``run.json``'s ``timing.seconds`` counts them (from before the first frame is
    read): after the last frame, the summary line's fps."""
    from vtrack.cli._progress import FrameProgress
    from vtrack.config import load_config
    from vtrack.geometry import Box
    from vtrack.request import RunRequest
    from vtrack.run import run

    clip = clip_factory("smooth", width=160, height=120, frames=10)
    progress = FrameProgress(quiet=False, period=0)
    calls: list[tuple[int, float, float]] = []
    opened: list[float] = []

    def on_open(info: object) -> None:
        progress.on_open(info)
        opened.append(time.monotonic())

    def on_frame(done: int, seconds: float) -> None:
        calls.append((done, seconds, time.monotonic()))
        progress.on_frame(done, seconds)

    summary = run(RunRequest(str(clip.path), tmp_path / "out", load_config("s0"),
                             init_box=Box(*clip.scene.boxes[0]), video=False),
                  on_frame=on_frame, on_open=on_open)
    lines = capsys.readouterr().err.splitlines()
    assert [done for done, _, _ in calls] == list(range(1, 11))
    assert 0 < calls[0][1] <= calls[0][2] - opened[0]  # the first frame's time counted
    assert [s for _, s, _ in calls] == sorted(s for _, s, _ in calls)
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert calls[-1][1] == record["timing"]["seconds"] == summary.seconds
    assert lines[0].startswith(f"{clip.path}: 1/10 frames"), lines
    assert lines[-1].startswith(f"{clip.path}: 10/10 frames (100%), {summary.fps:.1f} fps, "), \
        (lines[-1], summary.line())
