"""S2's claims (Di & Zhu 2008, kernel mean shift + Kalman failure logic), measured.

    python benchmarks/claims_s2.py [SEEDS]

The document claims that its failure logic follows a displacement between frames larger than the
target (33 px with a 30x20 target) that plain mean shift loses, rides through about 13 frames of
full occlusion, and tracks in 200 us - 1 ms per frame for a 32x20 target on its DSP (table 2).

Success (mean IoU, OTB AUC) is measured for the shipped ``s2`` config, for ``s2`` with
``kernel_meanshift.failure_logic=false`` (plain kernel mean shift, the document's reference [4]
with the document's simplifications) and for the shipped ``s0`` config on:

- the generated ``jump`` and ``occlusion`` scenes (320x240, 150 frames, seeds 0 .. SEEDS-1,
  mean over seeds);
- every single-target sequence of ``../shared/data`` (or ``$VTRACK_DATA``), when present.

Cost: microseconds per frame of the ``kernel_meanshift`` and ``kalman`` stages on a 1920x1080
``smooth`` scene held as I420 (what a decoded video hands over) and as BGR, for a 32x20 and a
100x100 box centred on the target (the document times mean shift alone: its Kalman ran on a
second DSP).
"""

from __future__ import annotations

import statistics
import sys
from collections.abc import Iterator

import cv2
from claims_s1 import Clip, _load
from common import single_target_sequences

from vtrack.config import load_config
from vtrack.evaluate import summarize
from vtrack.frame import BgrFrame, Frame, I420Frame
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.scenes import make_scene

#: Generated scenes of the claims (jump: fast motion; occlusion: full occlusion).
SCENES = ("jump", "occlusion")
#: (label, config, overrides) of the compared trackers.
TRACKERS = (
    ("S2", "s2", ()),
    ("S2 without failure logic", "s2", ("kernel_meanshift.failure_logic=false",)),
    ("S0", "s0", ()),
)
#: Box sizes timed at 1080p: the document's 32x20 target and a larger one.
COST_BOXES = ((32, 20), (100, 100))


def _success(clip: Clip, config: str, overrides: tuple[str, ...]) -> tuple[float, float]:
    """(mean IoU, AUC) of one tracker on one clip, started on the first ground-truth box."""
    pipeline = Pipeline(load_config(config).with_overrides(list(overrides)).build())
    frames = (BgrFrame(i, i / 30.0, bgr) for i, bgr in enumerate(clip.frames))
    assert clip.boxes[0] is not None
    predicted = [result.box for result in pipeline.track(frames, clip.boxes[0])]
    summary = summarize(predicted, clip.boxes)
    return summary["mean_overlap"] or 0.0, summary["auc"] or 0.0


def _rows(name: str, clips: list[Clip]) -> list[dict]:
    """One row per tracker: mean IoU and AUC averaged over ``clips`` (seeds of one sequence)."""
    rows = []
    for label, config, overrides in TRACKERS:
        scores = [_success(clip, config, overrides) for clip in clips]
        rows.append({
            "sequence": name,
            "seeds": len(clips),
            "tracker": label,
            "mean_iou": statistics.mean(s[0] for s in scores),
            "auc": statistics.mean(s[1] for s in scores),
        })
    return rows


def s2_success(seeds: int = 3) -> list[dict]:
    """Success of every tracker of :data:`TRACKERS` on the generated scenes and real sequences.

    One dict per (sequence, tracker): ``sequence`` (``"jump"``, ``"occlusion"`` or the real
    sequence's folder name), ``seeds`` (generated scenes: how many seeds were averaged; real
    sequences: 1), ``tracker``, ``mean_iou`` and ``auc`` (OTB success AUC, 21 thresholds).
    """
    rows = []
    for name in SCENES:
        clips = []
        for seed in range(seeds):
            scene = make_scene(name, seed=seed, width=320, height=240, frames=150, fps=30)
            clips.append(Clip(name, list(scene.frames()), scene.boxes))
        rows += _rows(name, clips)
    for seq in single_target_sequences():
        rows += _rows(seq.name, [_load(seq.folder, seq.name, seq.groundtruth)])
    return rows


def _ping_pong(frames: list[Frame], count: int) -> Iterator[Frame]:
    """``count`` frames playing ``frames`` forwards then backwards: the motion stays continuous."""
    cycle = frames + frames[-2:0:-1]
    return (cycle[i % len(cycle)] for i in range(count))


def s2_cost(repeats: int = 300) -> list[dict]:
    """Per-frame cost of S2 at 1080p (60 rendered frames played back and forth ``repeats`` times).

    One dict per (input layout, box size): ``input`` (``"I420"`` or ``"BGR"``), ``box``
    (``"32x20"`` ...), ``kernel_meanshift_us`` and ``kalman_us`` (microseconds per frame,
    measured by the pipeline around each stage), ``iterations`` (mean mean-shift steps per
    frame, all three bandwidths and reruns included) and ``decisions`` (how many frames took
    each branch).
    """
    scene = make_scene("smooth", seed=0, width=1920, height=1080, frames=60, fps=60)
    bgr = list(scene.frames())
    layouts: dict[str, list[Frame]] = {
        "I420": [I420Frame(i, i / 60.0, cv2.cvtColor(b, cv2.COLOR_BGR2YUV_I420))
                 for i, b in enumerate(bgr)],
        "BGR": [BgrFrame(i, i / 60.0, b) for i, b in enumerate(bgr)],
    }
    target = scene.boxes[0]
    assert target is not None
    rows = []
    for layout, frames in layouts.items():
        for width, height in COST_BOXES:
            pipeline = Pipeline(load_config("s2").build())
            start = Box.from_center(target.cx, target.cy, width, height)
            results = list(pipeline.track(_ping_pong(frames, repeats), start))
            micro = pipeline.stage_microseconds_per_frame()
            decisions: dict[str, int] = {}
            for result in results:
                decision = result.extras["decision"]
                decisions[decision] = decisions.get(decision, 0) + 1
            rows.append({
                "input": layout,
                "box": f"{width}x{height}",
                "kernel_meanshift_us": micro["kernel_meanshift"],
                "kalman_us": micro["kalman"],
                "iterations": statistics.mean(r.extras["iterations"] for r in results[1:]),
                "decisions": decisions,
            })
    return rows


def s2_claims(seeds: int = 3) -> list[dict]:
    """Everything measured: :func:`s2_success` rows, then :func:`s2_cost` rows."""
    return s2_success(seeds) + s2_cost()


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    print(f"Command: `python benchmarks/claims_s2.py {seeds}`\n")
    print("| sequence | seeds | tracker | mean IoU | AUC |\n|---|---:|---|---:|---:|")
    for row in s2_success(seeds):
        print(f"| {row['sequence']} | {row['seeds']} | {row['tracker']} | "
              f"{row['mean_iou']:.3f} | {row['auc']:.3f} |")
        sys.stdout.flush()
    print("\n| 1080p input | box | kernel_meanshift us/frame | kalman us/frame | "
          "iterations/frame | decisions |\n|---|---|---:|---:|---:|---|")
    for row in s2_cost():
        decisions = ", ".join(f"{k} {v}" for k, v in sorted(row["decisions"].items()))
        print(f"| {row['input']} | {row['box']} | {row['kernel_meanshift_us']:.0f} | "
              f"{row['kalman_us']:.0f} | {row['iterations']:.1f} | {decisions} |")
    print("\nDocument (TMS320C6416, 1 GHz, table 2): 200 us - 1 ms per frame for 32x20.")


if __name__ == "__main__":
    main()
