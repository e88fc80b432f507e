"""Edges of the report's pieces that its usual inputs do not reach: a table group without
rows, as few runs drawn as one, the package's names before its builder is loaded."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import vtrack.report
from vtrack.geometry import Box
from vtrack.report import build, plots
from vtrack.report.pages import _md
from vtrack.report.runs import RunResult
from vtrack.report.tables import Cell, Table, _say_beside, average_table


def test_no_notes_change_no_row() -> None:
    """`_say_beside` with no notes took `table.rows[-0:]`, every row (and failed to pair
    them with no notes); it touches none now."""
    table = Table(["Config", "Tracking miss"], [[Cell("s0"), Cell("0.100")],
                                               [Cell("s1"), Cell("0.200")]])
    _say_beside(table, 1, [])
    assert [c.text for row in table.rows for c in row] == ["s0", "0.100", "s1", "0.200"]
    _say_beside(table, 1, ["box 60x"])  # the last row added
    assert [row[1].text for row in table.rows] == ["0.100", "0.200 (box 60x)"]


def _run(config: str, overlap: float) -> RunResult:
    return RunResult(Path(config), "clip", config, "complete", 4, 30.0, 0, 0, False,
                     states=["tracking"] * 4, overlaps=[overlap] * 4, errors=[1.0] * 4)


TARGET = Box(0, 0, 10, 10)


def _scored(config: str, input: str, overlaps: list[float | None], state: str = "tracking",
            box: Box = TARGET) -> RunResult:
    """A run of 4 frames on ``input`` (the target :data:`TARGET` where ``overlaps`` has a
    value) whose box is ``box``."""
    truth = [TARGET if o is not None else None for o in overlaps]
    return RunResult(Path(config, input), input, config, "complete", 4, 30.0, 0, 0, False,
                     states=[state] * 4, overlaps=overlaps, errors=[1.0] * 4,
                     boxes=[box] * 4, truth=truth)


def test_averages_rank_a_config_only_if_it_has_every_input_another_has() -> None:
    """`z` has no frame evaluated: every config lacks every score there, yet every average
    said "(on 2 of 3 inputs)" and none was marked best. Now only a config lacking a score on
    an input where another has it (a's tracking miss on y: no frame called tracking) says so
    and is not ranked, its two notes in one parenthesis (they were "(on 1 of 2 inputs) (box
    >4x on 1 input)"); the others rank as before, on the inputs all have."""
    none: list[float | None] = [None] * 4
    by_config = {
        "a": [_scored("a", "x", [0.11] * 4, box=Box(0, 0, 30, 30)),
              _scored("a", "y", [0.0] * 4, "lost"), _scored("a", "z", none)],
        "b": [_scored("b", "x", [0.6] * 4), _scored("b", "y", [0.6] * 4),
              _scored("b", "z", none)],
        "c": [_scored("c", "x", [0.6, 0.6, 0.0, 0.0]), _scored("c", "y", [0.6] * 4),
              _scored("c", "z", none)],
    }
    table = average_table(by_config)
    cells = {row[0].text: dict(zip(table.header, row, strict=True)) for row in table.rows}
    assert cells["a"]["Tracking miss"].text == "0.000 (on 1 of 2 inputs; box >4x on 1 input)"
    assert [cells[c]["Tracking miss"].text for c in "bc"] == ["0.000", "0.250"]
    best = {title: {c for c in cells if cells[c][title].best} for title in table.header}
    assert best["Tracking miss"] == {"b"}  # (a's 0.000 as low, not ranked)
    assert best["AUC"] == best["Mean IoU"] == best["SR0.5"] == {"b"}
    assert best["Miss flagged"] == best["Inputs"] == set()
    # miss flagged: a's on y only (x: no frame misses), c's on x only, b's on neither
    assert [cells[c]["Miss flagged"].text for c in "abc"] == [
        "1.000 (on 1 of 2 inputs)", "—", "0.000 (on 1 of 2 inputs)"]
    assert [(c, title) for c in cells for title in table.header
            if "inputs" in cells[c][title].text] == [
        ("a", "Tracking miss"), ("a", "Miss flagged"), ("c", "Miss flagged")]


def test_one_run_drawn_is_the_best(monkeypatch: pytest.MonkeyPatch) -> None:
    """With one run drawn per input, none of the worst half (0 runs): `ranked[-0:]` took every
    run, so all were drawn."""
    monkeypatch.setattr(plots, "MAX_RUNS_DRAWN", 1)
    runs = [_run("a", 0.2), _run("b", 0.9), _run("c", 0.5)]
    assert [r.config for r in build._drawn_by_auc(runs)] == ["b"]


def test_the_package_lists_the_names_it_gives() -> None:
    """`dir(vtrack.report)` (and so `help()`, completion) did not show build_report, which
    the package gives only when asked for (its builder loads matplotlib)."""
    assert {"build_report", "Report", "DEFAULT_TITLE"} <= set(dir(vtrack.report))
    assert "build_report" in vtrack.report.__all__


def test_a_title_and_a_warning_with_a_newline_stay_one_markdown_line(clip_factory,
                                                                    tmp_path: Path) -> None:
    """summary.md wrote `--title $'a\\nb'` as '# a' and a line 'b' below the heading, and a
    warning naming an input with a newline ('x\\ny [s4]: no score ...') as a quote line and a
    plain one; both are now one line, the newline written '\\n' as in the page's tables."""
    from click.testing import CliRunner

    from vtrack.cli import main

    clip = clip_factory("smooth", width=160, height=120, frames=40)
    odd = tmp_path / "x\ny.mp4"
    odd.write_bytes(clip.path.read_bytes())
    ran = CliRunner().invoke(main, ["run", str(odd), "-c", "s4", "--no-video", "-q",
                                    "-o", str(tmp_path / "run")])
    assert ran.exit_code == 0, ran.output
    made = CliRunner().invoke(main, ["report", str(tmp_path / "run"), "--title", "a\nb",
                                     "-q", "-o", str(tmp_path / "rep")])
    assert made.exit_code == 0, made.output
    lines = (tmp_path / "rep" / "summary.md").read_text().splitlines()
    assert lines[0] == "# a\\nb"
    warned = [line for line in lines if line.startswith("> Warning: ")]
    assert any(line.startswith("> Warning: x\\ny \\[s4\\]: ") for line in warned), warned
    assert not any(line.startswith(("b", "y \\[s4\\]")) for line in lines)


@pytest.mark.parametrize("title", ["", "  "])
def test_an_empty_title_is_refused_in_one_line(tmp_path: Path, title: str) -> None:
    """`vtrack report R --title ""` wrote a page with an empty <title> and a bare '# ' heading
    in summary.md. The page's title is some text: an empty one is refused, naming the
    default, before anything is read or written."""
    from click.testing import CliRunner
    from conftest import one_error_line

    from vtrack.cli import main

    refused = CliRunner().invoke(main, ["report", str(tmp_path / "none"), "--title", title,
                                        "-o", str(tmp_path / "rep")])
    assert one_error_line(refused) == (
        "vtrack: error: Invalid value for '--title': empty; give the page's title, or leave "
        "--title out for 'vtrack report' (see 'main report --help')")
    assert list(tmp_path.iterdir()) == []


def test_names_in_summary_md_are_text_not_markup(clip_factory, tmp_path: Path) -> None:
    """A config named '<b>x</b>&amp;' (and a title '<i>t</i>') went into summary.md as they
    are, so a Markdown viewer showed a bold 'x&' (an italic 't'); '&', '<' and '>' are
    written as HTML entities now, so the viewer shows the names as written."""
    from click.testing import CliRunner

    from vtrack.cli import main

    clip = clip_factory("smooth", width=160, height=120, frames=30)
    shipped = Path(vtrack.report.__file__).parents[1] / "configs" / "s0.toml"
    config = tmp_path / "mine.toml"
    config.write_text(shipped.read_text().replace('name = "s0"', 'name = "<b>x</b>&amp;"', 1))
    ran = CliRunner().invoke(main, ["run", str(clip.path), "-c", str(config), "--gt",
                                    str(clip.gt), "--no-video", "-q", "-o", str(tmp_path / "run")])
    assert ran.exit_code == 0, ran.output
    made = CliRunner().invoke(main, ["report", str(tmp_path / "run"), "--title", "<i>t</i>",
                                     "-q", "-o", str(tmp_path / "rep")])
    assert made.exit_code == 0, made.output
    markdown = (tmp_path / "rep" / "summary.md").read_text()
    assert markdown.splitlines()[0] == "# &lt;i&gt;t&lt;/i&gt;"
    assert " | &lt;b&gt;x&lt;/b&gt;&amp;amp; | complete | " in markdown
    assert "<b>" not in markdown and "<i>" not in markdown


def test_markdown_specials_in_names_are_escaped_in_summary_md(clip_factory,
                                                              tmp_path: Path) -> None:
    """summary.md escaped '<', '>', '&' and '|' but not Markdown's own characters: an input
    named '*x*_a_b`c`' showed as an italic 'x', 'a_b' and a code span 'c', a config named
    '[s](u) ~~z~~\\' as a link and struck-through text (and its bold best cell ended early).
    Each is written after a backslash now (CommonMark's escapes), shown as named; a '_'
    between two letters or digits ('a_b'), which cannot be emphasis, stays as it is."""
    from click.testing import CliRunner

    from vtrack.cli import main

    clip = clip_factory("smooth", width=160, height=120, frames=30)
    odd = tmp_path / "*x*_a_b`c`.mp4"
    odd.write_bytes(clip.path.read_bytes())
    shipped = Path(vtrack.report.__file__).parents[1] / "configs" / "s0.toml"
    config = tmp_path / "mine.toml"
    config.write_text(shipped.read_text().replace('name = "s0"', 'name = "[s](u) ~~z~~\\\\"', 1))
    ran = CliRunner().invoke(main, ["run", str(odd), "-c", str(config), "--gt", str(clip.gt),
                                    "--no-video", "-q", "-o", str(tmp_path / "run")])
    assert ran.exit_code == 0, ran.output
    made = CliRunner().invoke(main, ["report", str(tmp_path / "run"), "--title", "_t_ a\\b",
                                     "-q", "-o", str(tmp_path / "rep")])
    assert made.exit_code == 0, made.output
    markdown = (tmp_path / "rep" / "summary.md").read_text()
    assert markdown.splitlines()[0] == "# \\_t\\_ a\\b"  # (a backslash before a letter is one)
    assert "| \\*x\\*\\_a_b\\`c\\` | \\[s\\](u) \\~\\~z\\~\\~\\\\ | complete | " in markdown
    assert "## \\*x\\*\\_a_b\\`c\\`" in markdown.splitlines()


def test_a_title_ending_in_a_hash_keeps_it_in_summary_md(clip_factory, tmp_path: Path) -> None:
    """`vtrack report R --title 'Ranking #'` wrote '# Ranking #', which CommonMark shows as
    "Ranking" (the '#'s ending a heading after a space close it); that '#' (and a title's first)
    is written '\\#' now, while a '#' inside a name ('clip #3') stays as it is."""
    from click.testing import CliRunner

    from vtrack.cli import main

    clip = clip_factory("smooth", width=160, height=120, frames=30)
    named = tmp_path / "clip #3.mp4"
    named.write_bytes(clip.path.read_bytes())
    ran = CliRunner().invoke(main, ["run", str(named), "-c", "s0", "--gt", str(clip.gt),
                                    "--no-video", "-q", "-o", str(tmp_path / "run")])
    assert ran.exit_code == 0, ran.output
    for title, heading in (("Ranking #", "# Ranking \\#"), ("#1 ##", "# \\#1 \\##")):
        made = CliRunner().invoke(main, ["report", str(tmp_path / "run"), "--title", title,
                                         "-q", "-o", str(tmp_path / "rep")])
        assert made.exit_code == 0, made.output
        markdown = (tmp_path / "rep" / "summary.md").read_text()
        assert markdown.splitlines()[0] == heading
        assert "| clip #3 | s0 | complete | " in markdown, markdown


def test_the_example_report_names_things_as_the_report_writes_them() -> None:
    """docs/example-report/summary.md names TIR_horse, VOT15_ball1, hue.sat_min as they are,
    but once every '_' was escaped the report wrote 'TIR\\_horse' (raw summary.md noisy,
    'groundtruth\\_rect.txt') and the shipped example was no longer what it writes. A '_'
    between two letters or digits cannot be emphasis: each name and error the example shows
    is written as the report writes it now."""
    example = Path(__file__).parents[1] / "docs" / "example-report" / "summary.md"
    written = []
    for line in example.read_text().splitlines():
        if line.startswith("## "):
            written.append(line[3:])
        elif line.startswith("| ") and not line.startswith("| ---"):
            written += [cell.strip() for cell in line.strip("|").split("|")[:2]]
        elif line.startswith("- **"):
            failed = re.fullmatch(r"- \*\*(.+)\*\* \[(.+)\] (\w+): (.+)", line)
            assert failed, line
            written += failed.groups()
    assert {"TIR_horse", "VOT15_ball1"} <= set(written)
    assert any("hue.sat_min" in text for text in written)
    assert {text: _md(text) for text in written if _md(text) != text} == {}
