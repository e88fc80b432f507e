"""What the benchmark scripts share: where the real sequences are, and running a config on one.

The real sequences live outside the project (``../shared/data`` beside the checkout, or the folder
named by ``VTRACK_DATA``); every benchmark skips them when they are absent.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

from vtrack.config import Config, load_config
from vtrack.run import RunRequest, RunSummary, run

REPO = Path(__file__).resolve().parent.parent


def data_dir() -> Path | None:
    """The folder of real benchmark sequences, or None when this machine has none."""
    candidates = [os.environ.get("VTRACK_DATA"), REPO.parent / "shared" / "data"]
    for candidate in candidates:
        if candidate and Path(candidate).is_dir():
            return Path(candidate)
    return None


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
