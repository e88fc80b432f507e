"""A box that leaves the frame for good ends ``lost`` after OFF_FRAME_FRAMES frames (issue 11
item 8): one pipeline rule for every single-target tracker."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from vtrack.cli import main
from vtrack.geometry import Box
from vtrack.pipeline import OFF_FRAME_FRAMES
from vtrack.scenes import make_scene

W, H = 160, 120


@pytest.fixture(scope="module")
def gone(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Box]:
    """The ``cover`` scene until the panel hides the moving target, then an empty white frame
    for 80 frames: a tracker that coasts on its motion model carries the box out of the frame
    and never sees the target again. Raw bgr24 frames, so no encoder is involved."""
    scene = make_scene("cover", 0, W, H, 60, 30)
    hidden = scene.events["occluded"][0]
    frames = [scene.frame(i) for i in range(hidden + 4)]
    frames += [np.full_like(frames[0], 250)] * 80
    path = tmp_path_factory.mktemp("gone") / "gone.raw"
    path.write_bytes(b"".join(np.ascontiguousarray(f).tobytes() for f in frames))
    first = scene.boxes[0]
    assert first is not None
    return path, first


def rows(out: Path) -> list[dict[str, str]]:
    with (out / "track.csv").open(newline="") as handle:
        return list(csv.DictReader(handle))


def outside(row: dict[str, str]) -> bool:
    box = Box(*(float(row[k]) for k in ("x", "y", "w", "h")))
    return box.outside(W, H)


@pytest.mark.parametrize("config", ["s2", "s0", "camshift", "s1", "s4"])
def test_a_box_outside_the_frame_ends_lost(gone: tuple[Path, Box], tmp_path: Path,
                                           config: str) -> None:
    path, box = gone
    out = tmp_path / "out"
    result = CliRunner().invoke(main, [
        "run", str(path), "--raw", f"{W}x{H}", "-c", config,
        "--init", f"{box.x},{box.y},{box.w},{box.h}", "--no-video", "-o", str(out)])
    assert result.exit_code == 0, result.output
    table = rows(out)
    run = longest = 0  # frames in a row with a claimed box entirely outside the frame
    for row in table:  # a run longer than OFF_FRAME_FRAMES would have ended lost
        if row["x"] == "":
            assert row["state"] == "lost"  # no box claimed only when lost
            run = 0
            continue
        assert row["state"] != "lost"
        run = run + 1 if outside(row) else 0
        longest = max(longest, run)
    assert longest <= OFF_FRAME_FRAMES
    if config == "s2":
        # S2 coasts on its CA model behind the panel and out of the frame: the rule fired, and
        # the run ends lost with no box beyond the frame.
        assert longest == OFF_FRAME_FRAMES
        assert table[-1]["state"] == "lost" and table[-1]["x"] == ""
        assert "lost 0" not in result.output
