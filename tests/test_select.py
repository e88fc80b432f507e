"""Picking the first box without ground truth (issue 12 item 2): the sidecar file, ``vtrack
frame``, and ``vtrack select`` driven through a real headless Chromium with real mouse drags.

The browser test needs Debian's ``chromium`` and ``chromium-driver`` packages and the
``selenium`` package (dev extra); it is skipped, saying which is missing, without them.
"""

from __future__ import annotations

import http.client
import json
import os
import queue
import shutil
import subprocess
import sys
import threading
import urllib.error
import urllib.request
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import START_BOUND_S

import vtrack as vtrack_package
from vtrack.errors import InputError
from vtrack.geometry import Box
from vtrack.io.sidecar import format_box, read_sidecar, sidecar_path, write_sidecar
from vtrack.scenes import make_scene, write_image_sequence, write_video

W, H = 320, 240


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    scene = make_scene("smooth", seed=3, width=W, height=H, frames=12, fps=30)
    return write_video(scene, tmp_path_factory.mktemp("select") / "clip.mp4")


def test_sidecar_lives_beside_a_video_and_inside_a_folder(tmp_path: Path) -> None:
    video = tmp_path / "walk.mp4"
    video.write_bytes(b"")
    folder = tmp_path / "Girl"
    folder.mkdir()
    assert sidecar_path(video) == tmp_path / "walk.init.txt"
    assert sidecar_path(str(folder) + "/") == folder / "init.txt"
    assert read_sidecar(video) is None and read_sidecar("-") is None
    written = write_sidecar(video, Box(12.0, 30.5, 40.0, 22.25))
    assert written.read_text() == "12,30.5,40,22.25\n"
    assert read_sidecar(str(video)) == Box(12.0, 30.5, 40.0, 22.25)
    write_sidecar(folder, Box(1, 2, 3, 4))
    assert read_sidecar(folder) == Box(1, 2, 3, 4)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temp left


@pytest.mark.parametrize(("text", "box"), [("# my target\n\n 5 6 7 8\n", Box(5, 6, 7, 8)),
                                           ("5,6,7,8  # drawn on frame 0\n", Box(5, 6, 7, 8)),
                                           ("5\t6\t7\t8", Box(5, 6, 7, 8))])
def test_sidecar_reads_what_people_write(tmp_path: Path, text: str, box: Box) -> None:
    (tmp_path / "a.init.txt").write_text(text)
    assert read_sidecar(tmp_path / "a.mp4") == box


@pytest.mark.parametrize("text", ["", "1,2,3", "1,2,0,4", "a,b,c,d", "1,2,nan,4"])
def test_a_malformed_sidecar_is_an_error_naming_the_file(tmp_path: Path, text: str) -> None:
    (tmp_path / "a.init.txt").write_text(text)
    with pytest.raises(InputError, match=r"a\.init\.txt"):
        read_sidecar(tmp_path / "a.mp4")


def test_a_sidecar_with_two_boxes_is_refused(tmp_path: Path) -> None:
    """Its second line was ignored without a word (a ground truth file saved as the sidecar)."""
    (tmp_path / "a.init.txt").write_text("10,10,40,30\n# comment\n20,20,40,30\n")
    with pytest.raises(InputError, match=r"a\.init\.txt: holds 2 lines of values; expected one"):
        read_sidecar(tmp_path / "a.mp4")


def test_format_box_is_what_init_takes() -> None:
    assert format_box(Box(10.0, 20.0, 30.0, 40.0)) == "10,20,30,40"
    assert format_box(Box(0.5, 1.25, 3.0, 4.126)) == "0.5,1.25,3,4.13"


def vtrack(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=START_BOUND_S, check=False)


def test_frame_writes_the_frame_with_a_light_grid(clip: Path, tmp_path: Path) -> None:
    out = tmp_path / "f.png"
    done = vtrack("frame", str(clip), "--at", "4", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert "frame 4" in done.stdout and f"{W}x{H}" in done.stdout
    plain = tmp_path / "plain.png"
    assert vtrack("frame", str(clip), "--at", "4", "-o", str(plain), "--no-grid").returncode == 0
    # --step with --no-grid was taken and ignored
    done = vtrack("frame", str(clip), "-o", str(tmp_path / "n.png"), "--no-grid", "--step", "20")
    assert (done.returncode, done.stderr) == (2, "vtrack: error: --step 20: spaces the grid's "
                                              "lines, and --no-grid draws none; give one of "
                                              "them\n")
    assert not (tmp_path / "n.png").exists()
    grid, frame = cv2.imread(str(out)).astype(int), cv2.imread(str(plain)).astype(int)
    assert grid.shape == frame.shape == (H, W, 3)
    # lines every 20 px are lighter than the frame, between them the frame is untouched
    assert (grid[100, :, :] - frame[100, :, :]).mean() > 5  # a horizontal grid line (y=100)
    assert np.abs(grid[110:118, 150:158] - frame[110:118, 150:158]).max() <= 2
    # a frame past the end is one error line naming the input and its length
    done = vtrack("frame", str(clip), "--at", "99", "-o", str(tmp_path / "x.png"))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.startswith(f"vtrack: error: {clip}") and "0..11" in done.stderr
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(("args", "said"), [
    (("frame", "--step", "100000000000000000000000"),
     "'--step': 100000000000000000000000 is not in the range 2<=x<=16384"),
    (("frame", "--step", "16385"), "'--step': 16385 is not in the range 2<=x<=16384"),
    (("select", "--frame", "1000000000001"),
     "'--frame': 1000000000001 is not in the range 0<=x<=1000000000000"),
], ids=["frame-step-huge", "frame-step-past-a-frame", "select-frame"])
def test_frame_and_select_numbers_have_an_upper_limit(args: tuple[str, ...], said: str,
                                                      clip: Path, tmp_path: Path) -> None:
    """`vtrack frame --step 100000000000000000000000` wrote an image (a grid of one line) and
    `vtrack select --frame` took any number, where --at stops at 10**12 and a frame is at most
    16384 pixels a side: each now has its declared range, refused in one line."""
    command, *options = args
    out = ["-o", str(tmp_path / "f.png")] if command == "frame" else []
    done = vtrack(command, str(clip), *options, *out)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and said in lines[0], done.stderr
    assert not list(tmp_path.iterdir())
    if command == "frame":  # the largest step is taken
        done = vtrack(command, str(clip), "--step", "16384", *out)
        assert done.returncode == 0 and (tmp_path / "f.png").exists(), done.stderr


def test_frame_of_a_sequence_folder_default_name(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=10, fps=30)
    folder = write_image_sequence(scene, tmp_path / "Seq")
    done = vtrack("frame", str(folder) + "/", "--at", "2", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert cv2.imread(str(tmp_path / "Seq-frame2.png")).shape == (120, 160, 3)


def test_select_and_frame_on_a_silent_stream_name_no_option_they_lack(tmp_path: Path) -> None:
    """On a silent udp:// input select and frame said "--timeout SECONDS waits longer", an
    option only vtrack run has."""
    import socket

    urls = []  # a port each: both listen at once
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as one, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as two:
        for probe in (one, two):
            probe.bind(("127.0.0.1", 0))
            urls.append(f"udp://127.0.0.1:{probe.getsockname()[1]}")
    with ThreadPoolExecutor(2) as pool:  # each waits the 10 s default
        done = list(pool.map(lambda args: vtrack(*args, cwd=tmp_path),
                             [("select", urls[0]), ("frame", urls[1])]))
    for result, quiet in zip(done, urls, strict=True):
        assert result.returncode == 2 and result.stdout == "", result.stderr
        assert result.stderr == (f"vtrack: error: {quiet}: cannot be opened (nothing came "
                                 "within 10 s)\n")
    assert list(tmp_path.iterdir()) == []


def test_frame_never_writes_into_its_input(clip: Path, tmp_path: Path) -> None:
    """``-o seq/img/0001.jpg`` burnt the grid into the input's own frame; ``frame -`` wrote
    ``--frame0.png``."""
    scene = make_scene("smooth", seed=1, width=160, height=120, frames=10, fps=30)
    folder = write_image_sequence(scene, tmp_path / "seq")
    first = (folder / "img" / "0001.jpg").read_bytes()
    for out in (folder / "img" / "0001.jpg", folder / "img" / "0011.png", folder / "x.png"):
        done = vtrack("frame", str(folder), "-o", str(out))
        assert done.returncode == 2, done.stderr
        assert done.stderr.strip() == (f"vtrack: error: --out {out}: is, or is inside, the "
                                       f"input {folder} (it would replace or add one of its "
                                       "frames); write the image elsewhere")
    assert (folder / "img" / "0001.jpg").read_bytes() == first
    assert sorted(p.name for p in folder.rglob("*.png")) == []
    with clip.open("rb") as stdin:
        done = subprocess.run([sys.executable, "-m", "vtrack", "frame", "-"], stdin=stdin,
                              capture_output=True, text=True, timeout=START_BOUND_S,
                              check=False,
                              cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(
                                  Path(vtrack_package.__file__).parents[1])})
    assert done.returncode == 0 and (tmp_path / "stdin-frame0.png").is_file(), done.stderr


def test_frame_replaces_an_image_already_there_only_with_overwrite(clip: Path,
                                                                  tmp_path: Path) -> None:
    """``vtrack frame CLIP -o f.png`` replaced an f.png already there without a word (a photo,
    an earlier frame), where vtrack run refuses its earlier results without -y: refused in one
    line naming the file, the file untouched; --overwrite (-y) replaces it. The default name
    (``clip-frame0.png``) the same; an empty file is written to."""
    out = tmp_path / "f.png"
    out.write_bytes(b"a photo")
    done = vtrack("frame", str(clip), "--at", "4", "-o", str(out))
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"vtrack: error: --out {out}: holds 7 bytes already; --overwrite "
                           "(-y) replaces it\n")
    assert out.read_bytes() == b"a photo"
    for flag in ("-y", "--overwrite"):
        done = vtrack("frame", str(clip), "--at", "4", "-o", str(out), flag)
        assert done.returncode == 0, done.stderr
        assert cv2.imread(str(out)).shape == (H, W, 3)
    assert vtrack("frame", str(clip), cwd=tmp_path).returncode == 0
    named = tmp_path / f"{clip.stem}-frame0.png"
    before = named.read_bytes()
    done = vtrack("frame", str(clip), "--at", "0", "--no-grid", cwd=tmp_path)
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"vtrack: error: {named.name}: holds {len(before)} bytes already; "
                           "--overwrite (-y) replaces it\n")
    assert named.read_bytes() == before
    (tmp_path / "empty.png").touch()
    assert vtrack("frame", str(clip), "-o", str(tmp_path / "empty.png")).returncode == 0


class Select:
    """``vtrack select`` running in a subprocess; ``url`` is the page it printed."""

    def __init__(self, *args: str, stdout_closed: bool = False) -> None:
        """``stdout_closed``: start it as ``vtrack select ARGS >&-`` (no stdout at all)."""
        command = [sys.executable, "-m", "vtrack", "select", *args]
        if stdout_closed:
            command = ["sh", "-c", 'exec "$0" "$@" >&-', *command]
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True)
        self.lines: queue.Queue[str] = queue.Queue()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()
        line = self.lines.get(timeout=30)
        assert "http://127.0.0.1:" in line, line
        self.url = line[line.index("http://"):].split()[0]

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.lines.put(line)

    def finish(self) -> tuple[int, str, str]:
        assert self.process.stdout is not None
        self.process.wait(timeout=30)  # its few lines fit in the pipe's buffer
        out = self.process.stdout.read()  # (not communicate(): the reader thread owns stderr)
        self.reader.join(timeout=10)  # stderr read to its end
        err = []
        while not self.lines.empty():
            err.append(self.lines.get())
        return self.process.returncode, out, "".join(err)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


def post(url: str, data: dict) -> tuple[int, dict]:
    request = urllib.request.Request(url, json.dumps(data).encode(),
                                     {"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(request, timeout=10) as response:
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


def test_frame_writes_through_a_link_it_is_given_as_out(clip: Path, tmp_path: Path) -> None:
    """``vtrack frame CLIP -o link.png -y`` with link.png a symbolic link replaced the link by
    a regular file (the file it led to kept its old bytes): the image goes to the file the link
    leads to, the link stays; a looping link is one line, nothing written."""
    (tmp_path / "real.png").write_bytes(b"old")
    link = tmp_path / "link.png"
    link.symlink_to("real.png")
    done = vtrack("frame", str(clip), "-o", str(link), "-y")
    assert done.returncode == 0, done.stderr
    assert link.is_symlink() and os.readlink(link) == "real.png"
    assert cv2.imread(str(tmp_path / "real.png")).shape == (H, W, 3)
    loop = tmp_path / "loop.png"
    loop.symlink_to("loop.png")
    done = vtrack("frame", str(clip), "-o", str(loop), "-y")
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == f"vtrack: error: --out {loop}: Too many levels of symbolic links\n"
    assert loop.is_symlink() and sorted(p.name for p in tmp_path.iterdir()) == [
        "link.png", "loop.png", "real.png"]


def test_frame_names_out_for_a_link_into_a_missing_folder(clip: Path, tmp_path: Path) -> None:
    """``vtrack frame CLIP -o d.png -y`` with d.png a link to nowhere/x.png said
    ``/abs/nowhere/x.png: cannot write (No such file or directory)``, naming neither --out nor
    the link: one line naming --out d.png and where its link leads, nothing written."""
    link = tmp_path / "d.png"
    link.symlink_to("nowhere/x.png")
    done = vtrack("frame", str(clip), "-o", str(link), "-y")
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"vtrack: error: --out {link}: its link leads to nowhere/x.png, "
                           "whose folder does not exist\n")
    assert link.is_symlink() and [p.name for p in tmp_path.iterdir()] == ["d.png"]


def test_a_box_drawn_on_a_later_frame_is_printed_with_its_frame_not_saved(clip: Path) -> None:
    """A box drawn on frame 7 was saved as the sidecar, which run and batch take as frame 0's
    box (only a warning said so)."""
    sidecar_path(clip).write_text("1,2,30,40\n")
    select = Select(str(clip), "--frame", "7")
    try:
        status, answer = post(select.url + "select", {"box": [10, 20, 30, 40], "frame": 7})
        assert status == 200 and answer == {"init": "10,20,30,40", "sidecar": None}
        code, out, err = select.finish()
    finally:
        select.stop()
    assert code == 0, err
    assert out.strip() == "--start 7 --init 10,20,30,40"
    assert "not saved (the sidecar holds frame 0's box)" in err
    assert read_sidecar(clip) == Box(1, 2, 30, 40)  # frame 0's box, as it was


def test_select_says_a_name_with_a_newline_in_one_line(clip: Path, tmp_path: Path) -> None:
    """`vtrack select 'new<newline>line.mp4'` said 'vtrack select: saved in .../new' and, on a
    line of its own, 'line.init.txt (vtrack run and vtrack batch use it ...)': its lines
    printed the name as it is, where its errors and warnings escape control characters. They
    do too now (`new\\nline.init.txt`), one line each."""
    video = tmp_path / "new\nline.mp4"
    shutil.copy(clip, video)
    select = Select(str(video))
    try:
        status, answer = post(select.url + "select", {"box": [10, 20, 30, 40], "frame": 0})
        code, out, err = select.finish()
    finally:
        select.stop()
    assert status == 200 and code == 0, err
    assert read_sidecar(video) == Box(10, 20, 30, 40)
    lines = err.splitlines()
    assert all(line.startswith("vtrack select: ") for line in lines), err
    assert lines[-1] == (f"vtrack select: saved in {tmp_path}/new\\nline.init.txt (vtrack run "
                         "and vtrack batch use it when no --init is given)")


def test_summary_lines_say_a_name_with_a_newline_in_one_line(clip: Path, tmp_path: Path
                                                             ) -> None:
    """`vtrack frame 'a<newline>b.mp4'` printed 'wrote a' and, on a line of its own,
    'b-frame0.png (frame 0, 320x240)'; so did the summary lines of vtrack vectors (its --out
    folder), vtrack scene and vtrack report, where vtrack run's and every error escape control
    characters."""
    video = tmp_path / "a\nb.mp4"
    shutil.copy(clip, video)
    frame = vtrack("frame", str(video), cwd=tmp_path)
    assert (frame.returncode, frame.stdout) == (0, f"wrote a\\nb-frame0.png (frame 0, {W}x{H})\n")
    assert (tmp_path / "a\nb-frame0.png").is_file()
    out = tmp_path / "v\nw"
    vectors = vtrack("vectors", str(video), "--init", "20,20,30,30", "--frames", "1", "-o",
                     str(out))
    assert vectors.returncode == 0, vectors.stderr
    assert vectors.stdout == f"wrote 1 frame of s0-fixed vectors to {tmp_path}/v\\nw\n"
    scene = vtrack("scene", "smooth", str(tmp_path / "x\ty.mp4"), "--frames", "10", "--size",
                   "64x48")
    assert scene.returncode == 0, scene.stderr
    assert scene.stdout.startswith(f"wrote {tmp_path}/x\\ty.mp4 (10 frames, ") and \
        scene.stdout.count("\n") == 1, scene.stdout


@pytest.mark.parametrize("size", [(3, 3), (2, 400)])
def test_select_refuses_frames_too_small_for_any_box(tmp_path: Path,
                                                    size: tuple[int, int]) -> None:
    """`vtrack select` of a 3x3 image served its page and waited for ever: every box dragged
    on it was refused (smaller than 4x4, or larger than the frame), as vtrack run refuses it."""
    image = tmp_path / "small.png"
    assert cv2.imwrite(str(image), np.zeros((*size, 3), np.uint8))
    process = subprocess.Popen([sys.executable, "-m", "vtrack", "select", str(image)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:  # its first line: the error (it printed the page's URL and waited)
        assert process.stderr is not None
        first = process.stderr.readline()
        if first.startswith("vtrack: error: "):
            process.wait(timeout=START_BOUND_S)
    finally:
        if process.poll() is None:
            process.kill()
        stdout, _ = process.communicate()
    assert first == (f"vtrack: error: {image}: its frames are {size[1]}x{size[0]}, too small "
                     "for the smallest box vtrack run tracks (4x4 pixels): there is no box to "
                     "select\n")
    assert (process.returncode, stdout) == (2, "")


def test_select_page_protocol_validates_and_writes_the_sidecar(clip: Path) -> None:
    """The page's server without a browser: info, frames, a rejected box, a confirmed one."""
    sidecar_path(clip).unlink(missing_ok=True)
    select = Select(str(clip), "--frame", "2")
    try:
        with urllib.request.urlopen(select.url + "info", timeout=10) as response:
            info = json.loads(response.read())
        assert (info["width"], info["height"], info["frame"]) == (W, H, 2)
        with urllib.request.urlopen(select.url + "frame/11", timeout=10) as response:
            jpeg = np.frombuffer(response.read(), np.uint8)
        assert cv2.imdecode(jpeg, cv2.IMREAD_COLOR).shape == (H, W, 3)
        with pytest.raises(urllib.error.HTTPError):
            urllib.request.urlopen(select.url + "frame/12", timeout=10)
        status, answer = post(select.url + "select", {"box": [300, 10, 50, 50], "frame": 0})
        assert status == 400 and "not inside the 320x240 frame" in answer["error"]
        assert not sidecar_path(clip).exists()
        status, answer = post(select.url + "select", {"box": [10, 20, 30, 40], "frame": 0})
        assert status == 200 and answer["init"] == "10,20,30,40"
        code, out, err = select.finish()
    finally:
        select.stop()
    assert code == 0, err
    assert out.strip() == "--init 10,20,30,40"
    assert read_sidecar(clip) == Box(10, 20, 30, 40)
    assert "clip.init.txt" in err


def test_select_of_a_sequence_img_folder_saves_the_box_run_and_batch_read(
        tmp_path: Path) -> None:
    """``select SEQ/img`` saved SEQ/img/init.txt and said run and batch would use it; ``run
    SEQ`` and ``batch`` read SEQ/init.txt and failed: "needs an initial box"."""
    scene = make_scene("smooth", seed=2, width=160, height=120, frames=10, fps=30)
    folder = write_image_sequence(scene, tmp_path / "footage" / "seqA")
    (folder / "groundtruth_rect.txt").unlink()  # the box can only come from the sidecar
    assert sidecar_path(folder / "img") == sidecar_path(folder) == folder / "init.txt"
    assert sidecar_path(str(folder / "img") + "/") == folder / "init.txt"
    select = Select(str(folder / "img"))
    try:
        status, answer = post(select.url + "select", {"box": [60, 50, 30, 24], "frame": 0})
        assert status == 200, answer
        code, out, err = select.finish()
    finally:
        select.stop()
    assert code == 0, err
    assert (folder / "init.txt").read_text() == "60,50,30,24\n"
    assert not (folder / "img" / "init.txt").exists()
    assert str(folder / "init.txt") in err
    for given in (folder, folder / "img"):
        out_dir = tmp_path / f"run-{given.name}"
        done = vtrack("run", str(given), "--no-video", "--frames", "3", "-o", str(out_dir))
        assert done.returncode == 0, done.stderr
        assert json.loads((out_dir / "run.json").read_text())["init_from"] == str(
            folder / "init.txt")
    batch = vtrack("batch", str(folder.parent), "--jobs", "1", "--no-video", "--frames", "3",
                   "--out", str(tmp_path / "batch"))
    assert batch.returncode == 0, batch.stdout + batch.stderr


def test_select_refuses_what_run_refuses_and_takes_one_confirm(tmp_path: Path,
                                                               clip: Path) -> None:
    """A 1x1 box and frame 123456 were saved (vtrack run then refused the sidecar); of 12
    confirms sent at once two were taken, the printed box not the saved one; a malformed
    sidecar stopped select from starting at all."""
    video = tmp_path / "clip.mp4"
    video.write_bytes(clip.read_bytes())
    sidecar_path(video).write_text("garbage\n")
    select = Select(str(video))
    try:
        status, answer = post(select.url + "select", {"box": [10.5, 20.25, 1, 1], "frame": 0})
        assert status == 400 and "smaller than 4x4" in answer["error"]
        status, answer = post(select.url + "select", {"box": [10, 20, 30, 40], "frame": 123456})
        assert status == 400 and "frame 123456: the input's frames are 0..11" in answer["error"]
        assert sidecar_path(video).read_text() == "garbage\n"
        def confirm(i: int) -> tuple[int | None, dict]:
            try:
                return post(select.url + "select", {"box": [i, 10, 20, 20], "frame": 0})
            except (OSError, http.client.HTTPException):  # closed once one was taken
                return None, {}

        with ThreadPoolExecutor(12) as pool:
            answers = list(pool.map(confirm, range(12)))
        taken = [i for i, (status, _) in enumerate(answers) if status == 200]
        assert all(answer["error"].startswith("a box was already confirmed")  # not 'not found'
                   for status, answer in answers if status not in (200, None))
        code, out, err = select.finish()
    finally:
        select.stop()
    assert len(taken) == 1 and code == 0, (answers, err)
    assert "garbage" in err and "the box you confirm replaces it" in err
    assert out.strip() == f"--init {taken[0]},10,20,20"
    assert read_sidecar(video) == Box(taken[0], 10, 20, 20)


def test_select_on_stdin_writes_no_sidecar(tmp_path: Path, clip: Path) -> None:
    """``select -`` wrote ``./-.init.txt``, which ``run -`` never reads, and said run used it."""
    with clip.open("rb") as stdin:
        process = subprocess.Popen([sys.executable, "-m", "vtrack", "select", "-"], stdin=stdin,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                   cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(
                                       Path(vtrack_package.__file__).parents[1])})  # this one
    select = Select.__new__(Select)
    select.process, select.lines = process, queue.Queue()
    select.reader = threading.Thread(target=select._read, daemon=True)
    select.reader.start()
    line = select.lines.get(timeout=30)
    select.url = line[line.index("http://"):].split()[0]
    try:
        status, answer = post(select.url + "select", {"box": [10, 20, 30, 40], "frame": 0})
        code, out, err = select.finish()
    finally:
        select.stop()
    assert status == 200 and answer["sidecar"] is None and code == 0, err
    assert out.strip() == "--init 10,20,30,40" and "give the box to vtrack run as --init" in err
    assert list(tmp_path.iterdir()) == []


def test_select_a_frame_past_the_end_is_an_error(clip: Path) -> None:
    done = vtrack("select", str(clip), "--frame", "50")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith(f"vtrack: error: {clip}") and "0..11" in done.stderr


def _browser() -> tuple[str, str]:
    """Chromium and its driver, or skip saying what is missing."""
    pytest.importorskip("selenium", reason="selenium is not installed (pip install -e '.[dev]')")
    binary = next(filter(None, map(shutil.which, ("chromium", "chromium-browser"))), None)
    driver = shutil.which("chromedriver")
    if binary is None or driver is None:
        pytest.skip("no headless browser: install Debian's chromium and chromium-driver "
                    "packages (apt-get install chromium chromium-driver)")
    return binary, driver


def test_select_in_a_real_browser_drag_a_box_and_confirm(tmp_path: Path) -> None:
    binary, driver_path = _browser()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    scene = make_scene("smooth", seed=5, width=W, height=H, frames=10, fps=30)
    folder = write_image_sequence(scene, tmp_path / "Seq")
    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--window-size=900,700",
                 f"--user-data-dir={tmp_path / 'profile'}"):
        options.add_argument(flag)
    select = Select(str(folder))
    browser = webdriver.Chrome(service=Service(driver_path), options=options)
    try:
        wait = WebDriverWait(browser, 20)
        browser.get(select.url)
        image = browser.find_element(By.ID, "frame")
        wait.until(lambda b: b.execute_script("return arguments[0].naturalWidth", image) == W)
        # step forward and back: the page shows which frame it is on
        browser.find_element(By.ID, "next").click()
        wait.until(lambda b: b.find_element(By.ID, "where").text.startswith("frame 1 "))
        browser.find_element(By.ID, "prev").click()
        wait.until(lambda b: b.find_element(By.ID, "where").text.startswith("frame 0 "))
        wait.until(lambda b: b.execute_script("return arguments[0].complete", image))
        shown = image.rect  # CSS pixels; the 320x240 frame fits the window unscaled
        assert round(shown["width"]) == W
        # drag from image pixel (40, 50) to (130, 110) with real mouse actions (offsets are
        # from the element's centre)
        x0, y0 = 40 - W / 2, 50 - H / 2
        (ActionChains(browser).move_to_element_with_offset(image, int(x0), int(y0))
         .click_and_hold().move_by_offset(45, 30).move_by_offset(45, 30).release().perform())
        typed = browser.find_element(By.ID, "init").get_attribute("value")
        x, y, w, h = (int(v) for v in typed.split(","))
        assert abs(x - 40) <= 1 and abs(y - 50) <= 1 and abs(w - 90) <= 1 and abs(h - 60) <= 1
        browser.find_element(By.ID, "confirm").click()
        wait.until(lambda b: b.find_element(By.TAG_NAME, "body").get_attribute("data-done"))
        code, out, err = select.finish()
    finally:
        browser.quit()
        select.stop()
    assert code == 0, err
    assert out.strip() == f"--init {typed}"
    assert (folder / "init.txt").read_text().strip() == typed
    assert read_sidecar(folder) == Box(x, y, w, h)


def test_select_stopped_by_sigterm_says_so_as_run_does(clip: Path) -> None:
    """``vtrack select clip.mp4 & kill $!`` exited 143 without a word."""
    select = Select(str(clip))
    try:
        select.process.terminate()
        code, out, err = select.finish()
    finally:
        select.stop()
    assert (code, out) == (143, "")
    assert err.splitlines()[-1] == "vtrack: interrupted" and "Traceback" not in err


@pytest.mark.parametrize("gone", ["Broken pipe", "closed before vtrack started"])
def test_select_with_stdout_gone_says_where_the_box_went(clip: Path, gone: str) -> None:
    """``vtrack select clip.mp4 | true``, then confirm: the box was saved and the command
    exited 1 without a word. ``vtrack select clip.mp4 >&-`` (stdout closed from the start)
    exited 0 without a word about the box it did not print."""
    sidecar_path(clip).unlink(missing_ok=True)
    select = Select(str(clip), stdout_closed=gone != "Broken pipe")
    try:
        assert select.process.stdout is not None
        select.process.stdout.close()  # its only reader: the next write breaks the pipe
        status, answer = post(select.url + "select", {"box": [10, 20, 30, 40], "frame": 0})
        assert status == 200 and answer["init"] == "10,20,30,40"
        code = select.process.wait(timeout=30)
        select.reader.join(timeout=10)
    finally:
        select.stop()
    err = []
    while not select.lines.empty():
        err.append(select.lines.get())
    assert code == 1
    assert err == [f"vtrack: error: standard output: {gone}: --init 10,20,30,40 was "
                   f"not printed there; it is saved in {sidecar_path(clip)}\n"]
    assert read_sidecar(clip) == Box(10, 20, 30, 40)


@pytest.mark.parametrize(("command", "option", "takes"), [
    ("frame", "'--out' / '-o'", "an image file name ending in .png or .jpg"),
    ("run", "'--gt'", "a ground-truth file name (OTB, VOT or MOTChallenge boxes)"),
])
def test_an_empty_file_option_names_what_it_takes(clip: Path, tmp_path: Path, command: str,
                                                  option: str, takes: str) -> None:
    """``vtrack frame -o ''`` and ``vtrack run --gt ''`` suggested "'.' for the current
    folder", which neither takes (-o then said "write a .png or .jpg image")."""
    flag = "-o" if command == "frame" else "--gt"
    done = vtrack(command, str(clip), flag, "", cwd=tmp_path)
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr.startswith(f"vtrack: error: Invalid value for {option}: empty; give "
                                  f"{takes} (see ")
    assert len(done.stderr.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_select_whose_address_line_stderr_cannot_take_ends_at_once(tmp_path: Path) -> None:
    """`vtrack select clip.mp4 2>/dev/full`: its page's address is the only way to it, and a
    note that stderr could not take was dropped (b3f5606), so select waited for ever for a box
    on a page nobody was told of. It ends at once, exit 1, nothing saved."""
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full (a device that takes no byte) on this machine")
    clip = write_video(make_scene("smooth", seed=3, width=W, height=H, frames=12, fps=30),
                       tmp_path / "clip.mp4")
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-m", "vtrack", "select", str(clip)],
                              stderr=full, stdout=subprocess.PIPE, cwd=tmp_path,
                              timeout=START_BOUND_S)
    assert done.returncode == 1, done
    assert not sidecar_path(clip).exists()
