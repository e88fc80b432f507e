"""Resident memory of ``vtrack.track`` over a long run: flat, since results keep no frame.

``vtrack.track(frames, ...)`` over N generated 640x360 BGR frames (one scene, replayed), config
robust; RSS (from /proc/self/statm) after every tenth of the run: once with the caller keeping no
result (a stream of results), once keeping every result in a list (results drop their frames:
the default), and once with ``keep_frames=True`` (at most 1000 frames) for comparison, each in
its own process.

    python benchmarks/track_memory.py [--frames 10000]

Prints a Markdown table (paste it into benchmarks/RESULTS.md).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from collections.abc import Iterator

import numpy as np


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def measure(frames: int, keep: bool, hold: bool = True) -> list[float]:
    import vtrack
    from vtrack.scenes import make_scene

    scene = make_scene("smooth", seed=1, width=640, height=360, frames=100, fps=30)
    images = list(scene.frames())

    def replay() -> Iterator[np.ndarray]:
        for i in range(frames):
            yield images[i % len(images)].copy()  # a new array per frame, as a decoder gives

    results, marks = [], []
    for n, result in enumerate(vtrack.track(replay(), "robust", scene.boxes[0],
                                            keep_frames=keep), start=1):
        if hold:
            results.append(result)
        if n % (frames // 10) == 0:
            marks.append(rss_mb())
    return marks


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10000)
    parser.add_argument("--child", choices=["drop", "keep", "none"])
    args = parser.parse_args()
    if args.child:
        marks = measure(args.frames, args.child == "keep", hold=args.child != "none")
        print(" ".join(f"{m:.0f}" for m in marks))
        return
    print("| results | RSS MB after each tenth of the run |")
    print("|---|---|")
    labels = {"none": "results not kept by the caller (a stream of results)",
              "drop": "keep_frames=False (default), every result kept in a list",
              "keep": "keep_frames=True (1000 frames at most: ~0.7 MB each)"}
    for child, frames in (("none", args.frames), ("drop", args.frames),
                          ("keep", min(args.frames, 1000))):
        out = subprocess.run([sys.executable, __file__, "--frames", str(frames),
                              "--child", child], capture_output=True, text=True, check=True)
        print(f"| {labels[child]}, {frames} frames | {out.stdout.strip()} |")


if __name__ == "__main__":
    main()
