"""Tune and ablate the ``robust`` tracker on every real single-target sequence, in memory.

    python benchmarks/robust_tune.py                 # per-sequence table and the mean
    python benchmarks/robust_tune.py --ablate --split check   # each part off, check sequences
    python benchmarks/robust_tune.py --starts 5      # five starts a sequence (steadier means)
    python benchmarks/robust_tune.py --starts 13     # OTB's spatial robustness set (steadiest)
    python benchmarks/robust_tune.py --starts 13 --jobs 2   # ... sequences in two processes
    python benchmarks/robust_tune.py --ablate --ablate-scenes # ... all 28, with the hard scenes
    python benchmarks/robust_tune.py --set robust_failure.lost_after=30   # try a change
    python benchmarks/robust_tune.py --config s0     # another config, scored the same way
    python benchmarks/robust_tune.py --speed         # tracking work per 1080p frame vs s0 (+ --set)
    python benchmarks/robust_tune.py --scenes        # generated scenes, robust and s0
    python benchmarks/robust_tune.py --hard          # randomised hard scenes, seeds 0-8
    python benchmarks/robust_tune.py --hard --frames 90 --size 480x360   # other geometry
    python benchmarks/robust_tune.py --hard --first-seed 100 --seeds 8    # held-out seeds
    python benchmarks/robust_tune.py --beyond --first-seed 100 --seeds 6  # parameters beyond
    python benchmarks/robust_tune.py --looks --first-seed 200 --seeds 4   # slab, other looks
    python benchmarks/robust_tune.py --variants --jobs 2   # the same footage made other footage
    python benchmarks/robust_tune.py --drift --seeds 3    # a slow target over 12000 frames

Per sequence: AUC (OTB success, 21 IoU thresholds, strict >; a lost frame is a failure),
precision at 20 px, mean IoU, the honest-state shares (of the frames called ``tracking``, the
share whose box misses the target, IoU 0; of the frames whose box misses, the share called
``occluded`` or ``lost``; the mean row pools the frames of all sequences) and the tracking
work in microseconds per frame (the chain's stages, frames held in memory as BGR). The means
are given over the tune sequences and over the check sequences apart (``CHECK_SEQUENCES``, the
data folder's split): decide on the first, confirm on the second, never on one sequence.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import multiprocessing
import statistics
import sys
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TypeVar

import cv2
import numpy as np
from common import (
    CHECK_SEQUENCES,
    Clip,
    Sequence,
    clip_results,
    load_clip,
    scene_clip,
    single_target_sequences,
    to_frame,
    track_clip,
)

from vtrack.config import load_config
from vtrack.errors import VtrackError
from vtrack.evaluate.metrics import auc, frame_scores, mean_overlap, precision_at
from vtrack.geometry import Box
from vtrack.pipeline import Pipeline
from vtrack.scenes import hard as hard_scenes
from vtrack.scenes import make_scene
from vtrack.stages.base import TrackState

T = TypeVar("T")
R = TypeVar("R")

#: The ablation: (column, what is off, --set overrides), one part of robust switched off each
#: through its declared parameters. Parts without a switch: the correlation filter itself and
#: the Kalman filter (robust_motion always runs).
ABLATIONS = (
    ("robust", "nothing: the shipped config", []),
    ("-colour", "colour histograms and their merge (fHOG filter only)",
     ["robust_model.colour=false", "robust_search.merge=0"]),
    ("-grey", "the cells' grey-level channel (fHOG's 31 only)",
     ["robust_model.grey_channel=false"]),
    ("-scale", "fDSST's scale filter (the first size kept)", ["robust_search.scale=false"]),
    ("-motion", "the second search region at the Kalman prediction",
     ["robust_model.motion_region=false"]),
    ("-shift", "ECO's moved learning sample (the region cut again at the found centre)",
     ["robust_model.shift_within=0"]),
    ("-kcfpad", "KCF's wider region (Staple's padding of 1)", ["robust_model.padding=1"]),
    ("-psr", "MOSSE's PSR test (never occluded by a flat response)",
     ["robust_failure.hidden_psr=0"]),
    ("-doubtful", "LMCF's doubtful label (a weak sharp peak called occluded)",
     ["robust_failure.hidden_peak=0"]),
    ("-colourcheck", "the colour check before a doubtful frame is learnt",
     ["robust_failure.doubtful_colour=0"]),
    ("-apce", "LMCF's APCE test to take a hidden target back (PSR and peak only)",
     ["robust_failure.retake_apce=0"]),
    ("-redetect", "the rings of regions searched while lost", ["robust_failure.redetect=false"]),
    ("-wide", "the frame-wide search (while lost, and after a frame whose colours are not "
     "the target's)", ["robust_model.filter_redetect=false"]),
    ("-colourwide", "the frame-wide search after a frame whose colours are not the target's "
     "or whose target it found far away (only while lost)",
     ["robust_failure.redetect_on_colour=false"]),
    ("-learnocc", "learning occluded frames whose colours agree (MOSSE: nothing learnt below "
     "PSR 7)", ["robust_failure.learn_occluded=false"]),
    ("-update", "learning after the first frame", ["robust_failure.update=false"]),
)


@dataclass
class Result:
    auc: float
    precision: float
    miou: float
    tracking: int  # frames called tracking (ground truth present)
    false_tracking: int  # ... of which the box misses (IoU 0)
    misses: int  # frames whose box misses (IoU 0, or no box while the target is present)
    flagged: int  # ... of which called occluded or lost
    us_per_frame: float


def evaluate(clip: Clip, overrides: list[str], name: str = "robust") -> Result:
    """Run config ``name`` with ``overrides`` on ``clip`` and score it."""
    pipeline, results = clip_results(clip, load_config(name).with_overrides(overrides))
    boxes = [r.box for r in results]
    overlaps, errors = frame_scores(boxes, clip.boxes)
    tracking = misses = false_tracking = flagged = 0
    for result, overlap in zip(results, overlaps, strict=True):
        if overlap is None:
            continue
        missed = overlap <= 0.0
        if result.state == TrackState.TRACKING:
            tracking += 1
            false_tracking += missed
        if missed:
            misses += 1
            flagged += result.state != TrackState.TRACKING
    work = sum(pipeline.stage_microseconds_per_frame().values())
    return Result(auc(overlaps), precision_at(errors, 20), mean_overlap(overlaps),
                  tracking, false_tracking, misses, flagged, work)


#: OTB's spatial robustness evaluation: the first box moved by this share of its size.
START_SHIFT = 0.1
#: OTB's scale variations of the first box (spatial robustness evaluation).
START_SCALES = (0.8, 0.9, 1.1, 1.2)


def start_boxes(box: Box | None, starts: int) -> list[Box]:
    """The given first box; then (``starts`` 5) the box moved by 10% of its size along each
    diagonal; then (``starts`` 13: OTB's spatial robustness evaluation, Wu, Lim and Yang,
    CVPR 2013) also along each axis, and scaled by 0.8, 0.9, 1.1 and 1.2 about its centre.
    One start decides little: rounding alone moves single sequences."""
    assert box is not None
    shifts = ((1, 1), (1, -1), (-1, 1), (-1, -1), (1, 0), (-1, 0), (0, 1), (0, -1))
    moved = [Box(box.x + sx * START_SHIFT * box.w, box.y + sy * START_SHIFT * box.h,
                 box.w, box.h) for sx, sy in shifts]
    scaled = [Box.from_center(box.cx, box.cy, box.w * f, box.h * f) for f in START_SCALES]
    return ([box] + moved + scaled)[:starts]


def from_starts(clip: Clip, overrides: list[str], config: str, starts: int) -> Result:
    """``clip`` scored under ``config`` with ``overrides`` from each of its ``starts`` first
    boxes (:func:`start_boxes`), combined."""
    return combined([evaluate(dataclasses.replace(clip, boxes=[box, *clip.boxes[1:]]),
                              overrides, config)
                     for box in start_boxes(clip.boxes[0], starts)])


def sequence_result(task: tuple[Sequence, list[str], str, int]) -> Result:
    """One sequence's score (its starts combined) under a config and overrides; a config that
    refuses the sequence (e.g. a hue tracker on a grey target) scores 0."""
    seq, overrides, config, starts = task
    clip = load_clip(seq)
    try:
        return from_starts(clip, overrides, config, starts)
    except VtrackError as exc:
        print(f"{seq.name}: {exc}", file=sys.stderr)
        present = sum(box is not None for box in clip.boxes)
        return Result(0.0, 0.0, 0.0, 0, 0, present, 0, float("nan"))


def in_order(score: Callable[[T], R], tasks: list[T], jobs: int) -> Iterator[R]:
    """``score`` of every task, in the tasks' order, each as soon as it and those before are
    done; ``jobs`` worker processes (1: here, one after another)."""
    if jobs <= 1:
        yield from map(score, tasks)
        return
    with multiprocessing.Pool(jobs) as pool:
        yield from pool.imap(score, tasks)


def combined(results: list[Result]) -> Result:
    """Several starts' results as one: the scores' means, the frame counts' sums."""
    def mean(key: str) -> float:
        return statistics.mean(getattr(r, key) for r in results)

    def total(key: str) -> int:
        return sum(getattr(r, key) for r in results)

    return Result(mean("auc"), mean("precision"), mean("miou"), total("tracking"),
                  total("false_tracking"), total("misses"), total("flagged"),
                  mean("us_per_frame"))


def mean_text(values: Iterable[float | None]) -> str:
    """The mean of ``values`` that are not None (the seeds that ran, the sequences of a part)
    to three places; ``-`` when there is none."""
    scored = [v for v in values if v is not None]
    return f"{statistics.mean(scored):.3f}" if scored else "-"


def split_means(values: list[float], names: list[str]) -> tuple[str, str]:
    """Mean of ``values`` over the tune sequences and over the check sequences (``-``: none)."""
    return (mean_text(v for v, n in zip(values, names, strict=True) if n not in CHECK_SEQUENCES),
            mean_text(v for v, n in zip(values, names, strict=True) if n in CHECK_SEQUENCES))


def share(part: int, whole: int) -> str:
    """``part / whole`` as a percentage, ``-`` when ``whole`` is 0."""
    return f"{part / whole:.1%}" if whole else "-"


def speed(overrides: list[str], rounds: int = 7) -> None:
    """Tracking work (the chain's stages, microseconds per frame) of robust and s0 on the same
    1080p60 I420 frames of the camera-like ``benchmark`` scene: per stage the fastest of
    ``rounds`` runs (the machine's other load only ever adds time), summed; with
    ``overrides``, also robust with them (same run)."""
    scene = make_scene("benchmark", seed=0, width=1920, height=1080, frames=120, fps=60)
    frames = [to_frame(i, 60, bgr) for i, bgr in enumerate(scene.frames())]
    box = scene.boxes[0]
    assert box is not None
    print(f"1920x1080 I420, {len(frames)} frames, target {box.w:.0f}x{box.h:.0f}; per stage "
          f"the fastest of {rounds} runs\n")
    print("| config | us per frame | x s0 | stages (us) |")
    print("|---|---:|---:|---|")
    work: dict[str, float] = {}
    runs = [("s0", "s0", []), ("robust", "robust", [])]
    if overrides:
        runs.append(("robust " + " ".join(overrides), "robust", overrides))
    for name, config, changes in runs:
        fastest: dict[str, float] = {}
        for _ in range(rounds):
            pipeline = Pipeline(load_config(config).with_overrides(changes).build(), seed=0)
            for _ in pipeline.track(frames, box):
                pass
            for stage, us in pipeline.stage_microseconds_per_frame().items():
                fastest[stage] = min(fastest.get(stage, math.inf), us)
        work[name] = sum(fastest.values())
        stages = ", ".join(f"{stage} {us:.0f}" for stage, us in fastest.items())
        print(f"| {name} | {work[name]:.0f} | {work[name] / work['s0']:.2f} | {stages} |")


SCENES = ("smooth", "occlusion", "lighting", "distractor", "leave_return", "scale", "accelerate",
          "cover", "jump", "bounce")


def scenes(seeds: tuple[int, ...] = (0, 1, 2)) -> None:
    """Mean IoU of robust and s0 on each generated scene of this project, per seed."""
    print("| scene | " + " | ".join(f"{c} (seeds {', '.join(map(str, seeds))})"
                                     for c in ("robust", "s0")) + " |")
    print("|---|---|---|")
    for name in SCENES:
        cells = []
        for config in ("robust", "s0"):
            values = []
            for seed in seeds:
                clip = scene_clip(name, seed)
                overlaps, _ = frame_scores(track_clip(clip, load_config(config)), clip.boxes)
                values.append(mean_overlap(overlaps))
            cells.append(" ".join(f"{v:.2f}" for v in values))
        print(f"| {name} | " + " | ".join(cells) + " |")


HARD = ("slab", "exit_return", "clip_ramp", "fast", "grow", "shrink", "crossing", "grey")
#: The ablation's scene columns: the slab passed slowly (partly covered ~40% of the clip), and
#: every hard scene at the tests' length and size.
SLOW_SLAB_SEEDS, SLOW_SLAB_FRAMES, HARD_SEEDS = range(6), 200, 3


def hard_means(overrides: list[str], seeds: range, frames: int = 120,
               size: tuple[int, int] | None = None,
               names: tuple[str, ...] = HARD) -> dict[str, list[float | None]]:
    """Per randomised hard scene, robust's (with ``overrides``) mean IoU on each seed; None for
    a seed whose scene cannot be made (its drawn parameters do not fit ``size`` or ``frames``:
    at 100x400 and 60 frames some slabs' occlusions) or robust refuses to start on (at a small
    ``size`` a target may start under the 4x4 pixels a tracker starts from), with its reason
    on stderr. :func:`can_be_made` first tells a scene no seed can be made of."""
    config = load_config("robust").with_overrides(overrides)
    width, height = size or (None, None)
    means: dict[str, list[float | None]] = {}
    for name in names:
        for seed in seeds:
            try:
                scene = make_scene(name, seed=seed, frames=frames, width=width, height=height)
                boxes = track_clip(Clip(name, list(scene.frames()), list(scene.boxes)), config)
            except VtrackError as exc:
                print(f"{name} seed {seed}: left out: {exc}", file=sys.stderr)
                means.setdefault(name, []).append(None)
                continue
            overlaps, _ = frame_scores(boxes, scene.boxes)
            means.setdefault(name, []).append(mean_overlap(overlaps))
    return means


def seed_cells(values: list[float | None]) -> str:
    """A table row's per-seed scores ('-' for a seed left out), their mean and their least."""
    cells = " ".join("-" if v is None else f"{v:.2f}" for v in values)
    least = min((v for v in values if v is not None), default=None)
    return f"{cells} | {mean_text(values)} | {'-' if least is None else f'{least:.2f}'} |"


def hard_size(text: str | None) -> tuple[int, int] | None:
    """``--size`` as (width, height), None when not given; not WxH: one line and exit."""
    if text is None:
        return None
    width, _, height = text.lower().partition("x")
    if not (width.strip().isdecimal() and height.strip().isdecimal()):  # what int() reads
        sys.exit(f"robust_tune.py: --size {text!r}: expected WIDTHxHEIGHT, e.g. 320x240")
    return int(width), int(height)


def can_be_made(names: Iterable[str], seeds: range, frames: int,
                size: tuple[int, int] | None) -> None:
    """Make each of ``names`` at ``frames`` and ``size`` from one of ``seeds`` on, so that a
    ``--frames`` or ``--size`` no seed's scene can be made at raises (the first seed's
    VtrackError) before a table's header is printed, not after it; a scene only some seeds
    cannot be made of is theirs to leave out (:func:`hard_means`)."""
    width, height = size or (None, None)
    for name in dict.fromkeys(names):
        first: VtrackError | None = None
        for seed in seeds:
            try:
                make_scene(name, seed=seed, frames=frames, width=width, height=height)
                break
            except VtrackError as exc:
                first = first or exc
        else:
            if first is not None:
                raise first


def hard(overrides: list[str], seeds: range, frames: int,
         size: tuple[int, int] | None) -> None:
    """Mean IoU of robust (with ``overrides``) on each randomised hard scene, per seed (the
    parameters are drawn per seed; the tests use seeds 0-2 at 120 frames, 320x240)."""
    can_be_made(HARD, seeds, frames, size)
    where = f"{size[0]}x{size[1]}" if size else "320x240"
    print(f"| scene ({where}, {frames} frames) | seeds {seeds.start}-{seeds.stop - 1} | mean "
          "| min |")
    print("|---|---|---:|---:|")
    for name in HARD:
        values = hard_means(overrides, seeds, frames, size, (name,))[name]
        print(f"| {name} | {seed_cells(values)}")
        sys.stdout.flush()


#: The slow target: ``smooth`` at 320x240 over this many frames moves ~0.05 px a frame (0.0013
#: of its width; stop 53's 640x480 clip of 36,000 frames, 0.0004), on a static textured
#: background, scored in this many parts of the clip.
DRIFT_FRAMES, DRIFT_PARTS = 12_000, 4


def drift(overrides: list[str], seeds: range, frames: int) -> None:
    """Mean IoU of robust (with ``overrides``) on a slowly moving target (``smooth`` over
    ``frames`` frames at 320x240), per seed and per part of the clip: a tracker whose estimate
    of each frame's sub-pixel motion is short of it trails the target more and more (the
    static background in its region matches best where it was)."""
    config = load_config("robust").with_overrides(overrides)
    can_be_made(("smooth",), seeds, frames, (320, 240))
    print(f"| seed (smooth, 320x240, {frames} frames) | mean IoU per 1/{DRIFT_PARTS} of the "
          "clip | mean | last frame |")
    print("|---|---|---:|---:|")
    means = []
    for seed in seeds:
        scene = make_scene("smooth", seed=seed, width=320, height=240, frames=frames)
        pipeline = Pipeline(config.build(), seed=0)
        first = scene.boxes[0]
        assert first is not None
        results = pipeline.track((to_frame(i, 30.0, bgr, "BGR")
                                  for i, bgr in enumerate(scene.frames())), first)
        overlaps, _ = frame_scores([r.box for r in results], scene.boxes)
        part = frames // DRIFT_PARTS
        parts = [mean_overlap(overlaps[i:i + part]) for i in range(0, part * DRIFT_PARTS, part)]
        means.append(mean_overlap(overlaps))
        print(f"| {seed} | {' '.join(f'{v:.3f}' for v in parts)} | {means[-1]:.3f} | "
              f"{overlaps[-1] or 0.0:.3f} |")
        sys.stdout.flush()
    print(f"| mean | | {statistics.mean(means):.3f} | |")


#: Hard scenes with one randomised parameter drawn beyond its declared range
#: (``vtrack.scenes.hard.RANGES``): scenes whose parameters differ from the ones the tests
#: and the tables use.
BEYOND: tuple[tuple[str, str, tuple[float, float]], ...] = (
    ("fast", "fast_speed", (0.8, 1.2)), ("fast", "fast_speed", (1.6, 2.0)),
    ("fast", "fast_size", (0.3, 0.5)), ("fast", "fast_size", (0.75, 1.0)),
    ("slab", "hidden", (8.0, 15.0)), ("slab", "hidden", (22.0, 30.0)),
    ("exit_return", "exit_speed", (0.4, 0.6)), ("exit_return", "out_frames", (25.0, 40.0)),
    ("grey", "grey_contrast", (20.0, 40.0)), ("grow", "scale_factor", (3.6, 4.5)),
    ("shrink", "scale_factor", (3.6, 4.5)), ("crossing", "gap", (0.0, 0.1)),
    ("crossing", "twin_size", (0.7, 0.9)), ("clip_ramp", "gain_high", (1.45, 1.7)),
)


#: ``slab`` with one of its looks drawn beyond its declared range: what hides the target and
#: what surrounds it in colours and sizes the tests never draw.
LOOKS: tuple[tuple[str, str, tuple[float, float]], ...] = (
    ("slab", "background_mean", (40.0, 100.0)), ("slab", "background_mean", (200.0, 240.0)),
    ("slab", "size", (1.0, 1.6)), ("slab", "saturation", (30.0, 170.0)),
    ("slab", "value", (120.0, 205.0)), ("slab", "texture", (0.0, 0.6)),
    ("slab", "texture", (1.6, 3.0)), ("slab", "slab_grey", (20.0, 70.0)),
)


def beyond(overrides: list[str], seeds: range, frames: int,
           draws: tuple[tuple[str, str, tuple[float, float]], ...] = BEYOND) -> None:
    """Mean IoU of robust (with ``overrides``) on each hard scene with one parameter drawn
    beyond its declared range (``draws``: :data:`BEYOND` or :data:`LOOKS`), per seed."""
    can_be_made((name for name, _, _ in draws), seeds, frames, None)
    print(f"| scene (320x240, {frames} frames) | parameter: declared -> drawn | seeds "
          f"{seeds.start}-{seeds.stop - 1} | mean | min |")
    print("|---|---|---|---:|---:|")
    for name, parameter, drawn in draws:
        declared = hard_scenes.RANGES[parameter]
        hard_scenes.RANGES[parameter] = drawn
        try:
            values = hard_means(overrides, seeds, frames, None, (name,))[name]
        finally:
            hard_scenes.RANGES[parameter] = declared
        print(f"| {name} | {parameter}: {declared[0]:g}-{declared[1]:g} -> "
              f"{drawn[0]:g}-{drawn[1]:g} | {seed_cells(values)}")
        sys.stdout.flush()


def usable(variants: tuple[tuple[str, str, list[str]], ...],
           extra: list[str]) -> list[tuple[str, str, list[str]]]:
    """The ablation variants whose overrides (with ``extra``) robust accepts; a line on stderr
    for each one it does not (e.g. a parameter that was renamed or removed)."""
    kept = []
    for key, what, overrides in variants:
        try:
            load_config("robust").with_overrides(overrides + extra)
        except VtrackError as exc:
            print(f"ablation {key}: skipped ({exc})", file=sys.stderr)
            continue
        kept.append((key, what, overrides))
    return kept


#: ``--variants``: each real sequence made into footage it never was (from its given box):
#: (name, what was done). Sequences tuned on come back at another size, speed, handedness or
#: direction, so a change that fits the sequences rather than the trackers' task shows here.
VARIANTS: tuple[tuple[str, str], ...] = (
    ("as_is", "the sequence as it is"),
    ("half", "every frame at half its width and height (area resample)"),
    ("skip2", "every second frame: the target moves twice as far a frame"),
    ("mirror", "every frame mirrored left to right"),
    ("reverse", "played backwards, from the last frame that has a box"),
)


def variant_clip(clip: Clip, variant: str) -> Clip:
    """``clip`` made into ``variant`` (a name of :data:`VARIANTS`), boxes moved to match."""
    frames, boxes = clip.frames, clip.boxes
    if variant == "half":
        frames = [cv2.resize(f, (f.shape[1] // 2, f.shape[0] // 2), interpolation=cv2.INTER_AREA)
                  for f in frames]
        boxes = [None if b is None else Box(b.x / 2, b.y / 2, b.w / 2, b.h / 2) for b in boxes]
    elif variant == "skip2":
        frames, boxes = frames[::2], boxes[::2]
    elif variant == "mirror":
        width = frames[0].shape[1]
        frames = [np.ascontiguousarray(f[:, ::-1]) for f in frames]
        boxes = [None if b is None else Box(width - b.x - b.w, b.y, b.w, b.h) for b in boxes]
    elif variant == "reverse":
        last = max(i for i, b in enumerate(boxes) if b is not None)
        frames, boxes = frames[last::-1], boxes[last::-1]
    elif variant != "as_is":
        raise ValueError(f"unknown variant {variant!r}")
    return dataclasses.replace(clip, frames=frames, boxes=boxes)


def variant_result(task: tuple[Sequence, str, list[str], str]) -> Result:
    """One sequence's score as one variant, from its (moved) given box."""
    seq, variant, overrides, config = task
    return evaluate(variant_clip(load_clip(seq), variant), overrides, config)


def variants(sequences: list[Sequence], overrides: list[str], config: str, jobs: int) -> None:
    """Mean AUC (tune, check, all) and the honest-state shares of ``config`` (with
    ``overrides``) on every variant of every sequence; then each sequence's AUC per variant."""
    names = [seq.name for seq in sequences]
    tasks = [(seq, variant, overrides, config) for variant, _ in VARIANTS for seq in sequences]
    results = list(in_order(variant_result, tasks, jobs))
    per_variant = {variant: results[k * len(sequences):(k + 1) * len(sequences)]
                   for k, (variant, _) in enumerate(VARIANTS)}
    print("| variant | what | mean AUC, tune | check | all | tracking & miss | miss & flagged |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for variant, what in VARIANTS:
        scored = per_variant[variant]
        tune, check = split_means([r.auc for r in scored], names)
        pooled = combined(scored)
        print(f"| {variant} | {what} | {tune} | {check} | "
              f"{statistics.mean(r.auc for r in scored):.3f} | "
              f"{share(pooled.false_tracking, pooled.tracking)} | "
              f"{share(pooled.flagged, pooled.misses)} |")
    print()
    print("| sequence | " + " | ".join(variant for variant, _ in VARIANTS) + " |")
    print("|---|" + "---:|" * len(VARIANTS))
    for k, name in enumerate(names):
        print(f"| {name} | " + " | ".join(f"{per_variant[v][k].auc:.3f}" for v, _ in VARIANTS)
              + " |")


def ablation_row(task: tuple[Sequence, list[tuple[str, str, list[str]]], list[str], int]
                 ) -> dict[str, Result]:
    """One sequence's score under each variant (its starts combined)."""
    seq, variants, extra, starts = task
    clip = load_clip(seq)
    return {key: from_starts(clip, overrides + extra, "robust", starts)
            for key, _, overrides in variants}


def ablate(sequences: list[Sequence], extra: list[str], with_scenes: bool, starts: int = 1,
           jobs: int = 1) -> None:
    """Robust with each part off (:data:`ABLATIONS`) on ``sequences`` (each from ``starts``
    first boxes, ``jobs`` sequences at once): AUC per sequence and variant, then per variant
    the means (all, tune, check), the honest-state shares pooled over the frames and, with
    ``with_scenes``, the slow slab and hard scenes' mean IoU."""
    variants = usable(ABLATIONS, extra)
    names = [seq.name for seq in sequences]
    table: dict[str, list[Result]] = {key: [] for key, _, _ in variants}
    rows = in_order(ablation_row, [(seq, variants, extra, starts) for seq in sequences], jobs)
    for seq, row in zip(sequences, rows, strict=True):
        for key, _, _ in variants:
            table[key].append(row[key])
        print(f"<!-- {seq.name}: " + ", ".join(f"{key} {row[key].auc:.3f}"
                                               for key, _, _ in variants) + " -->")
        sys.stdout.flush()
    print("\n| sequence | " + " | ".join(key for key, _, _ in variants) + " |")
    print("|---|" + "---:|" * len(variants))
    for i, name in enumerate(names):
        mark = " *" if name in CHECK_SEQUENCES else ""
        print(f"| {name}{mark} | " + " | ".join(f"{table[key][i].auc:.3f}"
                                               for key, _, _ in variants) + " |")
    print("| **mean** | " + " | ".join(f"**{statistics.mean(r.auc for r in table[key]):.3f}**"
                                        for key, _, _ in variants) + " |")
    base = statistics.mean(r.auc for r in table["robust"]) if "robust" in table else math.nan
    scene_head = (f" slow slab ({len(SLOW_SLAB_SEEDS)} seeds, {SLOW_SLAB_FRAMES} frames) | "
                  f"hard scenes (seeds 0-{HARD_SEEDS - 1}) |" if with_scenes else "")
    print("\n| variant | off | overrides | mean AUC | change | tune | check | tracking & miss "
          "| miss & flagged |" + scene_head)
    print("|---|---|---|---:|---:|---:|---:|---:|---:|" + ("---:|---:|" if with_scenes else ""))
    for key, what, overrides in variants:
        results = table[key]
        mean = statistics.mean(r.auc for r in results)
        tune, check = split_means([r.auc for r in results], names)
        false_tracking = share(sum(r.false_tracking for r in results),
                               sum(r.tracking for r in results))
        flagged = share(sum(r.flagged for r in results), sum(r.misses for r in results))
        scenes_cells = ""
        if with_scenes:
            slab = hard_means(overrides + extra, SLOW_SLAB_SEEDS, SLOW_SLAB_FRAMES,
                              names=("slab",))["slab"]
            kinds = hard_means(overrides + extra, range(HARD_SEEDS))
            every = [v for vs in kinds.values() for v in vs]
            scenes_cells = f" {mean_text(slab)} | {mean_text(every)} |"
        print(f"| {key} | {what} | {' '.join(f'`{o}`' for o in overrides) or '-'} | {mean:.3f} "
              f"| {mean - base:+.3f} | {tune} | {check} | {false_tracking} | {flagged} |"
              + scenes_cells)
        sys.stdout.flush()


def whole_number(least: int, most: int | None = None) -> Callable[[str], int]:
    """An argparse type: a whole number from ``least`` on (to ``most``, when given); else
    argparse's one-line error."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r}: not a whole number") from None
        if value < least or (most is not None and value > most):
            raise argparse.ArgumentTypeError(
                f"{text!r}: give {least} or more" if most is None else
                f"{text!r}: give {least} to {most}")
        return value
    return parse


def scored_config(args: argparse.Namespace) -> str:
    """The config the mode ``args`` asks for runs with ``--set``: ``--config`` for the
    per-sequence table and ``--variants``; robust for every other mode."""
    other = (args.ablate, args.speed, args.hard, args.beyond, args.looks, args.drift)
    return "robust" if any(other) else args.config


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ablate", action="store_true", help="mean AUC with each part off")
    parser.add_argument("--set", action="append", default=[], dest="overrides",
                        help="stage.param=value applied to every run")
    parser.add_argument("--only", action="append", default=[], help="sequence names")
    parser.add_argument("--split", choices=("all", "tune", "check"), default="all",
                        help="the data's tune or check sequences only (default: all)")
    parser.add_argument("--ablate-scenes", action="store_true",
                        help="--ablate: also the slow slab and the hard scenes' mean IoU")
    parser.add_argument("--scenes", action="store_true",
                        help="mean IoU on the generated scenes, robust against s0")
    parser.add_argument("--hard", action="store_true",
                        help="mean IoU on the randomised hard scenes (--seeds, --frames, --size)")
    parser.add_argument("--beyond", action="store_true",
                        help="the hard scenes with one parameter beyond its declared range")
    parser.add_argument("--looks", action="store_true",
                        help="slab with one of its looks beyond its declared range")
    parser.add_argument("--seeds", type=whole_number(1), default=9,
                        help="--hard, --beyond, --looks, --drift: how many seeds (default 9)")
    parser.add_argument("--first-seed", type=whole_number(0), default=0,
                        help="--hard, --beyond, --looks, --drift: the first seed (default 0; "
                             "the tests use 0-5, the tables 0-8: a higher one scores "
                             "parameters never looked at)")
    parser.add_argument("--drift", action="store_true",
                        help="mean IoU on a slowly moving target over a long clip (--seeds, "
                             f"--frames: default {DRIFT_FRAMES})")
    parser.add_argument("--frames", type=whole_number(1), default=None,
                        help="--hard, --beyond, --looks: frames per scene (default 120); "
                             f"--drift: frames of its clip (default {DRIFT_FRAMES})")
    parser.add_argument("--size", default=None,
                        help="--hard only: WxH (default 320x240; the other modes' scenes are "
                             "320x240)")
    parser.add_argument("--variants", action="store_true",
                        help="every sequence also at half size, every second frame, mirrored "
                             "and backwards, from the given box")
    parser.add_argument("--speed", action="store_true",
                        help="tracking work per 1080p frame, robust against s0")
    parser.add_argument("--starts", type=int, choices=(1, 5, 13), default=1,
                        help="runs per sequence: the given first box only; 5: also the box "
                             "moved 10%% of its size along each diagonal; 13: OTB's whole "
                             "spatial robustness set (also moved along each axis, and scaled "
                             "by 0.8-1.2); the scores are the runs' means")
    parser.add_argument("--jobs", type=whole_number(1, 64), default=1,
                        help="sequences scored at once in worker processes, 1 to 64 (scores "
                             "are the same; the us/frame column then also counts the other "
                             "jobs)")
    parser.add_argument("--config", default="robust",
                        help="another shipped config to score the same way (e.g. s0)")
    args = parser.parse_args()
    if args.size is not None and not args.hard:
        parser.error("--size: only --hard takes a size (the other modes' scenes are 320x240)")
    if args.overrides and args.scenes:
        parser.error("--set: --scenes scores the shipped robust and s0 as they are")
    try:  # a --set the config refuses, a scene that cannot be made at that --size or --frames
        load_config(scored_config(args)).with_overrides(args.overrides)
        run_mode(args)
    except VtrackError as exc:
        sys.exit(f"robust_tune.py: {exc}")


def run_mode(args: argparse.Namespace) -> None:
    """Print the table of the mode ``args`` asks for."""
    if args.speed:
        speed(args.overrides)
        return
    if args.scenes:
        scenes()
        return
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    frames = args.frames or 120
    if args.drift:
        drift(args.overrides, seeds, args.frames or DRIFT_FRAMES)
        return
    if args.beyond or args.looks:
        beyond(args.overrides, seeds, frames, LOOKS if args.looks else BEYOND)
        return
    if args.hard:
        hard(args.overrides, seeds, frames, hard_size(args.size))
        return
    sequences = [s for s in single_target_sequences() if not args.only or s.name in args.only]
    if args.split != "all":
        check = args.split == "check"
        sequences = [s for s in sequences if (s.name in CHECK_SEQUENCES) == check]
    if not sequences:
        print("no benchmark sequences found (../shared/data or $VTRACK_DATA): skipped")
        return
    if args.variants:
        variants(sequences, args.overrides, args.config, args.jobs)
        return
    if args.ablate:
        ablate(sequences, args.overrides, args.ablate_scenes, args.starts, args.jobs)
        return
    print("| sequence | AUC | P@20 | mIoU | tracking & miss | miss & flagged | us/frame |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    results: list[Result] = []
    tasks = [(seq, args.overrides, args.config, args.starts) for seq in sequences]
    for seq, result in zip(sequences, in_order(sequence_result, tasks, args.jobs), strict=True):
        results.append(result)
        print(f"| {seq.name} | {result.auc:.3f} | {result.precision:.3f} | "
              f"{result.miou:.3f} | {share(result.false_tracking, result.tracking)} | "
              f"{share(result.flagged, result.misses)} | {result.us_per_frame:.0f} |")
        sys.stdout.flush()

    def mean(key: str) -> float:
        return statistics.mean(getattr(r, key) for r in results)

    def total(key: str) -> int:
        return sum(getattr(r, key) for r in results)

    tune, check = split_means([r.auc for r in results], [seq.name for seq in sequences])
    print(f"| mean AUC, tune sequences | {tune} | | | | | |")
    print(f"| mean AUC, check sequences | {check} | | | | | |")
    # the honest-state shares pooled over all frames of all sequences
    print(f"| **mean** | **{mean('auc'):.3f}** | {mean('precision'):.3f} | {mean('miou'):.3f} | "
          f"{share(total('false_tracking'), total('tracking'))} | "
          f"{share(total('flagged'), total('misses'))} | {mean('us_per_frame'):.0f} |")
    # ... and averaged over the sequences (each sequence weighs the same; sequences without
    # such frames left out), so one long sequence cannot carry the pooled share
    per_tracking = [r.false_tracking / r.tracking for r in results if r.tracking]
    per_flagged = [r.flagged / r.misses for r in results if r.misses]
    print(f"| mean per sequence | | | | "
          f"{statistics.mean(per_tracking):.1%} | {statistics.mean(per_flagged):.1%} | |"
          if per_tracking and per_flagged else "")


if __name__ == "__main__":
    main()
