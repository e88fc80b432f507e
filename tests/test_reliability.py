"""Hostile values and damaged inputs, run as a user runs them (``python -m vtrack`` subprocesses
on small generated clips): issue 11 items 5, 7, 9 and 11."""

from __future__ import annotations

import csv
import json
import struct
import subprocess
import zlib
from pathlib import Path

import av
import numpy as np
import pytest
from test_cli import assert_one_line_error, vtrack

from vtrack.scenes import make_scene, write_clip, write_groundtruth, write_video

W, H, FRAMES = 64, 48, 20


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A 64x48 clip of 20 frames and its ground truth."""
    folder = tmp_path_factory.mktemp("tiny")
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    clip, gt = folder / "tiny.mp4", folder / "tiny.gt.txt"
    write_video(scene, clip)
    write_groundtruth(scene, gt)
    return clip, gt


def refused(result: subprocess.CompletedProcess, *needles: str) -> str:
    """Exit 2 (refused before tracking) with one error line naming every needle."""
    line = assert_one_line_error(result, *needles)
    assert result.returncode == 2, result.stderr.decode()
    return line


# --- item 5: values that passed validation and crashed later ---------------------------------

INIT = "10,10,12,10"


@pytest.mark.parametrize(("args", "needles"), [
    (("--init", "0,0,1e308,1e308"), ("--init", "larger than the 64x48 frame")),
    (("--init", "0,0,0.001,0.001"), ("--init", "smaller than 4x4 pixels")),
    (("--init", "0,0,100000,100000", "-c", "s2"), ("--init", "larger than the 64x48 frame")),
    (("-c", "s0", "--init", INIT, "--set", "hue.search_scale=1e308"),
     ("hue", "search_scale", "range 1 to 16")),
    (("-c", "s0", "--init", INIT, "--set", "kalman.q=1e308"),
     ("kalman", "'q'", "range 0 to 1e+06")),
    (("-c", "s0", "--init", INIT, "--set", "kalman.q=nan"),
     ("kalman", "'q'", "not a number", "range")),
    (("--init", INIT, "-c", "camshift", "--set", "meanshift.iterations=2147483648"),
     ("meanshift", "iterations", "range 1 to 100", "2147483648")),
    (("--init", INIT, "-c", "s1", "--set", "particle.particles=2147483648"),
     ("particle", "particles", "range 1 to 1024")),
    (("--init", INIT, "-c", "s1", "--set", "particle.spread=1e308"),
     ("particle", "spread", "range 0 to 10")),
    (("--init", INIT, "-c", "s1", "--set", f"particle.history={2**63}"),
     ("particle", "history", "range 1 to 1000")),
    (("-c", "s3", "--set", "mht.initial=1e308"), ("mht", "initial", "range 0 to 1e+06")),
    (("-c", "s3", "--set", "mht.max_hypotheses=1000000"),
     ("mht", "max_hypotheses", "range 1 to 64")),
])
def test_hostile_values_are_refused_in_one_line(tiny, tmp_path: Path, args, needles) -> None:
    clip, _ = tiny
    refused(vtrack("run", str(clip), *args, "--no-video", "-o", str(tmp_path / "o")), *needles)
    assert not (tmp_path / "o" / "run.json").exists()


def test_ground_truth_with_a_huge_first_box_is_refused(tiny, tmp_path: Path) -> None:
    clip, gt = tiny
    lines = gt.read_text().splitlines()
    for first in ("0,0,1e308,1e308", "0,0,500,500", "1,1,2,2"):
        bad = tmp_path / "bad.txt"
        bad.write_text("\n".join([first, *lines[1:]]) + "\n")
        refused(vtrack("run", str(clip), "--gt", str(bad), "-o", str(tmp_path / "o")),
                "bad.txt")
    # A damaged box later in the file is refused too (it overflowed the drawing).
    bad.write_text("\n".join([*lines[:5], "1e308,1e308,1e308,1e308", *lines[6:]]) + "\n")
    refused(vtrack("run", str(clip), "--gt", str(bad), "-o", str(tmp_path / "o")),
            "bad.txt", "line 6")


def test_raw_frames_too_large_are_refused_before_reading(tmp_path: Path) -> None:
    result = vtrack("run", "-", "--raw", "100000x100000", "--init", INIT, "-o",
                    str(tmp_path / "o"), stdin=b"")
    refused(result, "--raw", "16384x16384")


def _png_header_only(path: Path, width: int, height: int) -> None:
    """A PNG whose header says ``width`` x ``height`` (a few bytes of pixels follow)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b""))


def test_oversized_image_and_video_are_refused_from_their_header(tmp_path: Path) -> None:
    folder = tmp_path / "seq" / "img"
    folder.mkdir(parents=True)
    _png_header_only(folder / "0001.png", 17000, 8)
    refused(vtrack("run", str(tmp_path / "seq"), "--init", "1,1,5,5", "-o", str(tmp_path / "a")),
            "0001.png", "17000x8", "16384x16384")
    y4m = tmp_path / "wide.y4m"
    y4m.write_bytes(b"YUV4MPEG2 W17000 H8 F30:1 C420jpeg\nFRAME\n" + bytes(17000 * 12))
    refused(vtrack("run", str(y4m), "--init", "1,1,5,5", "-o", str(tmp_path / "b")),
            "wide.y4m", "17000x8", "16384x16384")


# --- item 9: --fps ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def tiny_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tiny scene as an OTB image folder (img/0001.jpg ... and groundtruth_rect.txt)."""
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    out = tmp_path_factory.mktemp("folder") / "seq"
    write_clip(scene, out, fmt="images")
    return out


@pytest.mark.parametrize("fps", ["0", "-5", "nan", "inf"])
def test_non_positive_fps_is_refused(tiny, tmp_path: Path, fps: str) -> None:
    clip, _ = tiny
    refused(vtrack("run", "-", "--raw", f"{W}x{H}", "--fps", fps, "--init", INIT, "-o",
                   str(tmp_path / "a"), stdin=bytes(W * H * 3)), "--fps")
    refused(vtrack("run", str(clip), "--fps", fps, "--init", INIT, "-o", str(tmp_path / "b")),
            "--fps")


def test_fps_sets_the_time_of_image_folder_frames(tiny_folder, tmp_path: Path) -> None:
    gt = tiny_folder / "groundtruth_rect.txt"
    result = vtrack("run", str(tiny_folder), "--fps", "8", "--gt", str(gt), "--no-video", "-o",
                    str(tmp_path / "o"))
    assert result.returncode == 0, result.stderr.decode()
    with (tmp_path / "o" / "track.csv").open() as handle:
        times = [float(row["time_s"]) for row in csv.DictReader(handle)]
    assert times == pytest.approx([i / 8 for i in range(FRAMES)])
    assert json.loads((tmp_path / "o" / "run.json").read_text())["input"]["fps"] == 8.0


def test_fps_is_refused_for_a_video_file(tiny, tmp_path: Path) -> None:
    clip, _ = tiny
    refused(vtrack("run", str(clip), "--fps", "10", "--init", INIT, "-o", str(tmp_path / "o")),
            "--fps", "tiny.mp4", "timestamps")


# --- item 7: damage in the middle of a file --------------------------------------------------


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def test_random_bytes_in_the_middle_of_an_mp4_are_skipped(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=2, width=160, height=120, frames=120, fps=30.0)
    clip, gt = tmp_path / "clip.mp4", tmp_path / "clip.gt.txt"
    write_video(scene, clip)
    write_groundtruth(scene, gt)
    data = bytearray(clip.read_bytes())
    size = min(20_000, len(data) // 8)  # 20 KB, as reported, or an eighth of a small file
    middle = len(data) // 2
    data[middle : middle + size] = np.random.default_rng(0).bytes(size)
    damaged = tmp_path / "damaged.mp4"
    damaged.write_bytes(bytes(data))

    result = vtrack("run", str(damaged), "--gt", str(gt), "-o", str(tmp_path / "o"))
    stderr = result.stderr.decode()
    assert result.returncode == 0, stderr
    assert "Traceback" not in stderr
    warnings = [line for line in stderr.splitlines() if line.startswith("vtrack: warning")]
    # one line for the frames skipped; a second one when the decoder also handed over pictures
    # decoded with errors (which ones it flags depends on its frame threads' timing)
    assert 1 <= len(warnings) <= 2 and all("damaged.mp4" in w for w in warnings)
    assert "skipped" in warnings[0]
    assert all("decoded with errors" in w for w in warnings[1:])
    record = json.loads((tmp_path / "o" / "run.json").read_text())
    skipped = record["summary"]["frames_skipped"]
    rows = _rows(tmp_path / "o" / "track.csv")
    assert record["status"] == "complete" and skipped > 0
    assert f"skipped {skipped}" in result.stdout.decode()
    # Tracking went on past the damage to the end of the clip, and every frame kept its place:
    # the tracked frames and the skipped ones make up the whole clip.
    frames = [int(row["frame"]) for row in rows]
    assert len(rows) + skipped == len(scene) and frames[-1] == len(scene) - 1
    assert frames == sorted(set(frames))
    assert all(float(row["time_s"]) == pytest.approx(int(row["frame"]) / 30.0, abs=1e-3)
               for row in rows)
    with av.open(str(tmp_path / "o" / "annotated.mp4")) as written:
        assert sum(1 for _ in written.decode(video=0)) == len(rows)


def test_an_unreadable_image_in_a_folder_is_skipped(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=1, width=W, height=H, frames=FRAMES, fps=30.0)
    folder = tmp_path / "seq"
    write_clip(scene, folder, fmt="images")
    images = sorted((folder / "img").iterdir())
    images[7].write_bytes(b"not an image at all")
    result = vtrack("run", str(folder), "--gt", str(folder / "groundtruth_rect.txt"),
                    "--no-video", "-o", str(tmp_path / "o"))
    stderr = result.stderr.decode()
    assert result.returncode == 0, stderr
    warnings = [line for line in stderr.splitlines() if line.startswith("vtrack: warning")]
    assert len(warnings) == 1 and images[7].name in warnings[0] and "frame 7" in warnings[0]
    rows = _rows(tmp_path / "o" / "track.csv")
    assert [int(row["frame"]) for row in rows] == [i for i in range(FRAMES) if i != 7]
    record = json.loads((tmp_path / "o" / "run.json").read_text())
    assert record["status"] == "complete" and record["summary"]["frames_skipped"] == 1


# --- item 11: vtrack report --gt and runs of other inputs ------------------------------------


def test_report_gt_is_only_used_for_runs_of_its_length(tmp_path: Path) -> None:
    runs, truths = {}, {}
    for name, frames in (("short", 20), ("long", 30)):
        scene = make_scene("smooth", seed=3, width=W, height=H, frames=frames, fps=30.0)
        clip, gt = tmp_path / f"{name}.mp4", tmp_path / f"{name}.gt.txt"
        write_video(scene, clip)
        write_groundtruth(scene, gt)
        first = gt.read_text().splitlines()[0]
        runs[name], truths[name] = tmp_path / "runs" / name, gt
        result = vtrack("run", str(clip), "--init", first, "--no-video", "-q", "-o",
                        str(runs[name]))
        assert result.returncode == 0, result.stderr.decode()

    def scored(report: Path) -> dict[str, str]:
        return {row["input"]: row["ground_truth"] for row in _rows(report / "summary.csv")}

    # One plain file for both: the run of the other length is not scored, and a warning names
    # the run, its input and the file.
    result = vtrack("report", str(tmp_path / "runs"), "--gt", str(truths["long"]), "-o",
                    str(tmp_path / "r1"))
    stderr = result.stderr.decode()
    assert result.returncode == 0, stderr
    assert scored(tmp_path / "r1") == {"long": str(truths["long"]), "short": ""}
    (warning,) = [line for line in stderr.splitlines() if "not scored" in line]
    assert str(runs["short"]) in warning and "short" in warning
    assert "long.gt.txt has 30 boxes for its 20 frames" in warning and "--gt short=" in warning

    # One file per input: each run scored against its own.
    result = vtrack("report", str(tmp_path / "runs"), "--gt", f"short={truths['short']}",
                    "--gt", f"long={truths['long']}", "-o", str(tmp_path / "r2"))
    assert result.returncode == 0, result.stderr.decode()
    assert "warning" not in result.stderr.decode()
    assert scored(tmp_path / "r2") == {name: str(path) for name, path in truths.items()}
