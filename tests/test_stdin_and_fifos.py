"""Standard input, FIFOs and growing files at their edges: a signal while FFmpeg reads or opens
them, stdin closed or a terminal, a --stream FIFO nobody reads, --follow where it cannot apply
(found by a hostile probe)."""

from __future__ import annotations

import contextlib
import csv
import fcntl
import json
import os
import pty
import shutil
import signal
import socket
import subprocess
import sys
import termios
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from conftest import START_BOUND_S, run_after_start, wait_for_stop_handlers

from vtrack.io import follow
from vtrack.io.follow import GrowingFile
from vtrack.scenes import make_scene, write_clip, write_groundtruth, write_video

FEEDER = """if True:
    import sys, time
    data = open(sys.argv[1], 'rb').read()
    try:
        for at in range(0, len(data), 200):
            sys.stdout.buffer.write(data[at:at + 200]); sys.stdout.buffer.flush(); time.sleep(0.1)
    except BrokenPipeError:
        pass"""


def _vtrack(args: list[str], **kwargs: object) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "vtrack", "run", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            **kwargs)  # type: ignore[call-overload]


def _signalled(run: subprocess.Popen, signum: int, after_s: float) -> bytes:
    try:
        wait_for_stop_handlers(run)
        time.sleep(after_s)  # reading (or opening) its input, whatever the exact moment
        run.send_signal(signum)
        _, stderr = run.communicate(timeout=60)
    finally:
        run.kill()
    return stderr


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_a_slow_pipe_is_read_interrupts_the_run(tmp_path: Path,
                                                               signum: int) -> None:
    """A container trickling in on stdin: Ctrl-C or SIGTERM was printed as an ignored
    exception inside FFmpeg's read and lost; the run went on to the end of the feed and said
    `complete` (exit 0), with a "damaged frame" the cut read had made."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=60, fps=30)
    clip = write_video(scene, tmp_path / "clip.ts", preset="veryfast")
    feeder = subprocess.Popen([sys.executable, "-c", FEEDER, str(clip)], stdout=subprocess.PIPE)
    try:
        run = _vtrack(["-", "-c", "s0", "--init", ",".join(f"{v:g}" for v in scene.boxes[0]),
                       "--no-video", "-o", str(tmp_path / "out")], stdin=feeder.stdout)
        stderr = _signalled(run, signum, 1.0)
    finally:
        feeder.kill()
        feeder.wait()
    assert run.returncode == 128 + signum, stderr
    assert b"interrupted" in stderr
    assert b"Exception ignored" not in stderr and b"Traceback" not in stderr
    assert b"damaged" not in stderr
    record = tmp_path / "out" / "run.json"
    if record.exists():  # the signal came after the first frame
        assert json.loads(record.read_text())["status"] == "interrupted"


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_a_fifo_waits_for_its_writer_interrupts_the_run(tmp_path: Path,
                                                                       signum: int) -> None:
    """FFmpeg's open of a FIFO no one writes to, cut by the signal, failed with EINTR: the run
    said "not a video FFmpeg can decode (Interrupted system call)" and exited 2."""
    fifo = tmp_path / "feed"
    os.mkfifo(fifo)
    run = _vtrack([str(fifo), "-c", "s0", "--init", "1,1,8,8", "--no-video", "-o",
                   str(tmp_path / "out")])
    stderr = _signalled(run, signum, 1.0)
    assert run.returncode == 128 + signum, stderr
    assert stderr.decode().strip() == "vtrack: interrupted"
    assert not (tmp_path / "out").exists()


def test_stream_into_a_fifo_no_reader_opens_ends_after_timeout(tmp_path: Path) -> None:
    """`--stream FIFO` waited for ever for a reader to open it (--timeout did not apply)."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=20, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    fifo = tmp_path / "lines"
    os.mkfifo(fifo)
    done = run_after_start([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s0",
                            "--init", ",".join(f"{v:g}" for v in scene.boxes[0]), "--no-video",
                            "--stream", str(fifo), "--timeout", "1", "-o",
                            str(tmp_path / "out")])
    assert done.returncode == 2, done.stderr
    assert done.stderr.decode().strip() == (f"vtrack: error: --stream {fifo}: a FIFO that no "
                                            "reader opened within 1 s (--timeout)")
    assert not (tmp_path / "out").exists()


def test_a_growing_file_ends_once_idle_for_its_time_in_all(tmp_path: Path,
                                                            monkeypatch: pytest.MonkeyPatch
                                                            ) -> None:
    """FFmpeg asks for more several times at the end of a followed file; each request waited
    the whole --follow time anew (--follow 2 ended ~9 s after the file stopped growing). Once
    the file has been idle that long since data last came, a read ends at once."""
    path = tmp_path / "grown.ts"
    path.write_bytes(b"x" * 1000)
    growing = GrowingFile(str(path), idle_s=0.2)
    buffer = bytearray(4096)
    assert growing.readinto(buffer) == 1000
    time.sleep(0.3)  # idle past --follow since the data came

    def no_waiting(seconds: float) -> None:
        raise AssertionError(f"waited {seconds} s more at an end already reached")

    monkeypatch.setattr(follow.time, "sleep", no_waiting)
    assert growing.readinto(buffer) == 0
    assert growing.readinto(buffer) == 0
    assert growing.interruption is None  # (a read keeps what is raised inside it)
    growing.close()


def test_follow_is_refused_where_it_cannot_apply(tmp_path: Path) -> None:
    """--follow was accepted and ignored for raw input, an image folder and stdin (run.json
    even recorded it)."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=10, fps=30)
    raw = write_clip(scene, tmp_path / "clip.raw", fmt="raw").clip
    folder = write_clip(scene, tmp_path / "seq", fmt="images").clip
    cases = [([str(raw), "--raw", "160x120"], "raw frames are read to the end"),
             ([str(folder)], "is an image folder"),
             (["-"], "stdin is read until its writer closes it"),
             (["udp://127.0.0.1:9"], "is a stream, read until it ends")]
    for args, reason in cases:
        done = subprocess.run([sys.executable, "-m", "vtrack", "run", *args, "--follow", "1",
                               "-c", "s0", "--init", "1,1,8,8", "-o", str(tmp_path / "out")],
                              capture_output=True, timeout=START_BOUND_S, check=False,
                              stdin=subprocess.DEVNULL)
        assert done.returncode == 2, (args, done.stderr)
        line = done.stderr.decode().strip()
        assert line.startswith("vtrack: error: --follow reads a video file that is still "
                               "being written;") and reason in line, line
        assert not (tmp_path / "out").exists()


def test_follow_is_refused_for_a_fifo_a_device_and_a_socket(tmp_path: Path) -> None:
    """`vtrack run FIFO --follow 1` tracked what its writer sent, then ended in a traceback
    (GrowingFile asked the FIFO where it was: 'OSError: [Errno 29] Illegal seek', exit 1,
    run.json 'failed'); /dev/zero with --follow was taken too. A FIFO is read until its
    writer closes it, as stdin is: --follow is refused for it, and for a device, before
    anything is read. A Unix socket was refused as "a device": it is called a socket."""
    fifo = tmp_path / "feed"
    os.mkfifo(fifo)
    sock_path = tmp_path / "sock"
    listening = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listening.bind(str(sock_path))
    clip = write_video(make_scene("smooth", seed=3, width=160, height=120, frames=10, fps=30),
                       tmp_path / "clip.ts")
    writer = subprocess.Popen([sys.executable, "-c", "import shutil, sys; shutil.copyfileobj("
                               "open(sys.argv[1], 'rb'), open(sys.argv[2], 'wb'))",
                               str(clip), str(fifo)], stderr=subprocess.DEVNULL)
    try:
        for spec, reason in ((fifo, f"{fifo} is a FIFO, read until its writer closes it"),
                             ("/dev/zero", "/dev/zero is a device, not a file being written"),
                             (sock_path, f"{sock_path} is a socket, not a file being written")):
            done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(spec), "--follow",
                                   "1", "--init", "1,1,8,8", "-o", str(tmp_path / "out")],
                                  capture_output=True, timeout=START_BOUND_S, check=False)
            assert done.returncode == 2, done.stderr
            assert done.stderr.decode().strip() == (
                "vtrack: error: --follow reads a video file that is still being written; "
                f"{reason}")
            assert not (tmp_path / "out").exists()
    finally:
        with contextlib.suppress(OSError):  # let a writer still waiting for a reader go on
            os.close(os.open(fifo, os.O_RDONLY | os.O_NONBLOCK))
        writer.kill()
        writer.wait()
        listening.close()


@pytest.mark.parametrize("raw", [False, True])
def test_stdin_closed_or_a_terminal_is_one_line(tmp_path: Path, raw: bool) -> None:
    """A closed stdin (`<&-`) was an AttributeError traceback; a terminal on stdin made a
    container read wait for ever (raw input was already refused)."""
    what = "raw frames" if raw else "a video"
    args = [sys.executable, "-m", "vtrack", "run", "-", *(["--raw", "160x120"] if raw else []),
            "-c", "s0", "--init", "1,1,8,8", "--no-video", "-o", str(tmp_path / "out")]
    closed = run_after_start(args, preexec_fn=lambda: os.close(0))
    assert closed.returncode == 2
    assert closed.stderr.decode().strip() == (f"vtrack: error: stdin is closed; pipe {what} "
                                              "into vtrack")
    leader, follower = pty.openpty()
    try:
        on_terminal = run_after_start(args, stdin=follower)
    finally:
        os.close(leader)
        os.close(follower)
    assert on_terminal.returncode == 2
    assert on_terminal.stderr.decode().strip() == (f"vtrack: error: stdin is a terminal; pipe "
                                                   f"{what} into vtrack")
    assert not (tmp_path / "out").exists()


def test_a_log_reader_that_goes_away_does_not_fail_the_run(tmp_path: Path) -> None:
    """Progress lines into a pipe whose reader left (`2>&1 | head -1`): the run failed with
    "[Errno 32] Broken pipe", naming nothing. The tracking is the product: it completes."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=150, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    run = subprocess.Popen([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s1",
                            "--init", ",".join(f"{v:g}" for v in scene.boxes[0]),
                            "--stats-period", "0.001", "-o", str(tmp_path / "out")],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        assert run.stderr is not None
        first = run.stderr.readline()
        run.stderr.close()  # the reader leaves after one line
        run.wait(timeout=120)
    finally:
        run.kill()
    assert b"frames" in first
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert record["status"] == "complete" and record["frames"] == 150
    assert run.returncode == 0  # the summary line it could not print is no failure


def test_a_summary_reader_that_goes_away_leaves_the_exit_status_to_the_run(
        tmp_path: Path) -> None:
    """`vtrack run ... | head -0`: the summary line met a closed stdout and the complete run
    exited 1, saying nothing."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=20, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    run = subprocess.Popen([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s0",
                            "--init", ",".join(f"{v:g}" for v in scene.boxes[0]), "--no-video",
                            "-o", str(tmp_path / "out")],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert run.stdout is not None and run.stderr is not None
    run.stdout.close()  # `| head -0`
    stderr = run.stderr.read()
    assert run.wait(timeout=120) == 0, stderr
    assert stderr == b""
    assert json.loads((tmp_path / "out" / "run.json").read_text())["status"] == "complete"


def test_a_summary_line_stdout_cannot_take_fails_the_run_in_one_line(tmp_path: Path) -> None:
    """`vtrack run ... > /dev/full`: the summary line met a full device (ENOSPC) and the run
    exited 0, saying nothing (the failed write was taken for a reader that went away)."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=20, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    with open("/dev/full", "wb") as full:
        done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s0",
                               "--init", ",".join(f"{v:g}" for v in scene.boxes[0]),
                               "--no-video", "-o", str(tmp_path / "out")],
                              stdout=full, stderr=subprocess.PIPE, timeout=120, check=False)
    assert done.returncode == 1
    assert done.stderr.decode() == ("vtrack: error: standard output: No space left on device: "
                                    "the summary line was not printed there\n")
    assert json.loads((tmp_path / "out" / "run.json").read_text())["status"] == "complete"


def _batch_folder(tmp_path: Path, clips: int) -> Path:
    """``clips`` short videos with their ground truth in ``tmp_path/in``."""
    folder = tmp_path / "in"
    folder.mkdir()
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=20, fps=30)
    clip = write_video(scene, folder / "c0.mp4")
    write_groundtruth(scene, folder / "c0.gt.txt")
    for n in range(1, clips):
        (folder / f"c{n}.mp4").write_bytes(clip.read_bytes())
        (folder / f"c{n}.gt.txt").write_bytes((folder / "c0.gt.txt").read_bytes())
    return folder


def _statuses(out: Path) -> list[str]:
    with (out / "summary.csv").open(newline="") as handle:
        return [row["status"] for row in csv.DictReader(handle)]


def test_a_batch_whose_stdout_reader_went_away_runs_on(tmp_path: Path) -> None:
    """`vtrack batch in/ -c s0 -j 1 | head -1`: the second run's line met the closed pipe and
    the batch stopped there, saying nothing, exit 1: the runs not started were `interrupted`
    in summary.csv ("never ran (the batch stopped first)"). As `vtrack run ... | head`, it now
    runs on, writes nothing more there and exits as its runs ended."""
    folder = _batch_folder(tmp_path, 3)
    batch = subprocess.Popen([sys.executable, "-m", "vtrack", "batch", str(folder), "-c", "s0",
                              "--jobs", "1", "--no-video", "-o", str(tmp_path / "out")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert batch.stdout is not None and batch.stderr is not None
    assert batch.stdout.readline().startswith("c0 [s0]: ")
    batch.stdout.close()  # `| head -1`
    stderr = batch.stderr.read()
    assert batch.wait(timeout=120) == 0, stderr
    assert "vtrack: " not in stderr
    assert _statuses(tmp_path / "out") == ["complete"] * 3


def test_a_batch_whose_stdout_cannot_take_its_lines_says_so_in_one_line(tmp_path: Path) -> None:
    """`vtrack batch in/ -c s0 > /dev/full` ended in a traceback (OSError: [Errno 28] No space
    left on device, from its first run's line), exit 1. The batch now runs on and says so in
    one line naming standard output and summary.csv, exit 1."""
    folder = _batch_folder(tmp_path, 2)
    out = tmp_path / "out"
    with open("/dev/full", "wb") as full:
        done = subprocess.run([sys.executable, "-m", "vtrack", "batch", str(folder), "-c", "s0",
                               "--no-video", "-o", str(out)],
                              stdout=full, stderr=subprocess.PIPE, timeout=120, check=False)
    assert done.returncode == 1
    assert done.stderr.decode() == (
        "vtrack: error: standard output: No space left on device: the batch's lines were not "
        f"all printed there ({out / 'summary.csv'} lists every run)\n")
    assert _statuses(out) == ["complete"] * 2



def test_a_batch_whose_warning_nobody_reads_runs(tmp_path: Path) -> None:
    """`vtrack batch in/ -c s0 2>&1 | true` with an input in a sub-folder: the warning naming
    it, written before any run, met the closed pipe (BrokenPipeError): the batch ended there,
    exit 1, saying nothing, with no summary.csv. A warning nobody reads is dropped, and the
    batch runs."""
    folder = _batch_folder(tmp_path, 2)
    (folder / "sub").mkdir()
    (folder / "c1.mp4").rename(folder / "sub" / "c1.mp4")
    reader, writer = os.pipe()
    os.close(reader)  # `2>&1 | true`: nobody reads either stream
    try:
        done = subprocess.run([sys.executable, "-m", "vtrack", "batch", str(folder), "-c", "s0",
                               "--no-video", "-o", str(tmp_path / "out")],
                              stdout=writer, stderr=writer, timeout=120, check=False)
    finally:
        os.close(writer)
    assert done.returncode == 0
    assert _statuses(tmp_path / "out") == ["complete"]


def test_a_batch_with_a_bar_hands_its_lines_on_as_they_come(tmp_path: Path) -> None:
    """`vtrack batch in/ -c s0 | tee log` in a terminal (a bar on stderr): tqdm.write does not
    flush, so a run's line reached the pipe only once 8 KB of lines had, or at exit. It now
    arrives as its run ends: the batch is still running when it is read (a stop then
    interrupts the runs left)."""
    folder = _batch_folder(tmp_path, 4)
    leader, follower = pty.openpty()
    drained = threading.Thread(target=_drain, args=(leader,), daemon=True)
    drained.start()
    batch = subprocess.Popen([sys.executable, "-m", "vtrack", "batch", str(folder), "-c", "s1",
                              "--jobs", "1", "--no-video", "-o", str(tmp_path / "out")],
                             stdout=subprocess.PIPE, stderr=follower, text=True,
                             env={**os.environ, "PYTHONUNBUFFERED": ""})  # (as by default)
    os.close(follower)
    try:
        assert batch.stdout is not None
        wait_for_stop_handlers(batch)
        first = batch.stdout.readline()  # (old code: at exit, every run done)
        batch.send_signal(signal.SIGINT)
        batch.wait(timeout=120)
    finally:
        batch.kill()
        batch.wait(timeout=30)
        drained.join(timeout=30)
    assert first.startswith("c0 [s1]: "), first
    assert "interrupted" in _statuses(tmp_path / "out")


def _drain(leader: int) -> None:
    """Read a terminal's output until its last writer is gone (a full terminal would block)."""
    with contextlib.suppress(OSError):
        while os.read(leader, 4096):
            pass
    os.close(leader)


def test_stdout_pointed_at_the_null_device_keeps_no_descriptor_open(tmp_path: Path) -> None:
    """stdout_to_null (after a line standard output could not take) opened the null device
    and duplicated it onto stdout, leaving the descriptor it opened open for the rest of the
    process: one more at each call."""
    script = ("import os, sys\n"
              "from vtrack.cli._messages import stdout_to_null\n"
              "before = sorted(os.listdir('/proc/self/fd'))\n"
              "stdout_to_null(); stdout_to_null()\n"
              "print(before == sorted(os.listdir('/proc/self/fd')), file=sys.stderr)\n")
    with open(tmp_path / "out.txt", "wb") as out:
        done = subprocess.run([sys.executable, "-c", script], stdout=out,
                              stderr=subprocess.PIPE, timeout=60, check=True)
    assert done.stderr.decode().strip() == "True"


def _closing_stderr() -> None:
    os.close(2)  # `2>&-`


def test_a_batch_without_stderr_keeps_its_errors_off_stdout(tmp_path: Path) -> None:
    """`vtrack batch in/ -c s0 -q 2>&- > out.txt` with an input that fails: its error line
    went to standard output (print and tqdm.write take ``file=None`` for stdout), into the
    file of results. With no stderr, the batch's error and warning lines are dropped."""
    folder = _batch_folder(tmp_path, 2)
    (folder / "c1.mp4").write_bytes((folder / "c0.mp4").read_bytes()[:3000])  # cut off
    done = subprocess.run([sys.executable, "-m", "vtrack", "batch", str(folder), "-c", "s0",
                           "-q", "--no-video", "-o", str(tmp_path / "out")],
                          stdout=subprocess.PIPE, timeout=120, check=False,
                          preexec_fn=_closing_stderr)
    assert done.returncode == 1
    assert done.stdout == b""
    assert _statuses(tmp_path / "out") == ["complete", "failed"]



@pytest.mark.parametrize("command", ["run", "batch"])
def test_progress_without_stderr_does_not_stop_the_work(tmp_path: Path, command: str) -> None:
    """`vtrack batch in/ -c s0 2>&-` (and `vtrack run`): the first progress asked
    ``sys.stderr.isatty()`` of no stderr: the batch stopped, its rows `interrupted`; the run
    ended `failed`: "'NoneType' object has no attribute 'isatty'". With no stderr there is no
    progress, and the work completes; stdout has its lines only."""
    folder = _batch_folder(tmp_path, 2)
    out = tmp_path / "out"
    if command == "run":
        scene = make_scene("smooth", seed=3, width=160, height=120, frames=20, fps=30)
        args = ["run", str(folder / "c0.mp4"), "--init",
                ",".join(f"{v:g}" for v in scene.boxes[0])]
    else:
        args = ["batch", str(folder)]
    done = subprocess.run([sys.executable, "-m", "vtrack", *args, "-c", "s0", "--no-video",
                           "--stats-period", "0.001", "-o", str(out)],
                          stdout=subprocess.PIPE, timeout=120, check=False,
                          preexec_fn=_closing_stderr)
    assert done.returncode == 0
    lines = done.stdout.decode().splitlines()
    if command == "run":
        assert json.loads((out / "run.json").read_text())["status"] == "complete"
        assert len(lines) == 1 and lines[0].startswith(f"{folder / 'c0.mp4'}: 20 frames"), lines
    else:
        assert _statuses(out) == ["complete"] * 2
        assert len(lines) == 3 and "frames" not in lines[-1], lines


@pytest.mark.parametrize(("command", "what"), [
    (["scene", "smooth", "OUT/clip.mp4", "--frames", "12"], "the summary line"),
    (["report", "OUT/run", "--out", "OUT/report"], "the summary line"),
    (["stages"], "the listing"),
    (["stages", "s0", "--toml"], "the config"),
    (["frame", "OUT/clip.mp4", "--at", "3", "-o", "OUT/fr.png"], "the summary line"),
    (["vectors", "OUT/clip.mp4", "--init", "INIT", "--frames", "2", "--out", "OUT/vec"],
     "the summary line"),
    (["vectors", "check", "OUT/vec", "OUT/vec"], "the comparison"),
    (["vectors", "check", "OUT/vec", "OUT/dump"], "the list of differences")])
def test_a_commands_result_stdout_cannot_take_is_one_line(tmp_path: Path, command: list[str],
                                                          what: str) -> None:
    """`vtrack scene smooth clip.mp4 > /dev/full` (and `vtrack report`, `vtrack stages`, `vtrack
    stages s0 --toml`) ended in a traceback (OSError: [Errno 28] No space left on device from
    click.echo), exit 1. As `vtrack run`'s summary line, it is now one line naming standard
    output and what was not printed, exit 1; the files are made as they would be. (`vtrack
    vectors check` of differing vectors said "the differences was not printed there".)"""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=12, fps=30)
    init = ",".join(f"{v:g}" for v in scene.boxes[0])
    if command[0] in ("report", "frame", "vectors"):  # a clip to read
        clip = write_video(scene, tmp_path / "clip.mp4")
    if command[:2] == ["vectors", "check"]:  # vectors to compare with themselves
        subprocess.run([sys.executable, "-m", "vtrack", "vectors", str(clip), "--init", init,
                        "--frames", "2", "--out", str(tmp_path / "vec")], capture_output=True,
                       timeout=120, check=True)
        dump = tmp_path / "dump"  # the vectors with one value of the trace changed
        shutil.copytree(tmp_path / "vec", dump)
        trace = (dump / "trace.csv").read_text().splitlines()
        trace[-1] = trace[-1][:-1] + ("1" if trace[-1][-1] != "1" else "2")
        (dump / "trace.csv").write_text("\n".join(trace) + "\n")
    if command[0] == "report":  # a run to report on
        subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s0", "--init",
                        init, "--no-video", "-o",
                        str(tmp_path / "run")], capture_output=True, timeout=120, check=True)
    args = [arg.replace("OUT", str(tmp_path)).replace("INIT", init) for arg in command]
    with open("/dev/full", "wb") as full:
        done = subprocess.run([sys.executable, "-m", "vtrack", *args], stdout=full,
                              stderr=subprocess.PIPE, timeout=120, check=False)
    assert done.returncode == 1
    assert "Traceback" not in done.stderr.decode()
    assert [line for line in done.stderr.decode().splitlines() if "error" in line] == [
        f"vtrack: error: standard output: No space left on device: {what} was not printed there"]
    if command[0] == "scene":
        assert (tmp_path / "clip.mp4").is_file() and (tmp_path / "clip.gt.txt").is_file()
    if command[0] == "report":
        assert (tmp_path / "report" / "index.html").is_file()
    if command[0] == "frame":
        assert (tmp_path / "fr.png").is_file()
    if command[0] == "vectors" and command[1] != "check":
        assert (tmp_path / "vec" / "trace.csv").is_file()
        assert sorted(p.name for p in (tmp_path / "vec").glob("frame_*")) == [
            "frame_0000", "frame_0001"]


@pytest.mark.parametrize(("args", "what"), [
    (["--version"], "the version"), (["--help"], "the help"), (["run", "--help"], "the help"),
    (["stages", "-h"], "the help"), (["vectors", "check", "--help"], "the help"),
    (["vectors", "clip.mp4", "--help"], "the help")])
def test_help_or_version_stdout_cannot_take_is_one_line(args: list[str], what: str) -> None:
    """`vtrack --version > /dev/full` and `vtrack run --help > /dev/full` ended in click's
    traceback (OSError: [Errno 28] No space left on device, from the option's callback, while
    the arguments were parsed), exit 1. As a command's result, it is one line naming standard
    output and what was not printed, exit 1; to a pipe they print as before."""
    with open("/dev/full", "wb") as full:
        done = subprocess.run([sys.executable, "-m", "vtrack", *args], stdout=full,
                              stderr=subprocess.PIPE, timeout=START_BOUND_S, check=False)
    assert done.returncode == 1
    assert done.stderr.decode().splitlines() == [
        f"vtrack: error: standard output: No space left on device: {what} was not printed there"]
    printed = subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                             text=True, timeout=START_BOUND_S, check=False)
    assert printed.returncode == 0 and printed.stderr == ""
    assert printed.stdout.startswith("vtrack, version 0." if what == "the version" else "Usage: ")


def test_stream_into_the_folders_lock_file_is_refused(tmp_path: Path) -> None:
    """`--stream OUT/.vtrack.lock` was accepted, and the lines were deleted with the lock at the
    end of the run."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s0",
                           "--init", ",".join(f"{v:g}" for v in scene.boxes[0]), "--no-video",
                           "--stream", str(out / ".vtrack.lock"), "-o", str(out)],
                          capture_output=True, timeout=START_BOUND_S, check=False)
    assert done.returncode == 2
    assert "is one of this run's own outputs" in done.stderr.decode()


@pytest.mark.parametrize("command", [["batch", "", "-c", "s0", "--out", "OUT"],
                                     ["report", ""], ["scene", "smooth", ""]])
def test_an_empty_path_argument_is_refused(tmp_path: Path, command: list[str]) -> None:
    """`vtrack batch ""` tracked every input of the current folder; `vtrack report ""` read
    it (an empty --out was already refused)."""
    args = [str(tmp_path / "o") if a == "OUT" else a for a in command]
    done = subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          timeout=START_BOUND_S, check=False, cwd=tmp_path)
    assert done.returncode == 2
    assert "empty; give " in done.stderr.decode()  # what the argument takes
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_frames_n_ends_with_its_last_frame_while_the_pipe_stays_open(tmp_path: Path) -> None:
    """`--frames 5` on a pipe that has sent 5 frames and stays open (a sender that waits for
    the results) waited for a sixth frame before ending, for ever: it ends with the fifth."""
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=10, fps=30)
    raw = write_clip(scene, tmp_path / "clip.bgr", fmt="raw").clip.read_bytes()
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    run = _vtrack(["-", "--raw", "160x120", "-c", "s0", "--init", box, "--frames", "5",
                   "--no-video", "-o", str(out), "-q"], stdin=subprocess.PIPE)
    assert run.stdin is not None
    try:
        run.stdin.write(raw[:len(raw) // 2])
        run.stdin.flush()
        assert run.wait(timeout=120) == 0  # a bound, not a measure: stdin is still open
    finally:
        run.kill()
        run.wait()
        run.stdin.close()
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "complete" and record["frames"] == 5
    assert record["stopped_by_frames"] is True


def test_a_signal_while_a_stream_reader_stalls_is_an_interrupted_run(tmp_path: Path) -> None:
    """SIGTERM while `--stream FIFO` waited for its reader to make room was held until
    `--timeout` ran out (10 s by default, docker stop's whole grace), and the run then ended
    `failed` ('its reader took nothing'): it ends interrupted at once, its outputs whole."""
    scene = make_scene("smooth", seed=3, width=64, height=48, frames=600, fps=30)
    raw = write_clip(scene, tmp_path / "clip.bgr", fmt="raw").clip
    fifo = tmp_path / "lines"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # opened, never read
    out = tmp_path / "out"
    run = _vtrack([str(raw), "--raw", "64x48", "-c", "s0", "--init",
                   ",".join(f"{v:g}" for v in scene.boxes[0]), "--no-video", "-o", str(out),
                   "--stream", str(fifo), "--timeout", "3600", "-q"])
    try:
        # vtrack waits in select() for the reader (Linux: its main thread's wait channel)
        # once the pipe is full: only then does the signal come
        wchan = Path(f"/proc/{run.pid}/task/{run.pid}/wchan")
        deadline = time.monotonic() + 120  # a bound, not a measure
        while not (fcntl.ioctl(reader, termios.FIONREAD, b"\0" * 4) != b"\0" * 4
                   and "poll" in wchan.read_text()):
            assert run.poll() is None and time.monotonic() < deadline, "the pipe never filled"
            time.sleep(0.05)
        run.send_signal(signal.SIGTERM)
        assert run.wait(timeout=120) == 143  # not --timeout's hour
    finally:
        run.kill()
        run.wait()
        os.close(reader)
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "interrupted" and record["error"] == "interrupted by SIGTERM"
    rows = (out / "track.csv").read_text().splitlines()
    assert len(rows) - 1 == record["frames"] < 600


def _following(tmp_path: Path, follow_s: int) -> tuple[Path, Path, Path, subprocess.Popen]:
    """``rec.ts`` (a finished 30-frame ``smooth`` clip) tracked by s0 with ``--follow
    follow_s`` and a ``--stream`` file: ``(recording, out folder, stream file, process)``."""
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=30, fps=30)
    recording = write_video(scene, tmp_path / "rec.ts")
    lines, out = tmp_path / "lines.jsonl", tmp_path / "out"
    run = _vtrack([str(recording), "--follow", str(follow_s), "-c", "s0", "--init",
                   ",".join(f"{v:g}" for v in scene.boxes[0]), "--no-video", "-o", str(out),
                   "--stream", str(lines), "-q"])
    return recording, out, lines, run


def _wait_until(run: subprocess.Popen, done: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + 120  # a bound, not a measure
    while not done():
        assert run.poll() is None and time.monotonic() < deadline, what
        time.sleep(0.05)


def test_a_followed_file_cut_shorter_ends_the_run_partial_naming_the_cut(tmp_path: Path) -> None:
    """A file cut shorter while `--follow` read it (a recorder restarted over the same name,
    `ffmpeg -y rec.ts`) was read on from the old end: the run waited, then tracked the middle
    of the new recording as if it went on, and ended `complete`. Now it ends `partial` at
    once, saying the file was cut."""
    recording, out, lines, run = _following(tmp_path, 60)
    try:
        _wait_until(run, lambda: lines.exists() and lines.stat().st_size > 0,
                    "nothing was tracked")  # the file is being read
        with recording.open("r+b") as handle:
            handle.truncate(0)
        _, stderr = run.communicate(timeout=120)  # a bound: --follow alone would wait 60 s
    finally:
        run.kill()
        run.wait()
    assert run.returncode == 1, stderr
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "partial"
    assert f"{recording}: reading stopped at frame {record['frames']}: the file was cut to 0 " \
           "bytes after " in record["error"]
    assert stderr.decode().count("vtrack: error:") == 1


def _read_to_its_end(process: subprocess.Popen, path: Path) -> bool:
    """Whether ``process`` has read ``path`` (open in it) as far as the file goes now."""
    for fd in Path(f"/proc/{process.pid}/fd").iterdir():
        try:
            if not fd.samefile(path):
                continue
            info = (Path(f"/proc/{process.pid}/fdinfo") / fd.name).read_text()
        except OSError:  # closed meanwhile
            continue
        position = int(info.split("pos:")[1].split()[0])
        return position >= path.stat().st_size
    return False


def test_a_signal_while_following_tracks_the_frames_already_in_the_file(tmp_path: Path) -> None:
    """SIGTERM while `--follow` waited for a finished file to grow ended the run at once: the
    frames the decoder's frame threads still held (in the file, read whole) were never tracked
    (49 of 60). Now the input ends where the file ends, they are tracked, and the run ends
    `interrupted` with every frame of the file."""
    recording, out, lines, run = _following(tmp_path, 600)
    try:
        # tracking has begun and the whole file has been read: the run waits for more
        _wait_until(run, lambda: bool(lines.exists() and lines.stat().st_size
                                      and _read_to_its_end(run, recording)),
                    "never read to its end")
        run.send_signal(signal.SIGTERM)
        _, stderr = run.communicate(timeout=120)  # a bound: --follow alone would wait 600 s
    finally:
        run.kill()
        run.wait()
    assert run.returncode == 128 + signal.SIGTERM, stderr
    record = json.loads((out / "run.json").read_text())
    assert (record["status"], record["error"]) == ("interrupted", "interrupted by SIGTERM")
    assert record["frames"] == 30
    assert len((out / "track.csv").read_text().splitlines()) - 1 == 30
    assert len(lines.read_text().splitlines()) == 30


def test_what_is_written_after_a_stop_at_the_end_is_not_read(tmp_path: Path) -> None:
    """A stop while a followed file was read to its end (a signal: ``stop_at_end``) ended the
    stream only at a read that found nothing: a recorder writing on kept the run going (600
    frames tracked, 4 s after the signal, of a file that held 60 when it came). Now nothing
    written after the stop is read."""
    import threading

    path = tmp_path / "rec.ts"
    path.write_bytes(b"x" * 1000)
    growing = GrowingFile(str(path), idle_s=600)
    buffer = bytearray(4096)
    assert growing.readinto(buffer) == 1000
    got: list[int] = []
    reader = threading.Thread(target=lambda: got.append(growing.readinto(buffer)), daemon=True)
    reader.start()  # waits at the end of the file for more (600 s)
    assert growing.stop_at_end()  # everything the file holds has been read
    with path.open("ab") as handle:
        handle.write(b"y" * 500)  # the recorder writes on
    reader.join(timeout=60)  # a bound: it ends at its next poll
    assert got == [0]
    assert growing.readinto(buffer) == 0
    growing.close()


def test_a_followed_file_replaced_by_rename_ends_the_run_partial_naming_it(
        tmp_path: Path) -> None:
    """A new recording renamed over the followed name (`mv new.ts rec.ts`) went unnoticed:
    `--follow` read on the old file (its name gone) until it went idle and said `complete`.
    Now the file opened is followed on as `tail -f` follows it; when it has not grown for
    --follow's seconds the run ends `partial`, saying another file now has the name and that
    --follow does not go on to it."""
    recording, out, lines, run = _following(tmp_path, 5)
    try:
        _wait_until(run, lambda: lines.exists() and lines.stat().st_size > 0,
                    "nothing was tracked")  # the file is being read
        newer = tmp_path / "new.ts"
        newer.write_bytes(recording.read_bytes())
        newer.replace(recording)
        _, stderr = run.communicate(timeout=120)  # a bound
    finally:
        run.kill()
        run.wait()
    assert run.returncode == 1, stderr
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "partial" and record["frames"] == 30
    assert f"{recording}: reading stopped at frame 30: another file now has its name " \
           "(renamed over it, or the recording rotated)" in record["error"]
    assert "(as tail -f, not tail -F)" in record["error"]
    assert stderr.decode().count("vtrack: error:") == 1


def test_raw_frames_from_a_file_on_stdin_read_past_its_start_are_counted_from_there(
        tmp_path: Path) -> None:
    """A file on stdin that an earlier reader had read 4 frames of (`{ dd ...; vtrack run -
    --raw WxH; } < clip.bgr`) was counted from its start: run.json said 10 frames for the 6
    tracked, and `--start 7` was refused as ``has no frame 7 (frames 0..9)`` only after
    reading to the end. They are counted from where stdin is."""
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=10, fps=30)
    clip = write_clip(scene, tmp_path / "clip.bgr", fmt="raw").clip
    box = ",".join(f"{v:g}" for v in scene.boxes[4])
    frame_bytes = 160 * 120 * 3
    out = tmp_path / "out"
    with clip.open("rb") as stdin:
        stdin.seek(4 * frame_bytes)
        done = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", "--raw", "160x120",
                               "-c", "s0", "--init", box, "--no-video", "-o", str(out), "-q"],
                              stdin=stdin, capture_output=True, timeout=120)
        assert done.returncode == 0, done.stderr.decode()
        stdin.seek(4 * frame_bytes)
        late = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", "--raw", "160x120",
                               "-c", "s0", "--init", box, "--start", "7", "--no-video",
                               "-o", str(tmp_path / "late")],
                              stdin=stdin, capture_output=True, timeout=120)
    record = json.loads((out / "run.json").read_text())
    assert (record["frames"], record["input"]["frame_count"]) == (6, 6)
    assert late.returncode == 2
    assert late.stderr.decode().strip() == ("vtrack: error: --start 7: -: has no frame 7 "
                                            "(frames 0..5)")


def _waiting_for_a_writer(process: subprocess.Popen) -> None:
    """Return once ``process`` is blocked opening a FIFO no writer opened (Linux: the kernel
    function it sleeps in, ``/proc/PID/wchan``), or has ended."""
    deadline = time.monotonic() + START_BOUND_S
    while process.poll() is None:
        with contextlib.suppress(OSError):
            if Path(f"/proc/{process.pid}/wchan").read_text() == "wait_for_partner":
                return
        assert time.monotonic() < deadline, "it never waited for the FIFO's writer"
        time.sleep(0.05)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("command", [["frame", "-o", "frame.png"],
                                     ["vectors", "--init", "1,1,8,8", "-o", "vec"],
                                     ["select"]])
def test_a_signal_while_frame_vectors_or_select_wait_for_a_fifos_writer_interrupts_them(
        tmp_path: Path, signum: int, command: list[str]) -> None:
    """`vtrack frame FIFO` (and vectors, select), given Ctrl-C or SIGTERM while FFmpeg's open
    waited for a writer, said "FIFO: not a video FFmpeg can decode (Interrupted system call)"
    and exited 2, as vtrack run did before it learnt to say `interrupted`."""
    fifo = tmp_path / "feed"
    os.mkfifo(fifo)
    process = subprocess.Popen([sys.executable, "-m", "vtrack", command[0], str(fifo),
                                *command[1:]], cwd=tmp_path, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        wait_for_stop_handlers(process)
        _waiting_for_a_writer(process)
        process.send_signal(signum)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
    assert (process.returncode, stdout, stderr) == (128 + signum, "", "vtrack: interrupted\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["feed"]
