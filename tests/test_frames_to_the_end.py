"""``stopped_by_frames``: whether ``--frames N`` ended a run before its input ended. An input
whose length is known without reading on (an image folder, a regular file of raw frames, an
image given alone) that ends at the N-th frame was read to its end, not stopped."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import pytest

from vtrack.scenes import make_scene, write_clip

FRAMES = 10


@pytest.fixture(scope="module")
def clips(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str]:
    """An image folder and a raw bgr24 file of one scene of :data:`FRAMES` frames, and the
    first ground-truth box."""
    folder = tmp_path_factory.mktemp("ends")
    scene = make_scene("smooth", seed=3, width=160, height=120, frames=FRAMES, fps=30)
    images = write_clip(scene, folder / "seq", fmt="images").clip
    raw = write_clip(scene, folder / "clip.bgr", fmt="raw").clip
    return images, raw, ",".join(f"{v:g}" for v in scene.boxes[0])


def _stopped(args: list[str], out: Path, stdin: Path | None = None) -> tuple[int, bool]:
    """``vtrack run ARGS`` (s2, no video): its run.json's frames and stopped_by_frames."""
    with open(stdin or "/dev/null", "rb") as feed:
        done = subprocess.run([sys.executable, "-m", "vtrack", "run", *args, "-c", "s2", "-q",
                               "--no-video", "-o", str(out)], stdin=feed, capture_output=True,
                              text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    record = json.loads((out / "run.json").read_text())
    assert record["status"] == "complete"
    return record["frames"], record["stopped_by_frames"]


@pytest.mark.parametrize(("span", "expected"), [
    (["--frames", str(FRAMES)], (FRAMES, False)),
    (["--start", str(FRAMES - 1), "--frames", "1"], (1, False)),
    (["--frames", str(FRAMES - 1)], (FRAMES - 1, True)),
])
def test_image_folder(clips: tuple[Path, Path, str], tmp_path: Path, span: list[str],
                      expected: tuple[int, bool]) -> None:
    images, _, _ = clips
    truth = str(images / "groundtruth_rect.txt")
    assert _stopped([str(images), "--gt", truth, *span], tmp_path / "out") == expected


@pytest.mark.parametrize(("frames", "expected"), [(FRAMES, False), (FRAMES - 1, True)])
def test_raw_file(clips: tuple[Path, Path, str], tmp_path: Path, frames: int,
                  expected: bool) -> None:
    _, raw, box = clips
    args = ["--raw", "160x120", "--init", box, "--frames", str(frames)]
    assert _stopped([str(raw), *args], tmp_path / "file") == (frames, expected)
    # a pipe: the end is not known without reading one more frame, which --frames must not
    fed = subprocess.Popen(["cat", str(raw)], stdout=subprocess.PIPE)
    try:
        done = subprocess.run([sys.executable, "-m", "vtrack", "run", "-", *args, "-c", "s2",
                               "-q", "--no-video", "-o", str(tmp_path / "pipe")],
                              stdin=fed.stdout, capture_output=True, text=True, timeout=120,
                              check=False)
    finally:
        fed.wait()
    assert done.returncode == 0, done.stderr
    assert json.loads((tmp_path / "pipe" / "run.json").read_text())["stopped_by_frames"]



@pytest.mark.parametrize(("ext", "copies", "expected"), [
    (".jpg", 1, False), (".png", 1, False), (".png", 2, True)])
def test_a_still_image_given_alone(clips: tuple[Path, Path, str], tmp_path: Path, ext: str,
                                   copies: int, expected: bool) -> None:
    """A JPEG or PNG given alone ends at frame 0: ``--frames 1`` read it to its end. It was
    recorded as stopped by ``--frames`` (a video's end is known only by reading on). A file of
    two PNGs one after the other (FFmpeg reads both) still is."""
    images, _, box = clips
    photo = tmp_path / f"photo{ext}"
    assert cv2.imwrite(str(photo), cv2.imread(str(sorted((images / "img").iterdir())[0])))
    photo.write_bytes(photo.read_bytes() * copies)
    assert _stopped([str(photo), "--init", box, "--frames", "1"], tmp_path / "out") == (
        1, expected)


def test_a_still_image_repeated_by_an_input_option_is_not_taken_as_ended(
        clips: tuple[Path, Path, str], tmp_path: Path) -> None:
    """``--input-option loop=1`` repeats a still image without end: ``--frames 1`` stopped it,
    which run.json said was its end (the first packet was still the whole file). ``loop=0``
    (image2's default) repeats nothing: its one frame is its end, as without the option (it
    was counted as repeating: stopped by --frames)."""
    images, _, box = clips
    photo = tmp_path / "photo.png"
    assert cv2.imwrite(str(photo), cv2.imread(str(sorted((images / "img").iterdir())[0])))
    looped = [str(photo), "--format", "image2", "--input-option", "loop=1", "--init", box]
    assert _stopped([*looped, "--frames", "1"], tmp_path / "one") == (1, True)
    assert _stopped([*looped, "--frames", "3"], tmp_path / "three") == (3, True)
    once = [str(photo), "--format", "image2", "--input-option", "loop=0", "--init", box]
    assert _stopped([*once, "--frames", "1"], tmp_path / "once") == (1, False)
