"""S1's claims (patent CN105869186A), measured on generated scenes and the real sequences.

    python benchmarks/claims_s1.py [SEEDS]

The document claims that, with 8 particles, centroid correction cuts the tracking error by 54%
against the plain particle filter (output = best particle's centre), and that 8 corrected
particles are about as accurate as 32 plain ones. Each sequence is tracked by the shipped ``s1``
config with ``particles`` 8 / 8 / 32 and ``centroid_correction`` on / off / off, once per seed
(the tracker's seed; generated scenes are also drawn with that seed), and scored by the mean
centre error over the frames where the tracker claims a box (a lost frame claims none), as the
document's error is a position error. ``claimed`` is the share of frames with ground truth where
a box was claimed: a config that loses the target more often is scored on fewer frames.

Sequences: the generated ``smooth``, ``distractor`` and ``leave_return`` scenes (320x240,
150 frames) and, when ``../shared/data`` or ``$VTRACK_DATA`` exists, every single-target sequence
there (images read once with ``cv2.imread``, 1-based OTB ground truth). Also prints the stage's
cost per frame on a 1080p frame (:func:`s1_cost`).
"""

from __future__ import annotations

import statistics
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from common import single_target_sequences

from vtrack.config import load_config
from vtrack.evaluate import frame_scores, mean_center_error
from vtrack.evaluate.groundtruth import read_boxes
from vtrack.frame import BgrFrame, Frame, I420Frame
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.scenes import make_scene

#: Generated scenes the claims are measured on.
SCENES = ("smooth", "distractor", "leave_return")
#: (label, particles, centroid correction) of the compared trackers.
VARIANTS = (("8 corrected", 8, True), ("8 plain", 8, False), ("32 plain", 32, False))
#: The document's numbers.
CLAIMED_REDUCTION = 0.54
#: "About equal": 8 corrected within this factor of 32 plain's error (or better).
EQUAL_WITHIN = 1.2


@dataclass(frozen=True)
class Clip:
    """Frames (BGR arrays) and ground truth of one sequence; ``boxes[0]`` starts the tracker."""

    name: str
    frames: list[np.ndarray]
    boxes: list[Box | None]


def _track(clip: Clip, particles: int, correction: bool, seed: int) -> tuple[float, float]:
    """(mean centre error over claimed frames, share of ground-truth frames claimed)."""
    config = load_config("s1").with_overrides(
        [f"particle.particles={particles}",
         f"particle.centroid_correction={str(correction).lower()}"]
    )
    pipeline = Pipeline(config.build(), seed=seed)
    frames = (BgrFrame(i, i / 30.0, bgr) for i, bgr in enumerate(clip.frames))
    assert clip.boxes[0] is not None
    predicted = [result.box for result in pipeline.track(frames, clip.boxes[0])]
    _, errors = frame_scores(predicted, clip.boxes)
    scored = [e for e in errors if e is not None]
    claimed = sum(1 for e in scored if np.isfinite(e)) / max(len(scored), 1)
    return mean_center_error(errors), claimed


def _clips(seed: int) -> list[Clip]:
    """The generated scenes drawn with ``seed``."""
    clips = []
    for name in SCENES:
        scene = make_scene(name, seed=seed, width=320, height=240, frames=150, fps=30)
        clips.append(Clip(name, list(scene.frames()), scene.boxes))
    return clips


def _load(folder: Path, name: str, groundtruth: Path) -> Clip:
    """A real sequence: its ``img/`` frames read with ``cv2.imread``, 1-based ground truth."""
    paths = sorted(p for p in (folder / "img").iterdir() if p.suffix in (".jpg", ".png"))
    frames = [cv2.imread(str(p), cv2.IMREAD_COLOR) for p in paths]
    return Clip(name, frames, read_boxes(groundtruth, origin=1)[: len(frames)])


def _row(name: str, runs: dict[str, list[tuple[float, float]]]) -> dict:
    """One table row from per-variant, per-seed (error, claimed) pairs."""
    row: dict = {"sequence": name, "seeds": len(runs[VARIANTS[0][0]])}
    for label, _, _ in VARIANTS:
        errors = [e for e, _ in runs[label]]
        row[label] = (statistics.mean(errors), statistics.stdev(errors) if len(errors) > 1 else 0.0)
        row[f"claimed {label}"] = statistics.mean(c for _, c in runs[label])
    corrected, plain, many = (
        [e for e, _ in runs[label]] for label, _, _ in VARIANTS
    )
    reductions = [1.0 - c / p for c, p in zip(corrected, plain, strict=True)]
    row["reduction"] = (statistics.mean(reductions),
                        statistics.stdev(reductions) if len(reductions) > 1 else 0.0)
    row["8c / 32p"] = statistics.mean(corrected) / statistics.mean(many)
    return row


def s1_claims(seeds: int = 10) -> list[dict]:
    """Measure both claims on every sequence over ``seeds`` seeds.

    Returns one dict per sequence: ``sequence``, ``seeds``; per variant label (``"8 corrected"``,
    ``"8 plain"``, ``"32 plain"``) the (mean, standard deviation over seeds) centre error in px
    and ``"claimed <label>"`` the mean share of frames claimed; ``reduction`` the (mean, sd)
    over seeds of ``1 - error(8 corrected) / error(8 plain)`` (claimed: 0.54); ``"8c / 32p"``
    the ratio of the mean errors of 8 corrected and 32 plain particles (claimed: about 1).
    """
    runs: dict[str, dict[str, list[tuple[float, float]]]] = {}

    def measure(clip: Clip, seed: int) -> None:
        per = runs.setdefault(clip.name, {label: [] for label, _, _ in VARIANTS})
        for label, particles, correction in VARIANTS:
            per[label].append(_track(clip, particles, correction, seed))

    for seed in range(seeds):
        for clip in _clips(seed):
            measure(clip, seed)
    for seq in single_target_sequences():
        clip = _load(seq.folder, seq.name, seq.groundtruth)
        for seed in range(seeds):
            measure(clip, seed)
    return [_row(name, per) for name, per in runs.items()]


def s1_cost(repeats: int = 300) -> dict[str, float]:
    """Microseconds per frame of the ``particle`` stage on a 1920x1080 ``smooth`` scene held as
    I420 (what a decoded video hands over), for 8 and 32 particles, tracked and while lost."""
    scene = make_scene("smooth", seed=0, width=1920, height=1080, frames=60, fps=60)
    frames: list[Frame] = [
        I420Frame(i, i / 60.0, cv2.cvtColor(bgr, cv2.COLOR_BGR2YUV_I420))
        for i, bgr in enumerate(scene.frames())
    ]
    assert scene.boxes[0] is not None
    cost = {}
    for particles in (8, 32):
        for state in ("tracking", "lost"):
            # threshold 0 never loses the target; threshold 1 loses it on the first dip
            threshold = 0.0 if state == "tracking" else 1.0
            config = load_config("s1").with_overrides(
                [f"particle.particles={particles}", f"particle.threshold={threshold}"]
            )
            pipeline = Pipeline(config.build(), seed=0)
            clip = (frames[i % len(frames)] for i in range(repeats))
            states = [r.state for r in pipeline.track(clip, scene.boxes[0])]
            assert states.count(state) > 0.9 * repeats, (state, states.count(state))
            cost[f"{particles} particles, {state}"] = pipeline.stage_microseconds_per_frame()[
                "particle"
            ]
    return cost


def _verdict(row: dict) -> str:
    reduction, spread = row["reduction"]
    if reduction <= 0:
        first = f"claim 1 fails ({reduction:+.0%})"
    elif reduction + spread >= CLAIMED_REDUCTION:
        first = f"claim 1 holds ({reduction:.0%} +- {spread:.0%} vs 54%)"
    else:
        first = f"claim 1 weaker ({reduction:.0%} +- {spread:.0%} vs 54%)"
    ratio = row["8c / 32p"]
    second = (f"claim 2 holds (8c = {ratio:.2f} x 32p)" if ratio <= EQUAL_WITHIN
              else f"claim 2 fails (8c = {ratio:.2f} x 32p)")
    return f"{first}; {second}"


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    print(f"Command: `python benchmarks/claims_s1.py {seeds}`\n")
    rows = s1_claims(seeds)
    labels = [label for label, _, _ in VARIANTS]
    print("| sequence | " + " | ".join(f"{label} err px (claimed)" for label in labels)
          + " | correction: error change | 8c / 32p | verdict |")
    print("|---|" + "---:|" * (len(labels) + 2) + "---|")
    for row in rows:
        cells = [f"{row[label][0]:.1f} +- {row[label][1]:.1f} ({row[f'claimed {label}']:.0%})"
                 for label in labels]
        reduction, spread = row["reduction"]
        print(f"| {row['sequence']} | " + " | ".join(cells)
              + f" | {-reduction:+.0%} +- {spread:.0%} | {row['8c / 32p']:.2f} | "
              + _verdict(row) + " |")
    holds_1 = sum(r["reduction"][0] + r["reduction"][1] >= CLAIMED_REDUCTION for r in rows)
    holds_2 = sum(r["8c / 32p"] <= EQUAL_WITHIN for r in rows)
    print(f"\nclaim 1 (-54% with correction) holds on {holds_1}/{len(rows)} sequences; "
          f"claim 2 (8 corrected ~ 32 plain, within x{EQUAL_WITHIN}) on {holds_2}/{len(rows)}.")
    print("\n| particle stage, 1080p I420 | us per frame |\n|---|---:|")
    for key, value in s1_cost().items():
        print(f"| {key} | {value:.0f} |")


if __name__ == "__main__":
    main()
