"""Issue 21 item 3: `kill -9` of a batch leaves no worker running: each worker stops with its
parent (its job ends `interrupted`, outputs whole, as on SIGTERM), and the resume that follows
runs those jobs again and writes a summary that agrees with the runs' own records. A worker
that finds the batch gone when it reports progress does not fail its run for it."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from vtrack.batch.jobs import Job, Progress
from vtrack.batch.summary import UNFINISHED
from vtrack.batch.worker import execute
from vtrack.config import load_config
from vtrack.request import RunRequest
from vtrack.scenes import make_scene, write_groundtruth, write_video

NAMES = ("a", "b")


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("parent")
    scene = make_scene("smooth", seed=1, width=320, height=240, frames=600, fps=30.0)
    write_video(scene, folder / "a.mp4", preset="veryfast")
    write_groundtruth(scene, folder / "a.gt.txt")
    shutil.copy(folder / "a.mp4", folder / "b.mp4")
    shutil.copy(folder / "a.gt.txt", folder / "b.gt.txt")
    return folder


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie waiting to be reaped does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def holders(out: Path) -> dict[str, int]:
    """The pid holding each job folder's lock, from the note in the lock file."""
    found = {}
    for name in NAMES:
        try:
            note = (out / name / "robust" / ".vtrack.lock").read_text()
        except OSError:
            continue
        if note.startswith("pid "):
            found[name] = int(note.split()[1].rstrip(":"))
    return found


def tracking(out: Path) -> bool:
    """Whether both jobs have written rows (their CSVs are still temporary files)."""
    rows = []
    for name in NAMES:
        temps = list((out / name / "robust").glob(".track.tmp-*.csv"))
        rows.append(sum(t.read_bytes().count(b"\n") for t in temps))
    return min(rows) > 10


def wait_for(condition, limit_s: float = 60.0) -> bool:
    deadline = time.monotonic() + limit_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="parent-death watch: Linux")
def test_workers_die_with_a_killed_batch_and_the_resume_agrees(folder: Path,
                                                               tmp_path: Path) -> None:
    out = tmp_path / "out"
    command = [sys.executable, "-m", "vtrack", "batch", str(folder), "-o", str(out), "-j", "2",
               "--preset", "slow", "-q"]
    batch = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        assert wait_for(lambda: len(holders(out)) == 2 and tracking(out)), "jobs should start"
        workers = holders(out)
        assert batch.pid not in workers.values()
        batch.send_signal(signal.SIGKILL)
        batch.wait()
        assert wait_for(lambda: not any(alive(pid) for pid in workers.values()), 30), \
            "the workers outlived their batch"
    finally:
        if batch.poll() is None:
            batch.kill()
    for name in NAMES:  # stopped part way (not left to finish), recorded whole
        record = json.loads((out / name / "robust" / "run.json").read_text())
        assert record["status"] == "interrupted", record["status"]
        assert 0 < record["frames"] < 600
    # the summary has a row for every pair, none finished (it had none: no summary.csv, or
    # after some runs a summary of those alone, that looked whole)
    with (out / "summary.csv").open() as handle:
        killed = {row["input"]: (row["status"], row["error"]) for row in csv.DictReader(handle)}
    assert killed == dict.fromkeys(NAMES, ("interrupted", UNFINISHED))

    resume = subprocess.run(command, capture_output=True, timeout=300, check=False)
    assert resume.returncode == 0, resume.stderr.decode()
    with (out / "summary.csv").open() as handle:
        rows = {row["input"]: row for row in csv.DictReader(handle)}
    for name in NAMES:
        record = json.loads((out / name / "robust" / "run.json").read_text())
        assert record["status"] == "complete"
        assert rows[name]["status"] in ("complete", "skipped")
        assert int(rows[name]["frames"]) == record["frames"] == 600
    assert not os.path.exists(out / NAMES[0] / "robust" / ".vtrack.lock")


def test_a_job_whose_batch_hung_up_runs_on_and_records_itself(clip_factory,
                                                              tmp_path: Path) -> None:
    """A worker whose progress messages can no longer be sent (the batch's end of the pipe is
    closed) keeps its run whole: the run is not failed by the broken pipe (the parent watch's
    SIGTERM is what stops it), and it reports nothing more."""
    clip = clip_factory("smooth", frames=40)
    request = RunRequest(input=str(clip.path), out_dir=tmp_path / "job", config=load_config("s0"),
                         gt_path=clip.gt, video=False)
    sent: list[Progress] = []

    def hung_up(progress: Progress) -> None:
        sent.append(progress)
        raise BrokenPipeError(32, "Broken pipe")

    outcome = execute(Job("clip", "s0", request), hung_up)
    assert outcome.status == "complete", outcome.error
    assert len(sent) == 1
    record = json.loads((tmp_path / "job" / "run.json").read_text())
    assert record["status"] == "complete" and record["frames"] == 40
