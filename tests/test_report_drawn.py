"""Which runs of an input the report draws over time when it cannot draw them all."""

from __future__ import annotations

import csv
import html
import re
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from click.testing import CliRunner, Result

from vtrack.cli import main

if TYPE_CHECKING:
    from conftest import ClipFactory

CONFIGS = ("s0", "camshift", "s1", "s2", "s0-fixed", "s2-fixed", "s4", "robust")
DRAWN = 6  # vtrack.report.plots.MAX_RUNS_DRAWN


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def test_an_input_with_more_runs_than_drawn_draws_its_best_and_worst_by_auc(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """8 configs over one clip: the overlap plot and the failure frames drew the first 6 by
    configuration name (camshift, robust, s0, s0-fixed, s1, s2), whatever they scored, and the
    note said only "the first by configuration name". They draw the 3 best and the 3 worst
    by AUC now, and the note names them with their AUC, and the runs not drawn (by AUC)."""
    clip = clip_factory("occlusion", width=160, height=120, frames=60)
    inputs = tmp_path / "in"
    inputs.mkdir()
    shutil.copy(clip.path, inputs / "occ.mp4")
    shutil.copy(clip.gt, inputs / "occ.gt.txt")
    out = tmp_path / "results"
    args = [arg for config in CONFIGS for arg in ("-c", config)]
    done = vtrack("batch", str(inputs), *args, "--no-video", "--out", str(out))
    assert done.exit_code == 0, done.output
    done = vtrack("report", str(out), "--out", str(tmp_path / "report"))
    assert done.exit_code == 0, done.output

    with (tmp_path / "report" / "summary.csv").open(newline="") as handle:
        auc = {row["config"]: float(row["auc"]) for row in csv.DictReader(handle)}
    ranked = sorted(CONFIGS, key=lambda config: (-auc[config], config))
    best, worst, left_out = ranked[:3], ranked[-3:], ranked[3:-3]
    assert sorted(CONFIGS)[:DRAWN] != sorted(best + worst)  # (the old choice, by name)

    page = html.unescape((tmp_path / "report" / "index.html").read_text())
    (note,) = re.findall(r'<p class="note">([^<]*)</p>', page)

    def named(configs: list[str]) -> str:
        return ", ".join(f"{config} {auc[config]:.3f}" for config in configs)

    assert note == (
        f"Of the {len(CONFIGS)} scored runs of this input, {DRAWN} are drawn over time and in "
        f"the failure frames (each plot draws at most {DRAWN}): the 3 best and the 3 worst by "
        f"AUC, the range of what was tracked: {named(best)}; and {named(worst)}. Not drawn: "
        f"{named(left_out)}. The success and precision plots draw every scored run; the "
        "tables list them all.")
