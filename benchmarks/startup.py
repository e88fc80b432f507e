"""Start-up time of every ``vtrack`` command against a bare import of its dependencies.

Each command runs as a whole process, the way a user starts it (``python -m vtrack ...``, with
this checkout first on ``PYTHONPATH``), alternating round by round with the baseline
``python -c "import av, numpy, cv2, click, tqdm"``; the table gives the median wall time of each
and the ratio to the baseline's median of the same run (issue 12's target: <= 1.5x).

    python benchmarks/startup.py [--rounds 9]

Prints a Markdown table (paste it into benchmarks/RESULTS.md).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

from common import process_env

BASELINE = "import av, numpy, cv2, click, tqdm"
TARGET = 1.5

COMMANDS: list[tuple[str, list[str]]] = [
    ("vtrack --version", ["--version"]),
    ("vtrack --help", ["--help"]),
    ("vtrack run --help", ["run", "--help"]),
    ("vtrack run MISSING.mp4 (error exit)", ["run", "MISSING.mp4", "--init", "1,1,5,5"]),
    ("vtrack batch --help", ["batch", "--help"]),
    ("vtrack report --help", ["report", "--help"]),
    ("vtrack stages", ["stages"]),
    ("vtrack scene --help", ["scene", "--help"]),
    ("vtrack select --help", ["select", "--help"]),
    ("vtrack frame --help", ["frame", "--help"]),
]


def _time(argv: list[str], cwd: str, env: dict[str, str]) -> float:
    started = time.perf_counter()
    subprocess.run(argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   check=False)
    return time.perf_counter() - started


def measure(rounds: int) -> tuple[list[float], dict[str, list[float]]]:
    """Wall times of the baseline and of each command, ``rounds`` alternating rounds."""
    env = process_env()
    baseline: list[float] = []
    times: dict[str, list[float]] = {name: [] for name, _ in COMMANDS}
    with tempfile.TemporaryDirectory() as cwd:
        for _ in range(rounds + 1):  # the first round warms the file cache and is dropped
            baseline.append(_time([sys.executable, "-c", BASELINE], cwd, env))
            for name, args in COMMANDS:
                times[name].append(_time([sys.executable, "-m", "vtrack", *args], cwd, env))
    return baseline[1:], {name: t[1:] for name, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=9, help="alternating rounds (median)")
    args = parser.parse_args()
    import av
    import cv2
    import numpy

    baseline, times = measure(args.rounds)
    base = statistics.median(baseline)
    print(f"Command: `python benchmarks/startup.py --rounds {args.rounds}`  ")
    print(f"Machine: {os.cpu_count()} cores, {platform.platform()}; Python "
          f"{platform.python_version()}, PyAV {av.__version__}, OpenCV {cv2.__version__}, "
          f"NumPy {numpy.__version__}  ")
    print(f"Whole processes, median of {args.rounds} rounds alternating with the baseline "
          f"(first round dropped)")
    print()
    print("| command | start-up (s, median) | ratio to bare import | target |")
    print("|---|---:|---:|---|")
    print(f"| `python -c \"{BASELINE}\"` (baseline) | {base:.3f} | 1.00x |  |")
    for name, _ in COMMANDS:
        median = statistics.median(times[name])
        ratio = median / base
        verdict = "ok" if ratio <= TARGET else "OVER"
        print(f"| `{name}` | {median:.3f} | {ratio:.2f}x | <= {TARGET}x: {verdict} |")


if __name__ == "__main__":
    main()
