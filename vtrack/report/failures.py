"""Failure thumbnails: the frames where the trackers of one input lost the target, every
configuration side by side, each with its own box and the ground truth's.

For each scored run the first frame of each of its longest stretches of misses (target present,
IoU 0 or no box) is taken (:func:`failure_frames`); the frames of all runs of the input are
decoded once from the input the runs read, and drawn as a grid: a row per frame, a column per
configuration, so the same moment is compared across trackers.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence

import cv2
import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from vtrack.errors import InputError, VtrackError, printable
from vtrack.geometry import Box
from vtrack.report.plots import DPI, runs_of
from vtrack.report.runs import RunResult

#: Failures taken per run, and frames (rows) shown per input at most.
PER_RUN, MAX_ROWS = 3, 6
#: Width of a thumbnail in pixels (frames are scaled to it, small ones at most twice up), and
#: the narrowest cell (room for its title).
THUMB_WIDTH, MIN_CELL = 320, 270
#: Pixels a character of the title takes at most (10 pt at :data:`DPI`), and the fewest
#: characters a title line is wrapped to.
TITLE_CHAR_PX, MIN_TITLE_CHARS = 8, 20


def failure_frames(run: RunResult, limit: int = PER_RUN) -> list[int]:
    """The input's frame numbers where the run's ``limit`` longest stretches of misses start
    (longest first; ties by time)."""
    missed = [o is not None and o <= 0 for o in run.overlaps or []]
    stretches = [(end - start, start) for start, end, miss in runs_of(missed) if miss]
    stretches.sort(key=lambda s: (-s[0], s[1]))
    return [run.first_frame + start for _, start in stretches[:limit]]


def _frames(source: str, wanted: set[int]) -> dict[int, np.ndarray]:
    """The BGR pictures of the ``wanted`` frame numbers of ``source`` (decoded in one pass)."""
    from vtrack.io import open_source

    found: dict[int, np.ndarray] = {}
    with open_source(source) as frames:
        for frame in frames:
            if frame.index in wanted:
                found[frame.index] = frame.bgr().copy()
            if len(found) == len(wanted) or frame.index >= max(wanted):
                break
    return found


def _draw_box(axis, box: Box | None, scale: float, colour: str, dashed: bool = False,
              width: float = 1.6) -> None:
    if box is not None:
        axis.add_patch(Rectangle((box.x * scale, box.y * scale), box.w * scale, box.h * scale,
                                 fill=False, edgecolor=colour, lw=width,
                                 ls="--" if dashed else "-"))


def _draw_truth(axis, box: Box | None, scale: float) -> None:
    """The ground truth in white on black, a colour no configuration gets."""
    _draw_box(axis, box, scale, "black", width=3.0)
    _draw_box(axis, box, scale, "white", width=1.2)


def failure_figure(name: str, runs: Sequence[RunResult], palette: Mapping[str, str]
                   ) -> Figure | None:
    """The grid of failure frames of ``runs`` (one input); None when no run misses the target.
    Raises InputError (a VtrackError) when the input cannot be read again or is not the file
    the runs read (it changed since)."""
    scored = [r for r in runs if r.truth is not None and r.overlaps]
    unread = [r for r in runs if r.truth is None and r.ground_truth and failure_frames(r)]
    if unread and not scored:  # scored with the overlaps the run recorded
        raise InputError(f"the ground truth {unread[0].ground_truth} is not found from here or "
                         "changed since the run (the failure frames draw its boxes)")
    rows = sorted({f for run in scored for f in failure_frames(run)})[:MAX_ROWS]
    sources = [r.source for r in scored if r.source]
    changed = [r.source_changed for r in scored if r.source_changed]
    if rows and changed and not sources:  # another video than the one tracked
        raise InputError(changed[0])
    if not rows or not sources:
        return None
    pictures = _frames(sources[0], set(rows))
    rows = [f for f in rows if f in pictures]
    if not rows:
        return None
    height, width = pictures[rows[0]].shape[:2]
    scale = min(2.0, THUMB_WIDTH / width)
    cell = (max(width * scale, MIN_CELL) / DPI * 1.05, height * scale / DPI * 1.05 + 0.3)
    figure = Figure(figsize=(cell[0] * len(scored), cell[1] * len(rows) + 0.5), dpi=DPI,
                    layout="constrained")
    axes = figure.subplots(len(rows), len(scored), squeeze=False)
    for r, frame in enumerate(rows):
        picture = cv2.cvtColor(cv2.resize(
            pictures[frame], None, fx=scale, fy=scale,
            interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR), cv2.COLOR_BGR2RGB)
        for c, run in enumerate(scored):
            axis = axes[r, c]
            axis.imshow(picture)
            axis.set_axis_off()
            at = frame - run.first_frame
            if not 0 <= at < len(run.boxes):
                axis.set_title(f"{printable(run.config)}, frame {frame}: not tracked", fontsize=8)
                continue
            assert run.truth is not None and run.overlaps is not None
            truth = run.truth[at] if at < len(run.truth) else None
            _draw_truth(axis, truth, scale)
            _draw_box(axis, run.boxes[at], scale, palette[run.config],
                      dashed=run.states[at] != "tracking")
            overlap = run.overlaps[at]
            said = run.states[at] or "skipped"
            score = "no box" if run.boxes[at] is None else (
                "—" if overlap is None else f"IoU {overlap:.2f}")
            axis.set_title(f"{printable(run.config)}, frame {frame}: {score} ({said})", fontsize=8,
                           color=palette[run.config])
    # wrapped to the figure's width: one column is narrower than the title's one line
    chars = max(MIN_TITLE_CHARS, int(figure.get_figwidth() * DPI / TITLE_CHAR_PX))
    figure.suptitle(textwrap.fill(f"{printable(name)}: where the trackers lost the target "
                                  "(white: ground truth; dashed: the tracker said occluded or "
                                  "lost)", chars), fontsize=10)
    return figure


def read_once_misses(runs: Sequence[RunResult]) -> bool:
    """Whether ``runs`` (one input) miss the target somewhere but their input was read once as
    it came (:attr:`RunResult.live_input`: a stream, a URL, stdin): their failure frames are
    not drawn, what the input sends now is not what was tracked."""
    return not any(r.source for r in runs) and any(
        r.live_input and r.truth is not None and failure_frames(r) for r in runs)


def try_failure_figure(name: str, runs: Sequence[RunResult], palette: Mapping[str, str]
                       ) -> tuple[Figure | None, str | None]:
    """:func:`failure_figure`, or (None, a warning) when the input cannot be read again."""
    try:
        return failure_figure(name, runs, palette), None
    except VtrackError as exc:
        return None, f"failure frames of {name} left out: {exc}"
