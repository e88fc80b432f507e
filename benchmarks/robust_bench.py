"""Issue 14's measurements: vtrack's configs against OpenCV's trackers, same frames, same scorer.

    python benchmarks/robust_bench.py [--contrib-python PATH] [--seeds 3] [--hd-frames 60]
                                      [--no-sequences] [--no-scenes]

KCF and CSRT live in ``opencv-contrib-python-headless``, which is never a dependency of vtrack.
Create a separate venv for them and give its python (or set ``VTRACK_CONTRIB_PYTHON``)::

    python -m venv ~/venv-contrib
    ~/venv-contrib/bin/pip install opencv-contrib-python-headless numpy
    python benchmarks/robust_bench.py --contrib-python ~/venv-contrib/bin/python

Without it, MIL and the meanShift tutorial run in this Python and KCF/CSRT are marked n/a.

Prints Markdown:

1. Per single-target sequence of ``../shared/data`` (or ``$VTRACK_DATA``; skipped when absent):
   AUC (OTB success, 21 thresholds), precision at 20 px, mean IoU, the share of frames called
   ``tracking`` whose box misses the target (IoU 0), the share of missed frames (IoU 0 or no
   box) called ``occluded``/``lost`` (:mod:`vtrack.evaluate.metrics`), and tracking fps, for
   ``robust``, ``s0``, ``s1``, ``s2``, ``s4``, ``camshift`` and OpenCV's
   meanShift tutorial, MIL, KCF and CSRT. Then the means over the sequences, and each tracker's
   tracking fps as a multiple of CSRT's on the same frames (median over sequences).
2. Scenes: mean IoU per randomised scene of :mod:`vtrack.scenes.hard` over ``--seeds`` seeds
   (320x240, 150 frames) for every tracker.
3. Tracking cost at 1080p: the ``benchmark`` scene (1920x1080, ``--hd-frames`` frames) per
   tracker.

Every tracker gets the same decoded frames and the first ground-truth box. vtrack's configs run
in-process on the frames ``vtrack run`` would read (same reader), timed around the pipeline only
(decoding excluded); OpenCV's trackers run in a subprocess (``opencv_trackers.py``) timed around
init + update only. OpenCV trackers have no ``occluded``: a frame whose update fails is ``lost``
(no box), every other frame ``tracking``. ``s3`` is not in the table: it is a multi-target
tracker whose output is a set of tracks, not one box. ``s4`` needs no ``--init`` and ignores it:
it follows the largest moving blob it detects (background subtraction), target or not.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
from common import Sequence, machine, single_target_sequences

from vtrack.config import load_config
from vtrack.errors import VtrackError
from vtrack.evaluate import metrics
from vtrack.evaluate.groundtruth import read_boxes
from vtrack.frame import BgrFrame, Frame
from vtrack.geometry import Box
from vtrack.io.inputs import open_source
from vtrack.pipeline import Pipeline
from vtrack.scenes import make_scene
from vtrack.scenes.hard import HARD_SCENARIOS

HERE = Path(__file__).resolve().parent
#: vtrack configs compared.
CONFIGS = ("robust", "s0", "s1", "s2", "s4", "camshift")
#: OpenCV trackers run by ``opencv_trackers.py``; the first two need no contrib.
OPENCV = ("meanshift", "MIL", "KCF", "CSRT")
NEEDS_CONTRIB = ("KCF", "CSRT")
COLUMNS = ("AUC", "P@20", "mIoU", "tracking miss", "miss flagged", "fps")


@dataclass
class Outcome:
    """One tracker on one clip: per-frame boxes and states, tracking seconds (None: n/a)."""

    boxes: list[Box | None] | None
    states: list[str] | None
    seconds: float | None
    note: str = ""
    failed: bool = False  # the tracker refused or broke (counts 0), rather than n/a

    def scores(self, gt: list[Box | None]) -> tuple[float, ...]:
        """(AUC, P@20, mean IoU, tracking miss, miss flagged, fps); NaN where not computable."""
        if self.boxes is None or self.states is None or self.seconds is None:
            return (math.nan,) * len(COLUMNS)
        overlaps, errors = metrics.frame_scores(self.boxes, gt)
        return (metrics.auc(overlaps), metrics.precision_at(errors),
                metrics.mean_overlap(overlaps),
                metrics.tracking_miss_rate(self.states, overlaps),
                metrics.flagged_miss_rate(self.states, overlaps),
                len(self.boxes) / self.seconds if self.seconds > 0 else math.nan)


def run_vtrack(config: str, frames: list[Frame], init: Box) -> Outcome:
    """``config`` over in-memory ``frames`` as ``vtrack run`` tracks them (seed 0)."""
    pipeline = Pipeline(load_config(config).build(), seed=0)
    boxes: list[Box | None] = []
    states: list[str] = []
    started = time.perf_counter()
    try:
        for result in pipeline.track(iter(frames), init):
            boxes.append(result.box)
            states.append(result.state)
    except VtrackError as exc:  # e.g. a refusal: scores as lost from there on
        return Outcome(None, None, None, f"{config}: {exc}", failed=True)
    return Outcome(boxes, states, time.perf_counter() - started)


def run_opencv(python: str | None, folder: Path, init: Box, n: int) -> dict[str, Outcome]:
    """OpenCV's trackers on the image ``folder`` in a subprocess (``python`` or this one)."""
    names = list(OPENCV) if python else [t for t in OPENCV if t not in NEEDS_CONTRIB]
    command = [python or sys.executable, str(HERE / "opencv_trackers.py"), str(folder),
               ",".join(f"{v:.2f}" for v in init), *names]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    outcomes = {t: Outcome(None, None, None, "n/a: give --contrib-python") for t in OPENCV}
    for line in done.stdout.splitlines():
        record = json.loads(line)
        if "error" in record:
            outcomes[record["tracker"]] = Outcome(None, None, None, record["error"])
            continue
        boxes = [Box(*b) if b is not None else None for b in record["boxes"]][:n]
        states = ["tracking" if ok else "lost" for ok in record["ok"]][:n]
        outcomes[record["tracker"]] = Outcome(boxes, states, record["seconds"])
    return outcomes


def track_all(frames: list[Frame], folder: Path, init: Box, python: str | None,
              configs: list[str]) -> dict[str, Outcome]:
    """Every tracker on one clip (``frames`` in memory, the same frames as files in ``folder``)."""
    results = {c: run_vtrack(c, frames, init) for c in configs}
    results.update(run_opencv(python, folder, init, len(frames)))
    return results


def _cell(value: float, digits: int = 3) -> str:
    return "n/a" if math.isnan(value) else f"{value:.{digits}f}"


def _row(label: str, values: tuple[float, ...]) -> str:
    cells = [_cell(v) for v in values[:-1]] + [_cell(values[-1], 0)]
    return f"| {label} | " + " | ".join(cells) + " |"


def _header(first: str) -> list[str]:
    return [f"| {first} | " + " | ".join(COLUMNS) + " |", "|---|" + "---:|" * len(COLUMNS)]


def _nanmean(values: list[float]) -> float:
    kept = [v for v in values if not math.isnan(v)]
    return statistics.mean(kept) if kept else math.nan


def sequences_section(python: str | None, configs: list[str]) -> None:
    sequences = single_target_sequences()
    if not sequences:
        print("no benchmark sequences found (../shared/data or $VTRACK_DATA): skipped\n")
        return
    trackers = [*configs, *OPENCV]
    table: dict[str, dict[str, tuple[float, ...]]] = {t: {} for t in trackers}
    notes: list[str] = []
    for seq in sequences:
        scores = sequence_scores(seq, python, configs, notes)
        print(f"### {seq.name}\n")
        print("\n".join(_header("tracker")))
        for tracker in trackers:
            table[tracker][seq.name] = scores[tracker]
            print(_row(tracker, scores[tracker]))
        print()
        sys.stdout.flush()
    print(f"### Means over the {len(sequences)} sequences\n")
    print("(AUC, P@20, mIoU: a run that failed counts 0; tracking miss / miss flagged: mean over "
          "the sequences where they are defined; fps: mean; x CSRT: median over sequences of "
          "the tracker's fps / CSRT's fps on the same frames)\n")
    print("| tracker | " + " | ".join(COLUMNS) + " | x CSRT fps |")
    print("|---|" + "---:|" * (len(COLUMNS) + 1))
    csrt = table["CSRT"]
    for tracker in trackers:
        rows = list(table[tracker].values())
        means = [statistics.mean(0.0 if math.isnan(r[i]) else r[i] for r in rows)
                 for i in range(3)]
        means += [_nanmean([r[i] for r in rows]) for i in range(3, len(COLUMNS))]
        ratios = [table[tracker][s][-1] / csrt[s][-1] for s in csrt
                  if not math.isnan(csrt[s][-1]) and not math.isnan(table[tracker][s][-1])]
        ratio = statistics.median(ratios) if ratios else math.nan
        print(_row(f"**{tracker}**", tuple(means)) + f" {_cell(ratio, 1)} |")
    print()
    for note in dict.fromkeys(notes):
        print(f"- {note}")
    print()


def sequence_scores(seq: Sequence, python: str | None, configs: list[str],
                    notes: list[str]) -> dict[str, tuple[float, ...]]:
    source = open_source(str(seq.folder))
    try:
        frames = list(source)
    finally:
        source.close()
    gt = read_boxes(seq.groundtruth, origin=1)[: len(frames)]
    assert gt[0] is not None
    outcomes = track_all(frames, seq.folder, gt[0], python, configs)
    for name, outcome in outcomes.items():
        if outcome.note:
            notes.append(f"{seq.name} [{name}]: {outcome.note}")
    return {name: outcome.scores(gt) for name, outcome in outcomes.items()}


def _scene_clip(name: str, seed: int, folder: Path, width: int = 320, height: int = 240,
                frames: int | None = None) -> tuple[list[Frame], list[Box | None]]:
    """Scene ``name``/``seed`` rendered once: in-memory frames and PNG files in ``folder``."""
    scene = make_scene(name, seed=seed, width=width, height=height, frames=frames)
    folder.mkdir(parents=True, exist_ok=True)
    images = []
    for i, bgr in enumerate(scene.frames()):
        cv2.imwrite(str(folder / f"{i + 1:04d}.png"), bgr)
        images.append(BgrFrame(i, i / scene.fps, bgr))
    return images, scene.boxes


def scenes_section(python: str | None, configs: list[str], seeds: int) -> None:
    trackers = [*configs, *OPENCV]
    names = [s.name for s in HARD_SCENARIOS]
    print(f"### Scenes: mean IoU over seeds 0..{seeds - 1} (320x240, 150 frames, parameters "
          "randomised per seed; a refused run counts 0)\n")
    print("| scene | " + " | ".join(trackers) + " |")
    print("|---|" + "---:|" * len(trackers))
    all_means: dict[str, list[float]] = {t: [] for t in trackers}
    for name in names:
        per: dict[str, list[float]] = {t: [] for t in trackers}
        for seed in range(seeds):
            with tempfile.TemporaryDirectory() as tmp:
                frames, gt = _scene_clip(name, seed, Path(tmp))
                assert gt[0] is not None
                outcomes = track_all(frames, Path(tmp), gt[0], python, configs)
            for t in trackers:
                per[t].append(0.0 if outcomes[t].failed else outcomes[t].scores(gt)[2])
        cells = []
        for t in trackers:
            value = _nanmean(per[t])
            all_means[t].append(value)
            cells.append(_cell(value))
        print(f"| {name} | " + " | ".join(cells) + " |")
        sys.stdout.flush()
    print("| **mean** | " + " | ".join(f"**{_cell(_nanmean(all_means[t]))}**"
                                        for t in trackers) + " |")
    print()


def hd_section(python: str | None, configs: list[str], frames: int) -> None:
    print(f"### Tracking cost at 1080p (`benchmark` scene, 1920x1080, {frames} frames, "
          "decoded frames in memory, tracking work only)\n")
    print("| tracker | ms per frame | fps | mean IoU |")
    print("|---|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        clip, gt = _scene_clip("benchmark", 0, Path(tmp), 1920, 1080, frames)
        assert gt[0] is not None
        outcomes = track_all(clip, Path(tmp), gt[0], python, configs)
    for name, outcome in outcomes.items():
        scores = outcome.scores(gt)
        ms = 1000.0 / scores[-1] if scores[-1] > 0 else math.nan
        print(f"| {name} | {_cell(ms, 2)} | {_cell(scores[-1], 0)} | {_cell(scores[2])} |")
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--contrib-python", default=os.environ.get("VTRACK_CONTRIB_PYTHON"),
                        help="python of a venv with opencv-contrib-python-headless (KCF, CSRT)")
    parser.add_argument("--seeds", type=int, default=3, help="seeds per scene")
    parser.add_argument("--hd-frames", type=int, default=60, help="frames of the 1080p clip")
    parser.add_argument("--no-sequences", action="store_true")
    parser.add_argument("--no-scenes", action="store_true")
    args = parser.parse_args()
    configs = list(CONFIGS)
    print("Command: `python benchmarks/robust_bench.py " + " ".join(
        a if not a.startswith("/") else "PATH" for a in sys.argv[1:]) + "`\n")
    print(machine() + "\n")
    if args.contrib_python is None:
        print("KCF and CSRT: n/a (no --contrib-python / VTRACK_CONTRIB_PYTHON given)\n")
    else:
        version = subprocess.run([args.contrib_python, "-c", "import cv2; print(cv2.__version__)"],
                                 capture_output=True, text=True, check=True).stdout.strip()
        print(f"OpenCV trackers: opencv-contrib-python-headless {version} (separate venv)\n")
    if not args.no_sequences:
        sequences_section(args.contrib_python, configs)
    if not args.no_scenes:
        scenes_section(args.contrib_python, configs, args.seeds)
        if args.hd_frames > 0:
            hd_section(args.contrib_python, configs, args.hd_frames)


if __name__ == "__main__":
    main()
