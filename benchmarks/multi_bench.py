"""Multi-target trackers measured: S3 (``mht``), S4 per track (``kalman_tracks``) and
``fixed_camera`` (``group_blobs`` + ``byte_tracks``).

    python benchmarks/multi_bench.py [SEEDS] [generated|tud|variants|sizes|people|vehicles|
        outside|cost|processes] [--set STAGE.PARAM=VALUE ...]

Prints Markdown tables (per-frame cost: the pipeline's wall time per frame, in this process):

1. MOTA / IDF1 / id switches (CLEAR MOT, IoU >= 0.5; IDF1 of Ristani et al.) of the shipped
   ``s3`` and ``s4_multi`` configs (and ``s4_multi`` with MOG2 instead of S4's mean background)
   and ``fixed_camera`` told the targets are small and round, on the generated ``multi`` scene
   (320x240 and 640x480, 150 frames, seeds 0 .. SEEDS-1, summed over seeds); then the
   randomised ``pedestrians`` scene (640x480 and 768x576, 150 frames at 25 fps, seeds
   200 .. 200+SEEDS-1: never looked at while choosing ``fixed_camera``'s values).
2. MOT_TUD-Campus (``../shared/data`` or ``$VTRACK_DATA``; skipped when absent): how S4's
   background subtraction (+ ``blobs``, and ``fixed_camera``'s detections) detects pedestrians
   compared with the public detections of ``det.txt`` (precision / recall of boxes at IoU >=
   0.5), then every tracker on the pixels and on the public detections (``mot_detections``).
   ``variants``: ``fixed_camera`` on MOT_TUD-Campus in eight variants of the same footage
   (each frame decoded by OpenCV and by PyAV, as it is and mirrored left to right, from frame 1
   and from frame 11), scores per variant and pooled, and with the ``--set`` overrides beside
   it (same run). One 71-frame run moves by several hundredths of MOTA between two JPEG
   decoders alone: a change to the detector or the tracker should hold on the pooled row.
   ``sizes``: ``fixed_camera`` (and with the ``--set`` overrides, same run) on ``pedestrians``
   drawn at three frame sizes (320x240, 768x576, 1280x720) with people of three heights (the
   generator's 0.22-0.5 of the frame height, and 0.12-0.27, 0.07-0.15), seeds 300 ..
   300+SEEDS-1: how its sizes in frame pixels (opening, closing, least blob area) hold up.
   ``people``: ``fixed_camera`` (and with the overrides) on ``pedestrians`` at 640x480 and
   768x576, seeds 205 .. 205+SEEDS-1, seed by seed and the mean per seed.
   ``vehicles``: ``fixed_camera`` (and with the overrides) and ``s4_multi`` on the generated
   ``vehicles`` (height/width 0.3-0.8) and ``street`` (people and vehicles) scenes at 640x480,
   seeds 0 .. SEEDS-1 (what ``fixed_camera``'s learning of wide targets was chosen on) and
   100 .. 100+SEEDS-1 (held out), pooled.
   ``outside``: every tracker on pixels (and ``fixed_camera`` with the overrides) on each
   MOTChallenge sequence named in ``$VTRACK_MOT`` (folders separated as in ``PATH``, each with
   ``gt/gt.txt`` and ``img1/`` or one video file; e.g. MOT15's TUD-Stadtmitte and
   PETS09-S2L1): real fixed-camera footage none of the values were chosen on; then where
   ``fixed_camera``'s misses come from there (its detections' and tracks' precision and recall
   of boxes, and the shape of the detections that overlap a person by IoU 0.2-0.5).
3. Cost per frame at 1080p (grey frames, as a decoded yuv420p video hands over the Y plane) with
   4, 16 and 64 moving targets, with and without clutter (extra bright specks each frame):
   microseconds per stage.
4. Whole processes: ``vtrack run --no-video`` of ``fixed_camera`` (and ``s4_multi``) on H.264
   ``pedestrians`` clips at 768x576 and 1920x1080 (25 fps), frames per second of wall time from
   start to exit, beside a PyAV decode-only process of the same file (best of ``ROUNDS``).
"""

from __future__ import annotations

import configparser
import os
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from common import data_dir, seeds_argument
from scipy.optimize import linear_sum_assignment
from speed import DECODE_THREADS, WORK, python_baseline, vtrack_run

from vtrack.batch import VIDEO_SUFFIXES
from vtrack.config import Config, load_config, parse_config
from vtrack.evaluate.groundtruth import read_mot, read_mot_detections
from vtrack.evaluate.mot import MATCH_IOU, evaluate_mot
from vtrack.frame import BgrFrame, Frame, GrayFrame
from vtrack.geometry import Box, iou
from vtrack.io.images import list_images, read_image
from vtrack.io.inputs import open_source
from vtrack.io.video import decoder_threads
from vtrack.machine import cpu_count
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.scenes import make_scene, pedestrians, write_video
from vtrack.stages.base import Stage, TrackContext, TrackStatus

#: (label, config, --set overrides) of the trackers on pixels.
TRACKERS = [
    ("S3 `s3`", "s3", []),
    ("S4 per track `s4_multi` (mean background)", "s4_multi", []),
    ("S4 per track `s4_multi` + MOG2", "s4_multi", ["background.method=mog2"]),
    ("`fixed_camera`", "fixed_camera", []),
]
#: What README tells ``fixed_camera`` for small round targets (the infrared-like ``multi``).
SMALL = ["group_blobs.aspect=1", "blobs.min_area=4", "background.open=1", "background.close=1"]
#: Seeds of the randomised pedestrians scene: from 200 on, none looked at while choosing
#: values (0..4 and 100..104 were).
PEDESTRIAN_SEEDS = 200
#: Rounds of each timed process (the best is kept: the machine is shared).
ROUNDS = 3
#: MOG2 foreground cleaned for pedestrians at 640x480: opening 3, closing 25, blobs of 1500+ px
#: (chosen on MOT_TUD-Campus itself: an upper bound for this detector, not a fair test).
CLEANED = ["background.method=mog2", "background.open=3", "background.close=25",
           "blobs.min_area=1500"]
#: (label, --set overrides) of the background-subtraction detectors compared on TUD-Campus.
DETECTORS = [
    ("mean of 30 frames (S4, shipped)", []),
    ("mean of 10 frames", ["background.frames=10"]),
    ("MOG2", ["background.method=mog2"]),
    ("mean of 30 frames, cleaned (open 3, close 25, >= 1500 px)",
     ["background.open=3", "background.close=25", "blobs.min_area=1500"]),
    ("MOG2, cleaned (open 3, close 25, >= 1500 px)", CLEANED),
]
COLUMNS = ("MOTA", "IDF1", "ID sw.", "FP", "FN", "MT", "ML", "ids", "ms/frame")


def confirmed(results: list[FrameResult]) -> dict[int, list[tuple[int, Box]]]:
    """What ``tracks.csv`` holds: the confirmed tracks of each frame."""
    return {r.index: [(t.id, t.box) for t in r.tracks if t.state == TrackStatus.CONFIRMED]
            for r in results}


def run_chain(config: Config, frames: Iterator[Frame]) -> tuple[list[FrameResult], Pipeline]:
    pipeline = Pipeline(config.build())
    return list(pipeline.track(frames)), pipeline


def scored(config: Config, frames: list[Frame], gt: dict) -> dict[str, Any]:
    """CLEAR MOT / IDF1 of ``config`` on ``frames`` and its pipeline's ms per frame (``ms``)."""
    results, pipeline = run_chain(config, iter(frames))
    scores = evaluate_mot(gt, confirmed(results), len(frames))
    scores["ms"] = sum(pipeline.stage_seconds.values()) * 1e3 / len(frames)
    return scores


def row(label: str, scores: dict[str, Any]) -> str:
    def fmt(value: Any) -> str:
        return "-" if value is None else f"{value:.3f}" if isinstance(value, float) else str(value)

    values = [scores["mota"], scores["idf1"], scores["id_switches"], scores["false_positives"],
              scores["misses"], scores["mostly_tracked"], scores["mostly_lost"],
              f"{scores['track_ids']}/{scores['gt_ids']}", f"{scores['ms']:.1f}"]
    return f"| {label} | " + " | ".join(fmt(v) for v in values) + " |"


def header(first: str) -> str:
    return (f"| {first} | " + " | ".join(COLUMNS) + " |\n|---|"
            + "---:|" * len(COLUMNS))


def summed(parts: list[dict[str, Any]]) -> dict[str, Any]:
    """Scores of several sequences pooled: counts added, MOTA and IDF1 recomputed."""
    total = {k: sum(p[k] for p in parts) for k in (
        "id_switches", "false_positives", "misses", "mostly_tracked", "mostly_lost", "gt_ids",
        "gt_boxes", "track_ids", "track_boxes", "matches")}
    total["ms"] = sum(p["ms"] * p["frames"] for p in parts) / sum(p["frames"] for p in parts)
    gt_boxes = total["gt_boxes"]
    errors = total["misses"] + total["false_positives"] + total["id_switches"]
    total["mota"] = 1 - errors / gt_boxes
    idtp = sum(p["idf1"] * (p["gt_boxes"] + p["track_boxes"]) / 2 for p in parts if p["idf1"])
    total["idf1"] = 2 * idtp / (gt_boxes + total["track_boxes"])
    return total


# --- 1. generated scenes ------------------------------------------------------------------------


def generated(seeds: int) -> None:
    print("## Generated `multi` scene (4 targets: two cross and merge, one leaves, one enters)\n")
    print(f"150 frames, seeds 0..{seeds - 1}, scores pooled over the seeds; `ids` = track ids "
          "written / ground-truth ids.\n")
    chains = [*TRACKERS[:3], ("`fixed_camera`, small round targets (README)", "fixed_camera",
                              SMALL)]
    for width, height in ((320, 240), (640, 480)):
        scenes = [make_scene("multi", seed, width, height, 150) for seed in range(seeds)]
        table(f"{width}x{height}", chains, scenes)
    print("## Generated `pedestrians` scene (4-6 people crossing, hiding each other, entering "
          "and leaving; shadows, slowly changing brightness)\n")
    last = PEDESTRIAN_SEEDS + seeds - 1
    print(f"150 frames at 25 fps, seeds {PEDESTRIAN_SEEDS}..{last} (never used while choosing "
          "`fixed_camera`'s values), scores pooled over the seeds.\n")
    for width, height in ((640, 480), (768, 576)):
        scenes = [make_scene("pedestrians", seed, width, height, 150)
                  for seed in range(PEDESTRIAN_SEEDS, PEDESTRIAN_SEEDS + seeds)]
        table(f"{width}x{height}", TRACKERS, scenes)


def table(first: str, chains: list[tuple[str, str, list[str]]], scenes: list) -> None:
    """One table: every chain on every scene, scores pooled."""
    print(header(first))
    clips = scene_clips(scenes)
    for label, config, overrides in chains:
        cfg = load_config(config).with_overrides(overrides)
        print(row(label, summed([scored(cfg, frames, gt) for frames, gt in clips])))
    print()


def scene_clips(scenes: list) -> list[tuple[list[Frame], dict]]:
    """Each generated scene as (its frames, its ground-truth tracks by frame)."""
    return [([BgrFrame(i, i / scene.fps, bgr) for i, bgr in enumerate(scene.frames())],
              dict(enumerate(scene.tracks))) for scene in scenes]


def beside_shipped(overrides: list[str], label: str) -> list[tuple[str, Config]]:
    """``fixed_camera`` as shipped and, with ``overrides``, with them (labelled ``label``):
    the columns of a table that puts a change beside the shipped config in the same run."""
    runs = [("`fixed_camera`", [])] + ([(label, overrides)] if overrides else [])
    return [(name, load_config("fixed_camera").with_overrides(changes))
            for name, changes in runs]


def mota_idf1(scores: dict[str, Any]) -> str:
    return f"{scores['mota']:.3f} / {scores['idf1']:.3f}"


# --- 2. MOT_TUD-Campus --------------------------------------------------------------------------


def tud_frames(folder: Path) -> Iterator[Frame]:
    for index, path in enumerate(sorted((folder / "img").glob("*.jpg"))):
        yield BgrFrame(index, index / 25.0, cv2.imread(str(path)))


def detection_scores(gt: dict[int, list[tuple[int, Box]]], found: dict[int, list[Box]],
                     frames: range) -> tuple[float, float, int]:
    """Precision, recall (one-to-one matching at IoU >= 0.5, per frame) and detections."""
    hits = total_found = total_gt = 0
    for frame in frames:
        truth = [b for _, b in gt.get(frame, [])]
        boxes = found.get(frame, [])
        total_gt += len(truth)
        total_found += len(boxes)
        if truth and boxes:
            overlap = np.array([[iou(t, b) for b in boxes] for t in truth])
            rows, cols = linear_sum_assignment(-overlap)
            hits += int((overlap[rows, cols] >= MATCH_IOU).sum())
    return hits / max(total_found, 1), hits / max(total_gt, 1), total_found


def tud(folder: Path) -> None:
    gt = read_mot(folder / "gt.txt")
    frames = len(list((folder / "img").glob("*.jpg")))
    print(f"## MOT_TUD-Campus ({frames} frames, 640x480, static camera, "
          f"{len({i for rows in gt.values() for i, _ in rows})} pedestrians)\n")
    print("### Detections: background subtraction vs the public `det.txt`\n")
    print("Frames 31..71 (after the 30 frames the shipped mean background learns from); a box "
          "counts when it overlaps a ground-truth box one to one with IoU >= 0.5.\n")
    print("| detector | precision | recall | boxes |\n|---|---:|---:|---:|")
    after = range(30, frames)
    public = read_mot_detections(folder / "det.txt")
    for threshold in (0.0, 30.0):
        kept = {f: [b for b, s in rows if s >= threshold] for f, rows in public.items()}
        p, r, n = detection_scores(gt, kept, after)
        print(f"| public det.txt, score >= {threshold:g} | {p:.3f} | {r:.3f} | {n} |")
    for label, overrides in DETECTORS:
        cfg = parse_config({"stage": [{"name": "background"}, {"name": "blobs"}]}, "bench")
        cfg = cfg.with_overrides(overrides)
        stages = cfg.build()
        found: dict[int, list[Box]] = {}
        for result, detections in _detections(stages, tud_frames(folder)):
            found[result] = [d.box for d in detections]
        p, r, n = detection_scores(gt, found, after)
        print(f"| background {label} | {p:.3f} | {r:.3f} | {n} |")
    grouped: dict[int, list[tuple[Box, float]]] = {}
    for result, detections in _detections(load_config("fixed_camera").build(),
                                          tud_frames(folder)):
        grouped[result] = [(d.box, d.score) for d in detections]
    for threshold in (0.0, 0.5):
        kept = {f: [b for b, s in rows if s >= threshold] for f, rows in grouped.items()}
        p, r, n = detection_scores(gt, kept, after)
        print(f"| `fixed_camera` (`group_blobs`), score >= {threshold:g} | {p:.3f} | {r:.3f} "
              f"| {n} |")
    print()
    print("### Trackers\n")
    print(header("chain"))
    det = folder / "det.txt"
    chains = [(label, load_config(c).with_overrides(o)) for label, c, o in TRACKERS]
    chains.append(("S4 per track `s4_multi` + MOG2, cleaned (as above)",
                   load_config("s4_multi").with_overrides(CLEANED + ["kalman_tracks.gate=40"])))
    for tracker in ("mht", "kalman_tracks"):
        for gate in (20.0, 40.0):
            chains.append((
                f"public det.txt -> `{tracker}` (gate {gate:g})",
                parse_config({"stage": [{"name": "mot_detections", "path": str(det)},
                                        {"name": tracker, "gate": gate}]}, "bench"),
            ))
    chains.append((
        "public det.txt -> `byte_tracks` (high 30, low 0: DPM's scale)",
        parse_config({"stage": [{"name": "mot_detections", "path": str(det), "min_score": -1e6},
                                {"name": "byte_tracks", "high": 30.0, "low": 0.0}]}, "bench"),
    ))
    images = list(tud_frames(folder))
    for label, cfg in chains:
        print(row(label, scored(cfg, images, gt)))
    print()


def tud_variants(folder: Path) -> list[tuple[str, list[Frame], dict]]:
    """MOT_TUD-Campus as eight clips of the same footage: decoded by OpenCV and by PyAV (as
    ``vtrack run`` reads it), as it is and mirrored left to right, from its first frame and
    from its eleventh; each with its ground truth moved to match."""
    gt = read_mot(folder / "gt.txt")
    decoded = {"OpenCV": [frame.bgr() for frame in tud_frames(folder)],
               "PyAV": [read_image(path) for path in list_images(folder / "img")]}
    width = decoded["OpenCV"][0].shape[1]
    clips = []
    for decoder, images in decoded.items():
        for mirrored in (False, True):
            for start in (0, 10):
                frames: list[Frame] = [
                    BgrFrame(i, i / 25.0, np.ascontiguousarray(image[:, ::-1]) if mirrored
                             else image) for i, image in enumerate(images[start:])]
                truth = {index - start: [(i, Box(width - b.x - b.w, b.y, b.w, b.h)
                                          if mirrored else b) for i, b in rows]
                         for index, rows in gt.items() if index >= start}
                label = f"{decoder}{', mirrored' if mirrored else ''}, from frame {start + 1}"
                clips.append((label, frames, truth))
    return clips


def variants(folder: Path, overrides: list[str]) -> None:
    """``fixed_camera`` (and with ``overrides``) on each of :func:`tud_variants`, pooled."""
    clips = tud_variants(folder)
    print("### `fixed_camera` on eight variants of MOT_TUD-Campus\n")
    runs = beside_shipped(overrides, f"`fixed_camera --set {' '.join(overrides)}`")
    print("| variant | " + " | ".join(f"{label}: MOTA / IDF1" for label, _ in runs) + " |")
    print("|---|" + "---:|" * len(runs))
    pooled: list[list[dict[str, Any]]] = [[] for _ in runs]
    for label, frames, truth in clips:
        cells = []
        for k, (_, config) in enumerate(runs):
            scores = scored(config, frames, truth)
            pooled[k].append(scores)
            cells.append(mota_idf1(scores))
        print(f"| {label} | " + " | ".join(cells) + " |")
    print("| **pooled** | " + " | ".join(
        f"**{mota_idf1(t)}** (FP {t['false_positives']}, FN {t['misses']}, ID sw. "
        f"{t['id_switches']})" for t in map(summed, pooled)) + " |\n")


#: ``sizes``: frame sizes, and people's heights (near the top, near the bottom of the walkway;
#: shares of the frame height: the generator's own first).
FRAME_SIZES = ((320, 240), (768, 576), (1280, 720))
PEOPLE_HEIGHTS = ((pedestrians.FAR_HEIGHT, pedestrians.NEAR_HEIGHT), (0.12, 0.27), (0.07, 0.15))
SIZES_SEEDS = 300


def sizes(seeds: int, overrides: list[str]) -> None:
    """``fixed_camera`` (and with ``overrides``) on ``pedestrians`` at each of
    ``FRAME_SIZES`` x ``PEOPLE_HEIGHTS``, pooled over the seeds."""
    runs = beside_shipped(overrides, f"`--set {' '.join(overrides)}`")
    print(f"### `fixed_camera` on `pedestrians` of other sizes (seeds {SIZES_SEEDS}.."
          f"{SIZES_SEEDS + seeds - 1}, 150 frames, pooled)\n")
    print("| frame | people's height (share of the frame) | "
          + " | ".join(f"{label}: MOTA / IDF1" for label, _ in runs) + " |")
    print("|---|---|" + "---:|" * len(runs))
    pooled: list[list[dict[str, Any]]] = [[] for _ in runs]
    generator = (pedestrians.FAR_HEIGHT, pedestrians.NEAR_HEIGHT)
    try:
        for width, height in FRAME_SIZES:
            for far, near in PEOPLE_HEIGHTS:
                # the generator's heights are module constants: set for this draw only
                pedestrians.FAR_HEIGHT, pedestrians.NEAR_HEIGHT = far, near
                scenes = [make_scene("pedestrians", seed, width, height, 150)
                          for seed in range(SIZES_SEEDS, SIZES_SEEDS + seeds)]
                clips = scene_clips(scenes)
                cells = []
                for k, (_, config) in enumerate(runs):
                    parts = [scored(config, frames, gt) for frames, gt in clips]
                    pooled[k].extend(parts)
                    cells.append(mota_idf1(summed(parts)))
                print(f"| {width}x{height} | {far}-{near} | " + " | ".join(cells) + " |")
    finally:
        pedestrians.FAR_HEIGHT, pedestrians.NEAR_HEIGHT = generator
    print("| **pooled** | | " + " | ".join(
        f"**{mota_idf1(t)}**" for t in map(summed, pooled)) + " |\n")


#: ``people``: the randomised pedestrians from the seeds after those of ``generated``'s table.
PEOPLE_SEEDS = 205


def people(seeds: int, overrides: list[str]) -> None:
    """``fixed_camera`` (and with ``overrides``) on ``pedestrians`` at 640x480 and 768x576,
    one row per seed, then the mean over the seeds: a change whose pooled score moves by a few
    hundredths on five seeds is told from one seed's identity swap here."""
    runs = beside_shipped(overrides, f"`--set {' '.join(overrides)}`")
    last = PEOPLE_SEEDS + seeds - 1
    print(f"### `fixed_camera` on `pedestrians`, seed by seed (seeds {PEOPLE_SEEDS}..{last}, "
          "150 frames)\n")
    print("| frame | seed | " + " | ".join(f"{label}: MOTA / IDF1 (ID sw.)" for label, _ in runs)
          + " |")
    print("|---|---|" + "---:|" * len(runs))
    for width, height in ((640, 480), (768, 576)):
        per_run: list[list[dict[str, Any]]] = [[] for _ in runs]
        for seed in range(PEOPLE_SEEDS, PEOPLE_SEEDS + seeds):
            ((frames, truth),) = scene_clips([make_scene("pedestrians", seed, width, height,
                                                         150)])
            cells = []
            for k, (_, config) in enumerate(runs):
                scores = scored(config, frames, truth)
                per_run[k].append(scores)
                cells.append(f"{mota_idf1(scores)} ({scores['id_switches']})")
            print(f"| {width}x{height} | {seed} | " + " | ".join(cells) + " |")
            sys.stdout.flush()
        means = [" / ".join(f"{sum(s[key] for s in scores) / len(scores):.3f}"
                            for key in ("mota", "idf1"))
                 + f" ({sum(s['id_switches'] for s in scores)})" for scores in per_run]
        print(f"| {width}x{height} | **mean per seed** | " + " | ".join(means) + " |")
    print()


#: ``vehicles``: the seeds ``fixed_camera``'s learning of wide targets was chosen on, and the
#: held-out ones it was confirmed on.
VEHICLE_SEEDS = {"chosen on": 0, "held out": 100}


def vehicles(seeds: int, overrides: list[str]) -> None:
    """``fixed_camera`` (and with ``overrides``) and ``s4_multi`` on the ``vehicles`` scene
    (and the ``street`` scene, people and vehicles mixed) at 640x480, seeds 0 .. SEEDS-1 and
    100 .. 100+SEEDS-1, scores pooled over the seeds; one row per scene and seed group."""
    runs = [*beside_shipped(overrides, f"`--set {' '.join(overrides)}`"),
            ("`s4_multi`", load_config("s4_multi"))]
    print("### Wide targets: `vehicles` (height/width 0.3-0.8) and `street` (people and "
          "vehicles), 640x480, 150 frames, pooled\n")
    print("| scene | seeds | " + " | ".join(f"{label}: MOTA / IDF1 (ID sw.)" for label, _ in runs)
          + " |")
    print("|---|---|" + "---:|" * len(runs))
    for scene in ("vehicles", "street"):
        for group, first in VEHICLE_SEEDS.items():
            clips = scene_clips([make_scene(scene, seed, 640, 480, 150)
                                 for seed in range(first, first + seeds)])
            cells = []
            for _, config in runs:
                total = summed([scored(config, frames, truth) for frames, truth in clips])
                cells.append(f"{mota_idf1(total)} ({total['id_switches']})")
            print(f"| {scene} | {first}..{first + seeds - 1} ({group}) | "
                  + " | ".join(cells) + " |")
            sys.stdout.flush()
    print()


def _contexts(stages: list[Stage], frames: Iterator[Frame]) -> Iterator[TrackContext]:
    """Run stages; the shared context after each frame (the same object, updated)."""
    ctx = None
    for frame in frames:
        if ctx is None:
            ctx = TrackContext(frame=frame, seed=0)
        ctx.new_frame(frame)
        for stage in stages:
            (stage.start if frame.index == 0 else stage.step)(ctx)
        yield ctx


def _detections(stages: list[Stage], frames: Iterator[Frame]) -> Iterator[tuple[int, list]]:
    """Run stages; each frame's index and its detections after the last stage that makes them
    (a tracker after them reads them and leaves them as they are)."""
    for ctx in _contexts(stages, frames):
        yield ctx.frame.index, ctx.detections


# --- 3. cost at 1080p ---------------------------------------------------------------------------


def synthetic_1080p(targets: int, clutter: int, frames: int, seed: int = 0) -> list[Frame]:
    """Grey 1920x1080 frames: a dark textured background with sensor noise, ``targets`` bright
    discs (radius 6-10 px) moving at 2-8 px/frame and bouncing off the borders, and ``clutter``
    bright 3x3 specks at random places each frame."""
    rng = np.random.default_rng(seed)
    h, w = 1080, 1920
    base = cv2.GaussianBlur(rng.normal(30, 12, (h, w)).astype(np.float32), (0, 0), 8) + 30
    position = rng.uniform((50, 50), (w - 50, h - 50), (targets, 2))
    velocity = rng.uniform(2, 8, (targets, 2)) * rng.choice((-1, 1), (targets, 2))
    radius = rng.uniform(6, 10, targets)
    out = []
    for index in range(frames):
        grey = base + rng.normal(0, 4, (h, w)).astype(np.float32)
        image = np.clip(grey, 0, 255).astype(np.uint8)
        for (x, y), r in zip(position, radius, strict=True):
            cv2.circle(image, (int(x), int(y)), int(r), 200, -1, cv2.LINE_AA)
        for x, y in rng.uniform((0, 0), (w - 3, h - 3), (clutter, 2)).astype(int):
            image[y : y + 3, x : x + 3] = 190
        out.append(GrayFrame(index, index / 60.0, image))
        position += velocity
        bounce = (position < 30) | (position > (w - 30, h - 30))
        velocity[bounce] *= -1
    return out


def cost(frames: int = 40, repeats: int = 3) -> None:
    print(f"## Cost per frame at 1080p (microseconds per stage, grey frames; best of {repeats} "
          f"runs over {frames} frames)\n")
    chains = [("s3", load_config("s3")), ("s4_multi", load_config("s4_multi")),
              ("s4_multi + MOG2", load_config("s4_multi").with_overrides(
                  ["background.method=mog2"])),
              ("fixed_camera (small)", load_config("fixed_camera").with_overrides(SMALL))]
    names = ("threshold", "background", "blobs", "group_blobs", "mht", "kalman_tracks",
             "byte_tracks")
    print("| targets | clutter/frame | chain | " + " | ".join(names) + " | total | tracks |")
    print("|---:|---:|---|" + "---:|" * (len(names) + 2))
    for targets in (4, 16, 64):
        for clutter in (0, 100):
            clip = synthetic_1080p(targets, clutter, frames)
            for label, cfg in chains:
                best: dict[str, float] = {}
                for _ in range(repeats):
                    started = time.perf_counter()
                    results, pipeline = run_chain(cfg, iter(clip))
                    wall = (time.perf_counter() - started) * 1e6 / len(clip)
                    timing = {**pipeline.stage_microseconds_per_frame(), "total": wall}
                    best = {k: min(v, best.get(k, v)) for k, v in timing.items()}
                cells = [f"{best[n]:.0f}" if n in best else "" for n in (*names, "total")]
                written = sum(t.state == TrackStatus.CONFIRMED for t in results[-1].tracks)
                print(f"| {targets} | {clutter} | {label} | " + " | ".join(cells)
                      + f" | {written} |")
    print()


# --- 4. whole processes -------------------------------------------------------------------------


def whole_processes() -> None:
    print(f"## Whole processes: `vtrack run --no-video` on H.264 `pedestrians` clips (best of "
          f"{ROUNDS})\n")
    print("Frames per second of wall time, start-up included; `decode only` is a PyAV process "
          "reading every frame with the same threads (speed.py's A').\n")
    print("| clip | frames | process | fps | x decode-only |\n|---|---:|---|---:|---:|")
    WORK.mkdir(exist_ok=True)
    for width, height, frames in ((768, 576, 500), (1920, 1080, 300)):
        clip = WORK / f"pedestrians_{width}x{height}_{frames}.mp4"
        if not clip.exists():
            write_video(make_scene("pedestrians", PEDESTRIAN_SEEDS, width, height, frames),
                        clip, crf=23, preset="medium")
        threads = str(decoder_threads(width, height, cpu_count()))
        decode = min(python_baseline(DECODE_THREADS, [str(clip), threads], frames, "decode")
                     for _ in range(ROUNDS))
        print(f"| {width}x{height} | {frames} | decode only | {frames / decode:.1f} | 1.00 |")
        for config in ("fixed_camera", "fixed_camera --set background.max_pixels=40000",
                       "s4_multi"):
            args = [str(clip), "-c", *config.split(), "--no-video"]
            seconds = min(vtrack_run(args, frames, config)[0] for _ in range(ROUNDS))
            print(f"| {width}x{height} | {frames} | `vtrack run -c {config} --no-video` | "
                  f"{frames / seconds:.1f} | {decode / seconds:.2f} |")
    print()


def main(argv: list[str]) -> None:
    overrides = [argv[i + 1] for i, arg in enumerate(argv[:-1]) if arg == "--set"]
    words = [arg for i, arg in enumerate(argv) if arg != "--set"
             and (i == 0 or argv[i - 1] != "--set")]
    seeds = seeds_argument(words, 5, __doc__)
    sections = words[1:] or list(SECTIONS)
    unknown = [name for name in sections if name not in SECTIONS]
    if unknown:
        raise SystemExit(f"multi_bench.py: no section {unknown[0]!r}; the sections: "
                         f"{', '.join(SECTIONS)}")
    for name in sections:
        SECTIONS[name](seeds, overrides)


def on_tud(measure: Callable[[Path], None]) -> None:
    """``measure`` MOT_TUD-Campus (``../shared/data`` or ``$VTRACK_DATA``), or say it is not
    there."""
    root = data_dir()
    folder = root / "MOT_TUD-Campus" if root else None
    if folder is not None and (folder / "gt.txt").is_file():
        measure(folder)
    else:
        print("(MOT_TUD-Campus not found: skipped)\n")


# --- 2b. MOTChallenge footage outside ../shared/data ---------------------------------------------


def mot_sequence(folder: Path) -> tuple[list[Frame], dict[int, list[tuple[int, Box]]]]:
    """A MOTChallenge sequence as ``vtrack run`` reads it: its frames (``img1/`` or ``img/``,
    at ``seqinfo.ini``'s frame rate, or the folder's one video file) and its ground truth
    (``gt/gt.txt`` or ``gt.txt``)."""
    truths = [path for path in (folder / "gt" / "gt.txt", folder / "gt.txt") if path.is_file()]
    if not truths:
        raise SystemExit(f"{folder}: no gt/gt.txt or gt.txt")
    images = [folder / name for name in ("img1", "img") if (folder / name).is_dir()]
    videos = sorted(path for path in folder.iterdir()
                    if path.suffix.lower() in VIDEO_SUFFIXES)
    if images:
        info = configparser.ConfigParser()
        info.read(folder / "seqinfo.ini")  # MOTChallenge's [Sequence] frameRate; none: 30 fps
        spec, fps = str(images[0]), info.getfloat("Sequence", "frameRate", fallback=None)
    elif videos:
        spec, fps = str(videos[0]), None
    else:
        raise SystemExit(f"{folder}: no img1/, img/ or video file")
    with open_source(spec, fps=fps) as source:
        frames: list[Frame] = [BgrFrame(frame.index, frame.time_s, frame.bgr().copy())
                               for frame in source]
    return frames, read_mot(truths[0])


def outside(overrides: list[str]) -> None:
    """Every tracker on pixels (and ``fixed_camera`` with ``overrides``) on each
    MOTChallenge sequence of ``$VTRACK_MOT`` (folders, separated as in ``PATH``): footage its
    values were never chosen on."""
    folders = [Path(path) for path in os.environ.get("VTRACK_MOT", "").split(os.pathsep) if path]
    if not folders:
        print("(VTRACK_MOT names no MOTChallenge sequence: skipped)\n")
        return
    chains = TRACKERS + ([(f"`fixed_camera --set {' '.join(overrides)}`", "fixed_camera",
                           overrides)] if overrides else [])
    for folder in folders:
        frames, truth = mot_sequence(folder)
        height, width = frames[0].height, frames[0].width
        print(f"### {folder.name} ({len(frames)} frames, {width}x{height}, "
              f"{len({i for rows in truth.values() for i, _ in rows})} people)\n")
        print(header("tracker"))
        for label, config, changes in chains:
            print(row(label, scored(load_config(config).with_overrides(changes), frames, truth)))
        print()
        boxes_found(folder.name, [c for c in chains if c[1] == "fixed_camera"], frames, truth)


def boxes_found(name: str, chains: list[tuple[str, str, list[str]]], frames: list[Frame],
                truth: dict[int, list[tuple[int, Box]]]) -> None:
    """Where ``fixed_camera``'s misses come from on one sequence: its detections (all, and
    those scoring >= 0.5, which may start tracks) and its confirmed tracks, each as precision
    / recall of boxes at IoU >= 0.5 (one to one per frame, no identities); then the
    ground-truth boxes whose best detection overlaps them by IoU 0.2-0.5 (found, but boxed
    wrong), with that detection's median width and height relative to the truth."""
    print(f"{name}, boxes one to one per frame (IoU >= 0.5) - detections, then confirmed "
          "tracks; near misses: ground-truth boxes whose best detection has IoU 0.2-0.5, "
          "and its median width / height relative to them\n")
    print("| config | detections P / R | score >= 0.5 P / R | tracks P / R "
          "| near misses | width, height x truth |\n|---|---:|---:|---:|---:|---:|")
    every = range(len(frames))
    for label, config, changes in chains:
        found: dict[int, list[tuple[Box, float]]] = {}
        tracks: dict[int, list[Box]] = {}
        for ctx in _contexts(load_config(config).with_overrides(changes).build(), iter(frames)):
            index = ctx.frame.index
            found[index] = [(d.box, d.score) for d in ctx.detections]
            tracks[index] = [t.box for t in ctx.tracks if t.state == TrackStatus.CONFIRMED]
        cells = []
        for boxes in ({f: [b for b, _ in rows] for f, rows in found.items()},
                      {f: [b for b, s in rows if s >= 0.5] for f, rows in found.items()},
                      tracks):
            precision, recall, _ = detection_scores(truth, boxes, every)
            cells.append(f"{precision:.3f} / {recall:.3f}")
        near = []
        for index, rows in truth.items():
            for _, box in rows:
                overlaps = [iou(box, b) for b, _ in found.get(index, [])]
                best = int(np.argmax(overlaps)) if overlaps else -1
                if overlaps and 0.2 <= overlaps[best] < MATCH_IOU:
                    b = found[index][best][0]
                    near.append((b.w / box.w, b.h / box.h))
        shape = ("-" if not near else
                 ", ".join(f"{v:.2f}" for v in np.median(np.array(near), axis=0)))
        print(f"| {label} | {' | '.join(cells)} | {len(near)} | {shape} |")
    print()


#: The sections, in order, each given the seeds and the ``--set`` overrides; ``python
#: multi_bench.py SEEDS NAME...`` prints only those named.
SECTIONS: dict[str, Callable[[int, list[str]], None]] = {
    "generated": lambda seeds, overrides: generated(seeds),
    "tud": lambda seeds, overrides: on_tud(tud),
    "variants": lambda seeds, overrides: on_tud(lambda folder: variants(folder, overrides)),
    "outside": lambda seeds, overrides: outside(overrides),
    "sizes": sizes,
    "people": people,
    "vehicles": vehicles,
    "cost": lambda seeds, overrides: cost(),
    "processes": lambda seeds, overrides: whole_processes(),
}


if __name__ == "__main__":
    main(sys.argv[1:])
