"""``vtrack report RESULTS...``: plots and tables from run or batch result folders."""

from __future__ import annotations

from pathlib import Path

import click

from vtrack.cli._messages import echo_summary, warn
from vtrack.cli._options import (
    VtrackCommand,
    gt_first_option,
    gt_origin_option,
    refuse_gt_origin_without_gt,
    stats_period_option,
)
from vtrack.cli._paths import PATH, NonEmptyText
from vtrack.cli._progress import StepProgress
from vtrack.cli._signals import stopping_as_interrupted
from vtrack.errors import plural

DEFAULT_TITLE = "vtrack report"  # vtrack.report.DEFAULT_TITLE; not imported: it loads matplotlib


@click.command("report", cls=VtrackCommand)
@click.argument("results", nargs=-1, required=True, type=PATH)
@click.option("--out", "-o", "out_dir", type=PATH,
              default=Path("vtrack-report"), show_default=True, metavar="DIR",
              help="Report folder: index.html, plots/*.png, summary.md, summary.csv.")
@click.option("--gt", "gt_specs", multiple=True, metavar="[INPUT=]FILE",
              type=NonEmptyText("a ground-truth file or INPUT=FILE"),
              help="Ground truth for single-target runs made without it (their track.csv "
                   "boxes are scored against it). INPUT=FILE gives the file of one input "
                   "(its name as the report shows it, or its path); repeat for several (one "
                   "file per input, one plain FILE). A run "
                   "whose frame count differs from the file's boxes is not scored (a warning "
                   "names it).")
@gt_origin_option()
@gt_first_option()
@click.option("--title", default=DEFAULT_TITLE, show_default=True,
              type=NonEmptyText(f"the page's title, or leave --title out for {DEFAULT_TITLE!r}"),
              help="Page title.")
@stats_period_option()
@click.option("--quiet", "-q", is_flag=True, help="No progress and no summary line.")
def command(results: tuple[Path, ...], out_dir: Path, gt_specs: tuple[str, ...],
            gt_origin: int | None, gt_first: int, title: str, stats_period: float,
            quiet: bool) -> None:
    """Write an overlap report of every run found in RESULTS (run folders or batch folders,
    searched for run.json): per-input overlap over time, OTB success and precision plots,
    tables per input and configuration; open DIR/index.html in a browser."""
    refuse_gt_origin_without_gt(bool(gt_specs))
    from vtrack.report import build_report  # plotting loads only for this command

    progress = StepProgress(quiet, "report", "inputs", stats_period)
    try:
        # SIGTERM as Ctrl-C: no staged plot left behind; once they go in place, nothing
        with stopping_as_interrupted() as settled:
            report = build_report(list(results), out_dir, gt=list(gt_specs),
                                  gt_origin=gt_origin, gt_first=gt_first, title=title,
                                  on_input=progress, settled=settled)
    finally:
        progress.close()
    for warning in report.warnings:
        warn(warning)
    if not quiet:
        echo_summary(f"{plural(len(report.runs), 'run')}, {plural(len(report.plots), 'plot')} "
                     f"-> {report.index}")
