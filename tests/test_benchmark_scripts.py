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
