"""The report's figures, drawn with matplotlib's Agg canvas (no display, no pyplot state).

- :func:`overlap_figure`: overlap (%) over time, one panel per configuration, occluded and lost
  frames shaded (the layout of S0's Fig. 20);
- :func:`state_figure`: without ground truth, the tracker's own score over time with its
  occluded and lost frames shaded, one panel per configuration;
- :func:`curves_figure`: OTB success plot (AUC in the legend) beside the precision plot (value at
  20 px in the legend).

Every function returns a matplotlib Figure; :func:`save` writes one as PNG.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from vtrack.errors import printable
from vtrack.evaluate.metrics import ERROR_THRESHOLDS, OVERLAP_THRESHOLDS, PRECISION_THRESHOLD_PX
from vtrack.report.runs import RunResult
from vtrack.stages.base import TrackState

DPI = 100
#: Shading of the frames a tracker reported occluded / lost, and of frames not evaluated.
SHADES = {TrackState.OCCLUDED: ("#f5a623", "occluded"), TrackState.LOST: ("#d0021b", "lost")}
NO_GT_SHADE = "#9b9b9b"


#: Configurations' colours: matplotlib's tab10 without its grey (C7), the grey of the curves
#: a legend does not name.
CONFIG_COLOURS = tuple(f"C{n}" for n in range(10) if n != 7)
#: Line styles of the success and precision plots' curves, one per round of the colours.
CURVE_STYLES = ("-", "--", ":", "-.")


def colours(configs: Sequence[str]) -> dict[str, str]:
    """One colour per configuration, the same in every figure (:data:`CONFIG_COLOURS` in turn:
    past 9 configurations colours repeat, and :func:`curve_style` tells their curves apart)."""
    cycle = [CONFIG_COLOURS[n % len(CONFIG_COLOURS)] for n in range(len(configs))]
    return dict(zip(configs, cycle, strict=True))


def curve_style(palette: Mapping[str, str], config: str) -> str:
    """The line style of ``config``'s curves: solid for the first 9 configurations of
    ``palette`` (from :func:`colours`), then dashed, dotted, dash-dotted for each further round
    of its colours, so no two of the first 36 share both colour and style in a legend."""
    rounds = list(palette).index(config) // len(CONFIG_COLOURS)
    return CURVE_STYLES[rounds % len(CURVE_STYLES)]


def runs_of(values: Sequence[object]) -> list[tuple[int, int, object]]:
    """Maximal stretches of equal values as ``(start, end, value)``, ``end`` exclusive."""
    stretches, start = [], 0
    for index in range(1, len(values) + 1):
        if index == len(values) or values[index] != values[start]:
            stretches.append((start, index, values[start]))
            start = index
    return stretches


def _shade(axis, values: Sequence[object], value: object, colour: str, label: str,
           first: int = 0) -> None:
    """Shade the frames where ``values`` (frame ``first`` on) equals ``value`` (one legend
    entry)."""
    spans = [(start, end) for start, end, v in runs_of(values) if v == value]
    for n, (start, end) in enumerate(spans):
        axis.axvspan(first + start - 0.5, first + end - 0.5, color=colour, alpha=0.22, lw=0,
                     label=label if n == 0 else None)


#: What the score panel of a run whose tracker gives no score says (S4: its document has none).
NO_SCORE = "no score: this tracker gives none (track.csv's score is empty); its state is shaded"

#: Configurations a success or precision plot names in its legend (the best); the others are
#: drawn in grey under one entry. Runs drawn as panels of an overlap or state plot (and as
#: columns of the failure frames): past these, a plot draws the first and the page says so.
MAX_LEGEND, MAX_RUNS_DRAWN = 10, 6

#: The y range of every 0..1 score axis (overlap over time, success and precision plots).
SCORE_YLIM = (0.0, 1.02)


def _line(axis, frames: np.ndarray, series: np.ndarray, colour: str) -> None:
    """``series`` over ``frames`` as a line, NaN left as gaps; a value with no value on either
    side (a run of one frame, a frame between frames without ground truth) as a dot, which a
    line would leave undrawn."""
    axis.plot(frames, series, color=colour, lw=1.2)
    known = np.isfinite(series)
    alone = known & ~np.r_[False, known[:-1]] & ~np.r_[known[1:], False]
    if alone.any():
        axis.plot(frames[alone], series[alone], "o", color=colour, ms=3)


def _panels(title: str, runs: Sequence[RunResult], palette: Mapping[str, str], ylabel: str,
            values: Callable[[RunResult], Sequence[float | None]],
            absent: Callable[[RunResult], Sequence[bool]] | None = None,
            empty: str | None = None) -> Figure:
    """A panel per run (configuration): ``values`` per frame (0..1) over the frames it reported
    occluded or lost (shaded), and frames where ``absent`` is true in grey (no ground truth);
    a run with frames but no value at all gets the text ``empty`` across its panel instead of
    a blank line. The shading legend sits above the panels, never over the data."""
    figure = Figure(figsize=(10, 0.9 + 1.7 * len(runs)), dpi=DPI, layout="constrained")
    axes = figure.subplots(len(runs), 1, sharex=True, squeeze=False)[:, 0]
    legend: dict[str, object] = {}
    series_of = [np.array([np.nan if v is None else v for v in values(run)], float)
                 for run in runs]
    for axis, run, series in zip(axes, runs, series_of, strict=True):
        for state, (colour, label) in SHADES.items():
            _shade(axis, run.states, state, colour, label, run.first_frame)
        if absent is not None:
            _shade(axis, absent(run), True, NO_GT_SHADE, "no ground truth", run.first_frame)
        _line(axis, run.first_frame + np.arange(len(series)), series, palette[run.config])
        if empty is not None and len(series) and not np.isfinite(series).any():
            axis.text(0.5, 0.5, empty, transform=axis.transAxes, ha="center", va="center",
                      fontsize=9, color="0.35")
        axis.set_ylim(*SCORE_YLIM)
        axis.set_ylabel(ylabel)
        axis.set_title(printable(run.config), loc="left", fontsize=10, color=palette[run.config])
        axis.grid(alpha=0.3)
        for handle, label in zip(*axis.get_legend_handles_labels(), strict=True):
            legend.setdefault(label, handle)
    if legend:  # one legend for all panels, outside them (constrained layout makes room)
        figure.legend(list(legend.values()), list(legend), loc="outside upper right",
                      fontsize=8, ncols=len(legend), frameon=False)
    # one frame axis for all panels (shared), in the input's frame numbers (a run from
    # --start N begins at N): from the first frame any run tracked to the last
    axes[-1].set_xlim(min(run.first_frame for run in runs) - 0.5,
                      max(run.first_frame + max(len(series), 1)
                          for run, series in zip(runs, series_of, strict=True)) - 0.5)
    axes[-1].xaxis.set_major_locator(MaxNLocator(integer=True, min_n_ticks=1))  # whole frames
    axes[-1].set_xlabel("frame")
    figure.suptitle(printable(title), fontsize=11)
    return figure


def overlap_figure(name: str, runs: Sequence[RunResult], palette: Mapping[str, str]) -> Figure:
    """Overlap (IoU, 0..1 like the success plot) with the ground truth per frame; a panel per
    run (configuration) with the frames it reported occluded or lost shaded, and frames without
    ground truth in grey."""
    return _panels(f"{name}: overlap with ground truth over time", runs, palette,
                   "overlap (IoU)", lambda run: run.overlaps or [],
                   lambda run: [o is None for o in run.overlaps or []])


def state_figure(name: str, runs: Sequence[RunResult], palette: Mapping[str, str]) -> Figure:
    """Without ground truth: each run's own score (0..1) per frame, its occluded and lost
    frames shaded (a run whose tracker gives no score: :data:`NO_SCORE` in its panel); a panel
    per run (configuration)."""
    return _panels(f"{name}: tracker's score and state over time (no ground truth)", runs,
                   palette, "score", lambda run: run.confidence, empty=NO_SCORE)


def _ranked_curves(axis, thresholds: np.ndarray, curves: Mapping[str, np.ndarray],
                   palette: Mapping[str, str], score: Callable[[np.ndarray], float],
                   notes: Mapping[str, str]) -> None:
    """Draw ``curves`` best ``score`` first, each labelled with its score (and its ``notes``
    entry, if any, after it: ``[0.948, on 1 of 2 inputs]``), in its colour and
    line style (:func:`curve_style`); past the best
    :data:`MAX_LEGEND` the others are thin grey lines under one legend entry that counts them
    (the legend stays within the figure however many configurations there are)."""
    ranked = sorted(curves, key=lambda c: -score(curves[c]))
    for config in ranked[:MAX_LEGEND]:
        axis.plot(thresholds, curves[config], color=palette[config], lw=1.8, zorder=3,
                  ls=curve_style(palette, config),
                  label=f"{printable(config)} [{score(curves[config]):.3f}"
                        f"{', ' + notes[config] if config in notes else ''}]")
    others = ranked[MAX_LEGEND:]
    if others:  # one collection: drawn as fast as a line, however many
        axis.add_collection(LineCollection(
            [np.column_stack([thresholds, curves[c]]) for c in others], colors="0.6", lw=0.7,
            alpha=0.6, zorder=2, label=f"{len(others)} more (grey; in the tables)"))


def curves_figure(title: str, success: Mapping[str, np.ndarray],
                  precision: Mapping[str, np.ndarray], palette: Mapping[str, str],
                  notes: Mapping[str, str] | None = None) -> Figure:
    """Success plot and precision plot side by side, configurations ordered best first; the
    legends name the best :data:`MAX_LEGEND` and count the others (drawn in grey), each
    score followed by the configuration's ``notes`` entry when it has one (the All inputs
    plot's ``on 1 of 2 inputs`` for a configuration scored on fewer inputs than the others).

    ``success[config]`` holds the 21 success rates at :data:`OVERLAP_THRESHOLDS`, its legend the
    AUC (their mean); ``precision[config]`` the 51 rates at :data:`ERROR_THRESHOLDS`, its legend
    the value at 20 px.
    """
    figure = Figure(figsize=(10, 3.8), dpi=DPI, layout="constrained")
    left, right = figure.subplots(1, 2)
    at20 = int(np.searchsorted(ERROR_THRESHOLDS, PRECISION_THRESHOLD_PX))
    notes = notes or {}
    _ranked_curves(left, OVERLAP_THRESHOLDS, success, palette, lambda curve: curve.mean(),
                   notes)
    _ranked_curves(right, ERROR_THRESHOLDS, precision, palette, lambda curve: curve[at20],
                   notes)
    right.axvline(PRECISION_THRESHOLD_PX, color="0.5", lw=0.8, ls="--")
    for axis, xlabel, name, xmax in (
        (left, "overlap threshold", "Success plot (AUC)", 1.0),
        (right, "location error threshold (px)", "Precision plot (at 20 px)", 50.0),
    ):
        axis.set_xlim(0, xmax)
        axis.set_ylim(*SCORE_YLIM)
        axis.set_xlabel(xlabel)
        axis.set_ylabel("success rate" if axis is left else "precision")
        axis.set_title(name, fontsize=10)
        axis.grid(alpha=0.3)
        axis.legend(loc="lower left" if axis is left else "lower right", fontsize=8)
    figure.suptitle(printable(title), fontsize=11)
    return figure


def save(figure: Figure, path: Path) -> Path:
    """Write ``figure`` as a PNG file at ``path`` (whatever its name) and return ``path``; the
    OSError of a file that cannot be written is the caller's."""
    figure.savefig(path, format="png")
    return path
