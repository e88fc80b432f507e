"""Same inputs, same outputs: a digest of every shipped config's CSV on generated scenes.

Runs every shipped config through ``vtrack run --no-video`` (the click command, in this process)
on small generated clips with fixed seeds, and records the sha256 of each ``track.csv`` /
``tracks.csv``. A refactoring that claims "behaviour unchanged" must leave every digest as it is:

    python benchmarks/identical_outputs.py            # compare with identical_outputs.json
    python benchmarks/identical_outputs.py --write    # record new digests (only for a real change)

Clips are raw frames (``bgr24`` or ``yuv420p``), so no encoder can make two runs differ.
Prints a Markdown table; exits 1 when a digest differs from the recorded one.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from click.testing import CliRunner

from vtrack.cli import main
from vtrack.scenes import make_scene, write_clip

RECORD = Path(__file__).with_name("identical_outputs.json")


@dataclass(frozen=True)
class Case:
    """One config on one generated clip."""

    config: str
    scenario: str
    seed: int
    width: int
    height: int
    frames: int
    pix_fmt: str = "yuv420p"

    @property
    def key(self) -> str:
        return (f"{self.config}/{self.scenario}-{self.seed}-{self.width}x{self.height}-"
                f"{self.frames}-{self.pix_fmt}")

    @property
    def multi(self) -> bool:
        return self.config in ("s3", "s4_multi")


CASES: tuple[Case, ...] = (
    Case("s0", "occlusion", 0, 320, 240, 60),
    Case("s0", "smooth", 1, 160, 120, 40, "bgr24"),
    Case("s0", "cover", 2, 160, 120, 60),
    Case("camshift", "smooth", 0, 320, 240, 40),
    Case("camshift", "occlusion", 1, 160, 120, 60, "bgr24"),
    Case("s1", "smooth", 0, 160, 120, 40),
    Case("s1", "leave_return", 1, 160, 120, 60, "bgr24"),
    Case("s2", "scale", 0, 160, 120, 40),
    Case("s2", "occlusion", 1, 320, 240, 60, "bgr24"),
    Case("s2", "cover", 0, 160, 120, 60),
    Case("s3", "multi", 0, 160, 120, 60),
    Case("s3", "multi", 1, 320, 240, 60, "bgr24"),
    Case("s4", "bounce", 0, 160, 120, 80),
    Case("s4", "bounce", 1, 320, 240, 90, "bgr24"),
    Case("s4_multi", "multi", 0, 160, 120, 60),
    Case("s4_multi", "multi", 2, 320, 240, 60, "bgr24"),
)


def digest(case: Case, work: Path) -> str:
    """sha256 of the CSV ``vtrack run --no-video`` writes for ``case`` (clips made in ``work``)."""
    stem = f"{case.scenario}-{case.seed}-{case.width}x{case.height}-{case.frames}-{case.pix_fmt}"
    clip = work / f"{stem}.raw"
    if not clip.exists():  # s3 and s4_multi share their clips
        scene = make_scene(case.scenario, seed=case.seed, width=case.width,
                           height=case.height, frames=case.frames, fps=30.0)
        write_clip(scene, clip, fmt="raw", pix_fmt=case.pix_fmt)
    gt = clip.with_name(f"{stem}.mot.txt" if case.multi else f"{stem}.gt.txt")
    out = work / case.key.replace("/", "_")
    args = ["run", str(clip), "--config", case.config, "--gt", str(gt), "--no-video", "--quiet",
            "--raw", f"{case.width}x{case.height}", "--pix-fmt", case.pix_fmt, "--fps", "30",
            "--out", str(out)]
    result = CliRunner().invoke(main, args, catch_exceptions=False)
    if result.exit_code != 0:
        raise RuntimeError(f"{case.key}: exit {result.exit_code}: {result.output}")
    csv = out / ("tracks.csv" if case.multi else "track.csv")
    return hashlib.sha256(csv.read_bytes()).hexdigest()


def digests(cases: tuple[Case, ...] = CASES) -> dict[str, str]:
    """Digest of every case, by :attr:`Case.key`."""
    with tempfile.TemporaryDirectory() as tmp:
        return {case.key: digest(case, Path(tmp)) for case in cases}


def recorded() -> dict[str, str]:
    """The digests recorded in ``identical_outputs.json``."""
    return json.loads(RECORD.read_text())


def main_(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="record the digests")
    args = parser.parse_args(argv)
    now = digests()
    if args.write:
        RECORD.write_text(json.dumps(now, indent=1, sort_keys=True) + "\n")
    before = recorded()
    print("| case | sha256 (first 16) | same as recorded |")
    print("|---|---|---|")
    for key, value in now.items():
        print(f"| {key} | {value[:16]} | {'yes' if before.get(key) == value else '**NO**'} |")
    return 0 if all(before.get(k) == v for k, v in now.items()) else 1


if __name__ == "__main__":
    sys.exit(main_())
