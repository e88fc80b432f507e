"""The benchmark scripts answer as the commands do: ``--help`` prints their usage and runs
nothing, a bad argument is one line naming it and a non-zero exit, never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from collections.abc import Callable

    from conftest import ClipFactory

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
SCRIPTS = sorted(path.name for path in BENCHMARKS.glob("*.py") if path.name != "common.py")
#: Scripts run as ``script [SEEDS] ...``.
SEEDS_SCRIPTS = ("claims_s1.py", "claims_s1_return.py", "claims_s2.py", "multi_bench.py")
#: A hang guard only (a script that ignored --help would run its whole benchmark), not a timing.
GUARD_S = 300


def run_script(name: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(BENCHMARKS / name), *args], capture_output=True,
                          text=True, timeout=GUARD_S, cwd=BENCHMARKS.parent)


@pytest.mark.parametrize("name", SCRIPTS)
def test_help_prints_the_usage_and_runs_nothing(name: str) -> None:
    done = run_script(name, "--help")
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    assert name in done.stdout or "python benchmarks/" in done.stdout, done.stdout[:300]
    assert "| " not in done.stdout  # no result table: nothing was measured


@pytest.mark.parametrize("name", SEEDS_SCRIPTS)
@pytest.mark.parametrize("seeds", ["many", "0", "-3"])
def test_a_bad_seeds_argument_is_one_line(name: str, seeds: str) -> None:
    done = run_script(name, seeds)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "SEEDS" in lines[0] and repr(seeds) in lines[0], done.stderr


def test_multi_bench_names_its_sections_for_an_unknown_one() -> None:
    done = run_script("multi_bench.py", "1", "everything")
    assert done.returncode != 0
    assert done.stderr.strip().splitlines() == [
        "multi_bench.py: no section 'everything'; the sections: generated, tud, variants, "
        "outside, sizes, people, vehicles, cost, processes"]


def test_robust_tune_hard_leaves_out_a_seed_whose_target_starts_too_small() -> None:
    """At 64x48, seed 812 draws slab's target under the 4x4 pixels a tracker starts from:
    that seed is left out (a '-' cell, a line on stderr saying why), the table goes on."""
    done = run_script("robust_tune.py", "--hard", "--size", "64x48", "--frames", "60",
                      "--first-seed", "811", "--seeds", "2")
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    rows = {line.split(" | ")[0]: line for line in done.stdout.splitlines()
            if line.startswith("| ") and " seeds " not in line}
    assert set(rows) == {f"| {name}" for name in ("slab", "exit_return", "clip_ramp", "fast",
                                                  "grow", "shrink", "crossing", "grey")}
    slab = rows["| slab"].split(" | ")
    assert slab[1].split()[1] == "-" and float(slab[1].split()[0]) >= 0, rows["| slab"]
    assert "slab seed 812: left out:" in done.stderr and "4x4" in done.stderr, done.stderr


@pytest.mark.parametrize("size", ["big", "10x10", "\u00b3x2"])
def test_robust_tune_hard_refuses_a_bad_size_in_one_line(size: str) -> None:
    done = run_script("robust_tune.py", "--hard", "--size", size, "--seeds", "1")
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "size" in lines[0] and size in lines[0], done.stderr


@pytest.mark.parametrize("args", [("--hard", "--frames", "30"), ("--hard", "--size", "10x10"),
                                  ("--beyond", "--frames", "1"), ("--looks", "--frames", "1"),
                                  ("--drift", "--frames", "5")])
def test_robust_tune_refuses_scenes_it_cannot_make_before_any_table(args: tuple[str, ...]
                                                                     ) -> None:
    """`--hard --frames 30` (slab needs 60) printed the table's header, then the error;
    `--beyond --frames 1`, `--looks --frames 1` and `--drift --frames 5` ended in a traceback.
    Each is one line naming the setting and a non-zero exit, with nothing on stdout."""
    done = run_script("robust_tune.py", *args, "--seeds", "1")
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("robust_tune.py: scene "), done.stderr
    assert args[2] in lines[0], done.stderr
    assert done.stdout == ""


@pytest.mark.parametrize("option, value", [("--seeds", "0"), ("--first-seed", "-1"),
                                           ("--frames", "0")])
def test_robust_tune_refuses_a_seed_count_or_first_seed_out_of_range(option: str,
                                                                     value: str) -> None:
    """`--hard --seeds 0` ended in KeyError 'slab' (no seed, no row); `--first-seed -1` in a
    traceback from the scene generator: argparse's usage error naming the option now."""
    done = run_script("robust_tune.py", "--hard", option, value)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1] == (
        f"robust_tune.py: error: argument {option}: '{value}': give "
        f"{1 if option != '--first-seed' else 0} or more"), done.stderr
    assert done.stdout == ""


@pytest.mark.parametrize("mode", [(), ("--starts", "5"), ("--hard",), ("--beyond",),
                                  ("--looks",), ("--drift",), ("--variants",), ("--speed",),
                                  ("--ablate",)], ids=lambda mode: " ".join(mode) or "table")
def test_robust_tune_refuses_a_bad_set_before_any_table(mode: tuple[str, ...]) -> None:
    """A --set robust refuses was taken up only as each mode got to it: `--hard` and
    `--beyond` printed the header first, `--variants` and `--speed` ended in a traceback, the
    default table and `--starts` printed rows of 0.000 and exited 0, `--ablate` exited with the
    message alone. Every mode now refuses it in one line before anything runs."""
    done = run_script("robust_tune.py", *mode, "--set", "nope.x=1", "--seeds", "1")
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines() == [
        "robust_tune.py: --set nope.x=1: stage 'nope' is not in the chain (robust_model -> "
        "robust_search -> robust_failure -> robust_motion)"], done.stderr
    assert done.stdout == ""


@pytest.mark.parametrize(("args", "error"), [
    (("--scenes", "--set", "robust_failure.lost_after=30"),
     "--set: --scenes scores the shipped robust and s0 as they are"),
    (("--looks", "--size", "480x360"),
     "--size: only --hard takes a size (the other modes' scenes are 320x240)"),
    (("--jobs", "65"), "argument --jobs: '65': give 1 to 64")])
def test_robust_tune_refuses_what_a_mode_would_pass_over(args: tuple[str, ...],
                                                         error: str) -> None:
    """`--scenes --set ...` scored the shipped configs without a word of the --set, and
    `--looks --size 480x360` its scenes at 320x240: both are refused now, as argparse refuses
    a --jobs out of range."""
    done = run_script("robust_tune.py", *args)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines()[-1] == f"robust_tune.py: error: {error}"
    assert done.stdout == ""


def test_robust_tune_looks_leaves_out_a_seed_whose_scene_cannot_be_made() -> None:
    """`--looks --frames 60 --first-seed 1 --seeds 5` printed the header and two rows, then
    ended with "60 frames are too few for its occlusion" (seed 4's slab of a size beyond its
    declared range): only the first seed was made before the table. That seed is now left out
    of its row (a '-' cell, the reason on stderr) and the table goes on, as a seed robust
    refuses to start on is."""
    done = run_script("robust_tune.py", "--looks", "--frames", "60", "--first-seed", "3",
                      "--seeds", "2")
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    rows = [line.split(" | ") for line in done.stdout.splitlines()
            if line.startswith("| slab | ")]
    assert len(rows) == 8, done.stdout  # every look of robust_tune's LOOKS
    cells = {row[1]: row[2].split() for row in rows}
    assert cells["size: 0.6-1 -> 1-1.6"][1] == "-", done.stdout
    assert float(cells["size: 0.6-1 -> 1-1.6"][0]) >= 0, done.stdout
    assert all(cell != "-" for name, row in cells.items() if not name.startswith("size")
               for cell in row), done.stdout
    assert done.stderr.splitlines() == [
        "slab seed 4: left out: scenario 'slab' at 320x240: 60 frames are too few for its "
        "occlusion"], done.stderr


#: The video of the sequence the outside_footage tests make the clone fail to give.
TUD_VIDEO = "benchmarks/MOT15/TUD-Stadtmitte/TUD-Stadtmitte.mp4"


def _outside_footage_without(tmp_path: Path, clip_factory: ClipFactory,
                             lose: Callable[[Path, list[str]], None]) -> None:
    """Run outside_footage.py on a real git clone laid out as MASA-OA's TUD-Stadtmitte and
    KITTI-17 (committed), after ``lose(clone, git)`` made it unable to give TUD_VIDEO:
    TUD-Stadtmitte is a line naming the file and nothing of it is written, KITTI-17 is laid
    out."""
    clips = {name: clip_factory("multi", seed=seed, width=160, height=120, frames=60)
             for seed, name in enumerate(("TUD-Stadtmitte", "KITTI-17"))}
    clone = tmp_path / "MASA-OA"
    for name, clip in clips.items():
        folder = clone / "benchmarks" / "MOT15" / name
        (folder / "gt").mkdir(parents=True)
        (folder / "gt" / "gt.txt").write_bytes(clip.mot.read_bytes())
        (folder / "seqinfo.ini").write_text(f"[Sequence]\nname={name}\nframeRate=30\n")
        (folder / f"{name}.mp4").write_bytes(clip.path.read_bytes())
    git = ["git", "-C", str(clone), "-c", "user.name=t", "-c", "user.email=t@t"]
    for args in (["init", "-q"], ["add", "."], ["commit", "-q", "-m", "sequences"]):
        subprocess.run([*git, *args], check=True, capture_output=True)
    lose(clone, git)
    out = tmp_path / "out"
    done = run_script("outside_footage.py", str(out), "--clone",
                      f"gonzalocarreteroh/MASA-OA={clone}")
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert (f"TUD-Stadtmitte: skipped ({TUD_VIDEO} is not in the clone of "
            "gonzalocarreteroh/MASA-OA" in done.stdout), done.stdout
    assert not (out / "mot" / "TUD-Stadtmitte").exists()
    assert "KITTI-17: video" in done.stdout
    kitti = clips["KITTI-17"]
    assert (out / "mot/KITTI-17/KITTI-17.mp4").read_bytes() == kitti.path.read_bytes()
    assert (out / "mot/KITTI-17/gt/gt.txt").read_text() == kitti.mot.read_text()


def test_outside_footage_skips_a_sequence_whose_file_the_clone_lacks(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """A clone made without its large files lists them but cannot give them: the sequence
    that needs one is a line naming the file, nothing of it is written, the others are laid
    out."""
    def unlink_the_blob(clone: Path, git: list[str]) -> None:
        blob = subprocess.run([*git, "rev-parse", f"HEAD:{TUD_VIDEO}"], check=True,
                              capture_output=True, text=True).stdout.strip()
        (clone / ".git" / "objects" / blob[:2] / blob[2:]).unlink()  # listed, not held

    _outside_footage_without(tmp_path, clip_factory, unlink_the_blob)


def test_outside_footage_skips_a_sequence_whose_file_is_a_git_lfs_pointer(
        tmp_path: Path, clip_factory: ClipFactory) -> None:
    """A clone whose Git LFS content was never fetched holds each such file as its pointer
    (~130 bytes of text), which git reports as present: the script wrote the pointer as the
    sequence's MP4. Such a file is now missing as an unheld one is."""
    def commit_a_pointer(clone: Path, git: list[str]) -> None:
        video = clone / TUD_VIDEO
        size = video.stat().st_size
        video.write_text("version https://git-lfs.github.com/spec/v1\n"
                         f"oid sha256:{'4d7a' * 16}\nsize {size}\n")
        subprocess.run([*git, "commit", "-q", "-a", "-m", "the video as an LFS pointer"],
                       check=True, capture_output=True)

    _outside_footage_without(tmp_path, clip_factory, commit_a_pointer)
