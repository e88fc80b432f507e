"""Messages and summaries a user reads (issue 12 item 6): MOTChallenge ground truth given to a
single-target config, shipped config names not shadowed by files, no ground-truth warning with
--frames, batch lines naming the config, multi-target summaries, no reprs, singular counts."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line

from vtrack.cli import main
from vtrack.config import load_config, shipped_configs
from vtrack.errors import InputError
from vtrack.frame import BgrFrame
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.run import RunSummary

if TYPE_CHECKING:
    from conftest import ClipFactory

W, H = 160, 120


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args))


def test_motchallenge_ground_truth_for_one_target_names_the_multi_target_configs(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    clip = clip_factory("multi", width=W, height=H, frames=60)
    assert clip.mot is not None
    line = one_error_line(vtrack("run", str(clip.path), "--gt", str(clip.mot), "--no-video",
                            "-o", str(tmp_path / "out")))
    assert str(clip.mot) in line and "MOTChallenge" in line
    assert "s3" in line and "s4_multi" in line


@pytest.mark.parametrize("columns", [6, 7, 8])
def test_motchallenge_rows_of_fewer_columns_for_one_target_are_named_as_such(
        clip_factory: ClipFactory, tmp_path: Path, columns: int) -> None:
    """Probe 51c: MOTChallenge ground truth of 8 columns (frame,id,x,y,w,h,consider,class, which
    multi-target configs read) was taken by a single-target config as VOT polygons (AUC 0,
    'more boxes than frames' only); of 6 or 7 it was 'expected 4 or 8 numbers'. Each is now
    named MOTChallenge ground truth, with every multi-target config (fixed_camera too)."""
    clip = clip_factory("multi", width=W, height=H, frames=60)
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(",".join(row.split(",")[:columns]) + "\n"
                          for row in clip.mot.read_text().splitlines()))
    out = tmp_path / "out"
    line = one_error_line(vtrack("run", str(clip.path), "-c", "s4", "--gt", str(gt),
                                 "--no-video", "-o", str(out)))
    assert line.startswith(f"vtrack: error: {gt} line 1: this is MOTChallenge ground truth")
    assert line.endswith("(--config fixed_camera, s3 or s4_multi)") and not out.exists()


def test_a_file_named_like_a_shipped_config_does_not_shadow_it(
        clip_factory: ClipFactory, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    clip = clip_factory("smooth", width=W, height=H, frames=10)
    toml = (shipped_configs()["camshift"].read_text()
            .replace('name = "camshift"', 'name = "mine"'))
    assert 'name = "mine"' in toml
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s2").write_text(toml)
    (tmp_path / "s0.toml").write_text(toml)
    names = {}
    for spec in ("s2", "./s2", "s0.toml", "s0"):
        out = tmp_path / f"out-{spec.replace('/', '_')}"
        result = vtrack("run", str(clip.path), "--gt", str(clip.gt), "-c", spec, "--no-video",
                        "-o", str(out))
        assert result.exit_code == 0, result.output
        names[spec] = json.loads((out / "run.json").read_text())["summary"]["config"]
    assert names == {"s2": "s2", "./s2": "mine", "s0.toml": "mine", "s0": "s0"}


def test_frames_with_longer_ground_truth_does_not_warn(clip_factory: ClipFactory,
                                                       tmp_path: Path) -> None:
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    stopped = vtrack("run", str(clip.path), "--gt", str(clip.gt), "--frames", "5",
                     "--no-video", "-o", str(tmp_path / "a"))
    assert stopped.exit_code == 0 and "warning" not in stopped.stderr, stopped.stderr
    # ground truth longer than the whole clip is still worth a warning
    longer = tmp_path / "longer.gt.txt"
    lines = clip.gt.read_text().splitlines()
    longer.write_text("\n".join(lines + lines[-3:]) + "\n")
    full = vtrack("run", str(clip.path), "--gt", str(longer), "--no-video",
                  "-o", str(tmp_path / "b"))
    assert full.exit_code == 0 and "23 boxes for 20 frames" in full.stderr, full.stderr


def test_counts_of_one_are_singular(clip_factory: ClipFactory, tmp_path: Path) -> None:
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    one = tmp_path / "one.gt.txt"
    one.write_text(clip.gt.read_text().splitlines()[0] + "\n")
    result = vtrack("run", str(clip.path), "--gt", str(one), "--frames", "1", "--no-video",
                    "-o", str(tmp_path / "a"))
    assert result.exit_code == 0, result.output
    assert ": 1 frame, " in result.stdout and "1 frames" not in result.output
    fewer = vtrack("run", str(clip.path), "--gt", str(one), "--no-video",
                   "-o", str(tmp_path / "b"))
    assert "has 1 box for 20 frames" in fewer.stderr, fewer.stderr


def test_a_box_in_a_message_is_x_y_w_h_not_a_repr() -> None:
    frame = BgrFrame(0, 0.0, np.full((H, W, 3), 128, np.uint8))
    pipeline = Pipeline(load_config("s0").build())
    with pytest.raises(InputError) as error:
        next(pipeline.track([frame], Box(10, 10, 20.5, 10)))
    assert "Box(" not in str(error.value) and "10,10,20.5,10" in str(error.value)


def test_batch_lines_name_the_config(clip_factory: ClipFactory, tmp_path: Path) -> None:
    clip = clip_factory("smooth", width=W, height=H, frames=12)
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "clip.mp4")
    shutil.copy(clip.gt, folder / "clip.gt.txt")
    result = vtrack("batch", str(folder), "-c", "s0", "-c", "camshift", "--jobs", "1",
                    "--no-video", "--out", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    lines = [line for line in result.stdout.splitlines() if line.startswith("clip")]
    assert sorted(line.split(":")[0] for line in lines) == ["clip [camshift]", "clip [s0]"]


def test_batch_lines_name_folders_as_the_tally_does(clip_factory: ClipFactory, tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack batch in -o results` printed each run's folder absolute ('-> /abs/results/clip/
    s0') and its tally relative ('-> results/summary.csv'); both now name it as -o gave it."""
    clip = clip_factory("smooth", width=W, height=H, frames=12)
    monkeypatch.chdir(tmp_path)
    Path("in").mkdir()
    shutil.copy(clip.path, "in/clip.mp4")
    shutil.copy(clip.gt, "in/clip.gt.txt")
    for _ in ("run", "resumed"):
        result = vtrack("batch", "in", "-c", "s0", "--jobs", "1", "--no-video", "-o", "results")
        assert result.exit_code == 0, result.output
        lines = result.stdout.splitlines()
        assert lines[0].startswith("clip [s0]: 12 frames")
        assert " -> results/clip/s0" in lines[0] and lines[1].endswith(" -> results/summary.csv")


def test_multi_target_summaries_show_only_multi_target_numbers(clip_factory: ClipFactory,
                                                                tmp_path: Path) -> None:
    clip = clip_factory("multi", width=W, height=H, frames=60)
    result = vtrack("run", str(clip.path), "-c", "s3", "--no-video", "-o", str(tmp_path / "a"))
    assert result.exit_code == 0, result.output
    assert "occluded" not in result.stdout and "lost" not in result.stdout
    scored = vtrack("run", str(clip.path), "-c", "s3", "--gt", str(clip.mot), "--no-video",
                    "-o", str(tmp_path / "b"))
    assert "mota" in scored.stdout and "occluded" not in scored.stdout
    # as the README says: mostly tracked / mostly lost too
    assert re.search(r"mostly_tracked \d+, mostly_lost \d+", scored.stdout), scored.stdout
    # a metric without a value (MOTP when nothing matched) is left out, not printed as None
    summary = RunSummary("clip.mp4", "out", "s3", "complete", 60, 1.0, 60.0,
                         mot={"mota": -1.0, "motp": None, "idf1": 0.0, "id_switches": 0},
                         multi_target=True)
    assert "None" not in summary.line() and "motp" not in summary.line()
    assert "mota -1.000" in summary.line()


def test_a_multi_target_run_without_ground_truth_counts_its_tracks(clip_factory: ClipFactory,
                                                                   tmp_path: Path) -> None:
    """Without ground truth a multi-target run said nothing of its tracks: the summary line
    was 'clip.mp4: 60 frames, 240.1 fps -> a', run.json's metrics {} and the report's columns
    all '—'. The line, run.json and the report now give the ids tracks.csv holds."""
    clip = clip_factory("multi", width=W, height=H, frames=60)
    out = tmp_path / "a"
    result = vtrack("run", str(clip.path), "-c", "s3", "--no-video", "-o", str(out))
    assert result.exit_code == 0, result.output
    ids = {line.split(",")[1] for line in (out / "tracks.csv").read_text().splitlines()[1:]}
    assert ids
    assert re.search(rf"60 frames, [\d.]+ fps, {len(ids)} tracks -> ", result.stdout), \
        result.stdout
    record = json.loads((out / "run.json").read_text())
    assert record["metrics"]["track_ids"] == record["summary"]["tracks"] == len(ids)
    report = vtrack("report", str(out), "--out", str(tmp_path / "rep"))
    assert report.exit_code == 0, report.output
    table = [line.split(" | ") for line in
             (tmp_path / "rep" / "summary.md").read_text().splitlines() if "| " in line]
    column = table[0].index("Tracks")
    assert table[2][column] == str(len(ids)), table


@pytest.mark.parametrize("args, usage", [((), "Usage: vtrack [OPTIONS] COMMAND"),
                                         (("vectors",), "Usage: vtrack vectors [OPTIONS]")])
def test_a_group_given_no_command_prints_its_help_not_an_error_line(
        args: tuple[str, ...], usage: str) -> None:
    result = CliRunner().invoke(main, list(args), prog_name="vtrack")
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith(usage), result.stderr
    assert "vtrack: error" not in result.stderr and "Commands:" in result.stderr
    assert "(see '" not in result.stderr


def test_an_unreadable_input_without_a_first_box_is_named_as_unreadable(tmp_path: Path) -> None:
    videos = tmp_path / "videos"  # a folder of videos is not an image sequence
    videos.mkdir()
    (videos / "a.mp4").write_bytes(b"\0" * 64)
    notes = tmp_path / "notes.mp4"
    notes.write_text("not a video\n" * 20)
    for spec, problem in ((videos, "no images"), (notes, "not a video")):
        for extra in ((), ("--start", "3")):
            line = one_error_line(vtrack("run", str(spec), *extra, "-o", str(tmp_path / "out")))
            assert line.startswith(f"vtrack: error: {spec}: {problem}"), line
            assert "box" not in line and "init" not in line, line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("args, named", [
    (("run", ""), "'INPUT'"),
    (("run", "clip.mp4", "-c", ""), "'--config'"),
    (("run", "clip.mp4", "--init", "1,1,5,5", "--stream", ""), "'--stream'"),
    (("batch", ".", "-c", ""), "'--config'"),
    (("frame", ""), "'INPUT'"),
    (("select", ""), "'INPUT'"),
    (("vectors", "", "--init", "1,1,5,5", "-o", "vec"), "'INPUT'"),
    (("vectors", "clip.mp4", "-c", "", "--init", "1,1,5,5", "-o", "vec"), "'--config'"),
    (("report", ".", "--gt", ""), "'--gt'"),
])
def test_an_empty_name_is_refused_naming_its_option(
        args: tuple[str, ...], named: str, tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # an empty name must not become this folder
    line = one_error_line(vtrack(*args))
    assert named in line and ": empty; give " in line, line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("args", "said"), [
    (("run", "in", "--fps", "abc"), "'--fps': 'abc' is not a frame rate (a number from 0.01 "
                                    "to 10000 frames per second)"),
    (("scene", "smooth", "x.mp4", "--fps", "fast"), "'--fps': 'fast' is not a frame rate"),
    (("scene", "smooth", "x.mp4", "--frames", "1.5"), "'--frames': '1.5' is not a whole "
                                                      "number of frames"),
    (("vectors", "in.mp4", "--init", "1,1,9,9", "-o", "v", "--frames", "all"),
     "'--frames': 'all' is not a whole number of frames, 1 to 300"),
], ids=["run-fps", "scene-fps", "scene-frames", "vectors-frames"])
def test_a_frame_rate_or_count_that_is_no_number_says_what_the_option_takes(
        args: tuple[str, ...], said: str) -> None:
    """`vtrack run in --fps abc` said "'abc' is not a valid float." (vtrack scene --frames 1.5
    and vtrack vectors --frames all: "is not a valid integer."), as -j abc did before it was
    told what it takes."""
    line = one_error_line(vtrack(*args))
    assert said in line, line
    assert "is not a valid" not in line


@pytest.mark.parametrize(("text", "said"), [
    ('[[stage]]\nname = 5\n', "mine.toml: stage #1: name must be text (a stage's name, e.g. "
                                'name = "hue"), got 5'),
    ('stage = ["hue"]\n', "mine.toml: stage #1 is not a [[stage]] table, got 'hue'"),
    ('[[stage]]\niterations = 5\n', "mine.toml: stage #1 has no name"),
], ids=["number", "not-a-table", "none"])
def test_a_stage_whose_name_is_wrong_is_told_what_is_wrong(
        text: str, said: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A config whose [[stage]] said `name = 5` (or `stage = ["hue"]`, a list of names) was
    refused 'mine.toml: stage #1 has no name': it has one, of the wrong kind."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text(text)
    line = one_error_line(vtrack("run", "in.mp4", "-c", "mine.toml", "--init", "1,1,9,9"))
    assert line == f"vtrack: error: {said}", line


def test_scene_with_an_empty_out_names_what_out_takes(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """`vtrack scene smooth ''` suggested "'.' for the current folder", which OUT then refused
    ('.: no video container format for this file name'); it now says what OUT takes."""
    monkeypatch.chdir(tmp_path)
    line = one_error_line(vtrack("scene", "smooth", ""))
    assert "'OUT': empty; give the clip's name: clip.mp4" in line, line
    assert "'.'" not in line
    assert list(tmp_path.iterdir()) == []


def test_a_batch_and_report_of_one_run_count_it_singular(clip_factory: ClipFactory,
                                                          tmp_path: Path) -> None:
    clip = clip_factory("smooth", width=W, height=H, frames=12)
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "clip.mp4")
    (folder / "clip.init.txt").write_text(clip.gt.read_text().splitlines()[0] + "\n")
    batch = vtrack("batch", str(folder), "-c", "s0", "--jobs", "1", "--no-video",
                   "--out", str(tmp_path / "out"))
    assert batch.exit_code == 0, batch.output
    assert "\n1 run (1 complete) -> " in batch.stdout, batch.stdout
    report = vtrack("report", str(tmp_path / "out"), "-o", str(tmp_path / "report"))
    assert report.exit_code == 0, report.output
    assert "1 single-target run has no ground truth" in report.stderr, report.stderr
    assert report.stdout.startswith("1 run, 1 plot -> "), report.stdout
    page = (tmp_path / "report" / "summary.md").read_text()
    assert "1 run of 1 input with 1 configuration;" in page
    assert "(s)" not in report.output + page


def test_help_names_the_ground_truth_files_batch_finds_and_scene_writes() -> None:
    """vtrack scene writes an image folder's MOTChallenge truth as groundtruth_mot.txt, which
    vtrack batch reads; its --help named only gt.txt. Scene's named one multi-target scenario."""
    from vtrack.batch.discover import SEQUENCE_MOT_GT, VIDEO_MOT_GT
    from vtrack.evaluate.groundtruth import SEQUENCE_GT, VIDEO_GT

    batch = vtrack("batch", "--help").output.split("Options:")[0]
    batch = " ".join(batch.split())  # lines wrapped anywhere
    for name in (*SEQUENCE_GT, *SEQUENCE_MOT_GT, *(n.format("name") for n in VIDEO_GT),
                 *(n.format("name") for n in VIDEO_MOT_GT)):
        assert name in batch, (name, batch)
    scene = " ".join(vtrack("scene", "--help").output.split("Options:")[0].split())
    assert "(multi, pedestrians, vehicles, street), OUT.mot.txt" in scene, scene


@pytest.mark.parametrize("command", ["frame", "select", "run"])
def test_a_raw_file_where_a_video_is_read_says_only_run_reads_raw_frames(
        clip_factory: ClipFactory, command: str) -> None:
    """`vtrack frame r.raw` and `vtrack select r.raw` (which take no --raw) said only
    'not a video FFmpeg can decode (Invalid argument)'."""
    raw = clip_factory("smooth", width=160, height=120, frames=10, fmt="raw").path
    line = one_error_line(vtrack(command, str(raw)))
    assert line == (f"vtrack: error: {raw}: not a video FFmpeg can decode (Invalid argument); "
                    "raw frames are read only by vtrack run --raw WxH (with --pix-fmt, --fps)")


@pytest.mark.parametrize(("args", "said"), [
    (("batch", "in", "-j", "abc"), "'--jobs' / '-j': 'abc' is not a whole number in the range "
                                   "1<=x<=512"),
    (("batch", "in", "-j", "1.5"), "'--jobs' / '-j': '1.5' is not a whole number in the range "
                                   "1<=x<=512"),
    (("run", "in.mp4", "--crf", "high"), "'--crf': 'high' is not a whole number in the range "
                                         "0<=x<=51"),
    (("batch", "in", "--scheduler-timeout", "soon"), "'--scheduler-timeout': 'soon' is not a "
                                                     "number of seconds from 0.1 to 86400"),
], ids=["jobs-word", "jobs-fraction", "crf", "seconds"])
def test_a_value_that_is_no_number_is_refused_naming_the_options_range(
        args: tuple[str, ...], said: str) -> None:
    """`vtrack batch -j abc` said "'abc' is not a valid integer range." (and a word for a time,
    "'soon' is not a valid seconds."): now what the option takes, as a number out of its
    range is told."""
    _said_not(args, said, "is not a valid")


@pytest.mark.parametrize(("args", "said"), [
    (("run", "in.ts", "--follow", "later"), "'--follow': 'later' is not a number of seconds "
                                            "above 0 and at most 86400"),
    (("batch", "in", "--worker-timeout", "soon"), "'--worker-timeout': 'soon' is not a number "
                                                  "of seconds above 0 and at most 86400"),
], ids=["follow", "worker-timeout"])
def test_a_word_for_a_wait_that_excludes_0_says_above_0(args: tuple[str, ...],
                                                        said: str) -> None:
    """`vtrack run rec.ts --follow later` said "is not a number of seconds from 0 to 86400",
    though --follow 0 is refused ('not in the range 0<x<=86400'): an open bound is said as one."""
    _said_not(args, said, "from 0 to")


def _said_not(args: tuple[str, ...], said: str, not_said: str) -> None:
    """``vtrack ARGS`` fails with one error line that holds ``said`` and not ``not_said``."""
    line = one_error_line(vtrack(*args))
    assert said in line, line
    assert not_said not in line


@pytest.mark.parametrize(("args", "said"), [
    (("run", "in.ts", "--timeout", "1e-400"), "'--timeout': '1e-400' is not a number of "
                                              "seconds from 0.1 to 3600"),
    (("run", "in.ts", "--stats-period", "-1"), "'--stats-period': '-1' is not a number of "
                                               "seconds from 0 to 3600"),
    (("run", "in.ts", "--stats-period", "nan"), "'--stats-period': 'nan' is not a number of "
                                                "seconds from 0 to 3600"),
    (("run", "in.ts", "--follow", "0"), "'--follow': '0' is not a number of seconds above 0 "
                                        "and at most 86400"),
    (("batch", "in", "--scheduler-timeout", "0.05"), "'--scheduler-timeout': '0.05' is not a "
                                                     "number of seconds from 0.1 to 86400"),
], ids=["timeout-underflow", "stats-period-negative", "stats-period-nan", "follow-0",
        "scheduler-timeout"])
def test_a_number_of_seconds_out_of_range_is_named_as_typed_in_one_wording(
        args: tuple[str, ...], said: str) -> None:
    """`--timeout 1e-400` said '0.0 is not in the range 0.1<=x<=3600.0' (click's words for the
    float it made of the value), `--stats-period -1` '-1.0 is not in the range 0<=x<=3600.'
    where `--stats-period nan` said "'nan' is not a number of seconds from 0 to 3600": every
    seconds option now refuses a value out of its range as it refuses a word, the value as
    typed."""
    line = one_error_line(vtrack(*args))
    assert said in line, line
    assert "<=x" not in line and "<x" not in line


RAW_RUN = ("run", "-", "--raw", "64x48", "--init", "1,1,8,8")


@pytest.mark.parametrize(("args", "said"), [
    ((*RAW_RUN, "--fps", "1e-400"), "'1e-400' is not a frame rate"),
    (("scene", "smooth", "out.mp4", "--fps", "1e-400"), "'1e-400' is not a frame rate"),
    (("scene", "smooth", "out.mp4", "--fps", "-1e400"), "'-1e400' is not a frame rate"),
    ((*RAW_RUN, "--fps", "1e-320"), "'1e-320' is not a frame rate"),
    (("scene", "smooth", "out.mp4", "--fps", "1e-320"), "'1e-320' is not a frame rate"),
    ((*RAW_RUN, "--fps", "2e-308"), "--fps 2e-308: must be a frame rate from 0.01 to 10000"),
    (("scene", "smooth", "out.mp4", "--fps", "2e-308"), "--fps 2e-308: must be from 0.01 to"),
], ids=["run-underflow", "scene-underflow", "scene-overflow", "run-subnormal",
        "scene-subnormal", "run-subnormal-held", "scene-subnormal-held"])
def test_a_frame_rate_beyond_a_float_is_named_as_typed(args: tuple[str, ...], said: str
                                                       ) -> None:
    """`--fps 1e-400` said '--fps 0: must be a frame rate ...' (the 0.0 the text became before
    the range check), `--fps -1e400` '--fps -inf', `--fps 1e-320` '--fps 9.99989e-321' (a
    subnormal float, some of its digits lost): the value is now named as typed. A subnormal
    that prints back as typed (`--fps 2e-308`) is a number, refused by its range (it was "not
    a frame rate" too)."""
    line = one_error_line(vtrack(*args))
    assert said in line, line
    assert "--fps 0" not in line and "inf" not in line and "--fps 9.9" not in line


def test_follow_taking_the_input_as_its_seconds_says_how_to_give_both() -> None:
    """`vtrack run --follow rec.ts --init ...` takes rec.ts as --follow's seconds (its number
    may be left out); the refusal said only that rec.ts is no number. It now says how to give
    both: INPUT before --follow, or the seconds after it. A timeout's refusal has no such
    words (its number is never left out)."""
    line = one_error_line(vtrack("run", "--follow", "rec.ts", "--init", "1,2,3,4"))
    assert ("'rec.ts' is not a number of seconds above 0 and at most 86400; if it is INPUT, "
            "put it before --follow or give the seconds (--follow 5 rec.ts)") in line, line
    line = one_error_line(vtrack("run", "--timeout", "rec.ts", "in.ts"))
    assert "INPUT" not in line and "'rec.ts' is not a number of seconds" in line


@pytest.mark.parametrize("command", ["run", "batch"])
def test_encoding_options_with_no_video_are_refused(clip_factory: ClipFactory, tmp_path: Path,
                                                    command: str) -> None:
    """`vtrack run clip.mp4 --no-video --preset slow --crf 10` (and `vtrack batch`) took both
    without a word, though --no-video writes no video for them to encode (--video-out with
    --no-video is refused). Each is now one line naming it, exit 2, nothing written."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    out = tmp_path / "out"
    given = [str(clip.path), "--gt", str(clip.gt)] if command == "run" else [str(clip.path.parent)]
    for option, value in (("--preset", "slow"), ("--crf", "10")):
        line = one_error_line(vtrack(command, *given, "--no-video", option, value,
                                     "-o", str(out)))
        assert line.startswith(f"vtrack: error: {option} {value}: sets the x264 encoding of "
                               "the annotated video, and --no-video writes none")
    assert not out.exists()


def test_a_batch_says_when_multi_target_configs_find_only_single_target_ground_truth(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """`vtrack batch d -c s3` with only a.gt.txt (one target's boxes) beside a.mp4 ran
    unscored without a word: a multi-target config reads MOTChallenge ground truth (a.mot.txt).
    One warning now names the file, what the config reads instead, and that it is not scored."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    folder = tmp_path / "d"
    folder.mkdir()
    shutil.copy(clip.path, folder / "a.mp4")
    shutil.copy(clip.gt, folder / "a.gt.txt")
    result = vtrack("batch", str(folder), "-c", "s3", "--jobs", "1", "--no-video",
                    "-o", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert [line for line in result.stderr.splitlines() if "warning" in line] == [
        f"vtrack: warning: {(folder / 'a.gt.txt').resolve()}: one target's ground truth; "
        "config 's3' tracks several targets and reads MOTChallenge ground truth (a.mot.txt "
        "beside a.mp4): its run is not scored"]
    (folder / "a.mot.txt").write_text("1,1,10,10,20,20,1,1,1\n")  # scored with it: no word
    result = vtrack("batch", str(folder), "-c", "s3", "--jobs", "1", "--no-video",
                    "-o", str(tmp_path / "out"), "-y")
    assert result.exit_code == 0, result.output
    assert "one target's ground truth" not in result.stderr  # (the run's own warnings stay)


def test_the_unscored_warning_counts_other_inputs_and_lists_configs_in_plain_english(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Probe R: with three such inputs and three multi-target configs the warning read
    '.../a.gt.txt (and 2 other inputs's): ...; configs 's3' and 's4_multi' and 'fixed_camera'
    track several targets ...'. It now says "(and 2 other inputs')" ("1 other input's") and
    "'s3', 's4_multi' and 'fixed_camera'"."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    folder = tmp_path / "d"
    folder.mkdir()
    for name in "abc":
        shutil.copy(clip.path, folder / f"{name}.mp4")
        shutil.copy(clip.gt, folder / f"{name}.gt.txt")
    result = vtrack("batch", str(folder), "-c", "s3", "-c", "s4_multi", "-c", "fixed_camera",
                    "--jobs", "1", "--no-video", "-o", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert [line for line in result.stderr.splitlines() if "warning" in line] == [
        f"vtrack: warning: {(folder / 'a.gt.txt').resolve()} (and 2 other inputs'): one "
        "target's ground truth; configs 's3', 's4_multi' and 'fixed_camera' track several "
        "targets and read MOTChallenge ground truth (a.mot.txt beside a.mp4): their runs are "
        "not scored"]
    (folder / "c.mp4").unlink()
    result = vtrack("batch", str(folder), "-c", "s3", "--jobs", "1", "--no-video",
                    "-o", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert f"{(folder / 'a.gt.txt').resolve()} (and 1 other input's): " in result.stderr


@pytest.mark.parametrize("fmt", ["images", "mp4"])
def test_a_run_without_a_first_box_names_the_ground_truth_batch_would_take(
        clip_factory: ClipFactory, tmp_path: Path, fmt: str) -> None:
    """``vtrack run Bird2/`` (no --gt) said only "give --init x,y,w,h, --gt FILE ...", though
    the folder holds the ground truth ``vtrack batch`` takes by itself; the message now names it
    as a --gt to give. An input without one is told --gt FILE, as before."""
    clip = clip_factory("smooth", frames=30, fmt=fmt)
    copy = tmp_path / ("seq" if fmt == "images" else "clip.mp4")
    if fmt == "images":
        shutil.copytree(clip.path, copy)
        truth = copy / "groundtruth_rect.txt"
    else:
        shutil.copy(clip.path, copy)
        truth = tmp_path / "clip.gt.txt"
        shutil.copy(clip.gt, truth)
    said = one_error_line(vtrack("run", str(copy), "--no-video", "--out", str(tmp_path / "o")))
    assert f"give --gt {truth} (its ground truth" in said
    truth.unlink()
    said = one_error_line(vtrack("run", str(copy), "--no-video", "--out", str(tmp_path / "o")))
    assert "give --gt FILE, --init x,y,w,h" in said


def test_live_raw_frames_are_refused_as_the_help_and_readme_say(tmp_path: Path) -> None:
    # `vtrack run - --raw 1920x1080 --live` was refused ("raw frames are read as they come")
    # while neither --live's help nor README's Keeping up said raw frames cannot be live
    raw = tmp_path / "frames.raw"
    raw.write_bytes(bytes(16 * 16 * 3 * 2))
    line = one_error_line(vtrack("run", str(raw), "--raw", "16x16", "--live", "--init",
                                 "2,2,8,8", "-o", str(tmp_path / "out")))
    assert line.startswith("vtrack: error: --live: raw frames are read as they come")
    assert "Refused for --raw frames" in " ".join(vtrack("run", "--help").output.split())
    readme = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    assert "`--live` with `--raw` is refused" in " ".join(readme.split())
    assert not (tmp_path / "out").exists()


def test_gt_origin_without_gt_is_refused_by_run_and_report(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Probe R: `vtrack report results --gt-origin 0` (a researcher re-scoring OTB runs as
    0-based) and `vtrack run clip.mp4 --init ... --gt-origin 1` ran as if it was not given:
    without --gt nothing reads it, and the report's numbers stayed the recorded ones. Both now
    refuse it in one line (exit 2), before anything is written; 'auto', the default, passes."""
    clip = clip_factory("smooth", width=W, height=H, frames=20)
    box = clip.gt.read_text().splitlines()[0]
    out = tmp_path / "run"
    ran = vtrack("run", str(clip.path), "--init", box, "--no-video", "-q", "-o", str(out),
                 "--gt-origin", "auto")
    assert ran.exit_code == 0, ran.output
    expected = ("vtrack: error: --gt-origin {}: sets the origin of --gt's boxes, and no --gt is "
                "given; give both or neither")
    refused = vtrack("run", str(clip.path), "--init", box, "--no-video", "-q",
                     "-o", str(tmp_path / "other"), "--gt-origin", "1")
    assert one_error_line(refused).startswith(expected.format(1))
    assert not (tmp_path / "other").exists()
    report = tmp_path / "report"
    refused = vtrack("report", str(out), "-o", str(report), "--gt-origin", "0")
    assert one_error_line(refused).startswith(expected.format(0))
    assert not report.exists()
    scored = vtrack("report", str(out), "-o", str(report), "-q", "--gt-origin", "0",
                    "--gt", str(clip.gt))
    assert scored.exit_code == 0, scored.output


def test_configs_whose_names_differ_only_in_case_are_refused_by_a_batch(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """`vtrack batch in -c s0 -c mine.toml`, mine.toml a copy of s0 named "S0", ran both into
    out/<input>/s0/ and out/<input>/S0/: one folder on a case-insensitive disk (macOS,
    Windows), where the second run's files replaced the first's. It is refused, as two configs
    of one name are, before anything is written."""
    folder = tmp_path / "in"
    folder.mkdir()
    clip = clip_factory("smooth", width=160, height=120, frames=10)
    shutil.copy(clip.path, folder / "a.mp4")
    shutil.copy(clip.gt, folder / "a.gt.txt")
    mine = tmp_path / "mine.toml"
    mine.write_text(vtrack("stages", "s0", "--toml").output.replace('name = "s0"', 'name = "S0"'))
    out = tmp_path / "out"
    line = one_error_line(vtrack("batch", str(folder), "-c", "s0", "-c", str(mine),
                                 "-o", str(out)))
    assert line == (f"vtrack: error: --config {mine}: the results folders of 'S0' and of 's0' "
                    "(s0) differ only in case, one folder on a case-insensitive disk (macOS, "
                    "Windows): rename one")
    assert not out.exists()


def test_a_config_given_twice_to_a_batch_is_said_so(tmp_path: Path) -> None:
    """Probe R: `vtrack batch in -c robust -c s0 -c robust` said 'vtrack: error: --config
    robust: another config has the results folder of 'robust' (robust); results are kept per
    name, rename one', as if two configs clashed: there is one, given twice. It now says so;
    two configs of one name (s0 and a copy of its file) still get the rename message."""
    folder = tmp_path / "in"
    folder.mkdir()
    out = tmp_path / "out"
    line = one_error_line(vtrack("batch", str(folder), "-c", "robust", "-c", "s0", "-c",
                                 "robust", "-o", str(out)))
    assert line == "vtrack: error: --config robust: given twice; each config runs once on " \
                   "every input"
    copy = tmp_path / "s0.toml"
    copy.write_text(vtrack("stages", "s0", "--toml").output)
    line = one_error_line(vtrack("batch", str(folder), "-c", "s0", "-c", str(copy),
                                 "-o", str(out)))
    assert line.startswith(f"vtrack: error: --config {copy}: another config has the results "
                           "folder of 's0'")
    assert not out.exists()


def test_a_config_file_given_twice_by_two_names_to_a_batch_is_said_so(tmp_path: Path) -> None:
    """`vtrack batch in -c mine.toml -c ./mine.toml` (or `-c s0 -c .../vtrack/configs/s0.toml`,
    the shipped file itself) said '--config ./mine.toml: another config has the results folder
    of 'mine' (mine.toml); results are kept per name, rename one': the two spellings of one
    file were compared as written. One file is one config, given twice."""
    folder = tmp_path / "in"
    folder.mkdir()
    out = tmp_path / "out"
    mine = tmp_path / "mine.toml"
    mine.write_text(vtrack("stages", "s0", "--toml").output.replace('name = "s0"',
                                                                    'name = "mine"'))
    for first, second in ((str(mine), f"{tmp_path}/in/../mine.toml"),
                          ("s0", str(shipped_configs()["s0"]))):
        line = one_error_line(vtrack("batch", str(folder), "-c", first, "-c", second,
                                     "-o", str(out)))
        assert line == f"vtrack: error: --config {second}: given twice; each config runs " \
                       "once on every input"
    assert not out.exists()
