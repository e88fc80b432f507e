"""`vtrack report` on results it cannot show whole (probe 49): runs of a live input whose frames
are gone, a batch still writing its folder, batch rows whose results folder was removed. Every
input is made here: generated clips run by `vtrack run` and `vtrack batch`."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vtrack.io.outdir import OutputFolder
from vtrack.io.specs import input_name
from vtrack.scenes import make_scene, write_groundtruth, write_video

W, H = 160, 120


def vtrack(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``python -m vtrack ARGS`` as a user runs it (a whole process: exit code, stderr)."""
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, timeout=300, check=False, cwd=cwd)


def warnings_of(done: subprocess.CompletedProcess) -> list[str]:
    """The ``vtrack: warning:`` lines of a command that succeeded."""
    assert done.returncode == 0, done.stderr
    return [line.removeprefix("vtrack: warning: ") for line in done.stderr.splitlines()
            if line.startswith("vtrack: warning: ")]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run of a 60-frame occlusion clip with s0 and its ground truth (the target is missed:
    the report draws failure frames of it)."""
    folder = tmp_path_factory.mktemp("incomplete")
    scene = make_scene("occlusion", seed=0, width=W, height=H, frames=60, fps=30)
    video = write_video(scene, folder / "occlusion.mp4")
    gt = write_groundtruth(scene, folder / "occlusion.gt.txt")
    done = vtrack("run", str(video), "-c", "s0", "--gt", str(gt), "--no-video", "-q",
                  "-o", str(folder / "run"))
    assert done.returncode == 0, done.stderr
    return folder / "run"


def test_a_live_input_is_not_read_again_for_the_failure_frames(run: Path,
                                                                 tmp_path: Path) -> None:
    """The report reopened a run's udp:// / tcp:// / rtsp:// / http:// input to draw the failure
    frames: it drew what the sender sent now (another video), or waited 10 s per run for a
    sender that was gone. Now the input the run recorded is not read again: one note names
    the inputs whose failure frames are left out."""
    live = ["udp://127.0.0.1:9", "tcp://127.0.0.1:9", "rtsp://127.0.0.1:9/cam",
            "http://127.0.0.1:9/clip.mp4", "-"]
    for index, spec in enumerate(live):
        folder = tmp_path / "runs" / f"r{index}"
        shutil.copytree(run, folder)
        record = json.loads((folder / "run.json").read_text())
        record["request"]["input"] = record["input"]["path"] = spec
        record["input"]["name"] = input_name(spec)
        (folder / "run.json").write_text(json.dumps(record))
    done = vtrack("report", str(tmp_path / "runs"), "-o", str(tmp_path / "report"))
    names = ", ".join(sorted(input_name(spec) for spec in live))
    assert warnings_of(done) == [
        f"failure frames of 5 inputs left out: {names}: a stream, URL, stdin or device, read "
        "by the runs as it came and not read again (it would show what it sends now, not the "
        "frames tracked)"]
    plots = {p.name for p in (tmp_path / "report" / "plots").iterdir()}
    assert not [p for p in plots if p.startswith("failures_")]
    assert {f"overlap_{input_name(spec)}.png" for spec in live} <= plots  # the rest is there


def _holds(folder: Path, pid: int) -> bool:
    """Whether process ``pid`` has taken ``folder`` (its lock file names it)."""
    try:
        return (folder / ".vtrack.lock").read_text().startswith(f"pid {pid}: ")
    except OSError:
        return False


def test_a_report_of_a_folder_a_batch_still_writes_says_so(run: Path, tmp_path: Path) -> None:
    """A report made while a batch still ran into the folder was silently incomplete. Now one
    warning names the folder and that a batch is still writing it; a stale lock (left by a
    killed batch, held by no process) is no warning."""
    clips = tmp_path / "clips"
    clips.mkdir()
    shutil.copy(run.parent / "occlusion.mp4", clips)
    shutil.copy(run.parent / "occlusion.gt.txt", clips)
    res = tmp_path / "res"
    assert vtrack("batch", str(clips), "-c", "s0", "--no-video", "-q", "-j", "1",
                  "-o", str(res)).returncode == 0
    stale = res / ".vtrack.lock"
    stale.write_text("pid 1: vtrack batch clips -c s0\n")  # running pid, but nobody holds it
    assert warnings_of(vtrack("report", str(res), "-o", str(tmp_path / "r1"))) == []
    stale.unlink()

    # the batch's next run waits for its folder, held here: the batch holds its own
    with OutputFolder(res / "occlusion" / "camshift"):
        batch = subprocess.Popen([sys.executable, "-m", "vtrack", "batch", str(clips), "-c",
                                  "s0", "-c", "camshift", "--no-video", "-q", "-j", "1",
                                  "-o", str(res)], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
        try:
            deadline = time.monotonic() + 120  # a bound on the wait, not a measure
            while not _holds(res, batch.pid):
                assert batch.poll() is None and time.monotonic() < deadline
                time.sleep(0.05)
            os.kill(batch.pid, signal.SIGSTOP)  # it stays in the middle of its work
            try:
                assert _holds(res, batch.pid)
                done = vtrack("report", str(res), "-o", str(tmp_path / "r2"))
                report_of_one_run = vtrack("report", str(res / "occlusion" / "s0"), "-o",
                                           str(tmp_path / "r3"))
            finally:
                os.kill(batch.pid, signal.SIGCONT)
        except BaseException:
            batch.kill()
            raise
    batch.wait(timeout=300)
    expected = (f"{res.resolve()}: a batch is still writing it (pid {batch.pid}: vtrack batch "
                f"{clips} -c s0 -c camshift --no-video -q -j 1 -o {res}); this report shows "
                "only what it had finished")
    assert warnings_of(done) == [expected]
    assert warnings_of(report_of_one_run) == [expected]  # a folder inside it


def test_complete_batch_rows_whose_results_are_gone_are_named(run: Path, tmp_path: Path
                                                              ) -> None:
    """`cp -r res1 resR; rm -rf resR/occlusion; vtrack report resR`: the complete rows of the
    removed folder were dropped silently. Now one warning per summary.csv names them."""
    clips = tmp_path / "clips"
    clips.mkdir()
    for name in ("occlusion.mp4", "occlusion.gt.txt"):
        shutil.copy(run.parent / name, clips)
        shutil.copy(run.parent / name, clips / name.replace("occlusion", "other"))
    res = tmp_path / "res"
    assert vtrack("batch", str(clips), "-c", "s0", "-c", "camshift", "--no-video", "-q",
                  "-j", "1", "-o", str(res)).returncode == 0
    assert warnings_of(vtrack("report", str(res), "-o", str(tmp_path / "whole"))) == []
    shutil.rmtree(res / "occlusion")
    done = vtrack("report", str(res), "-o", str(tmp_path / "part"))
    assert warnings_of(done) == [
        f"{res / 'summary.csv'}: 2 complete runs listed without results here (no run.json in "
        "<input>/<config>/: moved or removed): occlusion [camshift], occlusion [s0]; not in "
        "this report"]
    assert "2 runs" in done.stdout  # the other input's
