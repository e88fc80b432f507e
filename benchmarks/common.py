"""What the benchmark scripts share: where the real sequences are, and running a config on one.

The real sequences live outside the project (``../shared/data`` beside the checkout, or the folder
named by ``VTRACK_DATA``); every benchmark skips them when they are absent.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from vtrack.config import Config, load_config
from vtrack.evaluate.groundtruth import read_boxes
from vtrack.frame import BgrFrame, Frame, I420Frame
from vtrack.geometry import Box
from vtrack.pipeline import FrameResult, Pipeline
from vtrack.run import RunRequest, RunSummary, run, versions
from vtrack.scenes import make_scene

REPO = Path(__file__).resolve().parent.parent


def data_dir() -> Path | None:
    """The folder of real benchmark sequences, or None when this machine has none."""
    candidates = [os.environ.get("VTRACK_DATA"), REPO.parent / "shared" / "data"]
    for candidate in candidates:
        if candidate and Path(candidate).is_dir():
            return Path(candidate)
    return None


#: The data folder's check sequences (its README): measured to confirm a choice made on the
#: others (the tune sequences), never to make it.
CHECK_SEQUENCES = frozenset({
    "DTB70_Surfing06", "LaSOT_airplane-1", "OTB_Freeman1", "OTB_KiteSurf", "OTB_Walking2",
    "PTBTIR_airplane", "UAV123_bike1", "UAV123_group1_1", "VOTLT_yamaha", "VOT_bag"})


@dataclass(frozen=True)
class Sequence:
    """A single-target sequence: an ``img/`` folder and its ``groundtruth.txt`` (1-based boxes)."""

    name: str
    folder: Path
    groundtruth: Path


def single_target_sequences() -> list[Sequence]:
    """Every single-target sequence of the data folder (empty when there is none)."""
    root = data_dir()
    if root is None:
        return []
    found = []
    for folder in sorted(root.iterdir()):
        gt = folder / "groundtruth.txt"
        if (folder / "img").is_dir() and gt.is_file() and not (folder / "gt.txt").exists():
            found.append(Sequence(folder.name, folder, gt))
    return found


def run_sequence(seq: Sequence, config: str | Config, seed: int = 0,
                 overrides: list[str] | None = None) -> RunSummary:
    """Run a config on a real sequence the way ``vtrack run`` does (no video), return its summary.

    Ground truth of these sequences is 1-based (OTB/VOT/UAV MATLAB convention): ``gt_origin=1``.
    """
    cfg = load_config(config) if isinstance(config, str) else config
    if overrides:
        cfg = cfg.with_overrides(overrides)
    with tempfile.TemporaryDirectory() as tmp:
        return run(RunRequest(input=str(seq.folder), out_dir=Path(tmp), config=cfg,
                              gt_path=seq.groundtruth, gt_origin=1, video=False, seed=seed))


@dataclass(frozen=True)
class Clip:
    """Frames (BGR arrays) and ground truth of one sequence held in memory, for fast repeated
    runs; ``boxes[0]`` starts the tracker."""

    name: str
    frames: list[np.ndarray]
    boxes: list[Box | None]


def load_clip(seq: Sequence) -> Clip:
    """A real sequence: its ``img/`` frames read once with ``cv2.imread``, 1-based ground truth."""
    paths = sorted(p for p in (seq.folder / "img").iterdir() if p.suffix in (".jpg", ".png"))
    frames = [cv2.imread(str(p), cv2.IMREAD_COLOR) for p in paths]
    return Clip(seq.name, frames, list(read_boxes(seq.groundtruth, origin=1)[: len(frames)]))


def scene_clip(name: str, seed: int) -> Clip:
    """The generated scene ``name`` drawn with ``seed`` at its default size and length (320x240,
    150 frames for most; ``accelerate`` 640x240, 25 frames), 30 fps."""
    scene = make_scene(name, seed=seed, fps=30)
    return Clip(name, list(scene.frames()), scene.boxes)


def clip_results(clip: Clip, config: Config, seed: int = 0) -> tuple[Pipeline, list[FrameResult]]:
    """The pipeline and its result on every frame of ``clip`` (30 fps BGR frames, tracker
    seeded with ``seed``), started on the first ground-truth box."""
    pipeline = Pipeline(config.build(), seed=seed)
    frames = (BgrFrame(i, i / 30.0, bgr) for i, bgr in enumerate(clip.frames))
    assert clip.boxes[0] is not None
    return pipeline, list(pipeline.track(frames, clip.boxes[0]))


def track_clip(clip: Clip, config: Config, seed: int = 0) -> list[Box | None]:
    """The boxes ``config`` claims on every frame of ``clip`` (see :func:`clip_results`); None
    where it claims none."""
    return [result.box for result in clip_results(clip, config, seed)[1]]


def to_frame(index: int, fps: float, bgr: np.ndarray, layout: str = "I420") -> Frame:
    """A rendered BGR image as the pipeline receives it: ``"I420"`` (what a decoded video hands
    over, converted here, outside any timed call) or ``"BGR"``."""
    if layout == "I420":
        return I420Frame(index, index / fps, cv2.cvtColor(bgr, cv2.COLOR_BGR2YUV_I420))
    return BgrFrame(index, index / fps, bgr)


def process_env() -> dict[str, str]:
    """The environment of every timed process: this checkout first on ``PYTHONPATH``, and
    bytecode caches used as a default Python uses them (an inherited PYTHONDONTWRITEBYTECODE
    would make every vtrack process compile its modules again: not what a user's install does)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH")) if p))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def machine() -> str:
    """One line naming this machine and the versions that shape a measurement."""
    v = versions()
    return (f"Machine: {os.cpu_count()} cores, {v['platform']}; vtrack {v['vtrack']}, "
            f"Python {v['python']}, OpenCV {v['opencv']}, NumPy {v['numpy']}, PyAV {v['pyav']} "
            f"(FFmpeg {v['ffmpeg']}, libavcodec {v['libavcodec']})")


def seeds_argument(argv: list[str], default: int, usage: str | None) -> int:
    """The optional first argument SEEDS of a benchmark run as ``script [SEEDS] ...``
    (``argv`` without the script's name): ``--help`` prints ``usage`` and exits; anything but
    a positive whole number is a one-line error."""
    script = Path(sys.argv[0]).name
    if {"-h", "--help"} & set(argv):
        print(usage or f"python benchmarks/{script} [SEEDS]")
        raise SystemExit(0)
    if not argv:
        return default
    if not argv[0].isdigit() or int(argv[0]) < 1:
        raise SystemExit(f"{script}: SEEDS must be a positive whole number, got {argv[0]!r} "
                         "(--help for the usage)")
    return int(argv[0])


def no_arguments(usage: str | None) -> None:
    """For a benchmark that takes no arguments: ``--help`` prints ``usage`` and exits, any
    argument is a one-line usage error (argparse's)."""
    argparse.ArgumentParser(description=usage,
                            formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
