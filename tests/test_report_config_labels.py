"""Configs of one name from different files are labelled by the values that tell them apart."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from click.testing import CliRunner, Result

from vtrack.cli import main

if TYPE_CHECKING:
    from conftest import ClipFactory

SHIPPED = Path(__file__).parents[1] / "vtrack" / "configs" / "s0.toml"


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def labels(markdown: str) -> set[tuple[str, str]]:
    """(input, config) of the rows of the results table of ``summary.md``."""
    table = markdown.split("## Results per input and configuration")[1].split("\n## ")[0]
    rows = [line for line in table.splitlines() if line.startswith("| ")][2:]  # (no header)
    return {tuple(cell.strip() for cell in line.split("|")[1:3]) for line in rows}


def test_two_files_of_one_config_name_in_one_batch_are_labelled_by_their_values(
        clip_factory: ClipFactory, tmp_path: Path) -> None:
    """Two mine.toml, named "mine" both, the second with 10 mean-shift iterations, run into
    one results folder on two inputs (`vtrack batch in-a -c A/mine.toml -o res`, then
    `vtrack batch in-b -c B/mine.toml -o res`): the report labelled them by their first
    folders below the batch, the inputs' own, "mine (smooth)" and "mine (jump)", as if they
    were configs of those inputs. They are labelled by the value that differs now."""
    configs = {}
    for name, iterations in (("A", 1), ("B", 10)):
        (tmp_path / name).mkdir()
        configs[name] = tmp_path / name / "mine.toml"
        configs[name].write_text(SHIPPED.read_text().replace(
            'name = "s0"', 'name = "mine"', 1).replace(
            "\niterations = 1\n", f"\niterations = {iterations}\n", 1))
    results = tmp_path / "res"
    for name, scenario in (("A", "smooth"), ("B", "jump")):
        inputs = tmp_path / f"in-{name}"
        inputs.mkdir()
        clip = clip_factory(scenario, width=160, height=120, frames=40)
        shutil.copy(clip.path, inputs / f"{scenario}.mp4")
        shutil.copy(clip.gt, inputs / f"{scenario}.gt.txt")
        done = vtrack("batch", str(inputs), "-c", str(configs[name]), "--no-video", "--out",
                      str(results))
        assert done.exit_code == 0, done.output
    done = vtrack("report", str(results), "--out", str(tmp_path / "report"))
    assert done.exit_code == 0, done.output
    markdown = (tmp_path / "report" / "summary.md").read_text()
    assert labels(markdown) == {("smooth", "mine (meanshift.iterations=1)"),
                                ("jump", "mine (meanshift.iterations=10)")}
