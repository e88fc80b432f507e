"""SIGTERM (``kill``, ``timeout``, ``docker stop``) to the commands that write files without a
run's record, ``vtrack scene`` and ``vtrack report``: handled as Ctrl-C, so the files they
stage under temporary names are removed and the command ends ``vtrack: interrupted``, exit
143. The commands run as a user runs them, in subprocesses."""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from conftest import START_BOUND_S, sigterm_as_called, wait_for_stop_handlers

if TYPE_CHECKING:
    from conftest import ClipFactory


def _terminated(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """``vtrack ARGS`` sent SIGTERM once it handles it (its start-up over, its work begun)."""
    process = subprocess.Popen([sys.executable, "-m", "vtrack", *args], cwd=cwd,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for_stop_handlers(process)
        process.send_signal(signal.SIGTERM)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def _files(folder: Path) -> list[str]:
    """Every file under ``folder``, hidden ones too."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def test_sigterm_to_vtrack_scene_leaves_no_temporary_clip(tmp_path: Path) -> None:
    """`vtrack scene smooth c.mp4 --frames 3000` sent SIGTERM died at once (exit -15, not a
    word) and left its half-written '.c.tmp-PID-XXXX.mp4' beside (an image folder: a hidden
    folder of the JPEGs written so far)."""
    result = _terminated(["scene", "smooth", "c.mp4", "--frames", "3000"], tmp_path)
    assert result.returncode == 143, result.stderr
    assert result.stderr.strip().splitlines()[-1] == "vtrack: interrupted"
    assert "Traceback" not in result.stderr
    assert _files(tmp_path) == []


def test_sigterm_to_vtrack_scene_leaves_no_folder_it_created(tmp_path: Path) -> None:
    """`vtrack scene smooth d/e --format images` sent SIGTERM left the folders it had created,
    d/ and d/e/, empty; those that were there before (tmp_path) stay."""
    result = _terminated(["scene", "smooth", "d/e", "--format", "images", "--frames", "3000"],
                         tmp_path)
    assert result.returncode == 143, result.stderr
    assert result.stderr.strip().splitlines()[-1] == "vtrack: interrupted"
    assert list(tmp_path.iterdir()) == []


def test_sigterm_to_vtrack_report_leaves_no_staged_plot(clip_factory: ClipFactory,
                                                        tmp_path: Path) -> None:
    """`vtrack report RESULTS -o rep` sent SIGTERM died at once (exit -15, not a word) and
    left the plots it had staged ('plots/.curves_a.tmp-PID-XXXX.png' ...) in the report
    folder; `-o new/rep`, a folder it made, left new/rep/plots/ empty: it is removed, the
    folder that was there is not."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    for name in ("a", "b", "c"):
        clip = clip_factory("smooth", width=160, height=120, frames=40)
        shutil.copy(clip.path, inputs / f"{name}.mp4")
        shutil.copy(clip.gt, inputs / f"{name}.gt.txt")
    batch = subprocess.run([sys.executable, "-m", "vtrack", "batch", "in", "-c", "s0", "-c",
                            "s2", "--jobs", "2", "--no-video", "-o", "results"], cwd=tmp_path,
                           capture_output=True, text=True, timeout=300, check=False)
    assert batch.returncode == 0, batch.stderr
    (tmp_path / "rep").mkdir()
    result = _terminated_while_staging(["report", "results", "-o", "rep"], tmp_path,
                                       tmp_path / "rep" / "plots")
    assert result.returncode == 143, result.stderr
    assert result.stderr.strip().splitlines()[-1] == "vtrack: interrupted"
    assert "Traceback" not in result.stderr
    assert _files(tmp_path / "rep") == []
    assert (tmp_path / "rep").is_dir()
    result = _terminated_while_staging(["report", "results", "-o", "new/rep"], tmp_path,
                                       tmp_path / "new" / "rep" / "plots")
    assert result.returncode == 143, result.stderr
    assert not (tmp_path / "new").exists()


def _terminated_while_staging(args: list[str], cwd: Path, out: Path) -> subprocess.CompletedProcess:
    """``vtrack ARGS`` sent SIGTERM once it handles it and has staged a file in ``out`` (a
    hidden temporary name): part way through its writing."""
    process = subprocess.Popen([sys.executable, "-m", "vtrack", *args], cwd=cwd,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for_stop_handlers(process)
        deadline = time.monotonic() + START_BOUND_S
        while not (out.is_dir() and any(p.name.startswith(".") for p in out.iterdir())):
            assert process.poll() is None, "vtrack ended before it staged a file"
            assert time.monotonic() < deadline, "vtrack staged no file within the time"
            time.sleep(0.01)
        process.send_signal(signal.SIGTERM)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def test_sigterm_to_vtrack_vectors_leaves_the_earlier_vectors_whole(clip_factory: ClipFactory,
                                                                    tmp_path: Path) -> None:
    """`vtrack vectors c.mp4 --frames 300 --out v` sent SIGTERM died at once (exit -15, not a
    word) leaving v/frame_0000 ... half of them, the last with rgb.hex but no hue.hex, a
    trace.csv cut short and no manifest.json, beside what was left of earlier vectors. It now
    ends 'vtrack: interrupted' (143) with the earlier vectors as they were, no temporary file,
    and no folder it created (--out new/v)."""
    clip = clip_factory("smooth", width=640, height=480, frames=300)
    box = clip.scene.boxes[0]
    vectors = ["vectors", str(clip.path), "--init", f"{box.x},{box.y},{box.w},{box.h}"]
    earlier = subprocess.run([sys.executable, "-m", "vtrack", *vectors, "--frames", "2",
                              "-o", "v"], cwd=tmp_path, capture_output=True, text=True,
                             timeout=120, check=False)
    assert earlier.returncode == 0, earlier.stderr
    before = {name: (tmp_path / "v" / name).read_bytes() for name in _files(tmp_path / "v")}
    result = _terminated_while_staging([*vectors, "--frames", "300", "-o", "v"], tmp_path,
                                       tmp_path / "v")
    assert result.returncode == 143, result.stderr
    assert result.stderr.strip().splitlines()[-1] == "vtrack: interrupted"
    assert "Traceback" not in result.stderr
    after = {name: (tmp_path / "v" / name).read_bytes() for name in _files(tmp_path / "v")}
    assert after == before
    result = _terminated_while_staging([*vectors, "--frames", "300", "-o", "new/v"], tmp_path,
                                       tmp_path / "new" / "v")
    assert result.returncode == 143, result.stderr
    assert not (tmp_path / "new").exists()


def test_sigterm_while_vtrack_scene_makes_its_scene_says_interrupted(tmp_path: Path) -> None:
    """`vtrack scene smooth c.mp4 --frames 108000` spends its first seconds making the scene
    (measuring every frame's ground truth) before it writes a frame; SIGTERM then killed it
    without a word (exit 143, stderr empty): its stop handlers came only with the writing.
    The clip's name here is one the writing refuses (.xyz), so the command's handlers are in
    place only while the scene is made: the signal must land there."""
    result = _terminated(["scene", "smooth", "c.xyz", "--frames", "108000"], tmp_path)
    assert result.returncode == 143, result.stderr
    assert result.stderr.strip().splitlines()[-1] == "vtrack: interrupted"
    assert "Traceback" not in result.stderr
    assert _files(tmp_path) == []


def test_a_signal_once_the_files_go_in_place_changes_nothing() -> None:
    """`stopping_as_interrupted()` raised Interrupted for a signal at any point of its block,
    also once the block's staged files were put in place (vtrack vectors then closed its
    input, vtrack report removed stale plots): the files were final and the command ended
    'interrupted' (143). The block's ``settled()`` now ends that: a signal after it is
    ignored, and the block runs to its end."""
    import os

    import click
    from click.testing import CliRunner

    from vtrack.cli._signals import stopping_as_interrupted

    steps: list[str] = []

    @click.command()
    def settle() -> None:
        with stopping_as_interrupted() as settled:
            settled()
            os.kill(os.getpid(), signal.SIGTERM)
            steps.append("after the signal")

    result = CliRunner().invoke(settle, [])
    assert result.exception is None, result.output
    assert steps == ["after the signal"]



def test_a_command_of_its_own_process_never_has_the_default_sigterm_after_its_files() -> None:
    """`vtrack vectors ... -o v` sent SIGTERM as soon as v/manifest.json appeared was killed
    (exit -15, not a word) 1 run in 6: as the block ended its previous handlers (the
    default's, which kills) were put back, and only then were the signals ignored. They now
    go from vtrack's handler (or ignored) straight to ignored. Seen line by line: SIGTERM's
    handler at every line run in the block's code, from its handler's install to its end."""
    import click
    from click.testing import CliRunner

    from vtrack.cli._signals import stopping_as_interrupted

    seen: list[object] = []

    def trace(frame, event, arg):
        if frame.f_code.co_filename.endswith(("_signals.py", "errors.py")):
            seen.append(signal.getsignal(signal.SIGTERM))
            return trace
        return None

    @click.command()
    def settle() -> None:
        with stopping_as_interrupted():
            pass

    settle.owns_process = True  # as the vtrack command: a process of its own
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        sys.settrace(trace)
        try:
            result = CliRunner().invoke(settle, [])
        finally:
            sys.settrace(None)
        assert result.exception is None, result.output
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    handled = [i for i, h in enumerate(seen) if h not in (signal.SIG_DFL, None)]
    assert handled, seen
    assert signal.SIG_DFL not in seen[handled[0]:], seen


def test_a_batch_called_in_a_host_process_gives_it_its_signal_handlers_back(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """vtrack batch called in a host's process (click's test runner, a library) left SIGINT
    and SIGTERM ignored once it was done, as the vtrack command does until it exits: the
    host's Ctrl-C did nothing from then on. It now puts back the host's handlers, as vtrack
    run and the other commands do."""
    from click.testing import CliRunner

    from vtrack.cli import main

    clip = clip_factory("smooth", width=64, height=48, frames=10)
    (tmp_path / "in").mkdir()
    shutil.copy(clip.path, tmp_path / "in" / "a.mp4")
    shutil.copy(clip.gt, tmp_path / "in" / "a.gt.txt")

    def host(signum: int, frame: object) -> None:  # the host's own handler
        raise AssertionError("no signal is sent")

    previous = {s: signal.signal(s, host) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        result = CliRunner().invoke(main, ["batch", str(tmp_path / "in"), "-c", "s0",
                                           "--no-video", "-j", "1",
                                           "-o", str(tmp_path / "out")])
        assert result.exit_code == 0, result.output
        assert signal.getsignal(signal.SIGINT) is host
        assert signal.getsignal(signal.SIGTERM) is host
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def test_a_signal_as_vtrack_scene_puts_its_files_in_place_changes_nothing(tmp_path: Path
                                                                           ) -> None:
    """`vtrack scene smooth c.mp4` sent SIGTERM as it renamed its staged files into place
    (the clip, then c.gt.txt) stopped there, 'vtrack: interrupted' (143), part way through
    the renames (a signal after them: the files final, and the command still said
    interrupted). Once the files start to go in place a signal changes nothing now: exit 0,
    both files there. The signal is sent to the main thread as the first rename begins (a
    trace function)."""
    from click.testing import CliRunner

    from vtrack.cli import main
    from vtrack.io import files

    with sigterm_as_called(files._rename_over.__code__):
        result = CliRunner().invoke(main, ["scene", "smooth", str(tmp_path / "c.mp4"),
                                           "--frames", "10", "--size", "64x48"])
    assert result.exit_code == 0, result.output
    assert sorted(_files(tmp_path)) == ["c.gt.txt", "c.mp4"]
