"""S1 leaving and coming back (patent CN105869186A, [0017]-[0018], [0047]), measured.

    python benchmarks/claims_s1_return.py [SEEDS]

The patent claims S1 detects the target leaving the view and finds it again once it is back; it
gives no delay. The issue asks for ``tracking`` again within 10 frames of the target coming back.
On the generated ``leave_return`` scene (320x240, 150 frames, 30 fps; scene and tracker seeded
with the same seed, 0 .. SEEDS-1) this script measures, for the shipped ``s1`` config
(8 particles), for 8 particles with 64 while lost (``lost_particles``, not the document's) and
for 32 particles:

- *leave*: frames from the first frame the target is fully out of view to the first frame of the
  lost run that covers it (negative: lost while the target was still partly in view);
- *back*: frames from the first frame any part of the target is back in view to the first
  ``tracking`` frame, and the same from the first frame it is fully in view; a re-acquisition
  more than half a box from the truth is counted as *wrong*.

It also works out why: while lost, every particle is a box of the target's size placed
uniformly inside the frame, and the target is found again when the best particle's weight is at
least ``threshold`` x the frozen reference weight. On one frame with the target fully in view the
script scores every particle position (2 px grid) and reports the share ``p`` of positions that
pass; with N particles a frame re-acquires with probability ``1 - (1 - p)^N`` and the expected
wait is its inverse.
"""

from __future__ import annotations

import statistics
import sys

import numpy as np
from common import seeds_argument

from vtrack.config import load_config
from vtrack.frame import BgrFrame
from vtrack.geometry import Window, center_error
from vtrack.histograms import bhattacharyya_rows, hue_histogram
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.scenes import Scene, make_scene
from vtrack.stages.base import TrackState
from vtrack.stages.particle import HUE_LEVELS, hue_windows

#: (label, overrides, particles scattered while lost) of the compared settings: the patent's
#: embodiment, the same with more particles while lost, and 32 particles throughout.
VARIANTS = (
    ("8 particles", (), 8),
    ("8 particles, 64 while lost", ("particle.lost_particles=64",), 64),
    ("32 particles", ("particle.particles=32",), 32),
)
#: The delay the issue asks for, in frames.
WITHIN = 10


def _scene(seed: int) -> Scene:
    return make_scene("leave_return", seed=seed, width=320, height=240, frames=150, fps=30.0)


def _track(scene: Scene, frames: list[BgrFrame], overrides: tuple[str, ...],
           seed: int) -> list[FrameResult]:
    config = load_config("s1").with_overrides(list(overrides))
    assert scene.boxes[0] is not None
    return list(Pipeline(config.build(), seed=seed).track(frames, scene.boxes[0]))


def _fully_in_view(scene: Scene, since: int) -> int:
    """First frame from ``since`` on where the whole target box is inside the frame."""
    return next(i for i in range(since, len(scene))
                if (b := scene.boxes[i]) is not None and b.x >= 0 and b.y >= 0
                and b.x + b.w <= scene.width and b.y + b.h <= scene.height)


def leave_and_return(scene: Scene, results: list[FrameResult]) -> dict:
    """Delays of one run: ``leave`` (first lost frame of the run covering the first fully-out
    frame, minus that frame; None if not lost then), ``back`` and ``full`` (first tracking frame
    from the first frame back in view, minus that frame and minus the first frame fully in view;
    None if never) and ``wrong`` (that tracking frame is more than half a box from the truth)."""
    out, back = scene.events["leave"]
    states = [r.state for r in results]
    leave = None
    if states[out] == TrackState.LOST:
        first = out
        while first > 0 and states[first - 1] == TrackState.LOST:
            first -= 1
        leave = first - out
    found = next((i for i in range(back, len(results)) if states[i] == TrackState.TRACKING), None)
    full = _fully_in_view(scene, back)
    wrong = False
    if found is not None:
        truth, box = scene.boxes[found], results[found].box
        wrong = truth is None or box is None or center_error(box, truth) > truth.w / 2
    return {
        "leave": leave,
        "back": None if found is None else found - back,
        "full": None if found is None else found - full,
        "wrong": wrong,
        "left_in_clip": len(results) - full,
    }


class ReacquisitionTest:
    """The document's re-acquisition test on one run: does a particle box at a given position
    weigh at least ``threshold`` x the reference frozen at the loss (S1 step 8)?"""

    def __init__(self, scene: Scene, frames: list[BgrFrame], results: list[FrameResult]) -> None:
        settings = dict(load_config("s1").stages[0][1])
        self.bins, self.scene = settings["bins"], scene
        assert scene.boxes[0] is not None
        start = scene.boxes[0].window(scene.width, scene.height)
        assert start is not None
        self.size = (start.width, start.height)
        first = hue_windows(frames[0], [start])[0]
        self.target = hue_histogram(first, None, self.bins, HUE_LEVELS).astype(np.float64)
        lost = next(r for r in results if r.state == TrackState.LOST)
        reference = lost.extras["reference_weight"]
        self.cut = settings["threshold"] * reference
        self.frames = frames

    def passing(self, index: int, near_truth: bool, step: int = 2) -> np.ndarray:
        """Pass/fail of the particle positions on a ``step`` px grid of frame ``index``: all of
        them inside the frame, or only those within a box of the true position."""
        pw, ph = self.size
        xs = range(0, self.scene.width - pw + 1, step)
        ys = range(0, self.scene.height - ph + 1, step)
        truth = self.scene.boxes[index]
        if near_truth:
            assert truth is not None
            xs = range(max(0, int(truth.x) - pw), min(xs.stop, int(truth.x) + pw + 1), step)
            ys = range(max(0, int(truth.y) - ph), min(ys.stop, int(truth.y) + ph + 1), step)
        windows = [Window(x, y, x + pw, y + ph) for y in ys for x in xs]
        histograms = np.array([hue_histogram(hsv, None, self.bins, HUE_LEVELS)
                               for hsv in hue_windows(self.frames[index], windows)], np.float64)
        return bhattacharyya_rows(histograms, self.target) >= self.cut

    def first_passable(self, since: int) -> int | None:
        """First frame from ``since`` on where some particle position passes."""
        return next((i for i in range(since, len(self.scene))
                     if self.scene.boxes[i] is not None and self.passing(i, True).any()), None)


def pass_share(scene: Scene, frames: list[BgrFrame],
               results: list[FrameResult]) -> tuple[float, int | None]:
    """Share of particle positions that pass the re-acquisition test on the frame 5 frames after
    the target is fully back, and the first frame (minus the first frame back) where any does."""
    test = ReacquisitionTest(scene, frames, results)
    _, back = scene.events["leave"]
    first = test.first_passable(back)
    share = float(np.mean(test.passing(_fully_in_view(scene, back) + 5, False)))
    return share, None if first is None else first - back


def _spread(values: list[int]) -> str:
    return f"{statistics.median(values):.0f} [{min(values)}..{max(values)}]" if values else "-"


def return_rows(seeds: int = 10) -> list[dict]:
    """One dict per :data:`VARIANTS` entry: the per-seed delays, the share of seeds re-acquired
    within :data:`WITHIN` frames (of the first frame back, of fully in view), the mean pass share
    ``p``, the expected wait ``1 / (1 - (1 - p)^N)`` in frames and the per-seed first frame
    (after the first frame back) where any particle position passes."""
    scenes = [_scene(seed) for seed in range(seeds)]
    clips = [list(scene.as_frames()) for scene in scenes]  # rendered once for every variant
    rows = []
    shares: list[tuple[float, int | None]] = []
    for label, overrides, particles in VARIANTS:
        runs = [_track(scene, clip, overrides, seed)
                for seed, (scene, clip) in enumerate(zip(scenes, clips, strict=True))]
        delays = [leave_and_return(scene, run) for scene, run in zip(scenes, runs, strict=True)]
        if not shares:  # the reference weight of the shipped config's runs
            shares = [pass_share(scene, clip, run)
                      for scene, clip, run in zip(scenes, clips, runs, strict=True)]
        p = statistics.mean(share for share, _ in shares)
        per_frame = 1 - (1 - p) ** particles
        rows.append({
            "label": label,
            "particles": particles,
            "seeds": seeds,
            "delays": delays,
            "within_back": sum(d["back"] is not None and d["back"] <= WITHIN and not d["wrong"]
                               for d in delays) / seeds,
            "within_full": sum(d["full"] is not None and d["full"] <= WITHIN and not d["wrong"]
                               for d in delays) / seeds,
            "p": p,
            "passable": [first for _, first in shares if first is not None],
            "expected_wait": 1 / per_frame if per_frame > 0 else float("inf"),
        })
    return rows


def return_table(rows: list[dict]) -> list[str]:
    """Markdown table of :func:`return_rows` (delays: median [min..max] over the seeds)."""
    lines = [
        "| particles | seeds | leave: lost, frames after fully out | passable: frames after "
        "first back | back: tracking, frames after first back | after fully in view | within 10 "
        "of first back | within 10 of fully in view | never / wrong | positions passing p "
        "| expected wait, frames |",
        "|---|---:|---|---|---|---|---:|---:|---|---:|---:|",
    ]
    for row in rows:
        delays = row["delays"]
        never = sum(d["back"] is None for d in delays)
        wrong = sum(d["wrong"] for d in delays)
        lines.append(
            f"| {row['label']} | {row['seeds']} "
            f"| {_spread([d['leave'] for d in delays if d['leave'] is not None])} "
            f"| {_spread(row['passable'])} "
            f"| {_spread([d['back'] for d in delays if d['back'] is not None])} "
            f"| {_spread([d['full'] for d in delays if d['full'] is not None])} "
            f"| {row['within_back']:.0%} | {row['within_full']:.0%} | {never} / {wrong} "
            f"| {row['p']:.2%} | {row['expected_wait']:.1f} |"
        )
    return lines


def return_sentences(rows: list[dict]) -> list[str]:
    """Plain verdicts on "tracking again within 10 frames after it comes back"."""
    passable = rows[0]["passable"]
    lines = [
        f"- By the document's test no particle position can pass before "
        f"{min(passable)}-{max(passable)} frames after the target's first frame back "
        f"(median {statistics.median(passable):.0f}): its weight needs most of the target in view."
    ]
    for row in rows:
        lines.append(
            f"- {row['label']}: re-acquired within {WITHIN} frames of the target's "
            f"first frame back on {row['within_back']:.0%} of seeds, within {WITHIN} frames of it "
            f"being fully in view on {row['within_full']:.0%}; "
            f"{row['p']:.2%} of particle positions pass the re-acquisition test, so a frame of "
            f"{row['particles']} uniform particles finds it with probability "
            f"{1 / row['expected_wait']:.0%} (expected wait {row['expected_wait']:.0f} frames)."
        )
    return lines


def main() -> None:
    seeds = seeds_argument(sys.argv[1:], 10, __doc__)
    print(f"Command: `python benchmarks/claims_s1_return.py {seeds}`\n")
    rows = return_rows(seeds)
    print("\n".join(return_table(rows)))
    print()
    print("\n".join(return_sentences(rows)))


if __name__ == "__main__":
    main()
