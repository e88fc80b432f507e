"""``vtrack frame --at N`` and ``vtrack select --frame N`` on a long input: a frame past the
count the input states is refused before a frame is decoded, and a far frame of a seekable
video is read from the key frame before it, the very frame a full decode gives."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import av
import cv2
import numpy as np
import pytest
from conftest import START_BOUND_S

from vtrack.io import open_source
from vtrack.io.pyfile import CountedStream
from vtrack.io.video import _python_file
from vtrack.picker.frames import FrameStore, read_frame
from vtrack.scenes import make_scene, write_video

FRAMES, KEYINT = 300, 30
FAR = 10**12 - 1


@pytest.fixture(scope="module")
def long_clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    scene = make_scene("smooth", seed=1, width=64, height=48, frames=FRAMES, fps=30)
    return write_video(scene, tmp_path_factory.mktemp("seek") / "long.mp4", keyint=KEYINT)


def vtrack(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, timeout=START_BOUND_S, check=False)


def test_a_frame_past_the_stated_count_is_refused_before_any_is_decoded(
        long_clip: Path, tmp_path: Path) -> None:
    """Both commands decoded the whole input before saying it had no such frame."""
    with FrameStore(str(long_clip)) as store:
        assert store.get(FAR) is None and store.get(FRAMES) is None
        assert store.cached_bytes == 0  # no frame decoded (it read all 300 first)
    done = vtrack("frame", str(long_clip), "--at", str(FAR), "-o", str(tmp_path / "f.png"))
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"vtrack: error: {long_clip}: has no frame {FAR} "
                           f"(frames 0..{FRAMES - 1})\n")
    done = vtrack("select", str(long_clip), "--frame", str(FAR))
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"vtrack: error: {long_clip}: --frame {FAR}: there is no such "
                           f"frame (frames 0..{FRAMES - 1})\n")
    assert not (tmp_path / "f.png").exists()


def test_a_far_frame_is_read_from_the_key_frame_before_it(long_clip: Path) -> None:
    with open_source(str(long_clip)) as source:
        every = {frame.index: frame.bgr().copy() for frame in source}
    assert sorted(every) == list(range(FRAMES))
    with open_source(str(long_clip)) as source:
        assert source.start_near(5 * KEYINT + 7) == 5 * KEYINT  # the key frame before it
        rest = [frame.index for frame in source]  # to the end, not taken as a cut-off file
        assert rest == list(range(5 * KEYINT, FRAMES)) and source.frames_skipped == 0
    for index in (0, 7, 4 * KEYINT - 1, 4 * KEYINT, 4 * KEYINT + 1, FRAMES - 1):
        assert np.array_equal(read_frame(str(long_clip), index), every[index]), index
    with FrameStore(str(long_clip)) as store:  # the page's store jumps there too, and back
        for index in (FRAMES - 2, 3, 2 * KEYINT + 3):
            shown = cv2.imdecode(np.frombuffer(store.get(index), np.uint8), cv2.IMREAD_COLOR)
            assert np.abs(shown.astype(int) - every[index]).mean() < 3, index


def test_a_frame_past_an_estimated_count_names_the_estimate(tmp_path: Path) -> None:
    """Matroska lists no frame count: its duration times its rate estimates it."""
    scene = make_scene("smooth", seed=1, width=64, height=48, frames=40, fps=30)
    clip = write_video(scene, tmp_path / "clip.mkv")
    with FrameStore(str(clip)) as store:
        assert store.get(FAR) is None and store.cached_bytes == 0  # no frame decoded
    done = vtrack("frame", str(clip), "--at", str(FAR), "-o", str(tmp_path / "f.png"))
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"vtrack: error: {clip}: has no frame {FAR} (frames by its "
                           "duration and frame rate, about 0..39)\n")


def test_run_refuses_a_start_past_the_stated_count_before_asking_for_a_box(
        long_clip: Path, tmp_path: Path) -> None:
    """`vtrack run long.mp4 --start N` past its frames decoded the whole input before saying
    '--start N: long.mp4 has no frame N', and without --init first asked for the box of that
    frame, which does not exist. Now it is refused at once from the count the input states,
    as vtrack frame --at N is, before anything else is asked."""
    for extra in ((), ("--init", "10,10,20,20")):
        done = vtrack("run", str(long_clip), "--start", str(FRAMES), *extra, "-o",
                      str(tmp_path / "out"))
        assert (done.returncode, done.stdout) == (2, "")
        assert done.stderr == (f"vtrack: error: --start {FRAMES}: {long_clip}: has no frame "
                               f"{FRAMES} (frames 0..{FRAMES - 1})\n")
    assert not (tmp_path / "out").exists()


def test_a_start_at_0s_is_the_first_frame_as_no_start_is(tmp_path: Path) -> None:
    """`vtrack run bad.mp4 --gt badgt.txt --start 0s` opened the input before reading the
    ground truth, as for a later start, and named the input (not a video) where the same run
    without --start, or with --start 0, names the ground truth: 0 s is the first frame's time,
    which needs no opened input to be found (RunRequest.starts_later, as vtrack batch takes
    it: a sidecar box is that frame's)."""
    bad, gt = tmp_path / "bad.mp4", tmp_path / "badgt.txt"
    bad.write_bytes(b"garbage")
    gt.write_text("1,2\n")
    for start in ((), ("--start", "0"), ("--start", "0s")):
        done = vtrack("run", str(bad), "--gt", str(gt), *start, "-o", str(tmp_path / "out"))
        assert (done.returncode, done.stdout) == (2, ""), start
        assert done.stderr == (f"vtrack: error: {gt} line 1: expected 4 or 8 numbers, got "
                               "'1,2'\n"), start
    assert not (tmp_path / "out").exists()


def test_run_starts_from_the_key_frame_before_its_start_with_the_same_frames(
        long_clip: Path, tmp_path: Path) -> None:
    """`vtrack run long.mp4 --start N` (or `--start Ts`) decoded every frame before N to drop
    them. A seekable video is now read from the key frame at or before N (run.json
    ``read_from_frame``), and tracks the very frames, numbered and timed as before: the same
    track.csv as the input read whole through stdin (which cannot jump). The clip has B-frames
    (x264's default), so the frames come out of the decoder in another order than stored."""
    with av.open(str(long_clip)) as container:
        assert container.streams.video[0].codec_context.has_b_frames
    init = ("--init", "10,10,12,12", "--no-video", "--frames", "20")
    for start, first, key in (("157", 157, 150), (str(4 * KEYINT), 4 * KEYINT, 4 * KEYINT),
                              (str(4 * KEYINT - 1), 4 * KEYINT - 1, 3 * KEYINT),
                              ("5.1s", 153, 150), ("2s", 60, 60)):
        jumped, whole = tmp_path / f"file{start}", tmp_path / f"stdin{start}"
        done = vtrack("run", str(long_clip), "--start", start, *init, "-o", str(jumped))
        assert done.returncode == 0, done.stderr
        with long_clip.open("rb") as stdin:
            done = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", "--start", start,
                                   *init, "-o", str(whole)], stdin=stdin, capture_output=True,
                                  text=True, timeout=START_BOUND_S, check=False)
        assert done.returncode == 0, done.stderr
        records = [json.loads((out / "run.json").read_text()) for out in (jumped, whole)]
        assert [(r["start_frame"], r["read_from_frame"], r["frames"]) for r in records] == [
            (first, key, 20), (first, 0, 20)], start
        rows = (jumped / "track.csv").read_text()
        assert rows.splitlines()[1].startswith(f"{first},{round(first / 30, 4):g},"), start
        assert rows == (whole / "track.csv").read_text(), start


def test_frame_takes_a_time_as_run_start_does(long_clip: Path, tmp_path: Path) -> None:
    """`vtrack frame long.mp4 --at 5.1s` was refused ('5.1s' is not a whole number) while
    `vtrack run --start 5.1s` took it: both read N or Ts with one parser now, and the frame
    written is the one a run from that time starts at (153 at 30 fps), named by its index."""
    out = tmp_path / "f.png"
    done = vtrack("frame", str(long_clip), "--at", "5.1s", "--no-grid", "-o", str(out))
    assert (done.returncode, done.stderr) == (0, ""), done.stderr
    assert done.stdout == f"wrote {out} (frame 153, 64x48)\n"
    assert np.array_equal(cv2.imread(str(out)), read_frame(str(long_clip), 153))
    done = vtrack("frame", str(long_clip), "--at", "10s", "-o", str(tmp_path / "g.png"))
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"vtrack: error: {long_clip}: has no frame at or after 10 s (its last "
                           "frame is frame 299, at 9.96667 s)\n")  # as 'no frame 300 (...)'
    assert not (tmp_path / "g.png").exists()
    for negative in ("-1s", "-1"):  # refused as negative, not only as "expected a number"
        done = vtrack("frame", str(long_clip), "--at", negative, "-o", str(tmp_path / "g.png"))
        assert done.returncode == 2 and f"'{negative}': is negative; expected" in done.stderr
    helped = vtrack("frame", "--help")  # it opened 'Write frame N of INPUT'
    assert "Write one frame of INPUT (--at: frame N, or the first at time T)" in " ".join(
        helped.stdout.split())


def test_a_frame_just_before_a_key_frame_of_an_hevc_clip_is_reached_from_the_one_before(
        tmp_path: Path) -> None:
    """x265's B-frames put a key frame's decoding time up to 3 frames before its display time,
    and FFmpeg seeks by decoding time: `vtrack run h265.mp4 --start 119` (key frames every 30)
    found key frame 120, after 119, and fell back to decoding frames 0..118 (start_near gave 0
    for 59, 117..119, 146..149, ...). It now aims further back until it finds key frame 90;
    the frames read from there are the very frames a full decode gives."""
    try:
        av.codec.Codec("libx265", "w")
    except ValueError:  # an FFmpeg built without x265
        pytest.skip("no libx265 encoder")
    scene = make_scene("smooth", seed=1, width=64, height=48, frames=FRAMES, fps=30)
    clip = write_video(scene, tmp_path / "h265.mp4", keyint=KEYINT, codec="libx265")
    with open_source(str(clip)) as source:
        every = {frame.index: frame.bgr().copy() for frame in source}
    for index in range(KEYINT, FRAMES, 7):
        with open_source(str(clip)) as source:
            assert source.start_near(index) == index // KEYINT * KEYINT, index
    for index in (4 * KEYINT - 1, 5 * KEYINT - 2, 2 * KEYINT - 1):
        with open_source(str(clip)) as source:
            begin = source.start_near(index)
            assert begin == index // KEYINT * KEYINT
            for frame in source:
                assert np.array_equal(frame.bgr(), every[frame.index]), (index, frame.index)
                if frame.index == index:
                    break


def test_only_the_videos_the_docs_name_jump_to_a_key_frame(long_clip: Path, tmp_path: Path
                                                           ) -> None:
    """`--start`'s help, README and RunRequest said "a video file is read from the key frame
    at or before that frame", but only a constant-rate MP4/MOV file jumps: an MKV of the same
    frames decodes from frame 0 (the same frames tracked). They name those that jump."""
    scene = make_scene("smooth", seed=1, width=64, height=48, frames=FRAMES, fps=30)
    mkv = write_video(scene, tmp_path / "long.mkv", keyint=KEYINT)
    for clip, read_from in ((long_clip, 150), (mkv, 0)):
        with open_source(str(clip)) as source:
            assert source.start_near(157) == read_from, clip
    helped = " ".join(vtrack("run", "--help").stdout.split())
    readme = " ".join((Path(__file__).parents[1] / "README.md").read_text().split())
    for text in (helped, readme):
        assert "An MP4 or MOV file of constant frame rate" in text
        assert "other videos (MKV, WebM, MPEG-TS, AVI, fragmented MP4, a variable frame rate)" \
            in text
        assert "A video file is read from the key frame" not in text


def _fragmented(path: Path, movflags: str) -> Path:
    """The clip's 300 frames (a key frame every 30) as an MP4 written with ``movflags``: a
    fragmented one (frag_keyframe: a fragment per key frame), or a plain one (faststart)."""
    scene = make_scene("smooth", seed=1, width=64, height=48, frames=FRAMES, fps=30)
    with av.open(str(path), "w", options={"movflags": movflags}) as out:
        stream = out.add_stream("libx264", rate=30)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        stream.options = {"g": str(KEYINT)}
        for image in scene.frames():
            out.mux(stream.encode(av.VideoFrame.from_ndarray(image, format="bgr24")))
        out.mux(stream.encode())
    return path


def test_a_fragmented_mp4_is_not_judged_by_its_first_fragment(tmp_path: Path) -> None:
    """`cat frag.mp4 | vtrack run - --start 119 ...` (300 frames, movflags
    frag_keyframe+empty_moov) said "has no frame 119 (frames by its duration and frame rate,
    about 0..29)": read from a pipe, its duration is its first fragment's. A file written
    without empty_moov was refused so even read as a file ("frames 0..29": its index lists the
    first fragment's frames). Both start at 119 now."""
    init = ("--init", "10,10,12,12", "--no-video", "--frames", "5", "--start", "119")
    piped = _fragmented(tmp_path / "frag.mp4", "frag_keyframe+empty_moov")
    listed = _fragmented(tmp_path / "frag2.mp4", "frag_keyframe")
    done = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", *init,  # a pipe
                           "-o", str(tmp_path / "piped")], input=piped.read_bytes(),
                          capture_output=True, timeout=START_BOUND_S, check=False)
    assert done.returncode == 0, done.stderr.decode()
    done = vtrack("run", str(listed), *init, "-o", str(tmp_path / "listed"))
    assert done.returncode == 0, done.stderr
    for out in ("piped", "listed"):
        record = json.loads((tmp_path / out / "run.json").read_text())
        assert (record["start_frame"], record["frames"]) == (119, 5), out



def _run_on_stdin(stdin: Path | bytes, *args: str) -> subprocess.CompletedProcess:
    """``vtrack run`` with ``stdin`` redirected from a file, or piped ``bytes``."""
    command = [sys.executable, "-m", "vtrack", "run", *args]
    if isinstance(stdin, bytes):
        return subprocess.run(command, input=stdin, capture_output=True, text=False,
                              timeout=START_BOUND_S, check=False)
    with stdin.open("rb") as handle:
        return subprocess.run(command, stdin=handle, capture_output=True, timeout=START_BOUND_S,
                              check=False)


@pytest.mark.parametrize("how", ["pipe", "redirected", "followed"])
def test_a_fragmented_mp4_read_without_seeking_is_not_judged_by_its_index(
        tmp_path: Path, how: str) -> None:
    """`cat frag.mp4 | vtrack run - --start 119 ...` (300 frames, movflags frag_keyframe
    only: its index lists the first fragment's 30 frames) said "--start 119: -: has no frame
    119 (frames 0..29)", as did `vtrack run - < frag.mp4` and `vtrack run frag.mp4 --follow`:
    only a file read by seeking was looked at for fragments. Now the movie-extends box (mvex)
    in the index, read in the first bytes, says so, and all start at 119. An MP4 whose index
    comes first (faststart) piped keeps its frame count."""
    clip = _fragmented(tmp_path / "frag.mp4", "frag_keyframe")
    init = ("--init", "10,10,12,12", "--no-video", "--frames", "5", "-o")
    if how == "followed":
        done = vtrack("run", str(clip), "--follow", "0.5", "--start", "119", *init,
                      str(tmp_path / "out"))
    else:
        stdin = clip.read_bytes() if how == "pipe" else clip
        done = _run_on_stdin(stdin, "-", "--start", "119", *init, str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    record = json.loads((tmp_path / "out" / "run.json").read_text())
    assert (record["start_frame"], record["frames"]) == (119, 5)
    faststart = _fragmented(tmp_path / "fast.mp4", "faststart")
    done = _run_on_stdin(faststart.read_bytes(), "-", "--start", str(FRAMES), *init,
                         str(tmp_path / "fast"))
    assert done.stderr.decode().strip() == (
        f"vtrack: error: --start {FRAMES}: -: has no frame {FRAMES} (frames 0..{FRAMES - 1})")


def test_a_pipes_first_mib_is_let_go_once_its_layout_was_read(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`cat frag.mp4 | vtrack run - ...` kept the pipe's first MiB (read for the look at an
    MP4's layout) for the whole run: CountedStream.head was never released. Now it is let go
    once the input is open, the look made (the fragments still found: no frame count)."""
    clip = _fragmented(tmp_path / "frag.mp4", "frag_keyframe")
    data = clip.read_bytes()
    read_fd, write_fd = os.pipe()

    def feed() -> None:
        with open(write_fd, "wb") as pipe:
            pipe.write(data)

    feeder = threading.Thread(target=feed, daemon=True)
    with open(read_fd, "rb") as stdin:
        monkeypatch.setattr(sys, "stdin", stdin)
        feeder.start()
        with open_source("-") as source:
            pipe = _python_file(source._container)
            assert isinstance(pipe, CountedStream)
            assert source.info.frame_count is None  # fragmented: not judged by its index
            assert pipe.head is None
            assert sum(1 for _ in source) == FRAMES
            assert pipe.head is None and pipe.bytes_read == len(data)
    feeder.join()
