"""Images missing from a folder's numbering are called missing, as the warning says, not
undecodable or damaged (in the summary line, ``vtrack frame`` and ``--start``)."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
import threading
from pathlib import Path

import av
import cv2
import numpy as np
import pytest
from conftest import START_BOUND_S

import vtrack.io.images as images_module
from vtrack.errors import PartialInputError
from vtrack.io.images import ImageFolderSource, read_stored
from vtrack.scenes import make_scene, write_image_sequence, write_video


def vtrack(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, timeout=120, check=False)


def truth(images: Path) -> tuple[str, ...]:
    """The options that read the sequence's (1-based) ground truth."""
    return "--gt", str(images.parent / "groundtruth_rect.txt"), "--gt-origin", "1"


@pytest.fixture(scope="module")
def numbered(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A sequence of 12 images with 0004..0006.jpg (frames 3..5) removed."""
    folder = tmp_path_factory.mktemp("missing") / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 12, 30), folder)
    for number in (4, 5, 6):
        (folder / "img" / f"{number:04d}.jpg").unlink()
    return folder / "img"


def test_the_summary_counts_missing_images_as_missing(numbered: Path, tmp_path: Path) -> None:
    """The summary said ``skipped 3 undecodable`` under a warning of 3 missing images."""
    done = vtrack("run", str(numbered), *truth(numbered), "-c", "s0", "--no-video",
                  "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    assert "skipped 3 missing from the numbering" in done.stdout
    assert "undecodable" not in done.stdout
    summary = json.loads((tmp_path / "out" / "run.json").read_text())["summary"]
    assert (summary["frames_skipped"], summary["frames_missing"]) == (3, 3)


def test_a_run_counts_the_missing_images_among_the_frames_it_read(tmp_path: Path) -> None:
    """In 20 images with 0004.jpg and 0015.jpg (frames 3 and 14) missing, `vtrack run seq
    --frames 3` (frames 0..2) warned "2 images missing from the numbering (the first after
    0003.jpg)" and said "skipped 2 missing", and `--frames 8` the same: the whole folder's
    gaps, counted before a frame was read (and an unreadable 0011.jpg, frame 10, was warned of
    and counted by `--frames 8` whenever the reader had gone ahead to it). Now the counts and lines
    cover the frames the run read, to the last one it tracked: none, then frame 3 alone (named
    with its frame), then all three."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 20, 30), folder)
    for number in (4, 15):
        (folder / "img" / f"{number:04d}.jpg").unlink()
    images = folder / "img"
    (images / "0011.jpg").write_bytes(b"not an image")
    junk = (f"{images / '0011.jpg'}: not an image FFmpeg can decode (Invalid data found when "
            "processing input); frame 10 skipped")
    for frames, missing, skipped in (("3", 0, 0), ("8", 1, 1), ("20", 2, 3)):
        out = tmp_path / f"out{frames}"
        done = vtrack("run", str(images), *truth(images), "-c", "s0", "--no-video", "--frames",
                      frames, "-o", str(out))
        assert done.returncode == 0, done.stderr
        record = json.loads((out / "run.json").read_text())
        summary = record["summary"]
        assert (summary["frames_skipped"], summary["frames_missing"]) == (skipped, missing)
        said = [] if not missing else [
            f"{images}: {missing} image{'s' if missing > 1 else ''} missing from the numbering "
            "(the first: frame 3, after 0003.jpg); their frames are skipped"]
        said += [junk] if skipped > missing else []
        assert record["warnings"] == said, frames
        assert done.stderr == "".join(f"vtrack: warning: {line}\n" for line in said)
        assert ("missing from the numbering" in done.stdout) == bool(missing), done.stdout


def test_an_unreadable_image_the_reader_went_ahead_to_is_not_the_consumers(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Frames are read ahead of the consumer in a thread, which counted and warned of each
    unreadable image as it read it: a run that took frame 0 of 8 images whose fifth is junk
    said 'frame 4 skipped' (frames_skipped 1) once the reader had got there. Now the frames
    handed on decide: nothing until frame 4's place is passed, then the line as before,
    while the frames go on (a run of --frames 7 that has not ended counts it)."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 96, 72, 10, 30), folder)
    for number in (9, 10):
        (folder / "img" / f"{number:04d}.jpg").unlink()
    junk = folder / "img" / "0005.jpg"
    junk.write_bytes(b"not an image")
    past_junk = threading.Event()  # the reader went past 0005.jpg, its note taken

    def reading(path: Path) -> tuple[np.ndarray, int]:
        if path.name == "0006.jpg":
            past_junk.set()
        return read_stored(path)

    monkeypatch.setattr(images_module, "read_stored", reading)
    line = (f"{junk}: not an image FFmpeg can decode (Invalid data found when processing "
            "input); frame 4 skipped")
    with ImageFolderSource(str(folder)) as source:
        frames = iter(source)
        assert next(frames).index == 0
        # the reader has room for frames 1..3 and reads 0006.jpg (frame 5) before it waits
        assert past_junk.wait(60)
        assert (source.frames_skipped, source.warnings) == (0, [])
        assert [next(frames).index for _ in range(3)] == [1, 2, 3]
        assert (source.frames_skipped, source.warnings) == (0, [])
        assert next(frames).index == 5  # frame 4's place passed; frames 6 and 7 still to come
        assert (source.frames_skipped, source.warnings) == (1, [line])
        assert [frame.index for frame in frames] == [6, 7]
        assert (source.frames_skipped, source.warnings) == (1, [line])


@pytest.mark.parametrize("lost", ["unreadable", "missing"])
def test_an_image_of_another_size_ends_the_frames_with_those_lost_before_it_counted(
        tmp_path: Path, lost: str) -> None:
    """10 images whose 0007.jpg is junk (or deleted) and 0008.jpg 80x60: the run stopped at
    frame 7 having read frames 0..5, and said neither skip (frames_skipped 0, no warning): the
    image of another size ended the frames before frame 6 counted as handed on. Now the
    places before the image that stopped the run are the run's: frame 6 is counted and
    warned of."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 10, 30), folder)
    images = folder / "img"
    if lost == "missing":
        (images / "0007.jpg").unlink()
    else:
        (images / "0007.jpg").write_bytes(b"not an image")
    small = cv2.resize(cv2.imread(str(images / "0008.jpg")), (80, 60))
    assert cv2.imwrite(str(images / "0008.jpg"), small)
    with ImageFolderSource(str(images)) as source:
        taken: list[int] = []
        with pytest.raises(PartialInputError, match="stopped at frame 7"):
            for frame in source:
                taken.append(frame.index)
        assert taken == [0, 1, 2, 3, 4, 5]
        said = ([f"{images}: 1 image missing from the numbering (the first: frame 6, after "
                 "0006.jpg); their frames are skipped"] if lost == "missing" else
                [f"{images / '0007.jpg'}: not an image FFmpeg can decode (Invalid data found "
                 "when processing input); frame 6 skipped"])
        assert (source.frames_skipped, source.frames_missing, source.warnings) == (
            1, int(lost == "missing"), said)


def test_the_frame_that_ends_a_duration_leaves_the_gap_before_it_uncounted(
        tmp_path: Path) -> None:
    """20 images with 0004.jpg and 0015.jpg (frames 3 and 14) deleted and 0011.jpg (frame 10)
    junk: `--frames 0.1s` (frames 0..2) said 'skipped 1 missing', and `--frames 0.32s`
    (frames 0..9 but 3) counted and warned of 0011.jpg: the frame whose time ended the span
    was handed on and counted as read. Now it is given back: only the gaps among the frames
    tracked count, as README says ('what a run read'). With a start by time (`--start 0.05s
    --frames 0.05s`: frame 2 alone) frame 3's gap was counted still (the frames were noted
    as handed on twice, and giving one back undid nothing), where `--start 2` counted 0."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 20, 30), folder)
    images = folder / "img"
    for number in (4, 15):
        (images / f"{number:04d}.jpg").unlink()
    (images / "0011.jpg").write_bytes(b"not an image")
    gap = (f"{images}: 1 image missing from the numbering (the first: frame 3, after "
           "0003.jpg); their frames are skipped")
    for span, frames, skipped, said in (
            (("--frames", "0.1s"), 3, 0, []), (("--frames", "0.32s"), 9, 1, [gap]),
            (("--start", "0.05s", "--frames", "0.05s"), 1, 0, []),
            (("--start", "2", "--frames", "0.05s"), 1, 0, [])):
        out = tmp_path / "-".join(span)
        done = vtrack("run", str(images), *truth(images), "-c", "s0", "--no-video", *span,
                      "-o", str(out))
        assert done.returncode == 0, done.stderr
        record = json.loads((out / "run.json").read_text())
        summary = record["summary"]
        assert (summary["frames"], summary["frames_skipped"]) == (frames, skipped), span
        assert record["warnings"] == said, span


def test_a_sources_warnings_are_not_assigned(tmp_path: Path) -> None:
    """An image folder's ``warnings`` took an assignment and dropped it without a word (a
    setter that did nothing). Now no source's ``warnings`` can be assigned."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 96, 72, 10, 30), folder)
    with ImageFolderSource(str(folder)) as source, pytest.raises(AttributeError):
        source.warnings = ["dropped"]  # type: ignore[misc]


def test_frame_and_start_call_a_missing_image_missing(numbered: Path, tmp_path: Path) -> None:
    """``vtrack frame --at 4`` said ``frame 4 could not be decoded (damaged; ...)``."""
    picture = vtrack("frame", str(numbered), "--at", "4", "-o", str(tmp_path / "f.png"))
    assert picture.returncode != 0 and picture.stderr.count("\n") == 1, picture.stderr
    assert (f"{numbered}: frame 4 is missing from the numbering (no image between 0003.jpg "
            "and 0007.jpg); the next frame it has is frame 6") in picture.stderr
    started = vtrack("run", str(numbered), *truth(numbered), "-c", "s0", "--start", "3",
                     "--no-video", "-o", str(tmp_path / "out"))
    assert started.returncode == 2, started.stderr
    assert "frame 3 of" in started.stderr and "is missing from the numbering" in started.stderr
    assert "damaged" not in started.stderr


def test_an_image_removed_while_the_folder_is_read_is_called_unreadable(tmp_path: Path) -> None:
    """A folder is listed when it opens; an image removed after that (a folder being cleaned
    while it is tracked) was 'not an image FFmpeg can decode (No such file or directory)'.
    Now it 'cannot be read', and its frame is skipped as before."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 10, 30), folder)
    source = ImageFolderSource(str(folder))
    gone = folder / "img" / "0004.jpg"
    gone.unlink()
    with source:
        indices = [frame.index for frame in source]
    assert indices == [0, 1, 2, 4, 5, 6, 7, 8, 9]
    assert source.warnings == [f"{gone}: cannot be read (No such file or directory); "
                               "frame 3 skipped"]


def test_frames_the_input_skipped_are_no_unflagged_misses(tmp_path: Path) -> None:
    """Probe 52b: run.json's (and the report's) miss_flagged, the share of missed frames the
    tracker itself calls occluded or lost, counted each image missing from the numbering as a
    miss the tracker did not flag, though it never saw that frame (leave_return, s1: 0.933
    where every missed frame of track.csv is called lost, 1.0). Such frames still count as
    misses in the overlap, but are left out of the honest-state measures."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("leave_return", 0, 160, 120, 60, 30), folder)
    for number in (6, 7):  # frames 5 and 6: the target is in view
        (folder / "img" / f"{number:04d}.jpg").unlink()
    out = tmp_path / "out"
    done = vtrack("run", str(folder), *truth(folder / "img"), "-c", "s1", "--no-video",
                  "-o", str(out))
    assert done.returncode == 0, done.stderr
    with (out / "track.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    missed = [row["state"] for row in rows if row["overlap"] != "" and float(row["overlap"]) == 0]
    assert missed and 5 not in {int(row["frame"]) for row in rows}
    record = json.loads((out / "run.json").read_text())
    expected = sum(state in ("occluded", "lost") for state in missed) / len(missed)
    assert record["metrics"]["frames_evaluated"] == 2 + sum(row["overlap"] != "" for row in rows)
    assert record["metrics"]["miss_flagged"] == pytest.approx(expected)
    report = vtrack("report", str(out), "-o", str(tmp_path / "report"))
    assert report.returncode == 0, report.stderr
    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        (row,) = csv.DictReader(handle)
    assert float(row["miss_flagged"]) == pytest.approx(expected, abs=1e-6)


def test_the_report_says_why_evaluated_frames_may_exceed_the_frames(numbered: Path,
                                                                    tmp_path: Path) -> None:
    """Probe 52b: the report of a run whose input skipped 3 frames listed Frames 9 and
    Evaluated 12 with the note 'frames with ground truth present', as if it had scored frames
    it did not track; the note now says skipped frames count among them, as misses."""
    out = tmp_path / "out"
    done = vtrack("run", str(numbered), *truth(numbered), "-c", "s0", "--no-video",
                  "-o", str(out))
    assert done.returncode == 0, done.stderr
    report = vtrack("report", str(out), "-o", str(tmp_path / "report"))
    assert report.returncode == 0, report.stderr
    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        (row,) = csv.DictReader(handle)
    assert (int(row["frames"]), int(row["frames_evaluated"])) == (9, 12)
    html = (tmp_path / "report" / "index.html").read_text()
    assert "skipped among them included (misses: no box), so it may exceed Frames" in html


def test_a_late_start_neither_reads_nor_counts_the_images_before_it(
        numbered: Path, tmp_path: Path) -> None:
    """`vtrack run seq --start 8` read every image before frame 8 and its summary and warnings
    counted those it could not (``skipped 1 undecodable, skipped 3 missing from the
    numbering``, two warnings), frames the run did not track. It now begins at the image
    numbered 8 (run.json ``read_from_frame``): the run's frames 8..11 skipped none."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 12, 30), folder)
    for number in (4, 5, 6):
        (folder / "img" / f"{number:04d}.jpg").unlink()
    (folder / "img" / "0002.jpg").write_bytes(b"not an image")
    images = folder / "img"
    done = vtrack("run", str(images), *truth(images), "-c", "s0", "--no-video", "--start", "8",
                  "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    assert done.stderr == "" and "skipped" not in done.stdout, done.stdout
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert (record["read_from_frame"], record["start_frame"], record["frames"]) == (8, 8, 4)
    assert (record["summary"]["frames_skipped"], record["warnings"]) == (0, [])
    with (tmp_path / "out" / "track.csv").open(newline="") as handle:
        assert [row["frame"] for row in csv.DictReader(handle)] == ["8", "9", "10", "11"]
    with ImageFolderSource(str(images)) as source:  # a start in a gap: the image before it
        assert source.start_near(4) == 2
        assert [frame.index for frame in source] == [2, 6, 7, 8, 9, 10, 11]
        # counted from the start, 4: frames 4 and 5 are the run's, missing as in a whole run;
        # not frame 3 before it (it was counted), nor frame 1
        assert source.frames_skipped == source.frames_missing == 2


def test_a_late_start_by_time_counts_from_the_first_frame_tracked(tmp_path: Path) -> None:
    """`vtrack run seq --start 0.15s` on 60 images with 0003.jpg junk and 0005..0007 and 0021
    missing started at frame 7, read from frame 3 (the image before the frame 0.15 s x 30 fps
    names) and warned of "4 images missing from the numbering", "skipped 4 missing": frames
    4..6, before the start, counted as the run's. Only frame 20's place counts now."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 60, 30), folder)
    for number in (5, 6, 7, 21):
        (folder / "img" / f"{number:04d}.jpg").unlink()
    (folder / "img" / "0003.jpg").write_bytes(b"not an image")
    images = folder / "img"
    done = vtrack("run", str(images), *truth(images), "-c", "s0", "--no-video", "--start",
                  "0.15s", "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    assert "skipped 1 missing from the numbering" in done.stdout, done.stdout
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert (record["start_frame"], record["read_from_frame"]) == (7, 3)
    assert (record["summary"]["frames_skipped"], record["summary"]["frames_missing"]) == (1, 1)
    assert record["warnings"] == [f"{images}: 1 image missing from the numbering (the first: "
                                  "frame 20, after 0020.jpg); their frames are skipped"]


def test_an_undecodable_image_at_a_start_by_time_is_not_the_runs(tmp_path: Path) -> None:
    """`vtrack run seq --start 1s` on 60 images (30 fps) with 0031.jpg (frame 30, at 1 s) junk
    and 0032.jpg missing started at frame 32 but warned "0031.jpg: not an image FFmpeg can
    decode ...; frame 30 skipped" and counted frames 30 and 31 as the run's ("skipped 1
    undecodable, skipped 1 missing from the numbering"), though an image missing at the
    start, or a damaged frame there in a video, is not. The run now begins at its first frame
    tracked, 32: nothing before it is counted; an undecodable image after it still is."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 160, 120, 60, 30), folder)
    (folder / "img" / "0032.jpg").unlink()
    for number in (31, 41):
        (folder / "img" / f"{number:04d}.jpg").write_bytes(b"not an image")
    images = folder / "img"
    done = vtrack("run", str(images), *truth(images), "-c", "s0", "--no-video", "--start",
                  "1s", "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    assert done.stderr == (f"vtrack: warning: {images / '0041.jpg'}: not an image FFmpeg can "
                           "decode (Invalid data found when processing input); frame 40 "
                           "skipped\n")
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert (record["start_frame"], record["frames"]) == (32, 27)
    assert (record["summary"]["frames_skipped"], record["summary"]["frames_missing"]) == (1, 0)


def _started_at(given: Path, start: str, out: Path) -> tuple[str, int, int, int]:
    """``vtrack run GIVEN -c s4 --start START``'s warnings, run.json ``start_frame``, the first
    row of track.csv and ``frames_skipped``."""
    done = vtrack("run", str(given), "-c", "s4", "--no-video", "--start", start, "-o", str(out))
    assert done.returncode == 0, done.stderr
    record = json.loads((out / "run.json").read_text())
    with (out / "track.csv").open(newline="") as handle:
        first_row = int(next(csv.DictReader(handle))["frame"])
    return done.stderr, record["start_frame"], first_row, record["summary"]["frames_skipped"]


def test_a_chain_without_a_box_started_at_a_damaged_image_says_so(tmp_path: Path) -> None:
    """In a folder whose 0011.jpg (frame 10) is junk, `vtrack run seq -c s4 --start 8` warned
    "frame 10 skipped" (frames_skipped 1), but `--start 10` began at frame 11 saying nothing:
    no warning, frames_skipped 0, start_frame 10 while track.csv began at 11. A start given as
    a frame number is that frame, decoded or not, as in a whole run: frame 10 is warned of and
    counted (and an image missing from the numbering there, frame 12 of `--start 12`, too;
    and a video's frames lost there). A start by time begins at the first frame decoded at or
    after it, as before."""
    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 0, 96, 72, 20, 30), folder)
    images = folder / "img"
    (images / "0011.jpg").write_bytes(b"not an image")
    (images / "0013.jpg").unlink()
    junk = (f"vtrack: warning: {images / '0011.jpg'}: not an image FFmpeg can decode (Invalid "
            "data found when processing input); frame 10 skipped\n")
    gap = (f"vtrack: warning: {images}: 1 image missing from the numbering (the first: "
           "frame 12, after 0012.jpg); their frames are skipped\n")
    for start, said in (("8", (gap + junk, 8, 8, 2)), ("10", (gap + junk, 10, 11, 2)),
                        ("12", (gap, 12, 13, 1)), ("0.33s", (gap, 11, 11, 1))):
        assert _started_at(images, start, tmp_path / start) == said, start
    # A video whose frames 10 and 11 were lost (a key frame each, cut out of the stream): the
    # same, `--start 10` said nothing of them.
    clip = write_video(make_scene("smooth", 0, 96, 72, 20, 30), tmp_path / "intra.ts",
                       keyint=1)
    cut = tmp_path / "cut.ts"
    with av.open(str(clip)) as whole, av.open(str(cut), "w", format="mpegts") as target:
        stream = target.add_stream_from_template(whole.streams.video[0])
        for at, packet in enumerate(p for p in whole.demux(video=0) if p.size):
            if at not in (10, 11):
                packet.stream = stream
                target.mux(packet)
    lost = f"vtrack: warning: {cut}: 2 damaged frames could not be decoded and were skipped\n"
    for start, said in (("8", (lost, 8, 8, 2)), ("10", (lost, 10, 12, 2)),
                        ("0.33s", ("", 12, 12, 0))):
        assert _started_at(cut, start, tmp_path / f"video{start}") == said, start


def test_the_resume_hint_of_a_chain_without_a_box_goes_on_over_a_missing_image(
        tmp_path: Path) -> None:
    """A chain that needs no first box (s4) interrupted in a folder whose every other image is
    missing was told to go on with '--start LAST+1', a frame with no image, and that run was
    refused ('--start 85: frame 85 of SEQ is missing from the numbering ...; start at a frame
    it has'). A start frame without a picture is refused only where the first box is that
    frame's; such a chain starts at the next frame it has, so the hint goes on."""
    import signal
    import time

    from conftest import wait_for_stop_handlers

    folder = tmp_path / "seq"
    write_image_sequence(make_scene("smooth", 1, 64, 48, 3000, 30), folder)
    images = sorted((folder / "img").iterdir())
    for image in images[1:-1:2]:  # frames 1, 3, 5, ... have no image
        image.unlink()
    first = tmp_path / "first"
    process = subprocess.Popen([sys.executable, "-m", "vtrack", "run", str(folder), "-c", "s4",
                                "--no-video", "-o", str(first)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for_stop_handlers(process)
    deadline = time.monotonic() + START_BOUND_S
    while not any(len(p.read_bytes().splitlines()) > 20 for p in first.glob(".track*")):
        assert process.poll() is None and time.monotonic() < deadline, process.communicate()
        time.sleep(0.01)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    last = json.loads((first / "run.json").read_text())["last_frame"]
    assert last % 2 == 0  # the frames written are the even ones: LAST+1 has no image
    hint = stderr.splitlines()[-1]
    assert hint.endswith(f"run the same command with --start {last + 1} and another --out")
    done = vtrack("run", str(folder), "-c", "s4", "--start", str(last + 1), "--frames", "10",
                  "--no-video", "-o", str(tmp_path / "again"))
    assert done.returncode == 0, done.stderr
    with (tmp_path / "again" / "track.csv").open(newline="") as handle:
        frames = [int(row["frame"]) for row in csv.DictReader(handle)]
    assert frames[0] == last + 2  # the next frame the folder has: none written twice
