"""S2's claims (Di & Zhu 2008, kernel mean shift + Kalman failure logic), measured.

    python benchmarks/claims_s2.py [SEEDS]

The document claims that its failure logic follows a displacement between frames larger than the
target (33 px with a 30x20 target) that plain mean shift loses, rides through about 13 frames of
full occlusion, and tracks in 200 us - 1 ms per frame for a 32x20 target on its DSP (table 2).

Success (mean IoU, OTB AUC) is measured for the shipped ``s2`` config, for ``s2`` with
``kernel_meanshift.failure_logic=false`` (plain kernel mean shift, the document's reference [4]
with the document's simplifications) and for the shipped ``s0`` config on:

- the generated scenes (seeds 0 .. SEEDS-1, mean over seeds): ``accelerate`` (the document's
  32x20 target speeding up from rest until it moves more than its width per frame: the fast
  motion the document's predictor anticipates; 640x240, 25 frames), ``jump`` (2.5 target widths
  in one frame out of a slow wobble, which no predictor anticipates), ``cover`` (constant
  velocity, hidden at once for 18 frames: the document's full occlusion) and ``occlusion``
  (constant velocity behind a slab: partial occlusion before and after >= 18 hidden frames);
  320x240, 150 frames but ``accelerate``;
- every single-target sequence of ``../shared/data`` (or ``$VTRACK_DATA``), when present.

Cost: microseconds per frame of the ``kernel_meanshift`` and ``kalman`` stages on 300 frames of
1080p60 camera-like footage with a 32x20 (the document's) or a 100x100 target, held as I420 (what
a decoded video hands over) and as BGR (the document times mean shift alone: its Kalman ran on a
second DSP).
"""

from __future__ import annotations

import math
import statistics
import sys
from collections import Counter
from collections.abc import Iterator

import common
import numpy as np
from common import Clip, load_clip, scene_clip, single_target_sequences, to_frame, track_clip

from vtrack.config import load_config
from vtrack.errors import VtrackError
from vtrack.evaluate import summarize
from vtrack.frame import Frame
from vtrack.pipeline import Pipeline
from vtrack.scenes import Scene
from vtrack.scenes.render import (
    PAPER,
    Compositor,
    Ellipse,
    SensorNoise,
    StaticBackground,
    make_background,
    target_paint,
)
from vtrack.scenes.scene import SceneSpec, assemble

#: Generated scenes of the claims: fast motion (accelerate, jump), full occlusion (cover,
#: occlusion).
SCENES = ("accelerate", "jump", "cover", "occlusion")
#: (label, config, overrides) of the compared trackers.
TRACKERS = (
    ("S2", "s2", ()),
    ("S2 without failure logic", "s2", ("kernel_meanshift.failure_logic=false",)),
    ("S2 with T = 1 frame", "s2", ("kalman.timebase=frame",)),
    ("S2 with D = 20 px", "s2", ("kernel_meanshift.distance_unit=px",
                                 "kernel_meanshift.distance=20")),
    ("S0", "s0", ()),
)
#: Box sizes timed at 1080p: the document's 32x20 target and a larger one.
COST_BOXES = ((32, 20), (100, 100))


def _success(clip: Clip, config: str, overrides: tuple[str, ...]) -> tuple[float, float, str]:
    """(mean IoU, AUC, "") of one tracker on one clip, started on the first ground-truth box;
    (0, 0, the message) when the tracker refuses the clip (a hue tracker on grey footage)."""
    try:
        predicted = track_clip(clip, load_config(config).with_overrides(list(overrides)))
    except VtrackError as exc:
        return 0.0, 0.0, str(exc)
    summary = summarize(predicted, clip.boxes)
    return summary["mean_overlap"] or 0.0, summary["auc"] or 0.0, ""


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
            "error": next((s[2] for s in scores if s[2]), ""),
        })
    return rows


def s2_success(seeds: int = 3) -> list[dict]:
    """Success of every tracker of :data:`TRACKERS` on the generated scenes and real sequences.

    One dict per (sequence, tracker): ``sequence`` (a name of :data:`SCENES` or the real
    sequence's folder name), ``seeds`` (generated scenes: how many seeds were averaged; real
    sequences: 1), ``tracker``, ``mean_iou`` and ``auc`` (OTB success AUC, 21 thresholds),
    ``error`` (why the tracker refused a clip, which then scores 0; "" when it ran on all).
    """
    rows = []
    for name in SCENES:
        rows += _rows(name, [scene_clip(name, seed) for seed in range(seeds)])
    for seq in single_target_sequences():
        rows += _rows(seq.name, [load_clip(seq)])
    return rows


def _timing_scene(width: int, height: int, frames: int) -> Scene:
    """1920x1080 60 fps footage on the generated scenes' default background (where S2 tracks) with
    a ``width`` x ``height`` textured target going round a 400 x 300 px ellipse at ~2.5 px/frame."""
    spec = SceneSpec("s2_cost", 0, 1920, 1080, frames, 60.0)
    looks = spec.rng(1)
    angle = 2 * math.pi * np.arange(frames) / 900
    cx, cy = 960 + 400 * np.cos(angle), 540 + 300 * np.sin(angle)
    background = StaticBackground(make_background(looks, spec.height, spec.width, PAPER))
    target = Ellipse(cx, cy, np.full(frames, width / 2), np.full(frames, height / 2),
                     target_paint(looks), track_id=1)
    return assemble(spec, Compositor(background, [target], SensorNoise(3.5), spec.seed))


def _frames(scene: Scene, layout: str) -> Iterator[Frame]:
    """The scene's frames, rendered one at a time, as ``layout`` (I420 or BGR) frames."""
    for i, bgr in enumerate(scene.frames()):
        yield to_frame(i, scene.fps, bgr, layout)


def s2_cost(frames: int = 300) -> list[dict]:
    """Per-frame cost of S2 on ``frames`` frames of 1080p60 footage (:func:`_timing_scene`).

    One dict per (input layout, target size): ``input`` (``"I420"`` or ``"BGR"``), ``box``
    (``"32x20"`` ...), ``kernel_meanshift_us`` and ``kalman_us`` (microseconds per frame,
    measured by the pipeline around each stage; frames are rendered and converted outside the
    timed calls), ``iterations`` (mean mean-shift steps per frame, the three bandwidths and any
    rerun included), ``decisions`` (frames per branch) and ``mean_iou`` (to tell a cost measured
    while tracking from one measured while lost).
    """
    rows = []
    for width, height in COST_BOXES:
        scene = _timing_scene(width, height, frames)
        assert scene.boxes[0] is not None
        for layout in ("I420", "BGR"):
            pipeline = Pipeline(load_config("s2").build())
            results = list(pipeline.track(_frames(scene, layout), scene.boxes[0]))
            micro = pipeline.stage_microseconds_per_frame()
            summary = summarize([r.box for r in results], scene.boxes)
            rows.append({
                "input": layout,
                "box": f"{width}x{height}",
                "kernel_meanshift_us": micro["kernel_meanshift"],
                "kalman_us": micro["kalman"],
                "iterations": statistics.mean(r.extras["iterations"] for r in results[1:]),
                "decisions": dict(Counter(r.extras["decision"] for r in results)),
                "mean_iou": summary["mean_overlap"] or 0.0,
            })
    return rows


def s2_claims(seeds: int = 3) -> list[dict]:
    """Everything measured: :func:`s2_success` rows, then :func:`s2_cost` rows."""
    return s2_success(seeds) + s2_cost()


def success_table(rows: list[dict]) -> list[str]:
    """The Markdown table of :func:`s2_success` rows: a line per sequence, "mean IoU / AUC" per
    tracker ("fail" where the tracker refused the clip, scored 0), then the mean AUC over the
    real sequences."""
    labels = [label for label, _, _ in TRACKERS]
    lines = ["Cells: mean IoU / AUC (OTB success, 21 thresholds).", "",
             "| sequence | seeds | " + " | ".join(labels) + " |",
             "|---|---:|" + "---:|" * len(labels)]
    sequences = list(dict.fromkeys(row["sequence"] for row in rows))
    for sequence in sequences:
        cells = {row["tracker"]: row for row in rows if row["sequence"] == sequence}
        lines.append(f"| {sequence} | {cells[labels[0]]['seeds']} | " + " | ".join(
            "fail" if cells[label]["error"] else
            f"{cells[label]['mean_iou']:.3f} / {cells[label]['auc']:.3f}" for label in labels)
            + " |")
    real = [s for s in sequences if s not in SCENES]
    if real:
        means = [statistics.mean(r["auc"] for r in rows
                                 if r["tracker"] == label and r["sequence"] in real)
                 for label in labels]
        lines.append(f"| **mean AUC, {len(real)} real** | | "
                     + " | ".join(f"**{m:.3f}**" for m in means) + " |")
    return lines


def cost_table(rows: list[dict]) -> list[str]:
    """The Markdown table of :func:`s2_cost` rows."""
    lines = ["| 1080p input | target | kernel_meanshift us/frame | kalman us/frame | "
             "iterations/frame | decisions | mean IoU |", "|---|---|---:|---:|---:|---|---:|"]
    for row in rows:
        decisions = ", ".join(f"{k} {v}" for k, v in sorted(row["decisions"].items()))
        lines.append(f"| {row['input']} | {row['box']} | {row['kernel_meanshift_us']:.0f} | "
                     f"{row['kalman_us']:.0f} | {row['iterations']:.1f} | {decisions} | "
                     f"{row['mean_iou']:.3f} |")
    return lines


#: What the document reports for its cost (the claim :func:`s2_cost` is compared with).
DOCUMENT_COST = "Document (TMS320C6416, 1 GHz, table 2): 200 us - 1 ms per frame for 32x20."


def main() -> None:
    seeds = common.seeds_argument(sys.argv[1:], 3, __doc__)
    print(f"Command: `python benchmarks/claims_s2.py {seeds}`\n")
    print("\n".join(success_table(s2_success(seeds))))
    print()
    print("\n".join(cost_table(s2_cost())))
    print(f"\n{DOCUMENT_COST}")


if __name__ == "__main__":
    main()
