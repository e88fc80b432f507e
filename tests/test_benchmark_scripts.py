"""The benchmark scripts answer as the commands do: ``--help`` prints their usage and runs
nothing, a bad argument is one line naming it and a non-zero exit, never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

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
