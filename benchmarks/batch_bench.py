"""Batch throughput: `vtrack batch` with 1 and 2 local worker processes, and through Dask.

    python benchmarks/batch_bench.py [--clips 8] [--frames 150] [--size 640x360] [--rounds 2]

Generates (once, cached in benchmarks/_work/batch/) ``--clips`` camera-like H.264 clips with
ground truth, then times whole batches of them (S0, annotated video written, ``--force`` so
every input runs) in alternating rounds:

- the local pool with ``--jobs 1`` and ``--jobs 2`` (one worker process per job);
- a Dask ``LocalCluster`` of 2 worker processes x 1 thread on this machine, started before the
  clock (its start-up time is reported on its own).

The order of the three rotates from round to round.

Prints a Markdown table of the median wall time per batch, inputs per second, the 2-job / 1-job
speed-up and the Dask overhead against the local pool with 2 jobs. Machines here are shared and
noisy: only ratios measured in the same run mean much.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from vtrack.batch import (
    DaskExecutor,
    Executor,
    LocalExecutor,
    cpu_count,
    find_inputs,
    plan,
    run_batch,
)
from vtrack.config import load_config
from vtrack.request import RunRequest
from vtrack.run import STATUS_COMPLETE
from vtrack.scenes import make_scene, write_groundtruth, write_video

WORK = Path(__file__).resolve().parent / "_work" / "batch"


def make_clips(count: int, frames: int, width: int, height: int) -> Path:
    """A folder of ``count`` clips (``benchmark`` scenario, seeds 0..count-1) with ground truth."""
    folder = WORK / f"{count}x{width}x{height}x{frames}"
    folder.mkdir(parents=True, exist_ok=True)
    for seed in range(count):
        clip = folder / f"clip{seed}.mp4"
        if not clip.exists():
            scene = make_scene("benchmark", seed=seed, width=width, height=height,
                               frames=frames, fps=30)
            write_video(scene, clip, crf=23, preset="veryfast")
            write_groundtruth(scene, clip.with_suffix(".gt.txt"))
    return folder


def time_batch(folder: Path, executor: Executor, workers: int) -> float:
    """Seconds for one whole batch of ``folder`` (S0, with video), every input run."""
    with tempfile.TemporaryDirectory() as out:
        s0 = load_config("s0")
        settings = RunRequest(input=str(folder), out_dir=Path(out), config=s0)
        batch = plan(find_inputs(folder), {"s0": s0}, Path(out), settings,
                     threads=max(1, cpu_count() // workers), force=True)
        started = time.perf_counter()
        outcomes = list(run_batch(batch, executor, Path(out) / "summary.csv"))
        seconds = time.perf_counter() - started
    failed = [o.line() for o in outcomes if o.status != STATUS_COMPLETE]
    if failed:
        raise SystemExit("batch failed: " + "; ".join(failed))
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=8)
    parser.add_argument("--frames", type=int, default=150)
    parser.add_argument("--size", default="640x360")
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    folder = make_clips(args.clips, args.frames, width, height)

    from distributed import LocalCluster

    started = time.perf_counter()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address=None)
    startup = time.perf_counter() - started
    executors: dict[str, Callable[[], tuple[Executor, int]]] = {
        "jobs 1": lambda: (LocalExecutor(1), 1),
        "jobs 2": lambda: (LocalExecutor(2), 2),
        "dask 2x1": lambda: (DaskExecutor(cluster.scheduler_address), 2),
    }
    times: dict[str, list[float]] = {name: [] for name in executors}
    names = list(executors)
    try:
        for round_ in range(args.rounds):  # rotate the order: no executor always goes last
            for name in names[round_ % len(names):] + names[: round_ % len(names)]:
                times[name].append(time_batch(folder, *executors[name]()))
    finally:
        cluster.close()

    median = {name: statistics.median(values) for name, values in times.items()}
    print(f"\n{args.clips} clips of {args.frames} frames at {width}x{height} (H.264, "
          f"camera-like), S0 with annotated video, {cpu_count()} cores, median of "
          f"{args.rounds} rounds, load average {os.getloadavg()[0]:.1f} at the end\n")
    print("| executor | seconds per batch | inputs/s | frames/s | vs jobs 1 | vs jobs 2 |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, seconds in median.items():
        print(f"| {name} | {seconds:.2f} | {args.clips / seconds:.2f} | "
              f"{args.clips * args.frames / seconds:.0f} | "
              f"{median['jobs 1'] / seconds:.2f}x | {median['jobs 2'] / seconds:.2f}x |")
    overhead = median["dask 2x1"] / median["jobs 2"] - 1
    print(f"\nDask overhead against the local pool (2 workers): {100 * overhead:+.0f}% "
          f"per batch; LocalCluster start-up (not in the times above): {startup:.1f} s")


if __name__ == "__main__":
    main()
