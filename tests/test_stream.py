"""``vtrack run --stream FILE|-``: a flushed JSON line per frame, as the frame is done."""

from __future__ import annotations

import csv
import json
import os
import re
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from conftest import START_BOUND_S, LinesAsTheyCome

from vtrack.errors import StreamReaderGone
from vtrack.io.outdir import RUN_OUTPUTS
from vtrack.io.stream import StreamWriter
from vtrack.pipeline import FrameResult
from vtrack.scenes import make_scene, write_clip, write_raw, write_video
from vtrack.stages.base import TrackState

W, H = 160, 120


def _vtrack(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          timeout=120, check=False, text=True)


def _cell(text: str) -> float | None:
    """A CSV cell's number as a JSON line holds it (empty: null)."""
    return None if text == "" else float(text)


def test_stream_on_stdout_matches_the_csv_and_the_summary_goes_to_stderr(tmp_path: Path) -> None:
    """Each line holds its track.csv / tracks.csv row's values: the lines had full precision
    where the files round (x 62.323167616854874 where track.csv holds 62.323; on a 150-frame
    robust run 483 values differed)."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=20, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    done = _vtrack("run", str(clip), "--config", "s0", "--init", box, "--no-video",
                   "--out", str(out), "--stream", "-")
    assert done.returncode == 0, done.stderr
    lines = [json.loads(line) for line in done.stdout.splitlines()]
    assert "20 frames" in done.stderr  # the summary line
    with (out / "track.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [line["frame"] for line in lines] == [int(r["frame"]) for r in rows] == list(range(20))
    for line, row in zip(lines, rows, strict=True):
        assert set(line) == {"frame", "time_s", "x", "y", "w", "h", "state", "score", "extras"}
        assert line["state"] == row["state"]
        for key in ("x", "y", "w", "h", "time_s", "score"):
            assert line[key] == _cell(row[key]), (key, line, row)
        assert line["extras"] == {key: _cell(row[key]) for key in line["extras"]}
    assert any("bp_mass" in line["extras"] for line in lines)
    # a file target, for a multi-target config: the confirmed tracks of tracks.csv
    multi = make_scene("multi", seed=2, width=W, height=H, frames=60, fps=30)
    clip = write_video(multi, tmp_path / "multi.mp4")
    done = _vtrack("run", str(clip), "--config", "s3", "--no-video", "--out",
                   str(tmp_path / "m"), "--stream", str(tmp_path / "m.jsonl"))
    assert done.returncode == 0, done.stderr
    assert "frames" in done.stdout
    lines = [json.loads(t) for t in (tmp_path / "m.jsonl").read_text().splitlines()]
    assert len(lines) == 60
    # a multi-target line is the run's frame number (from 0, as track.csv's), its time and its
    # tracks: no single-target fields (they held "x":null,"state":"tracking","score":null)
    assert [line["frame"] for line in lines] == list(range(60))
    assert all(set(line) == {"frame", "time_s", "tracks"} for line in lines), lines[0]
    assert all(set(t) == {"id", "x", "y", "w", "h", "conf", "state"}
               for line in lines for t in line["tracks"])
    with (tmp_path / "m" / "tracks.csv").open() as f:
        rows = list(csv.DictReader(f))
    # a track's row in tracks.csv (MOTChallenge numbers frames from 1) is the line's frame + 1
    streamed = [(line["frame"] + 1, t["id"], t["x"], t["y"], t["w"], t["h"], t["conf"])
                for line in lines for t in line["tracks"]]
    assert streamed == [(int(r["frame"]), int(r["id"]), *(_cell(r[key]) for key in
                                                         ("x", "y", "w", "h", "conf")))
                        for r in rows] and streamed


def test_stream_help_names_every_key_of_a_line(tmp_path: Path) -> None:
    """`vtrack run --help` said a --stream line holds 'frame, time_s, x, y, w, h, state, score,
    extras': a multi-target config's line holds frame, time_s and tracks (id, conf ...)."""
    helped = _vtrack("run", "--help")
    assert helped.returncode == 0, helped.stderr
    text = helped.stdout.split("--stream FILE|-")[1].split("--stats-period")[0]
    named = set(re.findall(r"\w+", text))
    clip = write_video(make_scene("multi", seed=2, width=W, height=H, frames=60, fps=30),
                       tmp_path / "multi.mp4")
    done = _vtrack("run", str(clip), "--config", "s3", "--no-video", "--out",
                   str(tmp_path / "m"), "--stream", "-")
    assert done.returncode == 0, done.stderr
    lines = [json.loads(line) for line in done.stdout.splitlines()]
    keys = {key for line in lines for key in line}
    keys |= {key for line in lines for track in line["tracks"] for key in track}
    assert "id" in keys and keys <= named, sorted(keys - named)


def test_each_line_arrives_while_the_input_is_still_open(tmp_path: Path) -> None:
    """Raw frames fed one at a time on stdin: each frame's line can be read before the next
    frame is sent (the run is still going), so a reader follows the target live."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    raw = write_raw(scene, tmp_path / "clip.bgr").read_bytes()
    size = W * H * 3
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    proc = subprocess.Popen([sys.executable, "-m", "vtrack", "run", "-", "--raw", f"{W}x{H}",
                             "--config", "s0", "--init", box, "--no-video", "--out",
                             str(tmp_path / "out"), "--stream", "-", "-q"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    assert proc.stdin is not None and proc.stdout is not None
    lines = LinesAsTheyCome(proc.stdout)
    try:
        for index in range(10):
            proc.stdin.write(raw[index * size:(index + 1) * size])
            proc.stdin.flush()
            line = lines.next(START_BOUND_S if index == 0 else 60)  # bounds (start-up first)
            assert line, f"no line for frame {index} while the input stays open"
            assert json.loads(line)["frame"] == index
        proc.stdin.close()
        assert proc.wait(timeout=60) == 0
        assert lines.next(60) == b""
    finally:
        proc.kill()
        proc.wait()


def test_a_stream_that_cannot_be_written_is_one_line_and_the_run_is_recorded(
        tmp_path: Path) -> None:
    """`--stream /dev/full` ended in a traceback from closing the stream, with no run.json."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    done = _vtrack("run", str(clip), "-c", "s1", "--init", box, "--no-video", "--out", str(out),
                   "--stream", "/dev/full")
    assert done.returncode == 1
    assert done.stderr.strip() == "vtrack: error: --stream /dev/full: No space left on device"
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "failed" and record["error"].startswith("--stream /dev/full")
    with (out / "track.csv").open() as f:
        assert len(list(csv.DictReader(f))) == record["frames"]


def test_no_output_of_a_run_is_written_over_what_it_reads(tmp_path: Path) -> None:
    """`--stream` over the input, or `-y` with the input inside the output folder, replaced the
    input by the run's own results."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    original = clip.read_bytes()
    inside = tmp_path / "out" / "annotated.mp4"
    inside.parent.mkdir()
    inside.write_bytes(original)
    cases = [
        (["run", str(clip), "--init", box, "--out", str(tmp_path / "a"), "--stream", str(clip)],
         f"--stream {clip}: is the input of this run"),
        (["run", str(inside), "--init", box, "--out", str(inside.parent), "-y"],
         f"--out {inside}: is the input of this run"),
        (["run", str(clip), "--init", box, "--out", str(tmp_path / "b"), "--stream",
          str(tmp_path / "b" / "track.csv")], "is one of this run's own outputs"),
    ]
    for args, problem in cases:
        done = _vtrack(*args)
        assert done.returncode == 2 and problem in done.stderr, done.stderr
        assert done.stderr.count("\n") == 1
    assert clip.read_bytes() == original and inside.read_bytes() == original
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def _refused_as_stream(out: Path, stream: Path, problem: str, *args: str) -> None:
    """`vtrack run ARGS --no-video -y --out OUT --stream STREAM` is refused, exit 2, in one
    line: ``--stream STREAM: PROBLEM; write the results elsewhere``."""
    done = _vtrack("run", *args, "--no-video", "-y", "--out", str(out), "--stream", str(stream))
    assert (done.returncode, done.stderr) == (2, (
        f"vtrack: error: --stream {stream}: {problem}; write the results elsewhere\n"))


def test_an_image_of_the_input_sequence_is_refused_as_the_stream(tmp_path: Path) -> None:
    """`vtrack run SEQ -y --stream SEQ/img/0004.jpg` replaced an image of the sequence being
    read with the run's JSON lines, exit 0 (only an input file itself was refused)."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    seq = write_clip(scene, tmp_path / "seq", fmt="images").clip
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    image = seq / "img" / "0004.jpg"
    original = image.read_bytes()
    for given, stream in ((seq, image), (seq / "img", seq / "img" / ".." / "img" / "0004.jpg")):
        _refused_as_stream(tmp_path / "out", stream,
                           f"is an image of the input of this run ({given})",
                           str(given), "--init", box)
    assert image.read_bytes() == original and not (tmp_path / "out").exists()
    beside = seq / "notes.jpg"  # beside img/: not one of the sequence's images
    done = _vtrack("run", str(seq), "--init", box, "--no-video", "-q",
                   "--out", str(tmp_path / "out"), "--stream", str(beside))
    assert done.returncode == 0, done.stderr
    assert len(beside.read_text().splitlines()) == 10


def test_an_image_of_the_input_sequence_through_a_link_is_refused_as_the_stream(
        tmp_path: Path) -> None:
    """A stream that is a symbolic link to an image of the sequence (`--stream out.jsonl`,
    out.jsonl -> SEQ/img/0003.jpg) or an image of a sequence of links (`--stream L/0003.jpg`,
    L/0003.jpg -> SEQ/img/0003.jpg) replaced the image with the run's JSON lines, exit 0: the
    image name was read from the path as typed but its folder from the file it leads to."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    seq = write_clip(scene, tmp_path / "seq", fmt="images").clip
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    images = sorted((seq / "img").iterdir())
    originals = [image.read_bytes() for image in images]
    link = tmp_path / "out.jsonl"
    link.symlink_to(seq / "img" / "0003.jpg")
    links = tmp_path / "links"  # a sequence whose images are links to another's
    links.mkdir()
    for image in images:
        (links / image.name).symlink_to(image)
    for given, stream in ((seq, link), (links, links / "0003.jpg")):
        _refused_as_stream(tmp_path / "out", stream,
                           f"is an image of the input of this run ({given})",
                           str(given), "--init", box)
    assert [image.read_bytes() for image in images] == originals
    assert not (tmp_path / "out").exists()


def test_the_inputs_sidecar_box_is_refused_as_the_stream(tmp_path: Path) -> None:
    """`vtrack run clip.mp4 -y --stream clip.init.txt` read its first box from the sidecar
    and then wrote its JSON lines over it, exit 0; the next run without --init failed on it
    (``holds 10 lines of values; expected one line x,y,w,h``)."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    sidecar = tmp_path / "clip.init.txt"
    sidecar.write_text(",".join(f"{v:g}" for v in scene.boxes[0]) + "\n")
    original = sidecar.read_bytes()
    _refused_as_stream(tmp_path / "out", sidecar,
                       f"is the sidecar box of this run ({sidecar})", str(clip))
    assert sidecar.read_bytes() == original and not (tmp_path / "out").exists()


def test_the_sequences_seqinfo_is_refused_as_the_stream(tmp_path: Path) -> None:
    """`vtrack run SEQ -y --stream SEQ/seqinfo.ini` read the sequence's frame rate from it,
    then wrote its JSON lines over it, exit 0; the next run of SEQ failed on it (``not a
    MOTChallenge seqinfo.ini``)."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    seq = write_clip(scene, tmp_path / "seq", fmt="images").clip
    info = seq / "seqinfo.ini"
    original = info.read_bytes()
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    for given in (seq, seq / "img"):
        _refused_as_stream(tmp_path / "out", info,
                           f"is the sequence's seqinfo.ini of this run ({info})",
                           str(given), "--init", box)
    assert info.read_bytes() == original and not (tmp_path / "out").exists()


def test_a_sidecar_or_seqinfo_not_there_yet_is_refused_as_the_stream(tmp_path: Path) -> None:
    """With --init and no sidecar yet, `vtrack run SEQ --init BOX -y --stream SEQ/init.txt`
    wrote the sidecar as the run's JSON lines, exit 0, and the next `vtrack run SEQ` failed on
    it (``holds 10 lines of values``); the same for a video's clip.init.txt, and for
    `--stream SEQ/seqinfo.ini` in a sequence without one (next run: ``not a MOTChallenge
    seqinfo.ini``): only files that existed were compared."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    seq = write_clip(scene, tmp_path / "seq", fmt="images").clip
    (seq / "seqinfo.ini").unlink()
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    cases = [(seq, seq / "init.txt", "the sidecar box"),
             (seq / "img", seq / "init.txt", "the sidecar box"),
             (clip, tmp_path / "clip.init.txt", "the sidecar box"),
             (seq, seq / "seqinfo.ini", "the sequence's seqinfo.ini")]
    for given, stream, what in cases:
        _refused_as_stream(tmp_path / "out", stream, f"is {what} of this run ({stream})",
                           str(given), "--init", box)
        assert not stream.exists() and not (tmp_path / "out").exists()


def test_a_symbolic_link_to_itself_among_what_a_run_reads_or_writes(tmp_path: Path) -> None:
    """A seqinfo.ini or init.txt that is a link to itself (`ln -s seqinfo.ini SEQ/seqinfo.ini`),
    with --init given, made `vtrack run SEQ --init BOX -y -o OUT` end in a RuntimeError
    traceback (``Symlink loop from 'SEQ/seqinfo.ini'``: Path.resolve() on Python 3.11), and so
    did `--stream S` where S links to itself; the run now goes on (it reads neither), a
    looping link as the stream is still refused as what the run reads, and a looping stream
    is one line."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    for name in ("seqinfo.ini", "init.txt"):
        seq = write_clip(scene, tmp_path / name / "seq", fmt="images").clip
        (seq / name).unlink(missing_ok=True)
        (seq / name).symlink_to(name)
        out = tmp_path / name / "out"
        done = _vtrack("run", str(seq), "--init", box, "--no-video", "-y", "-o", str(out))
        assert done.returncode == 0, done.stderr
        assert "10 frames" in done.stdout and (out / "track.csv").is_file()
        what = "the sequence's seqinfo.ini" if name == "seqinfo.ini" else "the sidecar box"
        _refused_as_stream(tmp_path / "refused", seq / name, f"is {what} of this run "
                           f"({seq / name})", str(seq), "--init", box)
        assert (seq / name).is_symlink() and not (tmp_path / "refused").exists()
    clip = write_video(scene, tmp_path / "clip.mp4")
    stream = tmp_path / "s.jsonl"
    stream.symlink_to(stream.name)
    done = _vtrack("run", str(clip), "--init", box, "--no-video", "-y", "-o",
                   str(tmp_path / "out"), "--stream", str(stream))
    assert (done.returncode, done.stderr) == (2, (
        f"vtrack: error: --stream {stream}: Too many levels of symbolic links\n"))
    assert stream.is_symlink() and not (tmp_path / "out").exists()


def test_the_config_file_and_a_file_a_stage_reads_are_refused_as_the_stream(
        tmp_path: Path) -> None:
    """`vtrack run clip.mp4 -c mine.toml ... -y --stream mine.toml` exited 0 having written
    the run's JSON lines over the config file (the next run: ``not valid TOML``); the same for
    `--stream det.txt` over the det.txt a mot_detections stage reads."""
    scene = make_scene("multi", seed=0, width=W, height=H, frames=60, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{i + 1},-1,{b.x},{b.y},{b.w},{b.h},0.9\n"
                           for i, frame in enumerate(scene.tracks) for _, b in frame))
    config = tmp_path / "mine.toml"
    config.write_text(f'name = "mine"\n[[stage]]\nname = "mot_detections"\npath = "{det}"\n'
                      '[[stage]]\nname = "byte_tracks"\n')
    texts = {path: path.read_text() for path in (config, det)}
    for stream, what in ((config, "the config file"), (det, "the mot_detections.path file")):
        _refused_as_stream(tmp_path / "out", stream, f"is {what} of this run ({stream})",
                           str(clip), "-c", str(config))
    assert {path: path.read_text() for path in texts} == texts
    assert not (tmp_path / "out").exists()
    done = _vtrack("run", str(clip), "-c", str(config), "--no-video", "-y", "-q",
                   "--out", str(tmp_path / "out"), "--stream", str(tmp_path / "s.jsonl"))
    assert done.returncode == 0, done.stderr  # (a stream beside them is written)
    assert len((tmp_path / "s.jsonl").read_text().splitlines()) == 60


def test_every_file_the_folder_clearing_removes_is_refused_as_the_stream(
        tmp_path: Path) -> None:
    """`--stream OUT/tracks.csv` (or `error.log`; `track.csv` for a multi-target config) was
    filled during the run and then removed by the folder's clearing at its end, exit 0: only
    the files the run itself writes were refused, not all of RUN_OUTPUTS. A stream named as
    their temporaries (`--stream OUT/.track.tmp-1.csv`) was removed by it silently, exit 0."""
    smooth = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(smooth, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in smooth.boxes[0])
    multi = write_video(make_scene("multi", seed=2, width=W, height=H, frames=60, fps=30),
                        tmp_path / "multi.mp4")
    single = ["-c", "s0", str(clip), "--init", box]
    own, temporary = ("is one of this run's own outputs", "is named as a temporary file of "
                      "this run's outputs, which the folder's clean-up removes")
    cases = [(single, name, own) for name in RUN_OUTPUTS]
    cases += [(["-c", "s3", str(multi)], name, own) for name in ("track.csv", "error.log")]
    cases += [(single, name, temporary) for name in (".track.tmp-1.csv", ".run.tmp-1-ab.json",
                                                      ".error.tmp.log")]
    for index, (args, name, problem) in enumerate(cases):
        out = tmp_path / f"o{index}"
        done = _vtrack("run", *args, "--no-video", "-q", "--out", str(out),
                       "--stream", str(out / name))
        assert done.returncode == 2, (name, done.stderr)
        assert done.stderr == f"vtrack: error: --stream {out / name}: {problem}; name another " \
                              "file\n"
        assert not out.exists()


def test_a_stream_file_holding_lines_is_replaced_only_with_overwrite(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    lines = tmp_path / "lines.jsonl"
    args = ["run", str(clip), "--init", box, "--no-video", "--stream", str(lines)]
    assert _vtrack(*args, "--out", str(tmp_path / "a")).returncode == 0
    first = lines.read_bytes()
    again = _vtrack(*args, "--out", str(tmp_path / "b"))
    assert again.returncode == 2 and again.stderr.count("\n") == 1
    assert f"--stream {lines}: holds {len(first)} bytes already" in again.stderr
    assert lines.read_bytes() == first and not (tmp_path / "b").exists()
    assert _vtrack(*args, "--out", str(tmp_path / "b"), "-y").returncode == 0
    assert lines.read_bytes().count(b"\n") == 10


def test_a_run_refused_at_its_first_frame_leaves_the_stream_file_as_it_was(
        tmp_path: Path) -> None:
    """`vtrack run grey.mp4 -c s0 -o out -y --stream lines.jsonl --overwrite` (s0 refuses a
    grey target at its first frame, exit 2) left out/ holding the earlier run's 10 frames,
    as promised, but emptied lines.jsonl, that run's lines; a new --stream file was left
    behind empty, and so was the file a link to no file names (the link is the user's)."""
    scene = make_scene("grey", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "grey.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    lines, out = tmp_path / "lines.jsonl", tmp_path / "out"
    args = ["run", str(clip), "--init", box, "--no-video", "--out", str(out), "-y"]
    assert _vtrack(*args, "--stream", str(lines)).returncode == 0
    first, record = lines.read_bytes(), (out / "run.json").read_bytes()
    assert first.count(b"\n") == 10
    refused = _vtrack(*args, "-c", "s0", "--stream", str(lines), "--overwrite")
    assert refused.returncode == 2 and "no pixel of the initial box" in refused.stderr
    assert (out / "run.json").read_bytes() == record and lines.read_bytes() == first
    new = tmp_path / "new.jsonl"
    assert _vtrack(*args, "-c", "s0", "--stream", str(new)).returncode == 2
    assert not new.exists()
    link, named = tmp_path / "link.jsonl", tmp_path / "named.jsonl"
    link.symlink_to(named)
    assert _vtrack(*args, "-c", "s0", "--stream", str(link)).returncode == 2
    assert link.is_symlink() and not named.exists()
    assert _vtrack(*args, "--frames", "3", "--stream", str(lines), "--overwrite").returncode == 0
    assert lines.read_bytes().count(b"\n") == 3 and lines.read_bytes() == first[:len(
        lines.read_bytes())]  # emptied, then this run's lines


def _stalled_run(tmp_path: Path, frames: int, output: list[str], stdout: int | None) -> tuple[
        subprocess.Popen, dict]:
    """``vtrack run`` of a ``frames``-frame clip with ``output`` options whose receiver takes
    nothing (``--timeout 1``), ended by itself; its process (stdout never read) and run.json."""
    scene = make_scene("smooth", seed=1, width=320, height=240, frames=frames, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s0", "--init", box, "-q",
         "--out", str(out), "--timeout", "1", *output],
        stdout=stdout, stderr=subprocess.PIPE, text=True)
    try:
        process.wait(timeout=60)  # it hung until SIGKILL, SIGTERM held off while it waited
    finally:
        process.kill()
    return process, json.loads((out / "run.json").read_text())


def test_a_stream_reader_that_takes_nothing_ends_the_run_after_the_timeout(
        tmp_path: Path) -> None:
    process, record = _stalled_run(tmp_path, 1500, ["--no-video", "--stream", "-"],
                                   subprocess.PIPE)
    assert process.returncode == 1
    error = "--stream -: its reader took nothing for 1 s"
    assert process.stderr.read().strip() == f"vtrack: error: {error}"
    assert record["status"] == "failed" and record["error"] == error
    with (tmp_path / "out" / "track.csv").open() as f:  # what was tracked is whole
        assert 0 < len(list(csv.DictReader(f))) == record["frames"] < 1500


def test_a_live_video_receiver_that_takes_nothing_ends_the_run_after_the_timeout(
        tmp_path: Path) -> None:
    with socket.socket() as server:  # accepts, never reads
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        peers: list[socket.socket] = []
        threading.Thread(target=lambda: peers.append(server.accept()[0]), daemon=True).start()
        url = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        process, record = _stalled_run(tmp_path, 1500, ["--video-out", url, "--crf", "0"],
                                       subprocess.DEVNULL)
        for peer in peers:
            peer.close()
    error = f"--video-out {url}: the receiver took nothing for 1 s"
    assert process.returncode == 1
    assert process.stderr.read().strip() == f"vtrack: error: {error}"
    assert record["status"] == "failed" and record["error"] == error


def test_a_stream_reader_that_goes_away_stops_the_run_quietly_as_sigpipe(tmp_path: Path) -> None:
    """`vtrack run ... --stream - | head -2` ended `failed`, "vtrack: error: --stream -: Broken
    pipe", exit 1. Now the run stops there as a writer to a closed pipe does: exit 141 (128 +
    SIGPIPE), no error line, run.json `interrupted` saying the reader went away, track.csv
    whole."""
    # more lines than a pipe holds (64 KiB): the run cannot have written them all already
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=600, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    out = tmp_path / "out"
    run = subprocess.Popen([sys.executable, "-m", "vtrack", "run", str(clip), "-c", "s0",
                            "--init", ",".join(f"{v:g}" for v in scene.boxes[0]), "--no-video",
                            "-q", "-o", str(out), "--stream", "-"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert run.stdout is not None and run.stderr is not None
        taken = [run.stdout.readline(), run.stdout.readline()]  # `| head -2`
        run.stdout.close()
        stderr = run.stderr.read()
        run.wait(timeout=120)
    finally:
        run.kill()
    assert all(json.loads(line)["frame"] == i for i, line in enumerate(taken))
    assert run.returncode == 141, stderr
    assert stderr == b""
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "interrupted"
    assert record["error"].startswith("--stream -: its reader went away (closed the pipe) after ")
    assert record["error"].endswith(" lines: the run stopped there (SIGPIPE)")
    with (out / "track.csv").open() as f:
        assert len(list(csv.DictReader(f))) == record["frames"] < 600


def test_a_reader_gone_after_one_line_is_told_in_the_singular(tmp_path: Path) -> None:
    """A --stream FIFO whose reader took one line and closed it stopped the run with
    '--stream F: its reader went away (closed the pipe) after 1 lines: ...' (run.json's
    error): one line is now 'after 1 line'."""
    fifo = tmp_path / "lines"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # (the writer opens at once)
    writer = StreamWriter(str(fifo), multi_target=False, stall_s=5)
    result = FrameResult(index=0, time_s=0.0, box=None, state=TrackState.LOST, score=0.0,
                         prediction=None)
    try:
        assert writer.write(result)
        assert os.read(reader, 4096).count(b"\n") == 1
        os.close(reader)
        with pytest.raises(StreamReaderGone) as gone:
            writer.write(result)
    finally:
        writer.close()
    assert str(gone.value) == (f"--stream {fifo}: its reader went away (closed the pipe) after "
                               "1 line: the run stopped there (SIGPIPE)")


def test_stream_to_a_closed_standard_output_is_refused_in_one_line(tmp_path: Path) -> None:
    """`vtrack run clip.mp4 --stream - >&-` ended in a traceback (AttributeError: 'NoneType'
    object has no attribute 'flush'), exit 1: it is refused before a frame is tracked, as a
    --stream FIFO no reader opens is, and leaves no folder."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    out = tmp_path / "out"
    command = [sys.executable, "-m", "vtrack", "run", str(clip), "--init", box, "--no-video",
               "--out", str(out), "--stream", "-"]
    done = subprocess.run(["sh", "-c", '"$@" >&-', "sh", *command], capture_output=True,
                          timeout=120, check=False, text=True)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip() == ("vtrack: error: --stream -: standard output was closed "
                                   "before vtrack started (>&-): nothing can read the lines")
    assert not out.exists()


def test_an_input_given_as_a_file_url_is_refused_not_written_over(tmp_path: Path) -> None:
    """`vtrack run file:///.../clip.mp4 --stream .../clip.mp4 -y` wrote its lines over its own
    input (48862 bytes became 10063, the run then ending 'partial' at frame 80): read through
    FFmpeg's file protocol the input was a URL, none of the files a run keeps from writing
    over (also --out's annotated.mp4). A file: URL is refused, asking for the file's path
    (all of it: a name holding '#' or '?' was cut there); vtrack.open_source and vtrack.track
    the same."""
    import vtrack

    scene = make_scene("smooth", seed=1, width=W, height=H, frames=10, fps=30)
    clip = write_video(scene, tmp_path / "clip.mp4")
    before = clip.read_bytes()
    box = ",".join(f"{v:g}" for v in scene.boxes[0])
    url = f"file://{clip}"
    done = _vtrack("run", url, "--init", box, "--no-video", "--out", str(tmp_path / "out"),
                   "--stream", str(clip), "--overwrite")
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip() == (f"vtrack: error: {url}: a file: URL; give the file's path "
                                   f"({clip})")
    assert clip.read_bytes() == before and not (tmp_path / "out").exists()
    for call in (lambda: vtrack.open_source(url), lambda: vtrack.track(url, "s0", (1, 1, 8, 8))):
        with pytest.raises(vtrack.InputError, match=f"^{re.escape(url)}: a file: URL; give"):
            call()
    # a host named: this one's (localhost) asks for the URL's path, not "localhost/..." (a
    # relative path it suggested); another's cannot be read
    local = f"file://localhost{clip}"
    with pytest.raises(vtrack.InputError) as refused:
        vtrack.open_source(local)
    assert str(refused.value) == f"{local}: a file: URL; give the file's path ({clip})"
    with pytest.raises(vtrack.InputError) as refused:
        vtrack.open_source(f"file://server{clip}")
    assert str(refused.value) == (f"file://server{clip}: a file: URL of another host (server) "
                                  "cannot be read; give a local file's path")
    # a file name holding '#' or '?' is the path asked for, not cut there (it said /tmp/take)
    for name in ("take#2.mp4", "take?2.mp4"):
        named = f"file://{tmp_path / name}"
        with pytest.raises(vtrack.InputError) as refused:
            vtrack.open_source(named)
        assert str(refused.value) == f"{named}: a file: URL; give the file's path " \
                                     f"({tmp_path / name})"
