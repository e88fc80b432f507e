"""Issue 21 item 15: extreme values and odd places given to the helper commands and to `run`
are one line and a non-zero exit, never a traceback."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import START_BOUND_S
from test_cli import assert_one_line_error, vtrack

import vtrack as vtrack_package
from vtrack.scenes import make_scene, write_clip, write_groundtruth, write_video

W, H, FRAMES = 64, 48, 20


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """A video, its ground truth, and the same scene as an image folder."""
    folder = tmp_path_factory.mktemp("extreme")
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    write_video(scene, folder / "c.mp4")
    write_groundtruth(scene, folder / "c.gt.txt")
    write_clip(scene, folder / "seq", fmt="images")
    return folder / "c.mp4", folder / "c.gt.txt", folder / "seq"


@pytest.mark.parametrize("fps", ["1e12", "1e308", "1e-308", "0.001", "10001"])
def test_an_extreme_fps_is_refused(clip, tmp_path: Path, fps: str) -> None:
    _, _, seq = clip
    gt = str(seq / "groundtruth_rect.txt")
    result = vtrack("run", str(seq), "--fps", fps, "--gt", gt, "--gt-origin", "1",
                    "-o", str(tmp_path / "a"))
    assert_one_line_error(result, "--fps", "0.01 to 10000")
    result = vtrack("run", "-", "--raw", f"{W}x{H}", "--fps", fps, "--init", "10,10,12,10",
                    "-o", str(tmp_path / "b"), stdin=bytes(W * H * 3 * 2))
    assert_one_line_error(result, "--fps")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_the_fps_limits_themselves_run(clip, tmp_path: Path) -> None:
    _, _, seq = clip
    for fps in ("0.01", "10000"):
        result = vtrack("run", str(seq), "--fps", fps, "--gt", str(seq / "groundtruth_rect.txt"),
                        "--gt-origin", "1", "-c", "s0", "-o", str(tmp_path / fps))
        assert result.returncode == 0, result.stderr.decode()


@pytest.mark.parametrize(("args", "needle"), [
    (("--size", "99999x99999"), "7680x4320"),
    (("--size", "64x48"), "under the 4x4 a tracker starts from"),  # vtrack run refused it
    (("--fps", "1e308"), "fps"),
    (("--fps", "0"), "fps"),
])
def test_scene_extremes_are_one_line(tmp_path: Path, args, needle) -> None:
    result = vtrack("scene", "grow", str(tmp_path / "s.mp4"), *args)
    assert_one_line_error(result, needle)
    assert not (tmp_path / "s.mp4").exists()


@pytest.mark.parametrize("fmt", ["mp4", "raw", "images"])
def test_scene_to_a_dash_is_refused_not_a_file_named_dash(tmp_path: Path, fmt: str) -> None:
    """``vtrack scene smooth - --format raw`` wrote files named ``-`` and ``-.gt.txt``, while
    ``vtrack run -`` reads standard input."""
    result = subprocess.run([sys.executable, "-m", "vtrack", "scene", "smooth", "-", "--format",
                             fmt], capture_output=True, timeout=START_BOUND_S, check=False,
                            cwd=tmp_path,
                            env={**os.environ, "PYTHONPATH": str(
                                Path(vtrack_package.__file__).parents[1])})  # this vtrack
    assert_one_line_error(result, "OUT -: vtrack scene writes files")
    assert list(tmp_path.iterdir()) == []


def test_vectors_into_a_file_and_a_damaged_dump(clip, tmp_path: Path) -> None:
    video = clip[0]
    taken = tmp_path / "existing"
    taken.write_text("mine\n")
    result = vtrack("vectors", str(video), "-c", "s0-fixed", "--init", "20,15,12,10",
                    "--frames", "2", "--out", str(taken))
    assert_one_line_error(result, "existing", "not a folder")
    assert taken.read_text() == "mine\n"
    vec = tmp_path / "vec"
    made = vtrack("vectors", str(video), "-c", "s0-fixed", "--init", "20,15,12,10",
                  "--frames", "2", "--out", str(vec))
    assert made.returncode == 0, made.stderr.decode()
    dump = tmp_path / "dump" / "frame_0000"
    dump.mkdir(parents=True)
    (dump / "rgb.hex").write_bytes(b"\xff\xfe\x00\n" + b"A" * 10_000_000 + b"\n")
    result = vtrack("vectors", "check", str(vec), str(tmp_path / "dump"))
    out = result.stdout.decode()
    assert result.returncode == 1 and "Traceback" not in result.stderr.decode()
    assert "frame_0000/rgb.hex" in out and "\\xff" in out and len(out) < 1000, out[:300]


def test_an_output_name_taken_by_a_folder_is_one_line(clip, tmp_path: Path) -> None:
    video, gt, _ = clip
    out = tmp_path / "out"
    (out / "annotated.mp4").mkdir(parents=True)
    result = vtrack("run", str(video), "--gt", str(gt), "-c", "s0", "-o", str(out))
    assert_one_line_error(result, "annotated.mp4", "is a folder")
    assert result.returncode == 2
    assert sorted(p.name for p in out.iterdir()) == ["annotated.mp4"]
