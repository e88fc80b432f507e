"""Writing a report: ``index.html`` (self-contained, plots referenced relatively), ``summary.md``
and ``summary.csv``. Every file is written under a temporary name and renamed when complete."""

from __future__ import annotations

import html
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from vtrack import __version__
from vtrack.errors import printable
from vtrack.io.outdir import REPORT_GENERATOR
from vtrack.report import rows
from vtrack.report.runs import FailedRun, RunResult
from vtrack.report.tables import NOTES, Table

#: The footer of a report with single-target runs: what the numbers mean (OTB conventions,
#: vtrack.evaluate.metrics). ``{sorting}`` is :data:`SORTING` in index.html, nothing in
#: summary.md.
DEFINITIONS = (
    "Overlap is the intersection over union (IoU) of the tracker's box and the ground-truth box. "
    "Success plot: share of evaluated frames whose overlap is > t, for t = 0, 0.05, ..., 1; "
    "AUC is the mean of these 21 values. Precision plot: share of evaluated frames whose "
    "centre error is <= t pixels, t = 0 ... 50; the score is the value at 20 px. Frames whose "
    "ground truth is empty or marked absent (target out of view) are not evaluated; a frame "
    "where the tracker claims no box (lost) counts as a failure (overlap 0, infinite centre "
    "error); summary.csv's mean_center_error is the mean over the evaluated frames where the "
    "tracker claims a box, lost frames left out (read it beside precision20 and frames_lost). "
    "Averages over inputs are means of the per-input curves and scores (lost frames: "
    "their total) over the inputs that have them; a configuration lacking a score on an "
    "input where another has it (a dash in its row: tracking miss where no frame is called "
    "tracking) is not ranked by it, and its cell says over how many inputs it is (on 1 of 2 "
    "inputs). Best value per "
    "column (among the configurations of an input, or among configurations) in bold; columns "
    "that describe rather than rank (frames, miss flagged, lost frames) mark none.{sorting} "
    + " ".join(f"{title}: {note}." for title, note in NOTES.items()
               if title in ("Tracking miss", "Miss flagged", "Lost frames"))
)
#: The footer's start when only multi-target runs are shown (none of the overlap measures
#: above is on the page); ``{sorting}`` as above.
MOT_ONLY_DEFINITIONS = (
    "Best value per column (among the configurations of an input) in bold; columns that "
    "describe rather than rank (Frames, PT, GT ids, Tracks) mark none.{sorting}"
)
#: How index.html's tables answer the mouse (a Markdown table neither sorts nor hovers).
SORTING = " Click a column's header to sort by it; hover it for what it means."
#: Added to the footer when multi-target runs are shown; ``{hover}`` as ``{sorting}`` above.
MOT_DEFINITIONS = (
    "Multi-target runs show the CLEAR MOT and identity metrics (MOTA, MOTP, IDF1, ID switches "
    "...) that vtrack run recorded in run.json against MOTChallenge ground truth, abbreviated "
    "as MOTChallenge does (IDs: ID switches, FP: false positives, FN: misses, MT/PT/ML: mostly "
    "tracked/partially tracked/mostly lost objects{hover}); a dash means the run had "
    "no ground truth, or that a measure had nothing to be taken over (MOTP: no track box "
    "matched; IDP: no track box; MOTA, IDR: no ground-truth box). summary.csv holds every "
    "recorded metric."
)

CSS = """
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", sans-serif; color: #1d1d1f;
       max-width: 1100px; margin: 24px auto; padding: 0 16px; }
h1 { font-size: 24px; margin-bottom: 4px; } h2 { margin-top: 32px; border-bottom: 1px solid #ddd; }
.meta { color: #666; margin-top: 0; } .warn { color: #9a5b00; }
.scroll { overflow-x: auto; max-width: 100%; }
table { border-collapse: collapse; margin: 12px 0; font-variant-numeric: tabular-nums; }
th { cursor: pointer; user-select: none; } th[title] { text-decoration: underline dotted; }
th[data-dir="asc"]::after { content: " \\25B2"; } th[data-dir="desc"]::after { content: " \\25BC"; }
th, td { padding: 4px 8px; border-bottom: 1px solid #e5e5e5; text-align: right; }
th { background: #f4f4f6; } td.label, th.label { text-align: left; }
tr.group td { border-top: 2px solid #bbb; } td.best { font-weight: 700; background: #e6f4ea; }
img { max-width: 100%; display: block; margin: 8px 0; }
nav a { margin-right: 10px; } footer { margin-top: 40px; color: #555; font-size: 13px;
       border-top: 1px solid #ddd; padding-top: 8px; }
"""


@dataclass
class Section:
    """One input's part of the report: its name, anchor, plots (paths relative to the
    report folder) and notes shown under its heading (what its plots leave out)."""

    name: str
    anchor: str
    plots: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass
class Page:
    """Everything the report files show."""

    title: str
    meta: str
    warnings: list[str]
    overall_plot: str | None
    averages: Table | None
    results: Table | None
    mot: Table | None
    failed: list[FailedRun]
    sections: list[Section]


def _footer(page: Page, html_page: bool) -> str:
    """What the numbers mean; how the tables sort and explain themselves in ``html_page`` only
    (index.html, not summary.md)."""
    only_mot = page.mot is not None and page.results is None and page.averages is None
    text = (MOT_ONLY_DEFINITIONS if only_mot else DEFINITIONS).format(
        sorting=SORTING if html_page else "")
    if page.mot is not None:
        text += " " + MOT_DEFINITIONS.format(hover="; hover a header" if html_page else "")
    return text


# --- HTML ------------------------------------------------------------------------------------

def _e(text: object) -> str:
    return html.escape(str(text))


#: Sorting by a click on a header (numbers as numbers, dashes last; a second click reverses).
SORT_JS = """
document.querySelectorAll("table.sortable").forEach(function (table) {
  table.querySelectorAll("th").forEach(function (th, col) {
    th.addEventListener("click", function () {
      var dir = th.dataset.dir === "asc" ? "desc" : "asc";
      table.querySelectorAll("th").forEach(function (h) { delete h.dataset.dir; });
      th.dataset.dir = dir;
      var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
      function key(row) {
        var text = row.cells[col].textContent.trim(), number = parseFloat(text);
        return isNaN(number) ? text : number;
      }
      rows.sort(function (a, b) {
        var x = key(a), y = key(b), sign = dir === "asc" ? 1 : -1;
        if (typeof x === "number" && typeof y === "number") return sign * (x - y);
        if (typeof x === "number") return -1;
        if (typeof y === "number") return 1;
        return sign * x.localeCompare(y);
      });
      rows.forEach(function (row) { row.classList.remove("group"); body.appendChild(row); });
    });
  });
});
"""


def html_table(table: Table, labels: int) -> str:
    """A sortable table (click a header) in a horizontally scrolling box; the first
    ``labels`` columns are left-aligned text, best cells highlighted, headers with a note
    carry it as their tooltip."""

    def header(n: int, title: str) -> str:
        note = table.notes.get(title)
        attrs = (' class="label"' if n < labels else "") + (f' title="{_e(note)}"' if note
                                                             else "")
        return f"<th{attrs}>{_e(title)}</th>"

    head = "".join(header(n, h) for n, h in enumerate(table.header))
    rows = []
    for index, row in enumerate(table.rows):
        cells = "".join(
            f'<td class="{"label" if n < labels else ""}{" best" if cell.best else ""}">'
            f"{_e(cell.text)}</td>"
            for n, cell in enumerate(row)
        )
        group = ' class="group"' if index in table.groups[1:] else ""
        rows.append(f"<tr{group}>{cells}</tr>")
    return (f'<div class="scroll"><table class="sortable"><thead><tr>{head}</tr></thead>'
            f"<tbody>{''.join(rows)}</tbody></table></div>")


def _img(path: str, alt: str) -> str:
    return f'<img src="{_e(path)}" alt="{_e(alt)}" loading="lazy">'


#: The heading of the batch rows that left no results.
NO_RESULTS = "Runs without results (failed, or never ran)"


def render_html(page: Page) -> str:
    """The whole page: plots are ``<img>`` of PNG files beside it (relative paths)."""
    parts = [f"<h1>{_e(page.title)}</h1>", f'<p class="meta">{_e(page.meta)}</p>']
    if page.sections:
        links = " ".join(f'<a href="#{_e(s.anchor)}">{_e(s.name)}</a>' for s in page.sections)
        parts.append(f"<nav>Inputs: {links}</nav>")
    parts += [f'<p class="warn">Warning: {_e(w)}</p>' for w in page.warnings]
    if page.averages is not None:
        parts.append('<h2 id="overall">All inputs</h2>')
        if page.overall_plot:
            parts.append(_img(page.overall_plot, "success and precision plots, all inputs"))
        parts.append(html_table(page.averages, 1))
    if page.results is not None:
        parts += ['<h2 id="results">Results per input and configuration</h2>',
                  html_table(page.results, 3)]
    if page.mot is not None:
        parts += ['<h2 id="multi-target">Multi-target runs</h2>', html_table(page.mot, 3)]
    if page.failed:
        items = "".join(f"<li><b>{_e(f.input)}</b> [{_e(f.config)}] {_e(f.status)}: "
                        f"{_e(f.error)}</li>" for f in page.failed)
        parts += [f'<h2 id="failed">{NO_RESULTS}</h2>', f"<ul>{items}</ul>"]
    for section in page.sections:
        parts.append(f'<h2 id="{_e(section.anchor)}">{_e(section.name)}</h2>')
        parts += [f'<p class="note">{_e(note)}</p>' for note in section.notes]
        parts += [_img(p, f"{section.name}: {Path(p).stem}") for p in section.plots]
        if not section.plots:
            parts.append("<p>No frame tracked: nothing to plot.</p>")
    parts.append(f"<footer>{_e(_footer(page, html_page=True))}</footer>")
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f'{REPORT_GENERATOR} {_e(__version__)}">\n'
        f'<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{_e(page.title)}</title>\n<style>{CSS}</style>\n</head>\n<body>\n"
        + "\n".join(parts) + f"\n<script>{SORT_JS}</script>\n</body>\n</html>\n"
    )


# --- Markdown --------------------------------------------------------------------------------

#: Characters that would make inline Markdown of a name (emphasis, code, links, strikethrough,
#: a cell's end), a backslash that would escape what follows it (ASCII punctuation, or the
#: end of a bold cell), and a ``#`` that would make or end a heading (a text's first, or the
#: first of the ``#``s that end it after a space: ``# Ranking #`` shows "Ranking"): each is
#: written after a backslash (CommonMark's escapes), but for a run of ``_`` between two letters
#: or digits (:func:`_escaped`). A backslash before anything else is shown as it is (``\n``
#: from :func:`~vtrack.errors.printable`), and so is another ``#`` (``clip #3``).
MARKDOWN_SPECIALS = re.compile(r"[`*\[\]~|]|_+|\\(?=[!-/:-@\[-`{-~]|$)|^#|(?<=\s)#(?=#*\s*$)")


def _escaped(special: re.Match[str]) -> str:
    """A match of :data:`MARKDOWN_SPECIALS`, each character after a backslash; a run of ``_``
    between two letters or digits as it is (``groundtruth_rect``: CommonMark takes no
    emphasis there, and the raw file stays readable)."""
    text, start, end = special.string, special.start(), special.end()
    if special[0][0] == "_" and text[start - 1:start].isalnum() and text[end:end + 1].isalnum():
        return special[0]
    return "".join(f"\\{c}" for c in special[0])


def _md(text: object) -> str:
    """Text for one Markdown line or cell, shown as written: control characters escaped,
    ``&``, ``<`` and ``>`` as HTML entities (a name is not markup) and each of
    :data:`MARKDOWN_SPECIALS` after a backslash (``*x*`` is not italics, ``a|b`` not two
    cells, ``_x_`` not emphasis; ``a_b`` as it is)."""
    return html.escape(MARKDOWN_SPECIALS.sub(_escaped, printable(str(text))), quote=False)


def markdown_table(table: Table, labels: int) -> str:
    """A GitHub-flavoured Markdown table, best cells in bold."""
    align = ["---" if n < labels else "---:" for n in range(len(table.header))]
    lines = ["| " + " | ".join(_md(h) for h in table.header) + " |",
             "| " + " | ".join(align) + " |"]
    for row in table.rows:
        cells = [f"**{_md(c.text)}**" if c.best else _md(c.text) for c in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def render_markdown(page: Page) -> str:
    """The report's tables (and links to its plots) as Markdown."""
    parts = [f"# {_md(page.title)}", _md(page.meta)]  # one line each, whatever they name
    parts += [f"> Warning: {_md(w)}" for w in page.warnings]
    if page.averages is not None:
        parts.append("## All inputs")
        if page.overall_plot:
            parts.append(f"![success and precision plots]({page.overall_plot})")
        parts.append(markdown_table(page.averages, 1))
    if page.results is not None:
        parts += ["## Results per input and configuration", markdown_table(page.results, 3)]
    if page.mot is not None:
        parts += ["## Multi-target runs", markdown_table(page.mot, 3)]
    if page.failed:
        parts += [f"## {NO_RESULTS}",
                  "\n".join(f"- **{_md(f.input)}** [{_md(f.config)}] {_md(f.status)}: "
                            f"{_md(f.error)}" for f in page.failed)]
    for section in page.sections:
        if section.plots:
            parts.append(f"## {_md(section.name)}")
            parts += [_md(note) for note in section.notes]
            parts += [f"![{Path(p).stem}]({p})" for p in section.plots]
    parts.append("---\n" + _footer(page, html_page=False))
    return "\n\n".join(parts) + "\n"


# --- CSV -------------------------------------------------------------------------------------

def render_csv(runs: Sequence[RunResult], failed: Sequence[FailedRun] = ()) -> str:
    """``summary.csv`` (:mod:`.rows`, as a batch writes its own): one row per run, then one row
    per batch row without results (input, config, status and error only)."""
    return rows.render([*map(rows.run_row, runs),
                        *({"input": f.input, "config": f.config, "status": f.status,
                           "error": f.error} for f in failed)])
