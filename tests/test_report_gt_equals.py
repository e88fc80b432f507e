"""``vtrack report --gt INPUT=FILE`` for an input whose name holds ``=``: the suggestion the
report's warning gives works when pasted. A real generated clip."""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from click.testing import CliRunner, Result
from conftest import one_error_line

from vtrack.cli import main
from vtrack.errors import InputError
from vtrack.report.runs import GroundTruth

if TYPE_CHECKING:
    from conftest import ClipFactory


def vtrack(*args: str) -> Result:
    return CliRunner().invoke(main, [*args], catch_exceptions=False)


def test_the_suggested_gt_for_an_input_named_with_equals_works(
        tmp_path: Path, clip_factory: ClipFactory, monkeypatch) -> None:  # noqa: ANN001
    """Probe N: a run of `a=b.mp4` reported with a --gt that does not fit said 'give --gt
    a=b=FILE with its own ground truth'; pasted, `--gt a=b=a=b.gt.txt` was split at the first
    `=` ('b=a=b.gt.txt: cannot read ground-truth file'). Now it is split where the file is."""
    clip = clip_factory("smooth", frames=20)
    monkeypatch.chdir(tmp_path)
    Path("a=b.mp4").write_bytes(Path(clip.path).read_bytes())
    Path("a=b.gt.txt").write_text(Path(clip.gt).read_text())
    lines = Path(clip.gt).read_text().splitlines()
    Path("short.txt").write_text("\n".join(lines[:12]) + "\n")
    result = vtrack("run", "a=b.mp4", "--init", lines[0], "-c", "s0", "--no-video", "-o", "ab",
                    "-q")
    assert result.exit_code == 0, result.output
    result = vtrack("report", "ab", "-o", "r1", "--gt", "short.txt", "-q")
    assert "give --gt a=b=FILE with its own ground truth" in result.stderr, result.stderr
    suggested = shlex.split(result.stderr.split("give --gt ")[-1].split(" with")[0])[0]
    result = vtrack("report", "ab", "-o", "r2", "--gt", suggested.replace("FILE", "a=b.gt.txt"),
                    "-q")
    assert result.exit_code == 0 and result.stderr == "", result.output
    assert "a=b.gt.txt" in Path("r2/summary.csv").read_text()


def test_a_gt_that_reads_two_ways_is_refused(tmp_path: Path, clip_factory: ClipFactory,
                                             monkeypatch) -> None:  # noqa: ANN001
    """`--gt a=b=c.txt` with both `b=c.txt` and `c.txt` there was read silently as input `a`,
    file `b=c.txt` (the first split after which a file is there). Both readings are named in
    one line now (the report, below, with runs of both inputs); with one file there, it is
    read as before."""
    clip = clip_factory("smooth", frames=20)
    monkeypatch.chdir(tmp_path)
    Path("c.txt").write_text(Path(clip.gt).read_text())
    Path("b=c.txt").write_text(Path(clip.gt).read_text())
    with pytest.raises(InputError) as refused:
        GroundTruth.parse("a=b=c.txt")
    assert str(refused.value) == ("--gt a=b=c.txt: reads as input a with file b=c.txt or "
                                  "input a=b with file c.txt, and each file is there; rename "
                                  "b=c.txt")
    assert GroundTruth.parse("a=b=c.txt", names_run=lambda name: name == "a").input == "a"
    Path("b=c.txt").unlink()
    assert GroundTruth.parse("a=b=c.txt").input == "a=b"


def test_a_reading_that_names_no_run_does_not_count(tmp_path: Path, clip_factory: ClipFactory,
                                                    monkeypatch) -> None:  # noqa: ANN001
    """Review of 99ea5ac: input `a=b.mp4` with its ground truth `a=b.gt.txt`, and another
    input's `b.gt.txt` in the same folder: `--gt a=b=a=b.gt.txt` (as the report's warning
    says) was refused as reading also as input `a=b=a` with file `b.gt.txt`, an input no run
    has. Only readings naming a run found count now; two that do are still refused, naming
    those two."""
    clip = clip_factory("smooth", frames=20)
    monkeypatch.chdir(tmp_path)
    for name in ("a=b", "a", "b"):
        Path(f"{name}.mp4").write_bytes(Path(clip.path).read_bytes())
        Path(f"{name}.gt.txt").write_text(Path(clip.gt).read_text())
    first = Path(clip.gt).read_text().splitlines()[0]
    result = vtrack("run", "a=b.mp4", "--init", first, "-c", "s0", "--no-video", "-o", "ab",
                    "-q")
    assert result.exit_code == 0, result.output
    result = vtrack("report", "ab", "-o", "r1", "--gt", "a=b=a=b.gt.txt", "-q")
    assert result.exit_code == 0 and result.stderr == "", result.output
    assert "a=b.gt.txt" in Path("r1/summary.csv").read_text()
    # two readings that each name a run: input a with file b=c.txt, input a=b with c.txt
    Path("c.txt").write_text(Path(clip.gt).read_text())
    Path("b=c.txt").write_text(Path(clip.gt).read_text())
    result = vtrack("run", "a.mp4", "--init", first, "-c", "s0", "--no-video", "-o", "ab/a",
                    "-q")
    assert result.exit_code == 0, result.output
    line = one_error_line(vtrack("report", "ab", "-o", "r2", "--gt", "a=b=c.txt", "-q"))
    assert line == ("vtrack: error: --gt a=b=c.txt: reads as input a with file b=c.txt or "
                    "input a=b with file c.txt, and each file is there; rename b=c.txt"), line
    assert not Path("r2").exists()
