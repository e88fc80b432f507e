"""The sidecar initial box (``NAME.init.txt`` beside a video, ``init.txt`` in a sequence
folder) starts `vtrack run` and `vtrack batch` when no --init is given (issue 12 item 2):
0-based pixels in both, whatever --gt-origin says; run.json records where the box came from."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from click.testing import CliRunner, Result

from vtrack.cli import main
from vtrack.config import DEFAULT_CONFIG
from vtrack.geometry import Box

if TYPE_CHECKING:
    from conftest import ClipFactory

W, H, FRAMES = 160, 120, 20


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args))


def first_box(scene_box: Box | None, dx: float = 0.0) -> Box:
    assert scene_box is not None
    return Box(round(scene_box.x + dx, 2), round(scene_box.y, 2), round(scene_box.w, 2),
               round(scene_box.h, 2))


def text(box: Box) -> str:
    return ",".join(f"{v:g}" for v in box)


def first_row(out: Path) -> Box:
    with (out / "track.csv").open(newline="") as handle:
        row = next(csv.DictReader(handle))
    return Box(*(float(row[k]) for k in ("x", "y", "w", "h")))


def record(out: Path) -> dict:
    return json.loads((out / "run.json").read_text())


@pytest.fixture()
def video(clip_factory: ClipFactory, tmp_path: Path) -> tuple[Path, Box]:
    """A video with no ground truth beside it, and its sidecar box."""
    clip = clip_factory("smooth", width=W, height=H, frames=FRAMES)
    path = tmp_path / "footage" / "clip.mp4"
    path.parent.mkdir()
    shutil.copy(clip.path, path)
    box = first_box(clip.scene.boxes[0])
    (path.parent / "clip.init.txt").write_text(text(box) + "\n")
    return path, box


@pytest.fixture()
def sequence(clip_factory: ClipFactory, tmp_path: Path) -> tuple[Path, Box]:
    """An OTB folder (1-based ground truth inside) whose init.txt holds a box 3 px to the right
    of the first ground-truth box, in 0-based pixels."""
    clip = clip_factory("smooth", width=W, height=H, frames=FRAMES, fmt="images")
    folder = tmp_path / "footage" / "seq"
    shutil.copytree(clip.path, folder)
    box = first_box(clip.scene.boxes[0], dx=3)
    (folder / "init.txt").write_text(f"# picked by hand\n{text(box)}\n")
    return folder, box


def test_run_starts_from_the_sidecar_without_init_or_gt(video: tuple[Path, Box],
                                                        tmp_path: Path) -> None:
    path, box = video
    out = tmp_path / "out"
    result = vtrack("run", str(path), "--no-video", "-o", str(out))
    assert result.exit_code == 0, result.output
    assert first_row(out) == box
    data = record(out)
    assert data["init"] == list(box)
    assert data["init_from"] == str(path.with_name("clip.init.txt"))


def test_run_reads_a_sequence_sidecar_in_0_based_pixels_whatever_gt_origin(
        sequence: tuple[Path, Box], tmp_path: Path) -> None:
    folder, box = sequence
    out = tmp_path / "out"
    result = vtrack("run", str(folder), "--gt", str(folder / "groundtruth_rect.txt"),
                    "--gt-origin", "1", "--no-video", "-o", str(out))
    assert result.exit_code == 0, result.output
    assert first_row(out) == box  # not shifted by the ground truth's 1-based origin
    assert record(out)["init_from"] == str(folder / "init.txt")
    # --init still wins over the sidecar
    other = Box(box.x - 3, box.y, box.w, box.h)
    again = vtrack("run", str(folder), "--init", text(other), "--no-video", "-y", "-o",
                   str(out))
    assert again.exit_code == 0, again.output
    assert first_row(out) == other and record(out)["init_from"] == "--init"


def test_a_malformed_sidecar_is_one_line(video: tuple[Path, Box], tmp_path: Path) -> None:
    path, _ = video
    sidecar = path.with_name("clip.init.txt")
    sidecar.write_text("10,20,thirty\n")
    result = vtrack("run", str(path), "--no-video", "-o", str(tmp_path / "out"))
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        line for line in result.stderr.strip().splitlines() if line.startswith("vtrack: error: ")]
    assert str(sidecar) in result.stderr and "x,y,w,h" in result.stderr


def test_without_any_box_the_error_names_the_sidecar(video: tuple[Path, Box],
                                                     tmp_path: Path) -> None:
    path, _ = video
    path.with_name("clip.init.txt").unlink()
    result = vtrack("run", str(path), "--no-video", "-o", str(tmp_path / "out"))
    assert result.exit_code == 2
    assert "clip.init.txt" in result.stderr and "vtrack select" in result.stderr


def test_batch_tracks_a_folder_of_footage_without_ground_truth(
        video: tuple[Path, Box], sequence: tuple[Path, Box], tmp_path: Path) -> None:
    (path, video_box), (folder, sequence_box) = video, sequence
    (folder / "groundtruth_rect.txt").unlink()  # no ground truth at all
    out = tmp_path / "out"
    result = vtrack("batch", str(path.parent), "--jobs", "1", "--no-video", "--out", str(out))
    assert result.exit_code == 0, result.output
    with (out / "summary.csv").open(newline="") as handle:
        rows = {row["input"]: row for row in csv.DictReader(handle)}
    assert {name: row["status"] for name, row in rows.items()} == {
        "clip": "complete", "seq": "complete"}
    for name, box, sidecar in (("clip", video_box, path.with_name("clip.init.txt")),
                               ("seq", sequence_box, folder / "init.txt")):
        assert first_row(out / name / DEFAULT_CONFIG) == box
        data = record(out / name / DEFAULT_CONFIG)
        assert data["init"] == list(box) and data["init_from"] == str(sidecar)
    # a changed sidecar is a different run: resume tracks it again
    moved = Box(video_box.x + 2, *video_box[1:])
    path.with_name("clip.init.txt").write_text(text(moved) + "\n")
    refused = vtrack("batch", str(path.parent), "--jobs", "1", "--no-video", "--out", str(out))
    assert refused.exit_code == 1 and "made with other settings" in refused.output
    again = vtrack("batch", str(path.parent), "--jobs", "1", "--no-video", "--out", str(out),
                   "--overwrite")
    with (out / "summary.csv").open(newline="") as handle:
        rows = {row["input"]: row for row in csv.DictReader(handle)}
    assert rows["clip"]["status"] == "complete" and rows["seq"]["status"] == "complete"
    assert first_row(out / "clip" / DEFAULT_CONFIG) == moved, again.output


def test_init_is_refused_by_a_config_that_finds_its_targets_but_a_sidecar_is_not(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Probe 48 item 3: ``--init`` with s3 / fixed_camera was accepted, had no effect and was
    recorded in run.json as used. Now an explicit --init is refused in one line; a sidecar box
    beside the input (there for single-target configs) leaves a multi-target run alone, in
    ``vtrack run`` and ``vtrack batch``; s4 still takes one (and says it does not use it:
    test_s4_takes_init_but_reports_no_box_it_does_not_track)."""
    clip = clip_factory("multi", frames=60)
    path = tmp_path / "footage" / "clip.mp4"
    path.parent.mkdir()
    shutil.copy(clip.path, path)
    box = first_box(clip.scene.tracks[0][0][1])
    path.with_name("clip.init.txt").write_text(text(box) + "\n")
    for config in ("s3", "fixed_camera", "s4_multi"):
        out = tmp_path / f"refused-{config}"
        result = vtrack("run", str(path), "-c", config, "--init", text(box), "--no-video",
                        "-o", str(out))
        assert result.exit_code == 2, result.output
        assert result.stderr.splitlines() == [
            f"vtrack: error: --init: {config} finds its targets itself (it tracks several, each "
            "from where it is detected) and takes no first box; leave --init out"]
        assert not out.exists()
    out = tmp_path / "s3"
    assert vtrack("run", str(path), "-c", "s3", "--no-video", "-o", str(out)).exit_code == 0
    assert (record(out)["init"], record(out)["init_from"]) == (None, None)
    result = vtrack("run", str(path), "-c", "s4", "--init", text(box), "--no-video", "-o",
                    str(tmp_path / "s4"))
    assert result.exit_code == 0, result.output
    assert record(tmp_path / "s4")["init_ignored"] == list(box)
    batch = tmp_path / "batch"
    result = vtrack("batch", str(path.parent), "-c", "s3", "-c", "fixed_camera", "--jobs", "1",
                    "--no-video", "--out", str(batch))
    assert result.exit_code == 0, result.output
    for config in ("s3", "fixed_camera"):
        assert record(batch / "clip" / config)["status"] == "complete"
        assert record(batch / "clip" / config)["init"] is None


def test_batch_from_a_later_frame_does_not_take_the_sidecar_box(
        video: tuple[Path, Box], clip_factory: ClipFactory, tmp_path: Path) -> None:
    """The sidecar holds frame 0's box: `vtrack batch --start 10` put it on frame 10 and
    tracked background, `complete` (vtrack run refused). Without ground truth the pair fails
    now, saying why; with it, the ground truth's box of frame 10 starts the run."""
    path, _ = video
    out = tmp_path / "out"
    result = vtrack("batch", str(path.parent), "-c", "s2", "--start", "10", "--no-video", "-o",
                    str(out))
    assert result.exit_code != 0
    assert ("--start 10: config 's2' needs the target's box in that frame, and there is no "
            "ground truth (clip.gt.txt, clip.txt; a sidecar box is frame 0's)") in result.stderr
    assert not (out / "clip" / "s2" / "run.json").exists()
    scene = clip_factory("smooth", width=W, height=H, frames=FRAMES).scene  # the video's
    scene_boxes = [first_box(b) for b in scene.boxes]
    path.with_name("clip.gt.txt").write_text("".join(f"{text(b)}\n" for b in scene_boxes))
    again = vtrack("batch", str(path.parent), "-c", "s2", "--start", "10", "--no-video", "-o",
                   str(out))
    assert again.exit_code == 0, again.output
    assert record(out / "clip" / "s2")["init"] == list(scene_boxes[10])
    assert first_row(out / "clip" / "s2") == scene_boxes[10]


def test_init_takes_the_line_a_sidecar_file_holds(video: tuple[Path, Box],
                                                  tmp_path: Path) -> None:
    """``--init "X Y W H"`` (the line a sidecar file may hold) was refused as not x,y,w,h; a
    bad --init now lists the forms it takes."""
    path, box = video
    out = tmp_path / "out"
    spaced = " ".join(f"{v:g}" for v in box)
    result = vtrack("run", str(path), "--init", spaced, "--no-video", "-o", str(out))
    assert result.exit_code == 0, result.output
    assert first_row(out) == box and record(out)["init_from"] == "--init"
    bad = vtrack("run", str(path), "--init", "1 2 3", "--no-video", "-o", str(tmp_path / "b"))
    assert bad.exit_code == 2
    assert bad.stderr.strip() == ("vtrack: error: --init: expected x,y,w,h or x y w h "
                                  "(4 numbers separated by commas, spaces or tabs), got '1 2 3'")


def test_s4_takes_init_but_reports_no_box_it_does_not_track(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """`vtrack run m.mp4 -c s4 --init 10,20,30,40` drew that box, untracked, as `occluded` for
    the 30 frames s4 learns the background (frames_occluded 30), though s4 finds its target
    itself and tracked the same without it. Now --init is still taken but the rows are those
    of a run without it, and one warning says the box is not used; run.json records it as
    given and ignored (it recorded it as the run's first box: `init`, `init_from --init`)."""
    clip = clip_factory("bounce", width=W, height=H, frames=40)
    given, without = tmp_path / "given", tmp_path / "without"
    result = vtrack("run", str(clip.path), "-c", "s4", "--init", "10,20,30,40", "--no-video",
                    "-q", "-o", str(given))
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines() == [
        "vtrack: warning: --init: s4 finds its target itself (from its first detection, after "
        "learning the background) and does not use a first box: no box is reported until it "
        "detects the target"]
    assert vtrack("run", str(clip.path), "-c", "s4", "--no-video", "-q", "-o",
                  str(without)).exit_code == 0
    assert (given / "track.csv").read_text() == (without / "track.csv").read_text()
    assert record(given)["summary"]["frames_occluded"] == \
        record(without)["summary"]["frames_occluded"] == 0
    assert (record(given)["init"], record(given)["init_from"]) == (None, None)
    assert record(given)["init_ignored"] == [10, 20, 30, 40]
    assert record(given)["request"]["init"] == [10, 20, 30, 40]
    assert record(without)["init_ignored"] is None
    assert record(given)["warnings"] == [result.stderr.splitlines()[0][len("vtrack: warning: "):]]
