"""The stage contract: what stages share is declared, so a chain that loads runs.

Every chain of one, two or three registered stages is checked as a config; every chain the
loader accepts runs on a small generated clip (with the initial box, and without it when the
chain can start without one) and must not fail on a value no earlier stage set. Chains the
loader refuses are refused with one line naming the stage and what it lacks.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Callable
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import START_BOUND_S

from vtrack.cli import main
from vtrack.config import load_config, parse_config
from vtrack.errors import ConfigError, VtrackError
from vtrack.pipeline import Pipeline
from vtrack.scenes import make_scene
from vtrack.stages.base import PIPELINE_PROVIDES, TrackContext, all_stages


def _values(det: Path) -> dict[str, dict]:
    """Parameters that make each stage do its work within a few frames of a tiny clip."""
    return {"background": {"frames": 2}, "mot_detections": {"path": str(det)}}


def _check(chain: tuple[str, ...], values: dict[str, dict]):
    tables = [{"name": name, **values.get(name, {})} for name in chain]
    return parse_config({"stage": tables}, "chain.toml")


def test_every_declared_field_is_a_context_field() -> None:
    """Stages write context fields; they read fields or read-only properties (``rng``, made
    on first use)."""
    fields = set(TrackContext.__dataclass_fields__)
    readable = fields | {name for name, value in vars(TrackContext).items()
                         if isinstance(value, property)}
    assert readable >= PIPELINE_PROVIDES
    for name, cls in all_stages().items():
        assert cls.requires <= readable, name
        assert cls.provides <= fields, name


def test_every_accepted_chain_of_up_to_three_stages_runs(tmp_path: Path) -> None:
    scene = make_scene("smooth", seed=3, width=64, height=48, frames=10)
    frames = list(scene.as_frames())
    det = tmp_path / "det.txt"
    det.write_text("".join(f"{i + 1},-1,{b.x},{b.y},{b.w},{b.h},1\n"
                           for i, b in enumerate(scene.boxes) if b is not None))
    values = _values(det)
    names = list(all_stages())
    accepted = refused = 0
    crashes = []
    for length in (1, 2, 3):
        for chain in itertools.product(names, repeat=length):
            try:
                config = _check(chain, values)
            except ConfigError as exc:
                refused += 1
                message = str(exc)
                assert "\n" not in message and ("needs" in message or "chain" in message), chain
                continue
            accepted += 1
            pipeline = Pipeline(config.build())
            starts = [scene.boxes[0]] + ([None] if not pipeline.needs_init_box else [])
            for init in starts:
                pipeline = Pipeline(config.build())
                try:
                    results = list(pipeline.track(frames, init))
                except VtrackError:
                    continue  # a user error, reported as one line: not a crash
                except Exception as exc:  # noqa: BLE001 - collected, reported below
                    crashes.append(f"{' -> '.join(chain)} (init {init}): {exc!r}")
                    continue
                assert len(results) == len(frames), chain
    assert crashes == []
    assert accepted > 100 and refused > 100  # both sides of the check are exercised


@pytest.mark.parametrize(
    ("chain", "stage", "missing"),
    [
        (("background", "meanshift"), "meanshift", "search_box, target_model"),
        (("background", "blobs", "largest_blob", "occlusion"), "occlusion",
         "search_box, target_model"),
    ],
)
def test_a_chain_missing_a_shared_value_is_refused_before_anything_runs(
    tmp_path: Path, chain: tuple[str, ...], stage: str, missing: str
) -> None:
    config = tmp_path / "bad.toml"
    config.write_text("".join(f'[[stage]]\nname = "{name}"\n' for name in chain))
    clip = tmp_path / "clip.raw"
    clip.write_bytes(bytes(64 * 48 * 3))
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["run", str(clip), "--raw", "64x48", "--config", str(config), "--init",
               "1,1,8,8", "--no-video", "--out", str(out)])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("vtrack: error: ") and f"stage '{stage}' needs {missing}" in lines[0]
    assert not out.exists()


@pytest.mark.parametrize(("chain", "problem"), [
    (("hue", "backproject", "meanshift", "particle", "particle"),
     "stage 'particle' appears 2 times; a chain runs each stage once"),
    (("hue",), "no stage of the chain (hue) tracks: none sets the target's box"),
    (("threshold", "blobs"), "no stage of the chain (threshold -> blobs) tracks"),
    (("background", "blobs", "kalman_tracks", "mht"),
     "stages kalman_tracks and mht both set the tracks; a chain has one multi-target tracker"),
    (("threshold", "blobs", "mht", "largest_blob"),
     "stage 'largest_blob' sets the measurement of one target, but the chain tracks several "
     "targets (mht)"),
    (("hue", "backproject", "meanshift", "threshold", "blobs", "mht"),
     "stage 'hue' needs the target's first box, but the chain tracks several targets (mht)"),
])
def test_a_chain_that_cannot_track_is_refused_when_it_loads(chain: tuple[str, ...],
                                                            problem: str) -> None:
    """Each of these ran to `complete`, exit 0: a stage twice (its parameters set on both, its
    time merged), no tracking stage (the first box reported `tracking` on every frame), two
    multi-target trackers (every target written twice), a single-target stage in a
    multi-target chain (its box thrown away), or a chain no input could start."""
    with pytest.raises(ConfigError, match=re.escape(f"chain.toml: {problem}")):
        _check(chain, {})


@pytest.mark.parametrize(("top", "problem"), [
    ({"name": ""}, "name is empty"), ({"name": "  "}, "name is empty"),
    ({"name": 5}, "name must be text, got 5"), ({"name": {"a": 1}}, "name must be text"),
    ({"description": 3}, "description must be text, got 3"),
])
def test_a_config_name_that_cannot_name_a_results_folder_is_refused(top: dict,
                                                                    problem: str) -> None:
    """An empty name wrote the run's results into the input's own folder (vtrack-out/clip/);
    a number or a table was taken as its text."""
    with pytest.raises(ConfigError, match=f"^mine.toml: {problem}"):
        parse_config({**top, "stage": [{"name": "particle"}]}, "mine.toml")


def test_repeated_configs_and_integers_too_long_to_read_are_named_for_what_they_are(
        tmp_path: Path) -> None:
    """``vtrack run -c s0 -c s1`` ran s1 without a word; a 5000-digit integer was called
    "not an integer"."""
    import subprocess
    import sys

    def vtrack(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "vtrack", *args], capture_output=True,
                              text=True, timeout=START_BOUND_S, check=False)

    twice = vtrack("run", "clip.mp4", "-c", "s0", "-c", "s1", "--init", "1,1,8,8")
    assert twice.returncode == 2 and "Traceback" not in twice.stderr
    assert "--config given 2 times (s0, s1): a run tracks with one config" in twice.stderr
    config = load_config("s0")
    with pytest.raises(ConfigError, match="'iterations' must be in the range .*, got a "
                                          "5000-digit integer"):
        config.with_overrides(["meanshift.iterations=" + "9" * 5000])
    with pytest.raises(ConfigError, match="'bins' must be one of .*, got a 4001-digit integer"):
        load_config("robust").with_overrides(["robust_model.bins=" + "1" * 4001])


def test_vtrack_stages_lists_what_a_stage_needs_gives_and_the_rules_its_values_keep() -> None:
    """`vtrack stages` and docs/stages.md listed each parameter's range only: a config author
    learnt what a stage needs from earlier stages (`stage 'meanshift' needs likelihood,
    target_model, which no earlier stage provides`) and the rules between its values
    (`interp_scales (3) is smaller than scales (17)`, `low (0.9) is above high (0.5)`) only from
    a refusal. Each stage's entry now ends with what it needs and gives, and every stage whose
    values or place in a chain are checked beyond the ranges declares those rules, listed.
    hue_bp_fixed and kernel_meanshift_int did not declare that they may not share a chain (one
    fixed-point record, config._check_tracks): each rule declared is now broken on purpose and
    refused."""
    entries: dict[str, str] = {}  # each stage's indented lines, by the name starting its entry
    stage = ""
    for line in CliRunner().invoke(main, ["stages"]).output.splitlines(keepends=True):
        stage = stage if line.startswith(" ") else line.split(":")[0]
        entries[stage] = entries.get(stage, "") + line * line.startswith(" ")
    for name, cls in all_stages().items():
        entry = entries[name]
        needs = ", ".join(sorted(cls.requires - PIPELINE_PROVIDES)) or "nothing"
        assert f"    needs: {needs}; gives: {', '.join(sorted(cls.provides))}\n" in entry, name
        checked = {"values_problem", "chain_problem"} & set(vars(cls))
        assert not checked or cls.rules, (name, checked)
        for rule in cls.rules:
            assert f"    rule: {rule}\n" in entry, (name, rule)
    search = CliRunner().invoke(main, ["stages", "robust_search"]).output
    assert "    rule: interp_scales >= scales when scale is on\n" in search
    broken = _rules_broken()
    assert set(broken) == {(name, rule) for name, cls in all_stages().items()
                           for rule in cls.rules}  # (each rule declared is broken below)
    for (name, rule), (breaks, said) in broken.items():
        with pytest.raises(ConfigError) as refused:
            breaks()
        assert said in str(refused.value), (name, rule, str(refused.value))


def _rules_broken() -> dict[tuple[str, str], tuple[Callable[[], object], str]]:
    """Each stage's declared rule (stage, rule) -> a config breaking it on purpose (every other
    rule kept) and what its refusal says."""
    def chain(*names: str) -> Callable[[], object]:
        return lambda: parse_config({"stage": [{"name": n} for n in names]}, "chain.toml")

    def shipped(name: str, values: dict[str, object]) -> Callable[[], object]:
        return lambda: load_config(name).with_values(values)

    def without(name: str, stage: str) -> Callable[[], object]:
        return lambda: parse_config({"stage": [{"name": n, **v} for n, v in
                                               load_config(name).stages if n != stage]}, name)

    record = "it reads the S0 fixed-point record of hue_bp_fixed, which must come before it"
    both = ("stages hue_bp_fixed and kernel_meanshift_int both keep the chain's fixed-point "
            "record")
    one_record = ("no other stage keeping a fixed-point record (hue_bp_fixed, "
                  "kernel_meanshift_int) in the chain: a chain computes one")
    s0_record = "hue_bp_fixed before this stage (it reads its S0 fixed-point record)"
    return {
        ("blobs", "min_area <= max_area when max_area is set (not 0)"): (
            shipped("s4", {"blobs.min_area": 50, "blobs.max_area": 40}),
            "stage 'blobs': min_area (50) is larger than max_area (40)"),
        ("byte_tracks", "low <= high"): (
            shipped("fixed_camera", {"byte_tracks.low": 0.9, "byte_tracks.high": 0.5}),
            "stage 'byte_tracks': low (0.9) is above high (0.5)"),
        ("byte_tracks", "colour_gate below 1 needs detection_colours before this stage"): (
            without("fixed_camera", "detection_colours"),
            "stage 'byte_tracks': colour_gate below 1 needs the detection_colours stage"),
        ("robust_search", "interp_scales >= scales when scale is on"): (
            shipped("robust", {"robust_search.interp_scales": 3}),
            "stage 'robust_search': interp_scales (3) is smaller than scales (17)"),
        ("meanshift_fixed", s0_record): (
            chain("kernel_meanshift_int", "hue", "backproject", "meanshift_fixed"),
            f"stage 'meanshift_fixed': {record}"),
        ("kalman_f32", s0_record): (
            chain("kernel_meanshift_int", "kalman_f32"), f"stage 'kalman_f32': {record}"),
        ("hue_bp_fixed", one_record): (
            chain("hue_bp_fixed", "meanshift_fixed", "kernel_meanshift_int"), both),
        ("kernel_meanshift_int", one_record): (
            chain("hue_bp_fixed", "kernel_meanshift_int", "kalman_f32"), both),
    }


def test_a_chain_lacking_a_value_is_told_which_stages_make_it() -> None:
    """`[[stage]] name = "kalman"` before S0's stages said only "stage 'kalman' needs
    measurement, which no earlier stage provides (check the order of the chain)": which stage
    makes a measurement was for the author to find. The line now names, for each value lacking,
    the stages that make it (not those that only change one they need, as occlusion does).
    hue, backproject, meanshift_fixed was told "fixed comes from hue_bp_fixed,
    kernel_meanshift_int", though meanshift_fixed refuses kernel_meanshift_int (its record is
    S2's): a maker the needing stage's own check refuses is left out."""
    with pytest.raises(ConfigError) as refused:
        parse_config({"stage": [{"name": n} for n in ("kalman", "hue", "backproject",
                                                       "meanshift")]}, "chain.toml")
    assert str(refused.value) == (
        "chain.toml: stage 'kalman' needs measurement, which no earlier stage provides (check "
        "the order of the chain: measurement comes from kernel_meanshift, kernel_meanshift_int, "
        "largest_blob, meanshift, meanshift_fixed, robust_search)")
    with pytest.raises(ConfigError, match=r"^chain.toml: stage 'byte_tracks' needs detections, "
                       r"which no earlier stage provides \(check the order of the chain: "
                       r"detections comes from blobs, mot_detections\)$"):
        parse_config({"stage": [{"name": "byte_tracks"}]}, "chain.toml")
    with pytest.raises(ConfigError, match=r"^chain.toml: stage 'byte_tracks' needs detections, "
                       r"which no earlier stage provides \(check the order of the chain: "
                       r"detections comes from blobs, mot_detections\)$"):  # (none is the gate's)
        parse_config({"stage": [{"name": "byte_tracks", "colour_gate": 0.5}]}, "chain.toml")
    with pytest.raises(ConfigError) as refused:  # (not kernel_meanshift_int: S2's record)
        parse_config({"stage": [{"name": n} for n in ("hue", "backproject", "meanshift_fixed",
                                                       "kalman_f32")]}, "chain.toml")
    assert str(refused.value) == (
        "chain.toml: stage 'meanshift_fixed' needs fixed, which no earlier stage provides "
        "(check the order of the chain: fixed comes from hue_bp_fixed)")
    # kernel_meanshift_int would keep a second record (S2's) beside hue_bp_fixed's, before it
    # or named for the lacking fixed; hue_bp_fixed itself may give two values
    measurement = ("measurement {}from kernel_meanshift, largest_blob, meanshift, "
                   "meanshift_fixed, robust_search)")
    for names, lacking in [(("hue_bp_fixed", "kalman_f32"), measurement.format("comes ")),
                           (("kalman", "hue_bp_fixed", "meanshift_fixed"),  # (after it too)
                            "measurement comes from kernel_meanshift, largest_blob, meanshift, "
                            "meanshift_fixed, robust_search)"),
                           (("kalman_f32",), "fixed comes from hue_bp_fixed; "
                                             + measurement.format(""))]:
        with pytest.raises(ConfigError) as refused:
            parse_config({"stage": [{"name": n} for n in names]}, "chain.toml")
        assert str(refused.value).endswith(f"(check the order of the chain: {lacking}"), names
    with pytest.raises(ConfigError) as refused:
        parse_config({"stage": [{"name": "meanshift_fixed"}]}, "chain.toml")
    assert "; likelihood from background, backproject, hue_bp_fixed, " in str(refused.value)
    needed = set().union(*(cls.requires for cls in all_stages().values())) - PIPELINE_PROVIDES
    assert all(any(value in cls.provides - cls.requires for cls in all_stages().values())
               for value in needed)  # (no line says a value comes "from no stage")
