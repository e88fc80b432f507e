"""Output folders under faults, as a user meets them: two runs at once, a full disk, a bad
``--out``, SIGTERM/SIGINT, and the default folder ``vtrack-out/<stem>/<config>/``.

Every case runs the real command in a subprocess on small generated clips; the full-disk cases
mount a small tmpfs (we run as root in CI) and are skipped, saying why, where mounting is not
permitted.
"""

from __future__ import annotations

import contextlib
import csv
import json
import multiprocessing
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import av
import pytest
from conftest import START_BOUND_S, LinesAsTheyCome

from vtrack.batch import SUMMARY_COLUMNS, executors
from vtrack.batch.executors import LocalExecutor, _context, _Worker, stop_workers
from vtrack.batch.jobs import Job, Outcome, Progress
from vtrack.config import DEFAULT_CONFIG, load_config
from vtrack.errors import Interrupted
from vtrack.io.outdir import LOCK_NAME, OutputFolder
from vtrack.io.raw import PIPE_BYTES, RawFormat
from vtrack.request import RunRequest
from vtrack.run import run
from vtrack.scenes import make_scene, write_video

if TYPE_CHECKING:
    from conftest import Clip, ClipFactory, SceneFactory

    from vtrack.scenes import Scene

W, H, FRAMES = 160, 120, 48


def vtrack(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=120, check=False)


def start(*args: str, new_session: bool = False) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "vtrack", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=new_session)


def error_line(stderr: str) -> str:
    """The one ``vtrack: error:`` line of ``stderr`` (and no traceback)."""
    assert "Traceback" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if line.startswith("vtrack: error:")]
    assert len(lines) == 1, stderr
    return lines[0]


def csv_rows(path: Path) -> list[list[str]]:
    """The rows after the header; every row has the header's number of fields."""
    with path.open(newline="") as handle:
        header, *rows = list(csv.reader(handle))
    assert all(len(row) == len(header) for row in rows), "a cut row"
    return rows


def video_frames(path: Path) -> int:
    with av.open(str(path)) as container:
        return sum(1 for _ in container.decode(video=0))


def assert_records_agree(out: Path) -> dict:
    """run.json lists only files that exist and are whole; its frames are the CSV's rows."""
    record = json.loads((out / "run.json").read_text())
    for name in record["outputs"]:
        assert (out / name).is_file(), name
    assert "track.csv" in record["outputs"]
    assert len(csv_rows(out / "track.csv")) == record["frames"]
    if "annotated.mp4" in record["outputs"]:
        assert video_frames(out / "annotated.mp4") == record["frames"]
    else:
        assert not (out / "annotated.mp4").exists()
    assert not list(out.glob(".*.tmp*")), "temporary files left"
    return record


@pytest.fixture
def clip(clip_factory: ClipFactory) -> Clip:
    return clip_factory("smooth", width=W, height=H, frames=FRAMES)


@pytest.fixture
def inputs(tmp_path: Path, clip_factory: ClipFactory) -> Path:
    """A batch folder of four short clips with ground truth."""
    folder = tmp_path / "in"
    folder.mkdir()
    for n, scenario in enumerate(("smooth", "jump", "distractor", "bounce")):
        made = clip_factory(scenario, seed=n, width=W, height=H, frames=FRAMES)
        shutil.copy(made.path, folder / f"{scenario}.mp4")
        shutil.copy(made.gt, folder / f"{scenario}.gt.txt")
    return folder


def read_summary(out: Path) -> dict[str, dict[str, str]]:
    with (out / "summary.csv").open(newline="") as handle:
        reader = csv.DictReader(handle)
        assert tuple(reader.fieldnames or ()) == SUMMARY_COLUMNS
        return {row["input"]: row for row in reader}


# --- one folder, one run at a time ------------------------------------------------------------


def test_two_batches_into_one_folder_at_once(inputs: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ("batch", str(inputs), "-c", "s0", "-c", "camshift", "--jobs", "1", "--out", str(out))
    first = start(*args)
    deadline = time.monotonic() + START_BOUND_S
    while not (out / LOCK_NAME).exists() and first.poll() is None \
            and time.monotonic() < deadline:
        time.sleep(0.02)
    second = start(*args)  # while the first holds the folder
    _, second_err = second.communicate(timeout=120)
    first_running = first.poll() is None
    _, first_err = first.communicate(timeout=120)
    assert first.returncode == 0, first_err
    if first_running:  # (the first batch outlives the second's start-up on any sane machine)
        assert second.returncode == 2, second_err
        line = error_line(second_err)
        assert str(out) in line and "in use" in line and f"pid {first.pid}" in line
    else:
        assert second.returncode == 0, second_err
    rows = read_summary(out)
    assert {row["status"] for row in rows.values()} == {"complete"}
    for name in ("smooth", "jump", "distractor", "bounce"):
        for config in ("s0", "camshift"):
            record = assert_records_agree(out / name / config)
            assert record["status"] == "complete" and record["frames"] == FRAMES
            assert sorted(record["outputs"]) == ["annotated.mp4", "track.csv"]
    assert not (out / LOCK_NAME).exists()


def test_a_folder_in_use_is_refused_and_a_killed_holder_releases_it(
        clip: Clip, tmp_path: Path) -> None:
    out = tmp_path / "out"
    with OutputFolder(out):
        result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out))
        assert result.returncode == 2
        line = error_line(result.stderr)
        assert "in use by another vtrack" in line and f"pid {os.getpid()}" in line
    assert not out.exists()  # created for the lock, removed empty
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from vtrack.io.outdir import OutputFolder;"
         "f = OutputFolder(sys.argv[1]).__enter__(); print('held', flush=True); time.sleep(60)",
         str(out)], stdout=subprocess.PIPE, text=True)
    assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
    refused = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out))
    assert refused.returncode == 2 and f"pid {holder.pid}" in error_line(refused.stderr)
    holder.kill()  # SIGKILL: no clean-up runs, the kernel drops the lock
    holder.wait()
    result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert assert_records_agree(out)["status"] == "complete"


def test_a_folder_removed_while_taken_leaves_no_parent_it_created(tmp_path: Path) -> None:
    """OutputFolder created out/new/run (out/new too) and, the run's folder removed while it
    was taken (`rm -r out/new/run` during a run), left out/new behind empty: it stopped at the
    first folder it could not remove, gone. The folders it created are removed however each
    of them went, as a stopped report or scene removes its own (removing_new_folders)."""
    folder = tmp_path / "new" / "run"
    with OutputFolder(folder):
        shutil.rmtree(folder)
    assert list(tmp_path.iterdir()) == []
    with OutputFolder(folder):  # one that holds a file is kept, and so is its parent
        (folder / "note.txt").write_text("mine")
    assert [p.name for p in folder.iterdir()] == ["note.txt"]


# --- a full disk ------------------------------------------------------------------------------


@contextlib.contextmanager
def tmpfs(mount: Path, options: str, what: str) -> Iterator[Path]:
    """A tmpfs mounted at ``mount`` with ``options``, unmounted afterwards; the test is skipped
    where mounting is not permitted."""
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(mount)],
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        pytest.skip(f"cannot mount {what} here ({done.stderr.strip() or 'not permitted'})")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 2 MiB tmpfs."""
    with tmpfs(tmp_path / "disk", "size=2m", "a tmpfs") as mount:
        yield mount


def fill(disk: Path, leave: int) -> None:
    """Fill ``disk`` up to ``leave`` free bytes."""
    stats = os.statvfs(disk)
    free = stats.f_bavail * stats.f_frsize
    (disk / "filler").write_bytes(b"\0" * max(0, free - leave))


@pytest.mark.parametrize("video", [False, True], ids=["no-video", "video"])
def test_a_full_disk_is_one_line_exit_1_and_records_agree(
        clip: Clip, small_disk: Path, video: bool) -> None:
    # no-video: the CSV itself runs out of room (a 4 KiB page beside the lock file's: about
    # 37 of its 48 rows, s0's: robust's rows, without the stages' counters, fit in that page);
    # video: the video fills the disk, is removed, and run.json says what is left
    fill(small_disk, leave=8192 if not video else 24 * 1024)
    out = small_disk / "out"
    result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out),
                    *(() if video else ("--no-video", "-c", "s0")))
    assert result.returncode == 1, result.stderr
    line = error_line(result.stderr)
    assert "No space left on device" in line
    if (out / "run.json").exists():
        record = assert_records_agree(out)
        assert record["status"] == "failed"
        assert record["frames"] < FRAMES or video  # (the video may fail only as it closes)
        assert "No space left on device" in record["error"]
    else:  # no room left for the record itself: the line says so
        assert "run.json" in line
        assert len(csv_rows(out / "track.csv")) < FRAMES
    if video:  # room came back when the broken video was removed
        assert "annotated.mp4" not in assert_records_agree(out)["outputs"]


def test_a_batch_run_that_fails_part_way_has_the_row_of_its_records(
        clip: Clip, small_disk: Path) -> None:
    """The disk filled while a batch's run wrote its video: the run's folder kept its records
    (run.json: failed, 48 frames, track.csv listed) but its summary.csv row said none of it
    (frames, scores, ground_truth and run empty), against "each row agrees with its folder's
    run.json" and "a run that failed part way is listed with its frames"."""
    folder = small_disk.parent / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "a.mp4")
    shutil.copy(clip.gt, folder / "a.gt.txt")
    fill(small_disk, leave=56 * 1024)  # (room for the records, not for the video)
    out = small_disk / "out"
    result = vtrack("batch", str(folder), "--jobs", "1", "--out", str(out))
    assert result.returncode == 1, result.stderr
    assert "No space left on device" in error_line(result.stderr)
    record = assert_records_agree(out / "a" / "robust")
    assert record["status"] == "failed" and record["frames"] > 0, record
    row = read_summary(out)["a"]
    assert (row["status"], row["frames"], row["run"]) == ("failed", str(record["frames"]),
                                                         "a/robust"), row
    assert row["auc"] and row["ground_truth"], row
    assert "No space left on device" in row["error"]


def test_a_batch_run_with_no_room_for_its_run_json_keeps_its_track_csv(
        clip: Clip, small_disk: Path) -> None:
    """No room even for run.json: the error line said so, then the batch's worker removed the
    run's track.csv and left an empty a/robust/, where `vtrack run` keeps track.csv (whole
    rows) in the same situation. The batch's run keeps it too."""
    folder = small_disk.parent / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "a.mp4")
    shutil.copy(clip.gt, folder / "a.gt.txt")
    fill(small_disk, leave=24 * 1024)  # (room for the CSV, not for the video nor run.json)
    out = small_disk / "out"
    result = vtrack("batch", str(folder), "--jobs", "1", "--out", str(out))
    assert result.returncode == 1, result.stderr
    line = error_line(result.stderr)
    assert "run.json: cannot write (No space left on device)" in line, line
    run_dir = out / "a" / "robust"
    assert not (run_dir / "run.json").exists()
    assert sorted(p.name for p in run_dir.iterdir()) == ["track.csv"]
    assert 0 < len(csv_rows(run_dir / "track.csv")) <= FRAMES
    assert read_summary(out)["a"]["status"] == "failed"


def test_a_disk_full_before_the_header_leaves_nothing(clip: Clip, small_disk: Path) -> None:
    """No room even for track.csv's header: the run's new folder stayed behind with an empty
    temporary CSV in it (the README: such a run creates no folder)."""
    fill(small_disk, leave=0)
    result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--no-video", "--out",
                    str(small_disk / "out"))
    assert result.returncode != 0 and "No space left on device" in error_line(result.stderr)
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler"]


# --- a bad --out ------------------------------------------------------------------------------


@pytest.fixture
def read_only_folder(tmp_path: Path) -> Iterator[Path]:
    """A read-only file system (root writes anywhere else)."""
    with tmpfs(tmp_path / "ro", "ro,size=64k", "a read-only tmpfs") as mount:
        yield mount


@pytest.mark.parametrize("command", ["batch", "run"])
def test_a_bad_out_is_one_line_exit_2(clip: Clip, inputs: Path, tmp_path: Path,
                                      command: str) -> None:
    """A file in --out's place is said as a file inside --out's path is: "(a file, not a
    folder)" there, "(Not a directory)" for `-o results.txt/sub`, one wording now."""
    source = [str(inputs)] if command == "batch" else [str(clip.path), "--gt", str(clip.gt)]
    a_file = tmp_path / "results.txt"
    a_file.write_text("mine\n")
    for out, needle in ((a_file, "here (a file, not a folder)"),
                        (a_file / "sub", f"here ({a_file} is a file, not a folder)")):
        result = vtrack(command, *source, "--out", str(out))
        assert result.returncode == 2, result.stderr
        line = error_line(result.stderr)
        assert str(out) in line and needle in line
    assert a_file.read_text() == "mine\n"


def test_batch_into_a_read_only_folder_is_one_line(inputs: Path,
                                                   read_only_folder: Path) -> None:
    result = vtrack("batch", str(inputs), "--out", str(read_only_folder / "out"))
    assert result.returncode == 2, result.stderr
    line = error_line(result.stderr)
    assert str(read_only_folder / "out") in line and "Read-only file system" in line


# --- signals ----------------------------------------------------------------------------------


def wait_for(condition, process: subprocess.Popen | _Worker, what: str) -> None:
    """Wait until ``condition()``, failing if ``process`` (a subprocess or a batch's worker)
    ends first, or after START_BOUND_S (a hang)."""
    deadline = time.monotonic() + START_BOUND_S
    while not condition():
        if isinstance(process, _Worker):
            assert process.process.is_alive(), f"the worker ended before {what}"
        else:
            assert process.poll() is None, f"finished before {what}: {process.communicate()}"
        assert time.monotonic() < deadline, f"no {what}"
        time.sleep(0.01)


def test_sigterm_is_handled_as_ctrl_c(clip_factory: ClipFactory, tmp_path: Path) -> None:
    scene = clip_factory("smooth", width=W, height=H, frames=FRAMES).scene
    frames = list(scene.frames())
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-m", "vtrack", "run", "-", "--raw", f"{W}x{H}", "--fps", "30",
         "--init", ",".join(map(str, scene.boxes[0])), "--out", str(out)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdin is not None
    for frame in frames[:30]:
        process.stdin.write(frame.tobytes())
    process.stdin.flush()  # the rest never comes: the run waits for frame 30
    # every frame sent is tracked (header + 30 rows) before the signal comes
    wait_for(lambda: any(len(p.read_bytes().splitlines()) > 30 for p in out.glob(".track.tmp*")),
             process, "rows")
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 128 + signal.SIGTERM, stderr.decode()
    assert "SIGTERM" in error_line(stderr.decode())
    record = assert_records_agree(out)
    assert record["status"] == "interrupted" and "SIGTERM" in record["error"]
    assert record["frames"] == 30 and sorted(record["outputs"]) == ["annotated.mp4", "track.csv"]


#: ``vtrack run`` killed outright (SIGKILL) as its video starts to close: where a slow encoder
#: (``--preset placebo``) is flushing when a SIGTERM's grace runs out and the kill comes.
KILLED_AS_THE_VIDEO_CLOSES = """
import os, runpy, signal, sys
from vtrack.io.videowriter import VideoWriter
VideoWriter.close = lambda self: os.kill(os.getpid(), signal.SIGKILL)
sys.argv = ["vtrack", *sys.argv[1:]]
runpy.run_module("vtrack", run_name="__main__")
"""


def test_a_run_killed_while_its_video_closes_leaves_no_track_csv_without_a_record(
        clip: Clip, tmp_path: Path) -> None:
    """SIGTERM to `vtrack run --preset placebo`, then SIGKILL while the encoder still flushed:
    the folder held track.csv under its final name (96 of 900 rows) beside the video's
    temporary and no run.json: a file that looked complete and was not. The CSV is renamed
    only once the video is closed, just before run.json; the next run clears what is left."""
    out = tmp_path / "out"
    killed = subprocess.run(
        [sys.executable, "-c", KILLED_AS_THE_VIDEO_CLOSES, "run", str(clip.path), "--gt",
         str(clip.gt), "--out", str(out)], capture_output=True, text=True, timeout=120,
        check=False)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert not (out / "run.json").exists()
    assert not (out / "track.csv").exists(), "track.csv with no record vouching for it"
    assert len(csv_rows(next(out.glob(".track.tmp-*.csv")))) == FRAMES  # kept aside
    again = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out))
    assert again.returncode == 0, again.stderr
    assert assert_records_agree(out)["frames"] == FRAMES  # no temporary left either


def full_pipe() -> tuple[int, int]:
    """A pipe (read end, write end) full to its last byte: a write to it waits for a read."""
    read, write = os.pipe()
    os.set_blocking(write, False)
    for chunk in (b"x" * 4096, b"x"):
        with contextlib.suppress(BlockingIOError):
            while True:
                os.write(write, chunk)
    os.set_blocking(write, True)
    return read, write


def signal_until_it_ends(process: subprocess.Popen) -> None:
    """SIGTERM to ``process`` again and again until it ends (at most 60 s)."""
    deadline = time.monotonic() + 60
    while process.poll() is None:
        process.send_signal(signal.SIGTERM)
        assert time.monotonic() < deadline, "vtrack did not end"
        time.sleep(0.01)


def test_a_signal_after_a_complete_run_is_recorded_leaves_its_exit_status_0(
        scene_factory: SceneFactory, tmp_path: Path) -> None:
    """SIGTERM once run.json said `complete` (while the summary line was printed, or while
    the interpreter tore down after it) ended the process 143, the record and the exit
    disagreeing: the signal handlers were gone once the run had returned. Now the exit is 0,
    as the record says. Here the summary line waits for room in a full stdout pipe, never
    drained, while SIGTERM comes again and again once run.json is there."""
    scene = scene_factory("smooth", width=W, height=H, frames=FRAMES)
    raw = tmp_path / "in.raw"
    raw.write_bytes(b"".join(frame.tobytes() for frame in scene.frames()))
    out = tmp_path / "out"
    read, write = full_pipe()
    try:
        with raw.open("rb") as stdin, (tmp_path / "stderr.txt").open("wb") as stderr:
            process = subprocess.Popen(
                [sys.executable, "-m", "vtrack", "run", "-", "--raw", f"{W}x{H}", "--fps", "30",
                 "--init", ",".join(map(str, scene.boxes[0])), "--no-video", "--out", str(out)],
                stdin=stdin, stdout=write, stderr=stderr)
        wait_for(lambda: (out / "run.json").exists(), process, "run.json")
        signal_until_it_ends(process)
    finally:
        os.close(write)
        os.close(read)
    assert assert_records_agree(out)["status"] == "complete"
    assert process.returncode == 0, (tmp_path / "stderr.txt").read_text()


def test_a_signal_once_the_batch_has_said_its_tally_changes_nothing(
        clip: Clip, tmp_path: Path) -> None:
    """SIGTERM after the batch's summary.csv was final and its tally printed (while its error
    lines were written, or once its signal handlers were restored on the way out) ended it
    143, with no line saying why, or "vtrack: interrupted" after a whole summary (a batch of
    500 resumed pairs: `kill` 1.2 s in). Now the exit is the one its runs call for: 1 here,
    a pair that failed. Its error line waits for room in a full stderr pipe while SIGTERM
    comes again and again once the tally is out."""
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "a.mp4")  # no ground truth, no box: the pair fails
    out = tmp_path / "out"
    read, write = full_pipe()
    said: list[bytes] = []
    process = subprocess.Popen(
        [sys.executable, "-m", "vtrack", "batch", str(folder), "--out", str(out)],
        stdout=subprocess.PIPE, stderr=write)
    try:
        assert process.stdout is not None
        lines = LinesAsTheyCome(process.stdout)
        while not said or b" -> " not in said[-1]:  # the tally: the batch's last stdout line
            line = lines.next(START_BOUND_S)
            assert line, f"no tally ({'the batch ended' if line == b'' else 'no line'}): {said}"
            said.append(line)
        for _ in range(20):
            process.send_signal(signal.SIGTERM)
            time.sleep(0.01)
        drained = threading.Thread(target=lambda: os.read(read, 1 << 20) and None, daemon=True)
        drained.start()  # (room for the error line: it goes on)
        signal_until_it_ends(process)
        assert lines.next(START_BOUND_S) == b""  # (its stdout closed: the reader is done)
        process.stdout.close()
    finally:
        if process.poll() is None:  # (an assertion failed: no batch is left running)
            process.kill()
            process.wait()
        os.close(write)
        os.close(read)
    assert process.returncode == 1, said
    assert read_summary(out)["a"]["status"] == "failed"


def test_a_signal_before_the_first_tracked_frame_is_an_interrupted_run(
        scene_factory: SceneFactory, tmp_path: Path) -> None:
    """Interrupted while ``--start`` passes over the frames before it: no frame was tracked,
    so there is no video to write (an MP4 of no picture does not open: the run used to call
    that a broken output, exit 1, 'tuple index out of range')."""
    scene = scene_factory("smooth", width=640, height=480, frames=12)
    frames = list(scene.frames())
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-m", "vtrack", "run", "-", "--raw", "640x480", "--fps", "30",
         "--start", "10", "--init", ",".join(map(str, scene.boxes[10])), "--out", str(out)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdin is not None
    # 9 frames are more than the pipe holds (vtrack enlarges it to PIPE_BYTES) and one frame:
    # once written, frames past the first (which opening the input reads) have been read, so
    # the run is in its frame loop, passing over the frames before frame 10, which never comes
    assert 8 * frames[0].nbytes > PIPE_BYTES
    for frame in frames[:9]:
        process.stdin.write(frame.tobytes())
    process.stdin.flush()
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 128 + signal.SIGTERM, stderr.decode()
    assert error_line(stderr.decode()).endswith(f"interrupted by SIGTERM; partial results in {out}")
    record = assert_records_agree(out)
    assert (record["status"], record["frames"], record["outputs"]) == (
        "interrupted", 0, ["track.csv"])


def test_a_signal_while_the_outputs_open_is_an_interrupted_run(clip: Clip, tmp_path: Path
                                                               ) -> None:
    """A signal that came while the run opened its outputs (here: as it reports them open)
    cut the opening short: `.track.tmp-*` and `.annotated.tmp-*` were left in the folder,
    with no run.json. Now the run ends interrupted before its first frame, its records whole."""
    out = tmp_path / "out"
    request = RunRequest(str(clip.path), out, load_config("s0"), init_box=clip.scene.boxes[0])
    try:
        summary = run(request, on_open=lambda info: os.kill(os.getpid(), signal.SIGTERM))
    except Interrupted:  # (a KeyboardInterrupt: it would end the whole test session)
        pytest.fail(f"run() raised Interrupted, leaving {sorted(p.name for p in out.iterdir())}")
    assert (summary.status, summary.interrupted_by, summary.frames) == (
        "interrupted", "SIGTERM", 0)
    record = assert_records_agree(out)
    assert (record["status"], record["outputs"]) == ("interrupted", ["track.csv"])


def test_a_signal_while_a_stream_fifo_waits_for_its_reader_is_an_interrupted_run(
        clip: Clip, tmp_path: Path) -> None:
    """SIGTERM while `--stream FIFO` waited for a reader (the CSV's temporary file already
    open): the run removed its outputs and left no run.json. Now it is recorded interrupted."""
    fifo, out = tmp_path / "lines", tmp_path / "out"
    os.mkfifo(fifo)
    process = start("run", str(clip.path), "-c", "s0", "--init",
                    ",".join(map(str, clip.scene.boxes[0])), "--no-video", "--stream",
                    str(fifo), "--timeout", "600", "--out", str(out))
    wait_for(lambda: any(out.glob(".track.tmp*")), process, "CSV opened")
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 128 + signal.SIGTERM, stderr
    assert error_line(stderr).endswith(f"interrupted by SIGTERM; partial results in {out}")
    record = assert_records_agree(out)
    assert (record["status"], record["frames"], record["outputs"]) == (
        "interrupted", 0, ["track.csv"])


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_to_the_batch_alone_leaves_a_summary_that_agrees_with_the_runs(
        inputs: Path, tmp_path: Path, signum: int) -> None:
    """... and the stopped batch says what it did, as a finished one does: a line per run it
    has a record of (also one that finished in the grace period), the tally with where
    summary.csv is, then that it was interrupted. It used to print only "vtrack: interrupted"
    after the lines of the runs done before the signal. The pairs it never started say so in
    summary.csv's error, and how to run them (the error was empty; the tally did not say)."""
    out = tmp_path / "out"
    process = start("batch", str(inputs), "-c", "s0", "-c", "camshift", "--jobs", "1",
                    "--out", str(out))
    # signal once a job is under way: its worker (which gets no signal) finishes it in the
    # grace period, the batch stops before the rest
    wait_for(lambda: any(out.glob("*/*/.track.tmp*")), process, "a job running")
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + signum, stderr
    assert "Traceback" not in stderr
    with (out / "summary.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 8  # every input x config
    statuses = []
    for row in rows:
        folder = out / row["input"] / row["config"]
        if (folder / "run.json").exists():
            record = assert_records_agree(folder)
            assert row["status"] == record["status"], (row, record["status"])
            assert row["frames"] == str(record["frames"])
        else:  # its error says it never ran and how to run it (it was empty)
            assert row["status"] == "interrupted", row
            assert row["error"].startswith("never ran (the batch stopped first): the same "
                                           "vtrack batch command runs it"), row
        statuses.append(row["status"])
    assert "interrupted" in statuses  # the batch did stop early
    assert "complete" in statuses  # the job running at the signal finished in the grace
    stdout_lines = stdout.splitlines()
    for row in rows:
        if (out / row["input"] / row["config"] / "run.json").exists():
            label = f"{row['input']} [{row['config']}]: "
            assert sum(line.startswith(label) for line in stdout_lines) == 1, (label, stdout)
    tally = stdout_lines[-1]
    assert tally.startswith("8 runs (") and tally.endswith(f"-> {out / 'summary.csv'}"), stdout
    assert "not started: the batch was stopped, the same command runs them" in tally
    assert stderr.splitlines()[-1] == "vtrack: interrupted", stderr


@pytest.mark.parametrize(("signum", "error"), [(signal.SIGINT, "interrupted by the user"),
                                                (signal.SIGTERM, "interrupted by SIGTERM")],
                         ids=["SIGINT", "SIGTERM"])
def test_a_job_still_running_when_the_batch_stops_records_itself_interrupted(
        scene_factory: SceneFactory, tmp_path: Path, signum: signal.Signals, error: str) -> None:
    """A batch stopped alone (SIGTERM to its pid: ``kill``, ``docker stop``) gives its running
    jobs a grace period; a job still running after it (here: its input sends no more frames)
    gets SIGTERM and ends ``interrupted`` with its outputs whole and its ``run.json`` written.
    It used to be killed outright: temporary files only, its tracked frames unrecorded. The
    job gets the signal the batch got: a batch stopped by SIGINT alone gave it SIGTERM, and
    its record said "interrupted by SIGTERM"."""
    scene = scene_factory("smooth", width=W, height=H, frames=12)
    fifo = tmp_path / "feed"
    os.mkfifo(fifo)
    writer = os.open(fifo, os.O_RDWR)  # holds the feed open: the job waits for frame 10
    out = tmp_path / "out"
    request = RunRequest(input=str(fifo), out_dir=out, config=load_config("s0"),
                         init_box=scene.boxes[0], raw=RawFormat.parse(f"{W}x{H}", "bgr24", 30))
    worker = _Worker(_context())
    try:
        assert worker.start(Job("feed", "s0", request))
        data = b"".join(frame.tobytes() for frame in list(scene.frames())[:10])
        threading.Thread(target=os.write, args=(writer, data), daemon=True).start()
        wait_for(lambda: any(p.read_bytes().count(b"\n") > 10
                                    for p in out.glob(".track.tmp*")), worker, "rows")
        worker.stop(grace_s=0, signum=signum)
    finally:
        os.close(writer)
    assert not worker.process.is_alive()
    record = assert_records_agree(out)
    assert (record["status"], record["error"], record["frames"]) == (
        "interrupted", error, 10)


def _stalled_job(scene: Scene, folder: Path, name: str) -> tuple[Job, int]:
    """A job reading raw frames from a FIFO that gets only 10 frames and stays open (the job
    waits for frame 10 until it is stopped), results in ``folder / name``; and the FIFO's
    held end, for the caller to close."""
    fifo = folder / f"{name}.feed"
    os.mkfifo(fifo)
    writer = os.open(fifo, os.O_RDWR)
    data = b"".join(frame.tobytes() for frame in list(scene.frames())[:10])
    threading.Thread(target=os.write, args=(writer, data), daemon=True).start()
    request = RunRequest(input=str(fifo), out_dir=folder / name, config=load_config("s0"),
                         init_box=scene.boxes[0], raw=RawFormat.parse(f"{W}x{H}", "bgr24", 30))
    return Job(name, "s0", request), writer


def _ten_rows(out: Path) -> bool:
    return any(p.read_bytes().count(b"\n") > 10 for p in out.glob(".track.tmp*"))


def test_stopped_workers_share_each_wait_and_one_that_cannot_record_is_killed(
        scene_factory: SceneFactory, tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """stop_workers' phases are shared, not one worker after the other: with the first worker
    unable to act (SIGSTOP), the second still gets the signal after the (shared) grace and
    records itself while the first is held in the record grace; the first, still there when
    that grace ends, is killed (no run.json: it never recorded). One after the other, the
    second would get its signal only once the first had been killed."""
    scene = scene_factory("smooth", width=W, height=H, frames=12)
    jobs, writers, workers = [], [], []
    try:
        for name in ("held", "free"):
            job, writer = _stalled_job(scene, tmp_path, name)
            jobs.append(job)
            writers.append(writer)
            workers.append(_Worker(_context()))
            assert workers[-1].start(job)
        for job, worker in zip(jobs, workers, strict=True):
            wait_for(lambda out=job.request.out_dir: _ten_rows(out), worker, "rows")
        held = workers[0]
        os.kill(held.process.pid, signal.SIGSTOP)
        released = threading.Event()
        monkeypatch.setattr(executors, "RECORD_GRACE_S", 3600.0)  # ends when `held` does
        stopping = threading.Thread(target=lambda: (stop_workers(workers, grace_s=0),
                                                    released.set()), daemon=True)
        stopping.start()
        free_out = jobs[1].request.out_dir
        deadline = time.monotonic() + START_BOUND_S  # (it records, then ends: no wait_for)
        while not (free_out / "run.json").exists():
            assert time.monotonic() < deadline, "the free worker did not record itself"
            time.sleep(0.01)
        assert not released.is_set() and held.process.is_alive()  # the record grace goes on
        os.kill(held.process.pid, signal.SIGKILL)  # (as the grace's end would)
        stopping.join(60)
        assert released.is_set()
    finally:
        for worker in workers:  # (a failed test leaves no process held stopped)
            with contextlib.suppress(ProcessLookupError):
                os.kill(worker.process.pid, signal.SIGKILL)
        for writer in writers:
            os.close(writer)
    record = assert_records_agree(free_out)
    assert (record["status"], record["error"], record["frames"]) == (
        "interrupted", "interrupted by SIGTERM", 10)
    assert not (jobs[0].request.out_dir / "run.json").exists()
    assert not any(worker.process.is_alive() for worker in workers)
    # the end of the record grace kills what is still there: here, a worker held stopped
    job, writer = _stalled_job(scene, tmp_path, "again")
    worker = _Worker(_context())
    try:
        assert worker.start(job)
        wait_for(lambda: _ten_rows(job.request.out_dir), worker, "rows")
        os.kill(worker.process.pid, signal.SIGSTOP)
        monkeypatch.setattr(executors, "RECORD_GRACE_S", 0.0)
        stop_workers([worker], grace_s=0)
        worker.process.join(60)
    finally:
        os.close(writer)
    assert worker.process.exitcode == -signal.SIGKILL
    assert not (job.request.out_dir / "run.json").exists()


def test_a_job_killed_as_the_batch_stops_is_no_pair_never_started(
        scene_factory: SceneFactory, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A job still running at a stop that cannot record itself within the grace periods (here
    held stopped; in use: --preset placebo, whose encoder's flush outlasts them) is killed:
    its folder keeps track.csv and a temporary video, no run.json. Its summary.csv row said
    "never ran (the batch stopped first): the same vtrack batch command runs it" and the tally
    counted it "not started", while that command then refused the pair ("holds the results of
    an earlier run (track.csv) ... (made with other settings)")."""
    from vtrack.batch import run_batch
    from vtrack.batch.plan import Plan

    scene = scene_factory("smooth", width=W, height=H, frames=12)
    job, writer = _stalled_job(scene, tmp_path, "held")
    monkeypatch.setattr(executors, "RECORD_GRACE_S", 0.0)

    def on_progress(progress: Progress) -> None:
        """(The job's first message: it has opened its input.) Hold its worker, stop."""
        deadline = time.monotonic() + START_BOUND_S
        while not _ten_rows(job.request.out_dir):
            assert time.monotonic() < deadline, "no rows"
            time.sleep(0.01)
        lock = (job.request.out_dir / LOCK_NAME).read_text()
        os.kill(int(lock.split(":")[0].removeprefix("pid ")), signal.SIGSTOP)
        raise Interrupted(signal.SIGTERM)

    plan = Plan(jobs=[job], known=[], order=[(job.input, job.config)])
    late: list = []
    summary_path = tmp_path / "results" / "summary.csv"
    try:
        with pytest.raises(Interrupted):
            for _ in run_batch(plan, LocalExecutor(1, on_progress=on_progress), summary_path,
                               late):
                pass
    finally:
        os.close(writer)
    assert not (job.request.out_dir / "run.json").exists()  # (killed: it never recorded)
    with summary_path.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["status"] for row in rows] == ["interrupted"], rows
    error = rows[0]["error"]
    assert error.startswith("started, then killed when the batch stopped"), error
    assert "--overwrite" in error
    assert [(o.input, o.status, o.error) for o in late] == [("held", "interrupted", error)]


def test_a_batch_closed_while_a_job_runs_stops_it_with_its_records_whole(
        scene_factory: SceneFactory, tmp_path: Path) -> None:
    """The consumer of LocalExecutor.run gone while a job runs (the batch command ends on an
    error, closing the generator): the job still running after the grace gets SIGTERM and
    ends interrupted, its outputs whole and run.json written; no worker is left."""
    scene = scene_factory("smooth", width=W, height=H, frames=12)
    job, writer = _stalled_job(scene, tmp_path, "feed")

    class Gone(Exception):
        pass

    def on_progress(progress: Progress) -> None:
        """(The job's first message: it has opened its input.)"""
        deadline = time.monotonic() + START_BOUND_S
        while not _ten_rows(job.request.out_dir):
            assert time.monotonic() < deadline, "no rows"
            time.sleep(0.01)
        raise Gone  # the batch's own error, while the job waits for frame 10

    started = len(multiprocessing.active_children())
    try:
        with pytest.raises(Gone):
            for _ in LocalExecutor(1, on_progress=on_progress).run([job]):
                pass
    finally:
        os.close(writer)
    record = assert_records_agree(job.request.out_dir)
    assert (record["status"], record["error"], record["frames"]) == (
        "interrupted", "interrupted by SIGTERM", 10)
    assert len(multiprocessing.active_children()) <= started


def test_a_signal_to_the_batchs_process_group_leaves_a_summary_that_agrees_with_the_runs(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Ctrl-C, `timeout` or a scheduler signal the whole process group: the forkserver died
    too, so the batch took its worker for gone at once and wrote the running job's row
    (no frames, no error) before the worker wrote its run.json (frames and error)."""
    long = clip_factory("smooth", width=320, height=240, frames=900)
    inputs = tmp_path / "in"
    inputs.mkdir()
    for name in ("a", "b"):
        shutil.copy(long.path, inputs / f"{name}.mp4")
        shutil.copy(long.gt, inputs / f"{name}.gt.txt")
    out = tmp_path / "out"
    process = start("batch", str(inputs), "--jobs", "1", "--out", str(out), "--quiet",
                    new_session=True)
    wait_for(lambda: any(len(p.read_bytes().splitlines()) > 600
                         for p in out.glob("*/*/.track.tmp*")), process, "a job running")
    os.killpg(process.pid, signal.SIGTERM)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + signal.SIGTERM, stderr
    with (out / "summary.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    recorded = 0
    for row in rows:
        folder = out / row["input"] / row["config"]
        if (folder / "run.json").exists():
            record = assert_records_agree(folder)
            assert (row["status"], row["frames"], row["error"]) == (
                record["status"], str(record["frames"]), record["error"] or ""), row
            recorded += 1
    assert recorded >= 1


# --- the default folder, replacing an earlier run ---------------------------------------------


def test_default_folder_is_per_input_and_config(clip: Clip, tmp_path: Path) -> None:
    (tmp_path / "mine.toml").write_text(
        (Path(__file__).parents[1] / "vtrack" / "configs" / "camshift.toml").read_text()
        .replace('name = "camshift"', ""))
    for config, folder in (("s0", "s0"), ("camshift", "camshift"),
                           (str(tmp_path / "mine.toml"), "mine")):
        result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "-c", config,
                        "--no-video", cwd=tmp_path)
        assert result.returncode == 0, result.stderr
        out = tmp_path / "vtrack-out" / clip.path.stem / folder
        assert str(Path("vtrack-out") / clip.path.stem / folder) in result.stdout
        assert json.loads((out / "run.json").read_text())["request"]["config"]["name"] \
            == json.loads((out / "run.json").read_text())["config"]["name"]
        assert len(csv_rows(out / "track.csv")) == FRAMES
    assert sorted(p.name for p in (tmp_path / "vtrack-out" / clip.path.stem).iterdir()) == [
        "camshift", "mine", "s0"]


def test_a_second_run_replaces_only_vtracks_own_outputs(clip: Clip, tmp_path: Path) -> None:
    out = tmp_path / "out"
    first = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out))
    assert first.returncode == 0, first.stderr
    (out / "notes.txt").write_text("mine\n")
    (out / ".annotated.tmp-1-dead.mp4").write_bytes(b"left by a killed run")
    refused = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out),
                     "-c", "camshift", "--no-video", "--frames", "20")
    assert refused.returncode == 2
    assert error_line(refused.stderr) == (
        f"vtrack: error: {out}: holds the results of an earlier run (run.json, track.csv, "
        "annotated.mp4); give --overwrite (-y) to replace them, or another --out")
    second = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--out", str(out),
                    "-c", "camshift", "--no-video", "--frames", "20", "-y")
    assert second.returncode == 0, second.stderr
    record = assert_records_agree(out)
    assert record["outputs"] == ["track.csv"] and record["frames"] == 20
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "run.json", "track.csv"]
    assert (out / "notes.txt").read_text() == "mine\n"


def test_a_config_file_named_as_another_config_says_why_its_folder_is_taken(
        clip: Clip, tmp_path: Path) -> None:
    """`vtrack stages robust --toml > mine.toml` keeps `name = "robust"`: after a plain robust
    run, `vtrack run clip.mp4 -c mine.toml` was refused with only 'vtrack-out/clip/robust:
    holds the results of an earlier run ...', which did not say why mine.toml writes to
    robust/. The refusal of the default folder now says it is named after the config's name."""
    run_args = (str(clip.path), "--gt", str(clip.gt), "--no-video", "--frames", "5")
    assert vtrack("run", *run_args, cwd=tmp_path).returncode == 0
    copied = vtrack("stages", "robust", "--toml", cwd=tmp_path)
    (tmp_path / "mine.toml").write_text(copied.stdout)
    refused = vtrack("run", *run_args, "-c", "mine.toml", cwd=tmp_path)
    assert refused.returncode == 2
    folder = Path("vtrack-out") / clip.path.stem / "robust"
    assert error_line(refused.stderr) == (
        f"vtrack: error: {folder}: holds the results of an earlier run (run.json, track.csv); "
        "give --overwrite (-y) to replace them, or another --out (the folder is named after "
        "the config's name, 'robust' in mine.toml: give the config a name of its own)")
    # --out names the folder itself, and a shipped config's folder is its own name: no note
    for args in (("-c", "mine.toml", "--out", str(folder)), ("-c", "robust")):
        refused = vtrack("run", *run_args, *args, cwd=tmp_path)
        assert refused.returncode == 2
        assert error_line(refused.stderr).endswith("or another --out")


@pytest.mark.parametrize("args", [
    ("missing.mp4",),
    ("CLIP", "--init", "500,500,20,20"),
    ("CLIP", "-c", "s1"),  # no --init and no --gt
    ("CLIP", "--gt", "nothere.txt"),
], ids=["no-input", "init-outside", "no-box", "no-gt-file"])
def test_error_exits_leave_no_folders(clip: Clip, tmp_path: Path, args: tuple[str, ...]) -> None:
    args = tuple(str(clip.path) if a == "CLIP" else a for a in args)
    for out in ((), ("--out", str(tmp_path / "a" / "b" / "c"))):
        result = vtrack("run", *args, *out, cwd=tmp_path)
        assert result.returncode == 2, result.stderr
        error_line(result.stderr)
        assert sorted(p.name for p in tmp_path.iterdir()) == [], list(tmp_path.rglob("*"))


def test_batch_summary_counts_skipped_frames(clip_factory: ClipFactory, tmp_path: Path) -> None:
    folder = tmp_path / "in"
    shutil.copytree(clip_factory("smooth", width=W, height=H, frames=FRAMES, fmt="images").path,
                    folder / "seq")
    video = clip_factory("jump", width=W, height=H, frames=FRAMES)
    shutil.copy(video.path, folder / "jump.mp4")
    shutil.copy(video.gt, folder / "jump.gt.txt")
    images = sorted((folder / "seq" / "img").iterdir())
    for broken in (images[5], images[9]):
        broken.write_bytes(b"not an image")
    result = vtrack("batch", str(folder), "--no-video", "--jobs", "1", "--out",
                    str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    rows = read_summary(tmp_path / "out")
    for name, skipped in (("seq", 2), ("jump", 0)):
        record = json.loads((tmp_path / "out" / name / DEFAULT_CONFIG / "run.json").read_text())
        assert record["summary"]["frames_skipped"] == skipped
        assert rows[name]["frames_skipped"] == str(skipped)
        assert rows[name]["frames"] == str(FRAMES - skipped)


def _interrupted_long_run(tmp_path: Path, *options: str) -> tuple[Path, Path, str]:
    """`vtrack run long.mp4 OPTIONS --frames 2500` (a 3000-frame clip) stopped by SIGTERM
    once it has written 20 rows: the clip, the run's folder and its stderr."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=3000, fps=30)
    clip = write_video(scene, tmp_path / "long.mp4", preset="ultrafast", keyint=30)
    first = tmp_path / "first"
    return clip, first, _stopped_after(20, first, "run", str(clip), *options, "--frames", "2500")


def _stopped_after(rows: int, first: Path, *args: str) -> str:
    """`vtrack ARGS --no-video -o FIRST` stopped by SIGTERM once its CSV (track.csv or
    tracks.csv) has ``rows`` rows: its stderr."""
    process = start(*args, "--no-video", "-o", str(first))
    wait_for(lambda: any(len(p.read_bytes().splitlines()) > rows
                         for p in first.glob(".track*.tmp*")), process, f"{rows} rows")
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 128 + signal.SIGTERM, stderr
    return stderr


def test_an_interrupted_run_says_how_to_go_on_from_where_it_stopped(tmp_path: Path) -> None:
    """SIGTERM to `vtrack run long.mp4 --init ... --frames 2500` said only 'interrupted by
    SIGTERM; partial results in OUT', and run.json not which frame was the last written. Now
    run.json has last_frame and a line gives the options that go on from there (the last frame
    tracked, its box as track.csv wrote it, the frames left of --frames): the run they make
    starts on that row and ends where the whole run would have."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=3000, fps=30)
    init = ",".join(f"{v:.2f}" for v in scene.boxes[0])
    clip, first, stderr = _interrupted_long_run(tmp_path, "--init", init)
    out = tmp_path / "out"
    record = assert_records_agree(first)
    rows = csv_rows(first / "track.csv")
    assert record["status"] == "interrupted" and 20 <= record["frames"] < 2500
    assert record["last_frame"] == int(rows[-1][0]) == record["frames"] - 1
    last = next(row for row in reversed(rows) if row[8] == "tracking")
    options = (f"--start {last[0]} --init {','.join(last[2:6])} "
               f"--frames {2500 - int(last[0])}")
    assert record["summary"]["resume"] == options
    hint = stderr.splitlines()[-1]
    assert hint == (f"vtrack: {clip}: to go on from where it stopped, run the same command "
                    f"with {options} and another --out"), stderr
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), *options.split(),
                           "--no-video", "-o", str(out)],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    again = csv_rows(out / "track.csv")
    assert again[0][:6] == last[:6] and again[-1][0] == "2499"


def test_a_multi_target_run_taken_up_with_its_hint_numbers_its_tracks_on(
        tmp_path: Path) -> None:
    """SIGTERM to `vtrack run ped.mp4 -c fixed_camera --frames 800` (a generated pedestrians
    clip) printed `... with --start 73 --frames 727 and another --out (its track ids start
    again at 1: add 5, this run's highest, to them to join the two tracks.csv)`: the run that
    hint made numbered its tracks from 1 again (ids 2, 4, 5, 6, ... after the first run's 3
    and 5), so its tracks.csv gave a first run's id to another track. The hint now gives
    `--first-id` one after the first run's highest id (run.json's ``summary.last_track_id``)
    and the run it makes uses none of the first run's ids: its tracks are numbered on from
    there and it starts after the first run's last frame."""
    scene = make_scene("pedestrians", seed=4, width=320, height=240, frames=900, fps=30)
    clip = write_video(scene, tmp_path / "ped.mp4", preset="ultrafast", keyint=30)
    first = tmp_path / "first"
    stderr = _stopped_after(40, first, "run", str(clip), "-c", "fixed_camera", "--frames", "800")
    record = json.loads((first / "run.json").read_text())
    rows = csv_rows(first / "tracks.csv")
    ids = {int(row[1]) for row in rows}
    assert record["summary"]["last_track_id"] == max(ids), record["summary"]
    last = record["last_frame"]  # 0-based; tracks.csv's frames are 1-based
    options = f"--start {last + 1} --frames {800 - last - 1} --first-id {max(ids) + 1}"
    assert record["summary"]["resume"] == options
    prefix = f"vtrack: {clip}: to go on from where it stopped, run the same command with "
    hint = stderr.splitlines()[-1]
    assert hint == f"{prefix}{options} and another --out", stderr
    given = hint.removeprefix(prefix).removesuffix(" and another --out").split()
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "-c",
                           "fixed_camera", *given, "--no-video", "-o", str(tmp_path / "again")],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    again = csv_rows(tmp_path / "again" / "tracks.csv")
    assert again, "the resumed run confirmed no track: nothing was shown"
    assert min(int(row[1]) for row in again) > max(ids), (sorted(ids), again[:3])
    assert int(again[0][0]) > int(rows[-1][0])


def test_a_run_whose_track_ids_pass_2_to_the_53_stops_at_that_frame(tmp_path: Path) -> None:
    """`vtrack run ped.mp4 -c fixed_camera --first-id 9007199254740983` (10 ids below 2**53,
    up to which a double holds every whole number) numbered its tracks on past 2**53
    (tracks.csv and run.json's last_track_id 9007199254740993 and up, which MATLAB, pandas or
    JavaScript read as another id), exit 0. A run now numbers no track past 2**53: it stops at
    the frame whose new track would need such an id, in one line naming the first id and that
    frame (exit 2), its tracks.csv and run.json whole up to the frame before. The frame is the
    run's 0-based one and tracks.csv's 1-based one (it said only "frame 56", tracks.csv's last
    rows being frame 56's)."""
    largest = 2**53
    scene = make_scene("pedestrians", seed=4, width=320, height=240, frames=300, fps=30)
    clip = write_video(scene, tmp_path / "ped.mp4", preset="ultrafast", keyint=30)
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "-c",
                           "fixed_camera", "--first-id", str(largest - 9), "--no-video", "-o",
                           str(out)], capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2, done.stderr
    line = done.stderr.splitlines()[-1]
    stopped_at = int(line.split(" are used up at frame ")[1].split(" ")[0])
    assert line == (f"vtrack: error: the track ids from {largest - 9} are used up at frame "
                    f"{stopped_at} (frame {stopped_at + 1} counted from 1, as tracks.csv and "
                    f"MOTChallenge number them): a new track would be numbered past {largest} "
                    "(2^53, the largest id a double holds exactly: MATLAB, pandas and "
                    "JavaScript would read it as another's); number the tracks from a smaller "
                    "first id (--first-id N, first_track_id=N)"), \
        done.stderr
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "failed"
    assert record["error"] == line.removeprefix("vtrack: error: ")
    assert stopped_at > 0 and record["last_frame"] == stopped_at - 1
    rows = csv_rows(out / "tracks.csv")
    assert rows and {int(row[1]) for row in rows} <= set(range(largest - 9, largest + 1))
    assert max(int(row[0]) for row in rows) == stopped_at  # (MOTChallenge frames: 1-based)
    assert record["summary"]["last_track_id"] <= largest


def test_a_hint_past_2_to_the_53_gives_no_first_id_and_a_warning_says_so(
        tmp_path: Path) -> None:
    """An interrupted multi-target run whose highest track id is 2**53 (the largest
    --first-id; reached with ids numbered up to it, as a run now is) hints no --first-id
    (2**53 + 1 would be refused) and warns that the run the hint makes numbers its tracks as
    this one did; an id the option takes is hinted, without the warning. (_resume_options and
    _past_track_ids, called as run() calls them: the run that reached 2**53 end to end now stops
    at the id after it.)"""
    from vtrack.pipeline import Pipeline
    from vtrack.run import (
        STATUS_INTERRUPTED,
        RunSummary,
        _past_track_ids,
        _Resolved,
        _Resumable,
        _resume_options,
        _Span,
        _Tracked,
    )

    config = load_config("fixed_camera")
    request = RunRequest(input=str(tmp_path / "ped.mp4"), out_dir=tmp_path / "out",
                         config=config, max_frames=800, first_track_id=2**53 - 9)
    resolved = _Resolved(Pipeline(config.build()), None, None, None, span=_Span(count=800))
    tracked = _Tracked(status=STATUS_INTERRUPTED,
                       last_frame=_Resumable(index=40, time_s=40 / 30, before=40))
    past = 2**53 + 1
    assert _resume_options(resolved, tracked, 30.0, past) == "--start 41 --frames 759"
    assert _resume_options(resolved, tracked, 30.0, 2**53) == \
        "--start 41 --frames 759 --first-id 9007199254740992"
    summary = RunSummary(input=request.input, out_dir=str(request.out_dir), config=config.name,
                         status=STATUS_INTERRUPTED, frames=41, seconds=1.0, fps=41.0,
                         multi_target=True, resume="--start 41 --frames 759")
    assert _past_track_ids(request, summary, past) == (
        f"{tmp_path / 'out' / 'tracks.csv'}: its highest track id, 9007199254740992, leaves no "
        "--first-id (at most 9007199254740992) for the run the hint below makes: that run "
        "numbers its tracks as this one did; renumber one of the two tracks.csv to join them")
    assert _past_track_ids(request, summary, 2**53) is None  # (the hint gives it)
    summary.resume = None  # nothing to go on from: no hint to warn of
    assert _past_track_ids(request, summary, past) is None


def test_a_chain_that_needs_no_box_resumes_after_the_last_frame_written(tmp_path: Path) -> None:
    """SIGTERM to a run of a chain that needs no box (`vtrack run ped.mp4 -c fixed_camera
    --frames 1400`) said `--start 533 --frames 867` with last_frame 533: the resumed run wrote
    frame 533 again. It now resumes at the frame after (`--start 534 --frames 866`), and the two
    runs write each frame of the whole run once."""
    clip, first, _ = _interrupted_long_run(tmp_path, "-c", "s4")
    out = tmp_path / "out"
    record = json.loads((first / "run.json").read_text())
    last = record["last_frame"]
    assert record["status"] == "interrupted" and 20 <= last < 2499
    options = f"--start {last + 1} --frames {2500 - last - 1}"
    assert record["summary"]["resume"] == options
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s4",
                           *options.split(), "--no-video", "-o", str(out)],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    frames = [int(row[0]) for row in [*csv_rows(first / "track.csv"), *csv_rows(out / "track.csv")]]
    assert frames == list(range(2500))


def test_pairs_known_before_a_stop_are_reported_not_said_not_started(tmp_path: Path) -> None:
    """A batch of 500 pairs complete before, stopped (SIGTERM 1.15 s in) while it wrote
    summary.csv or printed their lines, said '500 runs (500 not started: the batch was
    stopped, the same command runs them)' beside a summary.csv of 500 complete rows: the
    pairs planned as known (complete before, refused, failed before running) that it had not
    yet handed over were counted as never started. They now come with the stopped batch's
    other late outcomes."""
    from vtrack.batch import run_batch
    from vtrack.batch.plan import Plan

    known = [Outcome(name, "s0", "failed", error="no box") for name in ("a", "b", "c")]
    plan = Plan(jobs=[], known=known, order=[(o.input, o.config) for o in known])
    late: list[Outcome] = []
    running = run_batch(plan, LocalExecutor(1), tmp_path / "out" / "summary.csv", late)
    assert next(running) is known[0]
    with pytest.raises(Interrupted):
        running.throw(Interrupted(signal.SIGTERM))
    assert {o.input for o in late} >= {"b", "c"}, late


def test_a_failure_while_the_run_is_recorded_leaves_no_temporary_csv(
        clip: Clip, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An error while the run was recorded, before the CSV got its final name, left
    `.track.tmp-PID-*.csv` in the folder: the folder's clearing keeps this process's own
    temporaries (taken to be still written), so it outlived the run, and every later run in the
    same process (a batch worker's). Now the run's error is raised and its temporary removed."""
    from vtrack import run as run_module

    def broken(*args: object) -> list[str]:
        raise RuntimeError("the record broke")

    monkeypatch.setattr(run_module._Timeline, "warnings", broken)
    out = tmp_path / "out"
    request = RunRequest(str(clip.path), out, load_config("s0"), init_box=clip.scene.boxes[0],
                         video=False)
    with pytest.raises(RuntimeError, match="the record broke"):
        run(request)
    left = sorted(p.name for p in out.iterdir()) if out.exists() else []
    assert left == []  # (the folder it made is removed too, when nothing else is in it)
