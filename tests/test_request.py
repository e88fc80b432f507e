"""One run request: ``run.json`` records it whole, and batch's resume reuses a result only for
exactly the same request."""

from __future__ import annotations

import csv
import json
import shutil
from dataclasses import fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from click.testing import CliRunner

from vtrack.batch import completed_summary
from vtrack.cli import main
from vtrack.config import load_config
from vtrack.geometry import Box
from vtrack.io import RawFormat
from vtrack.io.video import FFmpegInput
from vtrack.request import RunRequest
from vtrack.run import STATUS_COMPLETE, run

if TYPE_CHECKING:
    from conftest import ClipFactory

#: Another value for every field of RunRequest.
OTHER: dict[str, Any] = {
    "input": "other.mp4",
    "out_dir": Path("moved"),  # a copy of the results folder, see below
    "config": load_config("camshift"),
    "init_box": Box(1, 2, 30, 40),
    "gt_path": Path("other.gt.txt"),
    "gt_origin": 1,
    "gt_first": 4,
    "raw": RawFormat(160, 120, "bgr24", 30.0),
    "fps": 12.5,
    "video": False,
    "preset": "fast",
    "crf": 30,
    "seed": 7,
    "max_frames": 5,
    "start": 3,
    "start_s": 0.5,
    "max_s": 0.3,
    "init_from": "other.init.txt",
    "stream": "other.jsonl",
    "ffmpeg": FFmpegInput(format="mpegts", options=(("probesize", "32"),), timeout_s=2.0,
                          follow_s=1.0),
    "live": True,
    "video_out": "udp://127.0.0.1:5000",
    "target": 2,
    "first_track_id": 12,  # (a multi-target config's only: its own test below)
}


def test_changing_any_field_of_the_request_makes_resume_run_again(
    clip_factory: ClipFactory, tmp_path: Path
) -> None:
    clip = clip_factory("smooth", width=160, height=120, frames=20)
    # (s1 draws random numbers and makes a video: --seed, --preset and --crf count)
    request = RunRequest(input=str(clip.path), out_dir=tmp_path / "a", config=load_config("s1"),
                         gt_path=clip.gt, max_frames=12)
    assert run(request).status == STATUS_COMPLETE
    assert completed_summary(request) is not None  # the same request: reused
    assert {f.name for f in fields(RunRequest)} == set(OTHER)  # a new field needs a value here
    for name, value in OTHER.items():
        if name == "first_track_id":  # s1 numbers no tracks: refused (test_multi.py)
            continue
        if name == "out_dir":
            value = tmp_path / "b"
        changed = replace(request, **{name: value})
        assert changed != request, name
        if name == "out_dir":  # the same results, moved whole: still this request's
            shutil.copytree(request.out_dir, value)
            assert completed_summary(changed) is not None
            continue
        assert completed_summary(changed) is None, name
        assert request.differences(changed.to_dict()), name  # (named in a refusal)


def test_a_run_numbered_from_another_first_track_id_is_another_run(
    clip_factory: ClipFactory, tmp_path: Path
) -> None:
    """A multi-target request's ``first_track_id`` (``--first-id``) changes its tracks.csv, so
    a batch does not take a result numbered from another id as this request's: it is a
    difference named by its option. A run.json written before there was a first track id (its
    request has none) numbered from 1, as a request of 1 does: the same run."""
    clip = clip_factory("pedestrians", seed=4, frames=60)
    request = RunRequest(input=str(clip.path), out_dir=tmp_path / "a",
                         config=load_config("s4_multi"), video=False)
    assert run(request).status == STATUS_COMPLETE
    assert completed_summary(request) is not None
    later = replace(request, first_track_id=12)
    assert completed_summary(later) is None
    assert request.differences(later.to_dict()) == ["--first-id"]
    assert later.differences(request.to_dict()) == ["--first-id"]
    older = {k: v for k, v in request.to_dict().items() if k != "first_track_id"}
    assert request.differences(older) == [] and later.differences(older) == ["--first-id"]
    assert RunRequest.from_dict(older).first_track_id == 1
    assert RunRequest.from_dict(later.to_dict()).first_track_id == 12


def test_a_request_recorded_without_a_first_track_id_or_target_is_read_as_before_them() -> None:
    """RunRequest.from_dict of a request whose "first_track_id" was null stopped on int(None)
    (TypeError); absent or null, a field recorded since a later version (first_track_id,
    target) is what a record without it meant: 1, None; and the same run as that."""
    request = RunRequest(input="clip.mp4", out_dir=Path("out"), config=load_config("s3"),
                         video=False)
    for value in ({"first_track_id": None, "target": None}, {}):
        recorded = {k: v for k, v in request.to_dict().items()
                    if k not in ("first_track_id", "target")} | value
        read = RunRequest.from_dict(recorded)
        assert (read.first_track_id, read.target) == (1, None), value
        assert read.to_dict() == request.to_dict()
        assert request.differences(recorded) == [], value
    numbered = replace(request, first_track_id=7)
    assert numbered.differences({**request.to_dict(), "first_track_id": None}) == ["--first-id"]


def test_the_request_round_trips_through_its_dict() -> None:
    request = RunRequest(input="clip.mp4", out_dir=Path("out"), config=load_config("s2"),
                         init_box=Box(1.5, 2, 30, 40), gt_path=Path("gt.txt"), gt_origin=1,
                         raw=RawFormat(64, 48, "gray", 25.0), video=False, seed=3,
                         max_frames=9, ffmpeg=FFmpegInput("h264", (("fflags", "nobuffer"),),
                                                          3.0, 2.0), live=False, target=2)
    again = RunRequest.from_dict(request.to_dict())
    assert again.to_dict() == request.to_dict()
    assert again.config.resolved() == request.config.resolved()


def test_batch_runs_again_when_only_the_ground_truth_origin_changed(
    clip_factory: ClipFactory, tmp_path: Path
) -> None:
    clip = clip_factory("smooth", width=160, height=120, frames=20)
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "smooth.mp4")
    shutil.copy(clip.gt, folder / "smooth.gt.txt")
    out = tmp_path / "out"
    statuses = []
    for origin in ("0", "1", "1"):
        result = CliRunner().invoke(main, ["batch", str(folder), "--jobs", "1", "--no-video",
                                           "--gt-origin", origin, "--out", str(out), "-y"])
        assert result.exit_code == 0, result.output
        with (out / "summary.csv").open(newline="") as handle:
            statuses.append(next(csv.DictReader(handle))["status"])
        statuses.append("not run again" in result.output)
    assert statuses == ["complete", False, "complete", False, "complete", True]


def test_settings_that_change_nothing_do_not_make_resume_run_again(
    clip_factory: ClipFactory, tmp_path: Path
) -> None:
    """`vtrack batch in --no-video`, then `vtrack batch in --no-video --crf 30 --preset slow`
    refused every pair, 'made with other settings: --preset, --crf' (exit 1), though neither
    writes a video for them to change; --gt-origin without ground truth and --seed for a
    config that draws no random numbers (all but s1) likewise. Now such a
    pair is reused ('already complete: not run again'); with a video they still count, and a
    --video-out run is named by its option (was 'the video's place (--video)'). (--crf and
    --preset with --no-video are now refused by the CLI: the request still ignores them.)"""
    clip = clip_factory("smooth", width=160, height=120, frames=20)
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(clip.path, folder / "smooth.mp4")
    (folder / "smooth.init.txt").write_text(clip.gt.read_text().splitlines()[0])  # no --gt
    out = tmp_path / "out"
    outputs = []
    for extra in ([], ["--gt-origin", "1", "--seed", "5"]):
        result = CliRunner().invoke(main, ["batch", str(folder), "-c", "s0", "--jobs", "1",
                                           "--no-video", "--out", str(out), *extra])
        assert result.exit_code == 0, result.output
        outputs.append(result.output)
    assert "not run again" not in outputs[0] and "already complete: not run again" in outputs[1]
    record = (out / "smooth" / "s0" / "run.json").read_text()
    request = RunRequest.from_dict(json.loads(record)["request"])
    assert request.differences(replace(request, crf=30, preset="slow").to_dict()) == []
    video = replace(request, video=True)
    assert video.differences(replace(video, crf=30).to_dict()) == ["--crf"]
    particles = replace(video, config=load_config("s1"))
    assert particles.differences(replace(particles, seed=5).to_dict()) == ["--seed"]
    assert video.differences(replace(video, video_out="udp://127.0.0.1:5000").to_dict()) == [
        "--video-out"]


@pytest.mark.parametrize("config", ["s0", 5, ["s0"], None])
def test_a_recorded_config_of_another_shape_is_a_difference_not_a_crash(config: object) -> None:
    """A run.json whose request holds a config that is no table (hand-edited, another tool's)
    made the resume's comparison raise AttributeError ('str' object has no attribute 'get'):
    vtrack batch printed a traceback. It is now a difference like any other (review)."""
    request = RunRequest(input="clip.mp4", out_dir=Path("out"), config=load_config("s0"),
                         init_box=Box(1, 2, 30, 40), video=False)
    recorded = {**request.to_dict(), "config": config}
    assert request.differences(recorded) == ["the config (its file or a --set)"]
